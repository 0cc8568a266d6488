//! The link panel: what operators read first (MAVProxy's `link`, plus CRC failures, dropped
//! bytes, truth-stream loss and command round trips).
//!
//! Layer: presentation over the last `LinkStats` snapshot and the connection state.

use protocol::caps;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style, Stylize};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Sparkline, Wrap};
use ratatui::Frame;

use crate::app::App;
use crate::link::Connection;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let block = Block::bordered().title(" Link ");
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let lines = lines(app);
    let spark_h = if inner.height as usize > lines.len() + 2 {
        3
    } else {
        0
    };
    let [text, spark] =
        Layout::vertical([Constraint::Fill(1), Constraint::Length(spark_h)]).areas(inner);
    frame.render_widget(Paragraph::new(lines).wrap(Wrap { trim: true }), text);
    if spark_h > 0 {
        let data: Vec<u64> = app.rx_rate_history.clone();
        frame.render_widget(
            Sparkline::default()
                .block(Block::new().title("bytes/s in".dark_gray()))
                .style(Style::new().fg(Color::Cyan))
                .data(data),
            spark,
        );
    }
}

fn lines(app: &App) -> Vec<Line<'static>> {
    let dim = Style::new().fg(Color::DarkGray);
    let l = |s: &str| Span::styled(s.to_string(), dim);
    let mut out = vec![Line::from(vec![
        l("port "),
        Span::raw(app.port_label.clone()),
    ])];
    match &app.connection {
        Connection::Connected(p) => {
            let mut capnames = Vec::new();
            for (bit, n) in [
                (caps::ENCODERS, "enc"),
                (caps::IR_PROXIMITY, "ir"),
                (caps::AMBIENT_LIGHT, "light"),
                (caps::COMPASS, "compass"),
                (caps::GROUND_SENSOR, "ground"),
                (caps::LINE_SENSOR, "line"),
                (caps::BEACON, "beacon"),
                (caps::BATTERY, "battery"),
                (caps::ONBOARD_PLANNING, "planning"),
                (caps::TRANSFERS, "transfers"),
                (caps::EMULATED, "emulated"),
            ] {
                if p.has(bit) {
                    capnames.push(n);
                }
            }
            out.push(Line::from(vec![
                l("robot "),
                Span::raw(format!(
                    "{} {} {:?} session {:08x}",
                    p.firmware, p.firmware_version, p.profile, p.session
                )),
            ]));
            out.push(Line::from(vec![l("caps "), Span::raw(capnames.join(" "))]));
        }
        Connection::Handshaking { .. } => out.push(Line::from("handshaking…".yellow())),
        Connection::Closed { reason } => out.push(Line::from(Span::styled(
            format!("closed: {reason}"),
            Style::new().fg(Color::Red),
        ))),
        Connection::Refused { message } => out.push(Line::from(Span::styled(
            format!("refused: {message}"),
            Style::new().fg(Color::Red),
        ))),
    }
    let Some(s) = &app.stats else {
        return out;
    };
    let bad = |n: u64| {
        if n > 0 {
            Span::styled(n.to_string(), Style::new().fg(Color::Red).bold())
        } else {
            Span::raw("0")
        }
    };
    out.extend([
        Line::from(vec![
            l("up "),
            Span::raw(duration(s.uptime_ms)),
            l("  session "),
            Span::raw(duration(s.session_ms)),
            l("  opens "),
            Span::raw(s.port_opens.to_string()),
            l(" handshakes "),
            Span::raw(s.handshakes.to_string()),
            l(" timeouts "),
            bad(u64::from(s.link_timeouts)),
        ]),
        Line::from(vec![
            l("in "),
            Span::raw(format!(
                "{} fr {} ({}/s)",
                s.frames_in,
                bytes(s.bytes_in as f64),
                bytes(s.bytes_in_per_s)
            )),
            l("  out "),
            Span::raw(format!(
                "{} fr {} ({}/s)",
                s.frames_out,
                bytes(s.bytes_out as f64),
                bytes(s.bytes_out_per_s)
            )),
        ]),
        Line::from(vec![
            l("telemetry "),
            Span::raw(format!("{:.1} Hz", s.telemetry_hz)),
            l("  lost "),
            bad(s.robot_seq.lost),
            Span::raw(format!(" ({:.2}%)", s.robot_seq.loss_percent)),
            l(" dup "),
            Span::raw(s.robot_seq.duplicates.to_string()),
            l(" late "),
            Span::raw(s.robot_seq.late.to_string()),
        ]),
        Line::from(vec![
            l("CRC errors "),
            bad(u64::from(s.decoder.crc_errors)),
            l("  bad frames "),
            bad(s.decoder.errors()),
            l("  dropped bytes "),
            bad(s.decoder.bytes_dropped),
        ]),
    ]);
    // Link authentication (PROTOCOL.md §13): whether frames are signed, and frames refused
    // for a bad signature, a stale timestamp or a missing or unexpected signature.
    if s.auth.keyed || s.auth.refused() > 0 {
        out.push(Line::from(vec![
            l("auth "),
            if s.auth.keyed {
                Span::styled("signed", Style::new().fg(Color::Green))
            } else {
                Span::raw("unsigned")
            },
            l("  refused "),
            bad(s.auth.refused()),
        ]));
    }
    out.extend([
        // Each count after its word, comma-separated: "53 ok 0 refused" read as "ok 0".
        Line::from(vec![
            l("commands: "),
            Span::raw(format!("{} ok, ", s.commands.acked)),
            if s.commands.nacked > 0 {
                Span::styled(
                    format!("{} refused", s.commands.nacked),
                    Style::new().fg(Color::Yellow),
                )
            } else {
                Span::raw("0 refused")
            },
            Span::raw(", "),
            bad(s.commands.failed),
            Span::raw(" failed"),
            Span::raw(format!(", {} superseded", s.commands.superseded)),
        ]),
        Line::from(vec![
            l("resends: "),
            Span::raw(s.commands.resends.to_string()),
            l(", in flight: "),
            Span::raw(s.commands.in_flight.to_string()),
        ]),
        Line::from(vec![
            l("RTT "),
            Span::raw(match (s.rtt_ms.p50, s.rtt_ms.p99) {
                (Some(a), Some(b)) => {
                    format!("p50 {a:.1} ms  p99 {b:.1} ms  (n={})", s.rtt_ms.samples)
                }
                _ => "no samples yet".into(),
            }),
        ]),
    ]);
    if s.truth_seq.received > 0 {
        out.push(Line::from(vec![
            l("truth frames "),
            Span::raw(s.truth_seq.received.to_string()),
            l("  lost "),
            bad(s.truth_seq.lost),
        ]));
    }
    out
}

fn duration(ms: u64) -> String {
    let s = ms / 1000;
    format!("{:02}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60)
}

fn bytes(b: f64) -> String {
    if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.1} kB", b / 1e3)
    } else {
        format!("{b:.0} B")
    }
}
