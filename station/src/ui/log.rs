//! The log pane: robot log lines, robot events, command outcomes (with Nack reasons) and link
//! changes, newest at the bottom; severity as a letter (D I W E) and a colour; repeats as one
//! line with a count; the filter and the scroll state in the border.
//!
//! Layer: presentation over `LogBuffer`.

use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph};
use ratatui::Frame;

use crate::app::log::{Level, LogLine, Source};
use crate::app::App;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let log = &app.log;
    let mut title = vec![Span::raw(" Log ")];
    if log.filter.min > Level::Debug {
        title.push(Span::styled(
            format!("≥{} ", log.filter.min.name()),
            Style::new().fg(Color::Yellow),
        ));
    }
    if !log.filter.text.is_empty() {
        title.push(Span::styled(
            format!("/{}/ ", log.filter.text),
            Style::new().fg(Color::Yellow),
        ));
    }
    // Scrolled back, the newest lines are not on screen: say so, and how to get them back.
    let marker = (log.scroll > 0).then(|| {
        Span::styled(
            format!(" ▲ scrolled, {} newer — End to follow ", log.scroll),
            Style::new().fg(Color::Black).bg(Color::Yellow),
        )
    });
    let mut block = Block::bordered().title(Line::from(title));
    if let Some(m) = marker {
        block = block.title_top(Line::from(m).right_aligned());
    }
    if let Some(input) = &log.filter_input {
        block = block.title_bottom(Line::from(vec![
            Span::styled(" filter: ", Style::new().fg(Color::Yellow)),
            Span::raw(format!("{input}▏ ")),
            Span::styled("Enter apply, Esc clear ", Style::new().fg(Color::DarkGray)),
        ]));
    } else if area.width >= 40 {
        block = block.title_bottom(
            Line::from(Span::styled(
                " L severity  / filter  PgUp/PgDn  End ",
                Style::new().fg(Color::DarkGray),
            ))
            .right_aligned(),
        );
    }
    let inner = block.inner(area);
    let height = usize::from(inner.height);
    // A long line continues under its text rather than being cut off: a refusal's reason is
    // usually at its end.
    let room = usize::from(inner.width).saturating_sub(PREFIX).max(10);
    let shown = log.shown();
    // At the top (PgUp as far as it goes, or Home), the oldest entry is the first row even when
    // long entries wrap; otherwise the newest shown entry is the last row.
    let at_top = log.scroll > 0 && log.scroll >= log.max_scroll(height);
    let lines: Vec<Line> = if at_top {
        let mut lines = Vec::new();
        for l in &shown {
            if lines.len() >= height {
                break;
            }
            lines.extend(entry_lines(l, room));
        }
        lines.truncate(height.max(1));
        lines
    } else {
        let end = shown.len().saturating_sub(log.scroll);
        let mut lines: Vec<Line> = Vec::new();
        // The newest entries whole, as many as fit; the newest alone if even it does not.
        for l in shown.iter().take(end).rev() {
            let entry = entry_lines(l, room);
            if !lines.is_empty() && lines.len() + entry.len() > height {
                break;
            }
            lines.splice(0..0, entry);
        }
        let extra = lines.len().saturating_sub(height);
        lines.drain(..extra);
        lines
    };
    frame.render_widget(Paragraph::new(lines).block(block), area);
}

/// One entry's rows: time, severity letter (readable without colour), source, then the text
/// (with its repeat count), wrapped under itself.
fn entry_lines(l: &LogLine, room: usize) -> Vec<Line<'static>> {
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
    let mut level_style = Style::new().fg(color);
    if l.level >= Level::Warn {
        level_style = level_style.add_modifier(Modifier::BOLD);
    }
    wrap(&l.display(), room)
        .into_iter()
        .enumerate()
        .map(|(i, piece)| {
            let head = if i == 0 {
                vec![
                    Span::styled(
                        format!("{:>7.1} ", l.t_ms as f64 / 1000.0),
                        Style::new().fg(Color::DarkGray),
                    ),
                    Span::styled(l.level.letter().to_string(), level_style),
                    Span::styled(format!(" {tag:<5} "), Style::new().fg(Color::DarkGray)),
                ]
            } else {
                vec![Span::raw(" ".repeat(PREFIX))]
            };
            let mut spans = head;
            spans.push(Span::styled(piece, Style::new().fg(color)));
            Line::from(spans)
        })
        .collect()
}

/// Columns of the time and source before a line's text.
const PREFIX: usize = 16;

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
