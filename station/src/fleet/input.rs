//! The fleet's keys and clicks, before the selected robot's (`crate::input`).
//!
//! Layer: input to `Action`s, reading only. With several robots: Tab / Shift-Tab step the
//! picker (views stay on F1-F7), Alt-1 .. Alt-9 pick a robot (the digits alone stay the
//! selected robot's modes: a digit that sometimes picks a robot and sometimes drives one
//! would move a robot by surprise), `!` stops every robot, and a click on a fleet-panel
//! line or on another robot on the map picks it. Typing (a path, a filter, a value) and the
//! help overlay keep their keys. With one robot nothing here applies.

use ratatui::crossterm::event::{
    Event, KeyCode, KeyEventKind, KeyModifiers, MouseButton, MouseEventKind,
};
use ratatui::layout::Rect;

use crate::action::Action;
use crate::app::App;
use crate::ui::{self, Panel};

pub use crate::app::fleet::STOP_ALL_KEY;

/// Whether a terminal event is the fleet's (`Some`), and its action if it has one: `Alt-4`
/// with three robots is the fleet's and does nothing (it must not fall through to the robot's
/// key map, where `4` sets a mode). `None`: the selected robot's.
pub fn fleet_action_for(app: &App, ev: &Event) -> Option<Option<Action>> {
    let fleet = app.fleet.as_ref().filter(|f| f.robots.len() > 1)?;
    match ev {
        Event::Key(k) if k.kind != KeyEventKind::Release => {
            let typing = app.help
                || app.transfers.prompt.is_some()
                || app.log.filter_input.is_some()
                || app.params.input.is_some()
                || app.params.searching;
            if typing {
                return None;
            }
            match k.code {
                KeyCode::Char(STOP_ALL_KEY) => Some(Some(Action::StopAll)),
                KeyCode::Tab => Some(Some(Action::StepRobot(1))),
                KeyCode::BackTab => Some(Some(Action::StepRobot(-1))),
                KeyCode::Char(c)
                    if k.modifiers.contains(KeyModifiers::ALT) && c.is_ascii_digit() =>
                {
                    let i = (c.to_digit(10).unwrap_or(0) as usize).checked_sub(1);
                    Some(
                        i.filter(|&i| i < fleet.robots.len())
                            .map(Action::SelectRobot),
                    )
                }
                _ => None,
            }
        }
        // Under the help a click picks nothing (`crate::input`).
        Event::Mouse(m) if m.kind == MouseEventKind::Down(MouseButton::Left) && !app.help => {
            let screen = Rect::new(0, 0, app.size.0, app.size.1);
            let areas = ui::areas(screen, app);
            if let Some(panel) = areas.find(Panel::Fleet) {
                let inside = m.column >= panel.x
                    && m.column < panel.x + panel.width
                    && m.row > panel.y
                    && m.row < panel.y + panel.height.saturating_sub(1);
                if inside {
                    let i = usize::from(m.row - panel.y - 1);
                    return Some((i < fleet.robots.len()).then_some(Action::SelectRobot(i)));
                }
            }
            let map = areas.find(Panel::Map)?;
            let inner = ratatui::widgets::Block::bordered().inner(ui::map::map_area(app, map));
            let (x, y) = ui::map::to_world(app, inner, m.column, m.row)?;
            // A click within a cell or so of another robot picks it; elsewhere it is the
            // selected robot's go-to (`crate::input`).
            let (x2, _) = ui::map::to_world(app, inner, m.column.saturating_add(1), m.row)
                .or_else(|| ui::map::to_world(app, inner, m.column.saturating_sub(1), m.row))?;
            let reach = 1.5 * (x2 - x).abs();
            fleet
                .robots
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != fleet.selected)
                .filter_map(|(i, r)| r.pose.map(|(rx, ry, _)| (i, (rx - x).hypot(ry - y))))
                .filter(|(_, d)| *d <= reach)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| Some(Action::SelectRobot(i)))
        }
        _ => None,
    }
}

/// The action for a terminal event: the fleet's, else the selected robot's.
pub fn action_for(app: &App, ev: &Event) -> Option<Action> {
    fleet_action_for(app, ev).unwrap_or_else(|| crate::input::action_for(app, ev))
}
