//! The `?` overlay: every key, in one place.
//!
//! Layer: presentation; drawn last, over whatever is below, centred and clipped to the screen.

use ratatui::layout::{Constraint, Flex, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph, Wrap};
use ratatui::Frame;

/// (keys, what they do), in the order shown.
pub const KEYS: &[(&str, &str)] = &[
    ("q, Ctrl-C", "quit (stops the robot if driving)"),
    ("?, Esc", "this help / close"),
    ("Tab, Shift-Tab, F1-F7", "switch view (dashboard, sensors, charts, map, link, log, params)"),
    ("↑ ↓ / w s", "teleop: faster / slower (repeats at 10 Hz while driving)"),
    ("← → / a d", "teleop: turn left / right"),
    ("space", "stop: zero speed, send Stop"),
    ("0-8", "mode: 0 idle 1 manual 2 go-to 3 wander 4 edge-L 5 edge-R 6 light 7 explore 8 plan"),
    ("g, then arrows, Enter", "go-to with a cursor on the map (shift: 5x step)"),
    ("mouse click on map", "go-to that point"),
    ("p", "parameter editor: ↑↓ select, r read, R read all, Enter edit + send"),
    ("+ / -", "telemetry rate up / down (0 1 2 5 10 20 50 Hz)"),
    ("c", "next chart series"),
    ("t / x", "show or hide the true pose / clear tracks"),
    ("PgUp / PgDn", "scroll the log"),
];

pub fn render(frame: &mut Frame, screen: Rect) {
    let width = screen.width.min(86);
    let height = screen.height.min(KEYS.len() as u16 + 4);
    let [row] = Layout::vertical([Constraint::Length(height)])
        .flex(Flex::Center)
        .areas(screen);
    let [area] = Layout::horizontal([Constraint::Length(width)])
        .flex(Flex::Center)
        .areas(row);
    let key_w = KEYS.iter().map(|(k, _)| k.chars().count()).max().unwrap_or(0);
    let lines: Vec<Line> = KEYS
        .iter()
        .map(|(k, what)| {
            Line::from(vec![
                Span::styled(format!("{k:>key_w$}  "), Style::new().fg(Color::Yellow).bold()),
                Span::raw(*what),
            ])
        })
        .collect();
    frame.render_widget(Clear, area);
    frame.render_widget(
        Paragraph::new(lines)
            .wrap(Wrap { trim: false })
            .block(Block::bordered().title(" Keys ").title_bottom(" Esc closes ")),
        area,
    );
}
