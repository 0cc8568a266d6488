//! The status line at the top and the key hints at the bottom.
//!
//! Layer: presentation. The header is what an operator glances at: link state, robot, mode,
//! teleop command, telemetry rate, port. The footer lists the keys that work right now.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;
use ratatui::Frame;

use crate::app::{mode_name, App, View};
use crate::link::Connection;

pub fn render_header(app: &App, frame: &mut Frame, area: Rect) {
    // Full first; on a narrow terminal the least needed detail goes first, so the REC clock,
    // the mode and the link state stay readable at 80 columns.
    let width = usize::from(area.width);
    let line = [
        Detail::Full,
        Detail::ShortRec,
        Detail::ShortState,
        Detail::NoPort,
    ]
    .into_iter()
    .map(|d| header_line(app, d))
    .find(|l| l.width() <= width)
    .unwrap_or_else(|| header_line(app, Detail::NoPort));
    frame.render_widget(
        Paragraph::new(line).style(Style::new().bg(Color::Black)),
        area,
    );
}

/// How much the header says, from all to the least.
#[derive(Clone, Copy, PartialEq, PartialOrd)]
enum Detail {
    Full,
    /// The recording's clock without its file name.
    ShortRec,
    /// The robot's profile without firmware name and version.
    ShortState,
    /// No port label.
    NoPort,
}

fn header_line(app: &App, d: Detail) -> Line<'static> {
    let mut spans = match &app.connection {
        Connection::Connected(p) if d >= Detail::ShortState => vec![Span::styled(
            format!("● {:?}", p.profile),
            Style::new().fg(Color::Green).bold(),
        )],
        Connection::Connected(p) => vec![
            Span::styled("● connected ", Style::new().fg(Color::Green).bold()),
            Span::raw(format!(
                "{} {} {:?}",
                p.firmware, p.firmware_version, p.profile
            )),
        ],
        Connection::Handshaking { .. } => {
            vec![Span::styled(
                "◌ handshaking",
                Style::new().fg(Color::Yellow).bold(),
            )]
        }
        Connection::Closed { reason } => vec![Span::styled(
            format!("✕ {reason}"),
            Style::new().fg(Color::Red).bold(),
        )],
        Connection::Refused { message } => vec![Span::styled(
            format!("✕ refused: {message}"),
            Style::new().fg(Color::Red).bold(),
        )],
    };
    let sep = || Span::styled(" │ ", Style::new().fg(Color::DarkGray));
    // Values from telemetry that stopped coming are the past, not the robot's state: greyed
    // and marked with their age (colour alone would not carry it).
    let stale = app.stale_s();
    let grey = Style::new().fg(Color::DarkGray);
    if let Some(t) = &app.telemetry {
        spans.push(sep());
        spans.push(match stale {
            Some(age) => Span::styled(
                format!("mode {} (stale {age} s)", mode_name(t.mode)),
                grey.add_modifier(Modifier::CROSSED_OUT),
            ),
            None => Span::styled(
                format!("mode {}", mode_name(t.mode)),
                Style::new().fg(Color::Cyan),
            ),
        });
        // What the mode is doing (the robot's Progress report): the time goes first when
        // the terminal is narrow. Not shown once telemetry is stale: it would be the past.
        if stale.is_none() {
            if let Some(text) = app.progress_text(d >= Detail::ShortState) {
                spans.push(Span::styled(
                    format!(": {text}"),
                    Style::new().fg(Color::Cyan),
                ));
            }
        }
    }
    if app.teleop.driving {
        spans.push(sep());
        spans.push(Span::styled(
            format!(
                "▶ v {} mm/s ω {} mrad/s",
                app.teleop.v_mm_s, app.teleop.w_mrad_s
            ),
            Style::new().fg(Color::Magenta).bold(),
        ));
    }
    if let Some((file, since_ms)) = &app.recording {
        let s = app.now_ms.saturating_sub(*since_ms) / 1000;
        let name = std::path::Path::new(file)
            .file_name()
            .map_or_else(|| file.clone(), |n| n.to_string_lossy().into_owned());
        // A fleet's recording holds every robot's link (`R` records them all).
        let rec = match app.fleet.as_ref().filter(|_| app.in_fleet()) {
            Some(f) => format!("● REC {} robots", f.robots.len()),
            None => "● REC".to_string(),
        };
        let text = if d >= Detail::ShortRec {
            format!("{rec} {}:{:02}", s / 60, s % 60)
        } else {
            format!("{rec} {name} {}:{:02}", s / 60, s % 60)
        };
        spans.push(sep());
        spans.push(Span::styled(text, Style::new().fg(Color::Red).bold()));
    }
    if let Some(hz) = app.rate_hz {
        spans.push(sep());
        spans.push(match stale {
            Some(_) => Span::styled(format!("{hz} Hz?"), grey),
            None => Span::raw(format!("{hz} Hz")),
        });
    }
    if d < Detail::NoPort {
        spans.push(sep());
        spans.push(Span::styled(
            app.port_label.clone(),
            Style::new().fg(Color::DarkGray),
        ));
    }
    Line::from(spans)
}

