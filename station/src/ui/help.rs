//! The `?` overlay: every key, in one place.
//!
//! Layer: presentation; drawn last, over whatever is below, centred and clipped to the screen.

use ratatui::layout::{Constraint, Flex, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph};
use ratatui::Frame;

/// (keys, what they do), in the order shown.
pub const KEYS: &[(&str, &str)] = &[
    ("q  Ctrl-C", "quit (stops the robot if driving)"),
    (
        "?  Esc",
        "help / close; in the help ↑↓ PgUp PgDn Home End scroll, Esc ? q close",
    ),
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
        "go-to: a cursor on the map (shift: 5x step; a click puts it there), Enter sends the \
         robot; Esc clears the marker",
    ),
    (
        "z Z hjkl F",
        "map: zoom in / out (or the wheel; all of it recentres) / pan / follow the robot",
    ),
    (
        "p  /",
        "parameters: ↑↓ select, / search names and descriptions, r read, R read all, Enter edit",
    ),
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
        "record the link (a fleet: every robot's) into the recordings directory (--record-dir; \
         the log says where); R again saves it",
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

/// The keys shown: with several robots, the fleet's first.
fn keys(fleet: bool) -> Vec<(&'static str, &'static str)> {
    if fleet {
        FLEET_KEYS.iter().chain(KEYS).copied().collect()
    } else {
        KEYS.to_vec()
    }
}

/// Where the overlay goes on `screen`, and its text wrapped to fit inside its border.
fn layout(screen: Rect, fleet: bool) -> (Rect, Vec<Line<'static>>) {
    let width = screen.width.min(80);
    let lines = wrapped(&keys(fleet), usize::from(width.saturating_sub(2)));
    let height = screen.height.min(
        u16::try_from(lines.len())
            .unwrap_or(u16::MAX)
            .saturating_add(2),
    );
    let [row] = Layout::vertical([Constraint::Length(height)])
        .flex(Flex::Center)
        .areas(screen);
    let [area] = Layout::horizontal([Constraint::Length(width)])
        .flex(Flex::Center)
        .areas(row);
    (area, lines)
}

/// The furthest the help scrolls on `screen`: its wrapped lines less the rows shown.
pub fn max_scroll(screen: Rect, fleet: bool) -> u16 {
    let (area, lines) = layout(screen, fleet);
    let rows = usize::from(area.height.saturating_sub(2));
    u16::try_from(lines.len().saturating_sub(rows)).unwrap_or(u16::MAX)
}

/// Rows of help one page scroll moves on `screen`.
pub fn page(screen: Rect, fleet: bool) -> u16 {
    layout(screen, fleet).0.height.saturating_sub(3).max(1)
}

/// Each key with its description wrapped to `width` columns, the continuation lines indented
/// under the description: the key column stays a column however narrow the screen.
fn wrapped(keys: &[(&'static str, &'static str)], width: usize) -> Vec<Line<'static>> {
    let key_w = keys
        .iter()
        .map(|(k, _)| k.chars().count())
        .max()
        .unwrap_or(0);
    // A column of margin before the border.
    let room = width.saturating_sub(key_w + 3).max(10);
    let mut out = Vec::new();
    for (k, what) in keys {
        let mut first = true;
        for part in wrap_words(what, room) {
            let key = if first { *k } else { "" };
            out.push(Line::from(vec![
                Span::styled(
                    format!("{key:>key_w$}  "),
                    Style::new().fg(Color::Yellow).bold(),
                ),
                Span::raw(part),
            ]));
            first = false;
        }
    }
    out
}

/// `text` in lines of at most `room` characters, broken between words (a word longer than
/// a line gets a line of its own, cut).
fn wrap_words(text: &str, room: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split(' ') {
        let last = lines.last_mut().map_or(0, |l| l.chars().count());
        let n = word.chars().count();
        if last > 0 && last + 1 + n > room {
            lines.push(String::new());
        }
        if let Some(l) = lines.last_mut() {
            if !l.is_empty() {
                l.push(' ');
            }
            l.extend(word.chars().take(room));
        }
    }
    lines
}

/// The help overlay, scrolled down by `scroll` lines; `fleet`: with the fleet's keys first.
pub fn render_keys(frame: &mut Frame, screen: Rect, fleet: bool, scroll: u16) {
    let (area, lines) = layout(screen, fleet);
    let rows = usize::from(area.height.saturating_sub(2));
    let total = lines.len();
    let top = usize::from(scroll).min(total.saturating_sub(rows));
    // Where the reader is, and how to move, when it does not all fit.
    let bottom = if total > rows {
        format!(
            " {}-{} of {total}  ↑↓ PgUp PgDn Home End scroll  Esc ? q close ",
            top + 1,
            (top + rows).min(total)
        )
    } else {
        " Esc ? q close ".to_string()
    };
    let shown: Vec<Line> = lines.into_iter().skip(top).take(rows).collect();
    frame.render_widget(Clear, area);
    frame.render_widget(
        Paragraph::new(shown).block(
            Block::bordered()
                .title(" Keys ")
                .title_bottom(Line::from(bottom).right_aligned()),
        ),
        area,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;

    fn screen_text(scroll: u16, fleet: bool) -> String {
        let mut t = Terminal::new(TestBackend::new(80, 24)).unwrap_or_else(|e| panic!("{e}"));
        t.draw(|f| render_keys(f, f.area(), fleet, scroll))
            .unwrap_or_else(|e| panic!("{e}"));
        let buf = t.backend().buffer().clone();
        (0..24)
            .map(|y| (0..80).map(|x| buf[(x, y)].symbol()).collect::<String>())
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn scrolled_to_its_end_the_help_shows_every_key_at_80_by_24() {
        let screen = Rect::new(0, 0, 80, 24);
        for fleet in [false, true] {
            let max = max_scroll(screen, fleet);
            assert!(max > 0, "the help is longer than 24 rows");
            let mut seen = String::new();
            for s in 0..=max {
                seen.push_str(&screen_text(s, fleet));
            }
            for (k, what) in keys(fleet) {
                assert!(seen.contains(k), "{k} never shown");
                let first = what.split(' ').take(3).collect::<Vec<_>>().join(" ");
                assert!(seen.contains(&first), "{what} never shown");
            }
            // Past the end stays at the end.
            assert_eq!(screen_text(max, fleet), screen_text(max + 5, fleet));
        }
    }

    #[test]
    fn descriptions_wrap_under_themselves_not_under_the_keys() {
        let lines = wrapped(&[("k", "one two three four five")], 12);
        let text: Vec<String> = lines.iter().map(ToString::to_string).collect();
        assert_eq!(text, ["k  one two", "   three four", "   five"]);
    }
}
