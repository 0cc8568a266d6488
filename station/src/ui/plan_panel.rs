//! The plan panel: what the station's planner knows, beside the map when there is room.
//!
//! Layer: presentation. A map panel wider than its square-dotted arena needs (the Map view on
//! a large terminal, or even at 80 x 24) gives the spare columns to this panel: the grid, the
//! segmentation, the last plan with its waypoints, the layer keys and which layers are shown.
//! [`split`] decides the split and is used both to draw and to map mouse clicks, so a click
//! lands where the map is drawn. Timings are left to the log and `station plan` (they would
//! make every frame different). Cannot fail: a short panel clips its list.

use ratatui::layout::Rect;
use ratatui::style::{Color, Style, Stylize};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph};
use ratatui::Frame;

use super::map_layers::{self, RAW, SMOOTH};
use crate::app::App;

/// Narrowest plan panel worth drawing.
const MIN_WIDTH: u16 = 30;
/// Widest plan panel.
const MAX_WIDTH: u16 = 46;

/// The map's part of `area` and the plan panel's, if there is room for one.
pub fn split(app: &App, area: Rect) -> (Rect, Option<Rect>) {
    let Some(m) = app.map.plan.map() else {
        return (area, None);
    };
    let bounds = app.map.arena.as_ref().map_or(m.bounds(), |a| a.bounds);
    super::map::split_beside(area, bounds, MIN_WIDTH, MAX_WIDTH)
}

fn row(label: &str, value: String) -> Line<'static> {
    Line::from(vec![
        Span::styled(format!("{label:<9}"), Style::new().fg(Color::DarkGray)),
        Span::raw(value),
    ])
}

fn xy((x, y): (f64, f64)) -> String {
    format!("({x:.2}, {y:.2})")
}

/// Draws the panel.
pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    let state = &app.map.plan;
    let mut lines = Vec::new();
    if let Some(p) = state.planner() {
        let m = p.map();
        let (free, obstacle, unknown) = m.counts();
        lines.push(row("map", m.name.clone()));
        lines.push(row(
            "grid",
            format!(
                "{} x {} of {} m, radius {} m",
                m.grid.width(),
                m.grid.height(),
                m.cell_m(),
                m.radius_m
            ),
        ));
        lines.push(row(
            "cells",
            format!("{free} free, {obstacle} obst., {unknown} unkn."),
        ));
        lines.push(row("regions", format!("{} squares", p.squares().len())));
    }
    if let Some(e) = &state.error {
        let width = usize::from(area.width.saturating_sub(2)).max(10);
        lines.extend(wrap(e, width).into_iter().map(|l| Line::from(l.red())));
    }
    match &state.result {
        Some(r) => {
            lines.push(row("start", xy(r.start())));
            lines.push(row("goal", xy(r.goal())));
            lines.push(Line::from(vec![
                Span::styled(format!("{:<9}", "plan"), Style::new().fg(Color::DarkGray)),
                Span::styled(
                    format!("{:.2} m, {} regions", r.length_m, r.path.len()),
                    Style::new().fg(RAW),
                ),
            ]));
            if let Some(s) = &r.smoothed {
                lines.push(Line::from(vec![
                    Span::styled(
                        format!("{:<9}", "smoothed"),
                        Style::new().fg(Color::DarkGray),
                    ),
                    Span::styled(
                        format!("{:.2} m, {} points", s.length_m, s.waypoints.len()),
                        Style::new().fg(SMOOTH),
                    ),
                ]));
            }
        }
        None => lines.push(Line::from("no plan yet".dark_gray())),
    }
    if let Some((id, points)) = &app.transfers.robot_plan {
        lines.push(Line::from(vec![
            Span::styled(format!("{:<9}", "robot"), Style::new().fg(Color::DarkGray)),
            Span::styled(
                format!("plan {id:#010x}, {} points (X runs it)", points.len()),
                Style::new().fg(super::transfer::ROBOT_PLAN),
            ),
        ]));
    }
    lines.push(Line::from(""));
    lines.extend(layers(app));
    lines.push(Line::from(" P plan to the cursor (g) or goal".dark_gray()));
    if let Some(r) = &state.result {
        lines.push(Line::from(""));
        lines.push(Line::from("waypoints (region centres)".dark_gray()));
        let shown = usize::from(area.height.saturating_sub(2)).saturating_sub(lines.len());
        let n = r.waypoints.len();
        for (i, p) in r.waypoints.iter().enumerate().take(shown) {
            let last_slot = i + 1 == shown && n > shown;
            lines.push(if last_slot {
                Line::from(format!(" … {} more", n - i).dark_gray())
            } else {
                Line::from(format!("{i:>3} {}", xy(*p)))
            });
        }
    }
    let block = Block::bordered().title(" Plan (station) ");
    frame.render_widget(Paragraph::new(lines).block(block), area);
}

/// `text` broken at spaces into lines of at most `width` characters (longer words are cut).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let fits = line.chars().count() + 1 + word.chars().count() <= width;
        if !line.is_empty() && !fits {
            out.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
        while line.chars().count() > width {
            let head: String = line.chars().take(width).collect();
            line = line.chars().skip(width).collect();
            out.push(head);
        }
    }
    if !line.is_empty() {
        out.push(line);
    }
    out
}

/// The layer keys on two lines, each bright when its layer is shown.
fn layers(app: &App) -> [Line<'static>; 2] {
    let span = |key: char, name: &'static str, label: &str| {
        let style = if app.map.visible(name) {
            Style::new().fg(Color::White).bold()
        } else {
            Style::new().fg(Color::DarkGray)
        };
        Span::styled(format!(" {key} {label}"), style)
    };
    [
        Line::from(vec![
            span('o', map_layers::GRID, "grid"),
            span('r', map_layers::REGIONS, "regions"),
            span('n', map_layers::PLAN, "plan"),
        ]),
        Line::from(vec![
            span('m', map_layers::SMOOTHED, "smoothed"),
            span('e', map_layers::ENDS, "start/goal"),
        ]),
    ]
}