pub fn render_footer(app: &App, frame: &mut Frame, area: Rect) {
    let goto;
    let hints: &[(&str, &str)] = if app.help {
        &[
            ("↑↓ PgUp PgDn", "scroll"),
            ("Esc ? q", "close help"),
            ("Ctrl-C", "quit"),
        ]
    } else if app.transfers.prompt.is_some() {
        &[
            ("path", "map file or map/plan object"),
            ("Enter", "upload"),
            ("Esc", "cancel"),
        ]
    } else if app.log.filter_input.is_some() {
        &[
            ("text", "show lines containing it"),
            ("Enter", "apply"),
            ("Esc", "clear"),
        ]
    } else if app.params.input.is_some() {
        &[("0-9 . - e", "type"), ("Enter", "send"), ("Esc", "cancel")]
    } else if app.params.searching {
        &[
            ("text", "name or description"),
            ("↑↓", "select"),
            ("Enter", "keep"),
            ("Esc", "clear"),
        ]
    } else if app.map.cursor_mode {
        let (x, y) = app.map.cursor;
        goto = format!("send the robot to ({x:.2}, {y:.2}) m");
        &[
            ("Enter", goto.as_str()),
            ("Esc", "cancel"),
            ("←↑↓→", "move (shift ×5)"),
            ("O/P", "plan there"),
        ]
    } else if app.view == View::Params {
        &[
            ("↑↓", "select"),
            ("/", "search"),
            ("r", "read"),
            ("R", "read all"),
            ("Enter", "edit"),
            ("Esc", "back"),
            ("?", "help"),
        ]
    } else {
        &[
            ("?", "help"),
            ("q", "quit"),
            ("Tab", "view"),
            ("↑↓←→/wasd", "drive"),
            ("space", "stop"),
            ("0-9", "mode"),
            ("g", "go-to"),
            ("p", "params"),
            ("+/-", "rate"),
            ("c", "chart"),
        ]
    };
    // The plan's target, where a plan would go now (`app::plan_target`).
    let target;
    let mut hints = hints.to_vec();
    if !app.help
        && !app.map.cursor_mode
        && app.transfers.prompt.is_none()
        && app.params.input.is_none()
        && app.view != View::Params
        && !app.replaying
    {
        target = app.plan_target().short();
        // Beside go-to, so it stays on screen at 80 columns.
        let at = hints
            .iter()
            .position(|(k, _)| *k == "g")
            .map_or(0, |i| i + 1);
        if app.map.plan_target.is_some() {
            hints.insert(at, ("G", "goal"));
        }
        hints.insert(at, ("O", target.as_str()));
    }
    fleet_hints(app, &mut hints);
    let mut spans = Vec::new();
    for (k, what) in &hints {
        spans.push(Span::styled(
            format!(" {k} "),
            Style::new().add_modifier(Modifier::REVERSED),
        ));
        spans.push(Span::raw(format!(" {what} ")));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
}

/// Several robots: "stop all" first, where it is never cut off, whenever its key works (not
/// while typing); Tab picks robots instead of views.
fn fleet_hints(app: &App, hints: &mut Vec<(&str, &str)>) {
    if !app.in_fleet() {
        return;
    }
    let typing = app.help
        || app.transfers.prompt.is_some()
        || app.log.filter_input.is_some()
        || app.params.input.is_some()
        || app.params.searching;
    if typing {
        return;
    }
    if let Some(tab) = hints.iter_mut().find(|(k, _)| *k == "Tab") {
        *tab = ("Tab", "robot");
    }
    hints.insert(0, ("!", "STOP ALL"));
}
