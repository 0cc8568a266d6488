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
    ("q  Ctrl-C", "quit (stops the robot if driving)"),
    ("?  Esc", "help / close"),
    (
        "Tab  F1-F7",
        "views: dashboard sensors charts map link log params",
    ),
    ("↑ ↓  w s", "teleop faster / slower (repeats at 10 Hz)"),
    ("← →  a d", "teleop turn left / right"),
    ("space", "stop: zero speed and send Stop"),
    (
        "0-9 modes",
        "idle manual goto wander edgeL edgeR light explore plan forage",
    ),
    (
        "g ←↑↓→ Enter",
        "go-to with a cursor on the map (shift: 5x step), or click; Esc clears the marker",
    ),
    (
        "z Z hjkl",
        "map: zoom in / out (or the wheel; all of it recentres) / pan",
    ),
    ("p", "parameters: ↑↓ select, r read, R read all, Enter edit"),
    (
        "+  -  c",
        "telemetry rate (0 1 2 5 10 20 50 Hz) / next chart",
    ),
    (
        "t  T  x",
        "show/hide the true pose / the QT world model; clear the tracks",
    ),
    (
        "P",
        "plan on the station: robot (or map start) to the plan's target ◎",
    ),
    (
        "g … O/P  G",
        "plan to the cursor (it becomes the target) / back to the map's goal",
    ),
    (
        "o r n m e",
        "map layers: grid regions plan smoothed start/goal",
    ),
    (
        "S  y i v f",
        "survey the floor grid / odometry tracks, line events, PPD, grid",
    ),
    (
        "u  M",
        "upload a map/plan/calibration file / show the robot's map",
    ),
    (
        "E  O  X",
        "robot: explore (its map grows live) / plan on board / execute",
    ),
    (
        "PgUp/Dn End",
        "log: scroll (stops at the top) / follow the newest",
    ),
    (
        "L  /",
        "log: minimum severity (all info warn error) / text filter",
    ),
    (
        "R",
        "record the link (a fleet: every robot's) to a file here; R again saves it",
    ),
];

/// With several robots, these come first (`fleet::input`).
pub const FLEET_KEYS: &[(&str, &str)] = &[
    (
        "!",
        "STOP ALL: Stop to every connected robot; each one's answer in the log",
    ),
    (
        "Tab  Alt-1..9",
        "pick a robot (or click its fleet line or it on the map); F1-F7 views",
    ),
];

pub fn render(frame: &mut Frame, screen: Rect) {
    render_keys(frame, screen, false);
}

/// The help overlay; `fleet`: with the fleet's keys first.
pub fn render_keys(frame: &mut Frame, screen: Rect, fleet: bool) {
    let keys: Vec<(&str, &str)> = if fleet {
        FLEET_KEYS.iter().chain(KEYS).copied().collect()
    } else {
        KEYS.to_vec()
    };
    let keys = keys.as_slice();
    let width = screen.width.min(80);
    let height = screen.height.min(keys.len() as u16 + 4);
    let [row] = Layout::vertical([Constraint::Length(height)])
        .flex(Flex::Center)
        .areas(screen);
    let [area] = Layout::horizontal([Constraint::Length(width)])
        .flex(Flex::Center)
        .areas(row);
    let key_w = keys
        .iter()
        .map(|(k, _)| k.chars().count())
        .max()
        .unwrap_or(0);
    let lines: Vec<Line> = keys
        .iter()
        .map(|(k, what)| {
            Line::from(vec![
                Span::styled(
                    format!("{k:>key_w$}  "),
                    Style::new().fg(Color::Yellow).bold(),
                ),
                Span::raw(*what),
            ])
        })
        .collect();
    frame.render_widget(Clear, area);
    frame.render_widget(
        Paragraph::new(lines).wrap(Wrap { trim: false }).block(
            Block::bordered()
                .title(" Keys ")
                .title_bottom(" Esc closes "),
        ),
        area,
    );
}
