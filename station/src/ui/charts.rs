//! Time-series charts of the chosen telemetry series (`c` steps through the presets).
//!
//! Layer: presentation over `History`. The x axis is the last `WINDOW_S` seconds of station
//! time; the y axis fits the visible data with a margin, so a flat series still shows.

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::Line;
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Paragraph, Sparkline};
use ratatui::Frame;

use crate::app::history::{offered_series, CHART_PRESETS};
use crate::app::App;

/// Seconds of history on the x axis.
pub const WINDOW_S: f64 = 30.0;
const COLORS: [Color; 4] = [Color::Cyan, Color::Yellow, Color::Magenta, Color::Green];

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    // Only the series of sensors the robot has (a robot without a battery sensor sends 0).
    let shown = app.chart_shown();
    let name = CHART_PRESETS.get(shown).map_or("none", |p| p.0);
    let series = offered_series(shown, app.capabilities());
    let series = series.as_slice();
    let block = Block::bordered().title(format!(" Charts — {name} (c: next) "));
    let Some((t_first, t_end)) = app.history.span() else {
        frame.render_widget(Paragraph::new("no telemetry yet").block(block), area);
        return;
    };
    // Until a whole window has passed, the data fills the width.
    let t0 = (t_end - WINDOW_S).max(t_first.min(t_end - 1.0));
    let data: Vec<Vec<(f64, f64)>> = series
        .iter()
        .map(|s| {
            app.history
                .series(*s)
                .into_iter()
                .filter(|(t, _)| *t >= t0)
                .collect()
        })
        .collect();
    if area.height < 8 {
        // Too short for axes: a sparkline of the first series.
        let inner = block.inner(area);
        frame.render_widget(block, area);
        let first: Vec<u64> = data
            .first()
            .map(|d| d.iter().map(|(_, v)| v.max(0.0).round() as u64).collect())
            .unwrap_or_default();
        let [line] = Layout::vertical([Constraint::Fill(1)]).areas(inner);
        frame.render_widget(Sparkline::default().data(first.iter().copied()), line);
        return;
    }
    let (lo, hi) = y_range(&data);
    let datasets: Vec<Dataset> = series
        .iter()
        .zip(&data)
        .enumerate()
        .map(|(i, (s, d))| {
            Dataset::default()
                .name(s.label())
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(
                    Style::new().fg(COLORS
                        .get(i % COLORS.len())
                        .copied()
                        .unwrap_or(Color::White)),
                )
                .data(d)
        })
        .collect();
    let chart = Chart::new(datasets)
        .block(block)
        .x_axis(
            Axis::default()
                .bounds([t0, t_end])
                .labels([
                    Line::from(format!("-{:.0} s", t_end - t0)),
                    Line::from("now"),
                ])
                .style(Style::new().fg(Color::DarkGray)),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([Line::from(short(lo)), Line::from(short(hi))])
                .style(Style::new().fg(Color::DarkGray)),
        );
    frame.render_widget(chart, area);
}

fn y_range(data: &[Vec<(f64, f64)>]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for (_, v) in data.iter().flatten() {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.1).max(1.0);
    (lo - pad, hi + pad)
}

fn short(v: f64) -> String {
    if v.abs() >= 1000.0 {
        format!("{:.1}k", v / 1000.0)
    } else {
        format!("{v:.0}")
    }
}
