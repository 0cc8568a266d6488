//! The log pane: robot log lines, robot events, command outcomes (with Nack reasons) and link
//! changes, newest at the bottom, coloured by severity.
//!
//! Layer: presentation over `LogBuffer`.

use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph};
use ratatui::Frame;

use crate::app::log::{Level, Source};
use crate::app::App;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let title = if app.log.scroll > 0 {
        format!(" Log (scrolled back {}; PgDn) ", app.log.scroll)
    } else {
        " Log ".to_string()
    };
    let block = Block::bordered().title(title);
    let inner = block.inner(area);
    let height = usize::from(inner.height);
    // A long line continues under its text rather than being cut off: a refusal's reason is
    // usually at its end.
    let room = usize::from(inner.width).saturating_sub(PREFIX).max(10);
    let entries: Vec<Vec<Line>> = app
        .log
        .window(height)
        .map(|l| {
            let color = match l.level {
                Level::Debug => Color::DarkGray,
                Level::Info => Color::Reset,
                Level::Warn => Color::Yellow,
                Level::Error => Color::Red,
            };
            let tag = match l.source {
                Source::Robot => "robot",
                Source::Event => "event",
                Source::Command => "cmd",
                Source::Link => "link",
                Source::Arena => "arena",
            };
            wrap(&l.text, room)
                .into_iter()
                .enumerate()
                .map(|(i, piece)| {
                    let head = if i == 0 {
                        format!("{:>7.1} {tag:<5} ", l.t_ms as f64 / 1000.0)
                    } else {
                        " ".repeat(PREFIX)
                    };
                    Line::from(vec![
                        Span::styled(head, Style::new().fg(Color::DarkGray)),
                        Span::styled(piece, Style::new().fg(color)),
                    ])
                })
                .collect()
        })
        .collect();
    // The newest entries whole, as many as fit; the newest alone if even it does not.
    let mut lines: Vec<Line> = Vec::new();
    for entry in entries.into_iter().rev() {
        if !lines.is_empty() && lines.len() + entry.len() > height {
            break;
        }
        lines.splice(0..0, entry);
    }
    let extra = lines.len().saturating_sub(height);
    lines.drain(..extra);
    frame.render_widget(Paragraph::new(lines).block(block), area);
}

/// Columns of the time and source before a line's text.
const PREFIX: usize = 14;

/// `text` in pieces of at most `room` characters, broken at spaces where it can be.
fn wrap(text: &str, room: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let (have, want) = (line.chars().count(), word.chars().count());
        if have > 0 && have + 1 + want > room {
            out.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
        // A word longer than the room is cut into pieces of the room.
        while line.chars().count() > room {
            let head: String = line.chars().take(room).collect();
            line = line.chars().skip(room).collect();
            out.push(head);
        }
    }
    if !line.is_empty() || out.is_empty() {
        out.push(line);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::wrap;

    #[test]
    fn long_lines_break_at_spaces_and_long_words_at_the_room() {
        assert_eq!(
            wrap("refused: mode Explore: unsupported", 16),
            ["refused: mode", "Explore:", "unsupported"]
        );
        assert_eq!(
            wrap("/tmp/station-20261122/robot closed", 10),
            ["/tmp/stati", "on-2026112", "2/robot", "closed"]
        );
        assert_eq!(wrap("", 10), [""]);
    }
}
