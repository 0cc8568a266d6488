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
    let mut spans = match &app.connection {
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
    if let Some(t) = &app.telemetry {
        spans.push(sep());
        spans.push(Span::styled(
            format!("mode {}", mode_name(t.mode)),
            Style::new().fg(Color::Cyan),
        ));
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
        spans.push(sep());
        spans.push(Span::styled(
            format!("● REC {name} {}:{:02}", s / 60, s % 60),
            Style::new().fg(Color::Red).bold(),
        ));
    }
    if let Some(hz) = app.rate_hz {
        spans.push(sep());
        spans.push(Span::raw(format!("{hz} Hz")));
    }
    spans.push(sep());
    spans.push(Span::styled(
        app.port_label.clone(),
        Style::new().fg(Color::DarkGray),
    ));
    frame.render_widget(
        Paragraph::new(Line::from(spans)).style(Style::new().bg(Color::Black)),
        area,
    );
}

pub fn render_footer(app: &App, frame: &mut Frame, area: Rect) {
    let hints: &[(&str, &str)] = if app.help {
        &[("Esc", "close help"), ("q", "quit")]
    } else if app.transfers.prompt.is_some() {
        &[
            ("path", "map file or map/plan object"),
            ("Enter", "upload"),
            ("Esc", "cancel"),
        ]
    } else if app.params.input.is_some() {
        &[("0-9 . - e", "type"), ("Enter", "send"), ("Esc", "cancel")]
    } else if app.map.cursor_mode {
        &[
            ("arrows/hjkl", "move 0.1 m"),
            ("shift", "×5"),
            ("Enter", "go"),
            ("Esc", "cancel"),
        ]
    } else if app.view == View::Params {
        &[
            ("↑↓", "select"),
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
    let mut spans = Vec::new();
    for (k, what) in hints {
        spans.push(Span::styled(
            format!(" {k} "),
            Style::new().add_modifier(Modifier::REVERSED),
        ));
        spans.push(Span::raw(format!(" {what} ")));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), area);
}
