//! Where everything goes on the screen: the header, the footer and the panels of the view
//! shown, for a terminal of a given size. App state, not drawing: the views draw into these
//! areas, the app pages its log by them, input finds what a click hit.

use ratatui::layout::{Constraint, Layout, Rect};

use super::{App, View};

/// A panel of the main area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Panel {
    Sensors,
    Charts,
    Map,
    Link,
    Log,
    Params,
    /// One line per robot, with several robots.
    Fleet,
}

/// Where everything goes.
#[derive(Clone, Debug, PartialEq)]
pub struct Areas {
    pub header: Rect,
    pub footer: Rect,
    pub panels: Vec<(Panel, Rect)>,
}

impl Areas {
    /// Where `panel` is drawn, if it is.
    pub fn find(&self, panel: Panel) -> Option<Rect> {
        self.panels
            .iter()
            .find(|(p, _)| *p == panel)
            .map(|(_, r)| *r)
    }
}

/// Terminal sizes at which the dashboard shows more panels.
const LARGE: (u16, u16) = (150, 38);
const MEDIUM: (u16, u16) = (100, 30);

/// The layout for a terminal of `area` showing `app.view`.
pub fn areas(area: Rect, app: &App) -> Areas {
    let [header, main, footer] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Fill(1),
        Constraint::Length(1),
    ])
    .areas(area);
    // Several robots: their lines above the selected robot's panels.
    let (fleet, main) = fleet_split(app, main);
    let mut panels = match app.view {
        View::Dashboard => dashboard(main),
        View::Sensors => vec![(Panel::Sensors, main)],
        View::Charts => vec![(Panel::Charts, main)],
        View::Map => vec![(Panel::Map, main)],
        View::Link => vec![(Panel::Link, main)],
        View::Log => vec![(Panel::Log, main)],
        View::Params => vec![(Panel::Params, main)],
    };
    panels.extend(fleet.map(|r| (Panel::Fleet, r)));
    Areas {
        header,
        footer,
        panels,
    }
}

fn dashboard(main: Rect) -> Vec<(Panel, Rect)> {
    use Constraint::{Fill, Length, Percentage};
    let (w, h) = (main.width, main.height + 2);
    if w >= LARGE.0 && h >= LARGE.1 {
        let [c1, c2, c3] =
            Layout::horizontal([Percentage(30), Percentage(42), Percentage(28)]).areas(main);
        let [sensors, link] = Layout::vertical([Percentage(55), Percentage(45)]).areas(c1);
        let [map, charts] = Layout::vertical([Percentage(65), Percentage(35)]).areas(c2);
        vec![
            (Panel::Sensors, sensors),
            (Panel::Link, link),
            (Panel::Map, map),
            (Panel::Charts, charts),
            (Panel::Log, c3),
        ]
    } else if w >= MEDIUM.0 && h >= MEDIUM.1 {
        let [left, right] = Layout::horizontal([Percentage(45), Percentage(55)]).areas(main);
        let [sensors, link] = Layout::vertical([Percentage(60), Percentage(40)]).areas(left);
        let [map, log] = Layout::vertical([Percentage(65), Percentage(35)]).areas(right);
        vec![
            (Panel::Sensors, sensors),
            (Panel::Link, link),
            (Panel::Map, map),
            (Panel::Log, log),
        ]
    } else {
        let [top, log] = Layout::vertical([Fill(1), Length(6)]).areas(main);
        let [sensors, map] = Layout::horizontal([Percentage(50), Percentage(50)]).areas(top);
        vec![
            (Panel::Sensors, sensors),
            (Panel::Map, map),
            (Panel::Log, log),
        ]
    }
}

/// The fleet panel above the main area, with several robots; the rest of `main`.
fn fleet_split(app: &App, main: Rect) -> (Option<Rect>, Rect) {
    let Some(f) = app.fleet.as_ref().filter(|_| app.in_fleet()) else {
        return (None, main);
    };
    let rows = (f.robots.len() as u16 + 2).min(main.height / 2);
    let [panel, rest] =
        Layout::vertical([Constraint::Length(rows), Constraint::Fill(1)]).areas(main);
    (Some(panel), rest)
}
