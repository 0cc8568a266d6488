//! Drawing: `render(&App, &mut Frame)` and the layout it uses.
//!
//! Layer: pure presentation (gitui's `draw(&self)`): reads the app immutably, writes cells, does
//! no I/O and changes nothing. The layout is a function of the terminal size and the view, so
//! input handling can find where the map was drawn (for mouse clicks) by calling `areas` with
//! the same arguments. Every panel degrades to something readable at 80 x 24 and uses the
//! room of a large terminal. Cannot fail: a panel too small for its content clips it.

pub mod alice_sensors;
pub mod charts;
pub mod fleet;
pub mod forage;
pub mod header;
pub mod help;
pub mod link;
pub mod localization;
pub mod log;
pub mod map;
pub mod map_layers;
pub mod params;
pub mod plan_panel;
pub mod qt_map;
pub mod retrace_layer;
pub mod sensors;
pub mod transfer;

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::Frame;

use crate::app::{App, View};

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
    let (fleet, main) = fleet::split(app, main);
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

/// Draws the whole screen.
pub fn render(app: &App, frame: &mut Frame) {
    let a = areas(frame.area(), app);
    header::render_header(app, frame, a.header);
    header::render_footer(app, frame, a.footer);
    for (panel, area) in &a.panels {
        match panel {
            Panel::Sensors => sensors::render(app, frame, *area),
            Panel::Charts => charts::render(app, frame, *area),
            Panel::Map => map::render(app, frame, *area),
            Panel::Link => link::render(app, frame, *area),
            Panel::Log => log::render(app, frame, *area),
            Panel::Params => params::render(app, frame, *area),
            Panel::Fleet => fleet::render(app, frame, *area),
        }
    }
    if let Some(main) = main_area(&a) {
        notice(app, frame, main);
        transfer::render(app, frame, main);
    }
    if app.help {
        help::render_keys(frame, frame.area(), app.in_fleet());
    }
}

fn main_area(a: &Areas) -> Option<Rect> {
    a.panels
        .iter()
        .map(|(_, r)| *r)
        .reduce(|acc, r| acc.union(r))
}

/// When the link is down, says why in full over the bottom of the main area: a port held by
/// another program or a schema mismatch must be readable, not cut off in the header.
fn notice(app: &App, frame: &mut Frame, main: Rect) {
    use ratatui::style::{Color, Style};
    use ratatui::widgets::{Block, Clear, Paragraph, Wrap};
    // In a fleet the robot's fleet line and link panel say why, and the box would cover the
    // log where "stop all" reports each robot.
    if app.in_fleet() {
        return;
    }
    let (title, text) = match &app.connection {
        // A replay between sessions: the header says so; nobody is trying anything.
        crate::link::Connection::Closed { .. } if app.replaying => return,
        crate::link::Connection::Closed { reason } => (" Not connected ", reason.clone()),
        crate::link::Connection::Refused { message } => (" Robot refused ", message.clone()),
        _ => return,
    };
    let width = main.width.saturating_sub(4).max(10);
    let text = if app.replaying {
        format!("{text} (recorded).")
    } else {
        format!("{text}. The station keeps trying.")
    };
    let lines = (text.chars().count() as u16).div_ceil(width.saturating_sub(2).max(1));
    let height = (lines + 2).min(main.height);
    let area = Rect {
        x: main.x + (main.width - width.min(main.width)) / 2,
        y: main.y + main.height.saturating_sub(height + 1),
        width: width.min(main.width),
        height,
    };
    frame.render_widget(Clear, area);
    frame.render_widget(
        Paragraph::new(text)
            .wrap(Wrap { trim: true })
            .style(Style::new().fg(Color::Red))
            .block(Block::bordered().title(title)),
        area,
    );
}
