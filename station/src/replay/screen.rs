//! The replay screen: the live screen, with the bottom line replaced by the replay's progress
//! bar (state, speed, time, a bar, duration and the keys), and the replay's own help overlay.
//!
//! Layer: pure presentation (`render(&App, &ReplayStatus, &mut Frame)`), no I/O. Every view of
//! the live station works unchanged above the bar. Cannot fail: a narrow terminal drops the
//! key hints first, then shortens the bar.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Clear, Paragraph};
use ratatui::Frame;

use crate::app::App;

/// What the progress bar shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplayStatus<'a> {
    pub position_us: u64,
    pub duration_us: u64,
    pub speed: f64,
    pub paused: bool,
    /// The replay's help overlay is open.
    pub help: bool,
    /// Where the recording is damaged, if it is (shown in red).
    pub damage_offset: Option<u64>,
    pub file: &'a str,
    /// Robots (links) in the file: with several, the picker's keys are listed too.
    pub robots: usize,
}

/// Draws the whole replay screen.
pub fn render(app: &App, st: &ReplayStatus<'_>, frame: &mut Frame) {
    crate::ui::render(app, frame);
    let area = frame.area();
    if area.height == 0 {
        return;
    }
    let bar = Rect {
        x: area.x,
        y: area.y + area.height - 1,
        width: area.width,
        height: 1,
    };
    frame.render_widget(Clear, bar);
    frame.render_widget(Paragraph::new(progress_line(st, bar.width)), bar);
    if st.help {
        help(frame, area, st);
    }
}

/// `m:ss.s`, or `h:mm:ss` from an hour on.
pub fn clock(us: u64) -> String {
    let tenths = us / 100_000;
    let s = tenths / 10;
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60)
    } else {
        format!("{}:{:02}.{}", s / 60, s % 60, tenths % 10)
    }
}

/// `1×`, `0.25×`, `16×`.
pub fn speed_text(speed: f64) -> String {
    if (speed - speed.round()).abs() < 1e-9 {
        format!("{}×", speed.round() as i64)
    } else {
        format!("{speed}×")
    }
}

/// The bottom line.
pub fn progress_line(st: &ReplayStatus<'_>, width: u16) -> Line<'static> {
    let width = usize::from(width);
    let at_end = st.position_us >= st.duration_us;
    let (icon, colour) = match (st.paused, at_end) {
        (_, true) => ("■ end", Color::Yellow),
        (true, false) => ("❚❚ paused", Color::Yellow),
        (false, false) => ("▶", Color::Green),
    };
    let left = format!(
        " {icon} {} {} ",
        speed_text(st.speed),
        clock(st.position_us)
    );
    let right = format!(" {} ", clock(st.duration_us));
    let damage = st
        .damage_offset
        .map(|o| format!(" damaged at byte {o} "))
        .unwrap_or_default();
    let hints: &[(&str, &str)] = &[
        ("space", if st.paused { "play" } else { "pause" }),
        ("←→", "±5 s"),
        ("+-", "speed"),
        ("?", "help"),
        ("q", "quit"),
    ];
    let hints_len: usize = hints
        .iter()
        .map(|(k, w)| k.chars().count() + w.chars().count() + 4)
        .sum();
    let fixed = left.chars().count() + right.chars().count() + damage.chars().count();
    let show_hints = width >= fixed + hints_len + 10;
    let bar_w = width.saturating_sub(fixed + if show_hints { hints_len } else { 0 });
    let frac = if st.duration_us == 0 {
        1.0
    } else {
        (st.position_us as f64 / st.duration_us as f64).clamp(0.0, 1.0)
    };
    let filled = ((bar_w as f64) * frac).round() as usize;
    let mut spans = vec![
        Span::styled(left, Style::new().fg(colour).bold()),
        Span::styled("━".repeat(filled), Style::new().fg(Color::Cyan)),
        Span::styled(
            "─".repeat(bar_w.saturating_sub(filled)),
            Style::new().fg(Color::DarkGray),
        ),
        Span::raw(right),
    ];
    if !damage.is_empty() {
        spans.push(Span::styled(damage, Style::new().fg(Color::Red).bold()));
    }
    if show_hints {
        for (k, what) in hints {
            spans.push(Span::styled(
                format!(" {k} "),
                Style::new().add_modifier(Modifier::REVERSED),
            ));
            spans.push(Span::raw(format!(" {what} ")));
        }
    }
    Line::from(spans)
}

/// The picker's keys in the replay of several robots (`fleet::input`, less "stop all").
pub const FLEET_KEYS: &[(&str, &str)] = &[
    ("Tab Alt-1…9", "pick the robot whose panels are shown"),
    ("F1-F7", "views (Tab picks robots here)"),
];

/// The replay keys.
pub const KEYS: &[(&str, &str)] = &[
    ("space", "pause / resume (at the end: from the start)"),
    ("← →", "back / forward 5 s"),
    ("Home End", "start / end"),
    ("+ -", "speed: 0.1× … 128×"),
    ("1 … 9", "speed 1× … 9×"),
    ("Tab F1-F7", "views, as live"),
    ("c t x", "chart series, truth layer, clear tracks"),
    ("PgUp PgDn", "scroll the log"),
    ("? Esc", "this help / close"),
    ("q", "quit"),
];

fn help(frame: &mut Frame, area: Rect, st: &ReplayStatus<'_>) {
    let width = 64.min(area.width);
    let keys: Vec<(&str, &str)> = if st.robots > 1 {
        KEYS.iter().chain(FLEET_KEYS).copied().collect()
    } else {
        KEYS.to_vec()
    };
    let height = (keys.len() as u16 + 4).min(area.height);
    let r = Rect {
        x: area.x + (area.width - width) / 2,
        y: area.y + (area.height - height) / 2,
        width,
        height,
    };
    let mut lines: Vec<Line> = keys
        .iter()
        .map(|(k, what)| {
            Line::from(vec![
                Span::styled(format!(" {k:<10} "), Style::new().fg(Color::Cyan).bold()),
                Span::raw(*what),
            ])
        })
        .collect();
    lines.push(Line::raw(""));
    lines.push(Line::styled(
        " Nothing is sent to any port during a replay.",
        Style::new().fg(Color::DarkGray),
    ));
    frame.render_widget(Clear, r);
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title(format!(" Replay {} ", st.file))),
        r,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_and_speed_read_naturally() {
        assert_eq!(clock(0), "0:00.0");
        assert_eq!(clock(83_450_000), "1:23.4");
        assert_eq!(clock(3_723_000_000), "1:02:03");
        assert_eq!(speed_text(1.0), "1×");
        assert_eq!(speed_text(0.25), "0.25×");
    }

    #[test]
    fn the_bar_fits_any_width() {
        let st = ReplayStatus {
            position_us: 30_000_000,
            duration_us: 60_000_000,
            speed: 2.0,
            paused: false,
            help: false,
            damage_offset: Some(1234),
            file: "x.rec",
            robots: 1,
        };
        for w in [0u16, 10, 40, 80, 200] {
            let line = progress_line(&st, w);
            assert!(
                line.width() <= usize::from(w).max(50),
                "{w}: {}",
                line.width()
            );
        }
    }
}
