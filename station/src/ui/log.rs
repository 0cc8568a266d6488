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
    let lines: Vec<Line> = app
        .log
        .window(usize::from(inner.height))
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
            };
            Line::from(vec![
                Span::styled(
                    format!("{:>7.1} {tag:<5} ", l.t_ms as f64 / 1000.0),
                    Style::new().fg(Color::DarkGray),
                ),
                Span::styled(l.text.clone(), Style::new().fg(color)),
            ])
        })
        .collect();
    frame.render_widget(Paragraph::new(lines).block(block), area);
}
