//! The parameter editor: the firmware's parameter table with the values read back, and the
//! robot's reason whenever it refused a read or a write.
//!
//! Layer: presentation over `ParamEditor`. The table scrolls to keep the selection visible
//! (a `TableState` built per frame: rendering changes nothing in the app).

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Cell, Paragraph, Row, Table, TableState};
use ratatui::Frame;

use crate::app::params::{range_text, status_text, ParamStatus};
use crate::app::App;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let block = Block::bordered().title(" Parameters (/ search, r read, R read all, Enter edit) ");
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let [table_area, desc_area, edit_area] = Layout::vertical([
        Constraint::Fill(1),
        Constraint::Length(1),
        Constraint::Length(1),
    ])
    .areas(inner);
    let shown = app.params.shown();
    let params = app.params.params();
    let rows: Vec<Row> = shown
        .iter()
        .filter_map(|&i| Some((params.get(i)?, app.params.status.get(i)?)))
        .map(|(p, s)| {
            let color = match s {
                ParamStatus::Refused { .. } | ParamStatus::Failed(_) => Color::Red,
                ParamStatus::Pending => Color::Yellow,
                ParamStatus::Value(_) => Color::Reset,
                ParamStatus::Unknown | ParamStatus::Absent => Color::DarkGray,
            };
            Row::new(vec![
                Cell::from(p.id.to_string()),
                Cell::from(p.name),
                Cell::from(Span::styled(status_text(p, s), Style::new().fg(color))),
                Cell::from(p.unit),
                Cell::from(range_text(p)),
            ])
        })
        .collect();
    let table = Table::new(
        rows,
        [
            Constraint::Length(3),
            Constraint::Length(23),
            Constraint::Fill(1),
            Constraint::Length(11),
            Constraint::Length(18),
        ],
    )
    .header(
        Row::new(["id", "name", "value", "unit", "range"])
            .style(Style::new().add_modifier(Modifier::BOLD)),
    )
    .row_highlight_style(Style::new().add_modifier(Modifier::REVERSED));
    let selected = shown.iter().position(|&i| i == app.params.selected);
    let mut state = TableState::default().with_selected(selected);
    frame.render_stateful_widget(table, table_area, &mut state);
    let search = &app.params.search;
    let edit = match (&app.params.input, app.params.selected_info()) {
        // The search box: what is typed, and what it finds.
        (None, _) if app.params.searching || !search.is_empty() => {
            let found = match shown.len() {
                0 => "no parameter matches".to_string(),
                n if n == params.len() => format!("all {n}"),
                n => format!("{n} of {}", params.len()),
            };
            let hint = if app.params.searching {
                "  (Enter keeps it, Esc clears)"
            } else {
                "  (/ changes it, Esc clears)"
            };
            let mut spans = vec![
                Span::styled("/ ", Style::new().fg(Color::Yellow)),
                Span::raw(search.clone()),
            ];
            if app.params.searching {
                spans.push(Span::styled("▏", Style::new().fg(Color::Yellow)));
            }
            spans.push(Span::styled(
                format!("  {found}"),
                Style::new().fg(if shown.is_empty() {
                    Color::Red
                } else {
                    Color::Reset
                }),
            ));
            spans.push(Span::styled(hint, Style::new().fg(Color::DarkGray)));
            Line::from(spans)
        }
        (Some(text), Some(p)) => Line::from(vec![
            Span::styled(format!("{} = ", p.name), Style::new().fg(Color::Yellow)),
            Span::raw(text.clone()),
            Span::styled("▏", Style::new().fg(Color::Yellow)),
            match &app.params.input_error {
                // Where the eyes are: a typo is not news for the log alone.
                Some(e) => Span::styled(format!("  {e}"), Style::new().fg(Color::Red)),
                None => Span::styled(
                    format!("  ({} {})", range_text(p), p.unit),
                    Style::new().fg(Color::DarkGray),
                ),
            },
        ]),
        _ => Line::from(Span::styled(
            "values are read from the robot; a refused write shows the robot's reason",
            Style::new().fg(Color::DarkGray),
        )),
    };
    frame.render_widget(Paragraph::new(edit), edit_area);
    // The selected parameter's one-line description, where QGroundControl shows it.
    if let Some(p) = app.params.selected_info() {
        let desc = Line::from(vec![
            Span::styled(
                format!("{}: ", p.name),
                Style::new().add_modifier(Modifier::BOLD),
            ),
            Span::raw(p.desc),
        ]);
        frame.render_widget(Paragraph::new(desc), desc_area);
    }
}
