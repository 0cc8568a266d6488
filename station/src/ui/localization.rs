//! Floor-grid line correction on screen (seed 003): map layers for the plain-odometry and
//! nearest-line tracks, the line events, the PPD samples and the floor grid, and a panel
//! beside the map with each estimate's error against the emulator's truth over time.
//!
//! Layer: presentation over `app.localization` (`app::localization`). The corrected track is
//! the believed track (cyan): while line correction runs, the pose the robot reports IS the
//! corrected one; the truth is magenta. Here: plain odometry yellow `·`, nearest-line
//! baseline red `·`, line events `+` green (corrected), `x` red (rejected), `"` grey (echo),
//! PPD samples white dots, the grid dark grey. Every layer paints nothing until the robot has
//! sent a `Localization`, so other robots' screens do not change. [`split`] gives the panel
//! the map's spare columns (after the plan panel, which wins). Cannot fail.

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::{Line as TLine, Span};
use ratatui::widgets::canvas::{Context, Line, Points};
use ratatui::widgets::{Axis, Block, Chart, Dataset, GraphType, Paragraph};
use ratatui::Frame;

use protocol::LineVerdict;

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// Layer names (keys in `input.rs` and the help).
pub const ODOMETRY: &str = "odometry";
pub const LINES: &str = "lines";
pub const PPD: &str = "ppd";
pub const FLOOR: &str = "floor";

/// Plain odometry.
pub const UNCORRECTED: Color = Color::Yellow;
/// The nearest-line baseline.
pub const BASELINE: Color = Color::LightRed;
/// The corrected estimate (as the believed track).
pub const CORRECTED: Color = Color::Cyan;

/// Floor grid pitch the firmware assumes, metres (seed 003 §2.6.4), through the origin.
const PITCH_M: f64 = 0.10;
/// Narrowest and widest panel.
const MIN_WIDTH: u16 = 30;
const MAX_WIDTH: u16 = 44;
/// Seconds of error history on the chart.
const WINDOW_S: f64 = 120.0;
/// Line events marked on the map: the latest few (marks cover whole cells, so more would
/// hide the tracks they explain).
const MARKED_EVENTS: usize = 24;
/// Half a grid square, mm: the thesis's bound for the corrected error, drawn on the chart.
const HALF_SQUARE_MM: f64 = 50.0;

/// Plain-odometry and nearest-line tracks.
pub struct OdometryLayer;
/// Line events where the robot placed them.
pub struct LinesLayer;
/// The PPD samples the robot sent last.
pub struct PpdLayer;
/// The floor grid.
pub struct FloorLayer;

impl MapLayer for FloorLayer {
    fn name(&self) -> &'static str {
        FLOOR
    }

    fn dots(&self, app: &App) -> bool {
        app.localization.active()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        if !app.localization.active() {
            return;
        }
        // Under 6 braille dots per square the grid buries the tracks (`f` shows it when the
        // map is large enough).
        let dots_per_m = f64::from(view.cols) * 2.0 / (view.x[1] - view.x[0]).max(1e-9);
        if dots_per_m * PITCH_M < 6.0 {
            return;
        }
        let color = Color::Indexed(238);
        let (kx0, kx1) = (
            (view.x[0] / PITCH_M).ceil() as i64,
            (view.x[1] / PITCH_M).floor() as i64,
        );
        for k in kx0..=kx1 {
            let x = k as f64 * PITCH_M;
            ctx.draw(&Line::new(x, view.y[0], x, view.y[1], color));
        }
        let (ky0, ky1) = (
            (view.y[0] / PITCH_M).ceil() as i64,
            (view.y[1] / PITCH_M).floor() as i64,
        );
        for k in ky0..=ky1 {
            let y = k as f64 * PITCH_M;
            ctx.draw(&Line::new(view.x[0], y, view.x[1], y, color));
        }
    }
}

impl MapLayer for OdometryLayer {
    fn name(&self) -> &'static str {
        ODOMETRY
    }

    fn dots(&self, app: &App) -> bool {
        let l = &app.localization;
        l.uncorrected.points().next().is_some() || l.baseline.points().next().is_some()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let l = &app.localization;
        for (track, color) in [(&l.uncorrected, UNCORRECTED), (&l.baseline, BASELINE)] {
            let pts: Vec<(f64, f64)> = track.points().copied().collect();
            ctx.draw(&Points {
                coords: &pts,
                color,
            });
        }
    }
}

impl MapLayer for LinesLayer {
    fn name(&self) -> &'static str {
        LINES
    }

    fn dots(&self, _app: &App) -> bool {
        false
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let events = &app.localization.events;
        for e in events
            .iter()
            .skip(events.len().saturating_sub(MARKED_EVENTS))
        {
            let mark = match e.verdict {
                LineVerdict::Corrected => "+".green(),
                LineVerdict::Rejected => "x".red(),
                LineVerdict::Echo => "\"".dark_gray(),
            };
            ctx.print(e.x, e.y, mark);
        }
    }
}

impl MapLayer for PpdLayer {
    fn name(&self) -> &'static str {
        PPD
    }

    fn dots(&self, app: &App) -> bool {
        app.localization.last.is_some()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(m) = &app.localization.last else {
            return;
        };
        let (cx, cy) = (
            f64::from(m.corrected.x_mm) / 1000.0,
            f64::from(m.corrected.y_mm) / 1000.0,
        );
        let pts: Vec<(f64, f64)> = m
            .samples
            .iter()
            .map(|s| {
                (
                    cx + f64::from(s.dx_mm) / 1000.0,
                    cy + f64::from(s.dy_mm) / 1000.0,
                )
            })
            .collect();
        ctx.draw(&Points {
            coords: &pts,
            color: Color::White,
        });
    }
}

/// The map's part of `area` and the panel's, when the robot corrects with lines and there is
/// room.
pub fn split(app: &App, area: Rect) -> (Rect, Option<Rect>) {
    if !app.localization.active() {
        return (area, None);
    }
    let bounds = app
        .map
        .arena
        .as_ref()
        .map_or([0.0, 0.0, 2.0, 2.0], |a| a.bounds);
    super::map::split_beside(area, bounds, MIN_WIDTH, MAX_WIDTH)
}

/// The panel: errors over time (with the emulator's truth) and the last line event.
pub fn render_panel(app: &App, frame: &mut Frame, area: Rect) {
    let l = &app.localization;
    let text_h = 9u16.min(area.height);
    let [chart_area, text_area] =
        Layout::vertical([Constraint::Fill(1), Constraint::Length(text_h)]).areas(area);
    let block = Block::bordered().title(" Position error, mm ");
    if l.errors.is_empty() {
        let why = if app.truth.is_some() {
            "waiting for line correction"
        } else {
            "needs the emulator's truth"
        };
        frame.render_widget(
            Paragraph::new(why)
                .style(Style::new().fg(Color::DarkGray))
                .block(block),
            chart_area,
        );
    } else {
        render_chart(app, frame, chart_area, block);
    }
    frame.render_widget(status(app), text_area);
}

fn render_chart(app: &App, frame: &mut Frame, area: Rect, block: Block<'_>) {
    let l = &app.localization;
    let t_end = l.errors.back().map_or(0.0, |e| e.t_s);
    let t_first = l.errors.front().map_or(0.0, |e| e.t_s);
    let t0 = (t_end - WINDOW_S).max(t_first.min(t_end - 1.0));
    let pick = |f: fn(&crate::app::localization::ErrorPoint) -> f64| -> Vec<(f64, f64)> {
        l.errors
            .iter()
            .filter(|e| e.t_s >= t0)
            .map(|e| (e.t_s, f(e)))
            .collect()
    };
    let bound = vec![(t0, HALF_SQUARE_MM), (t_end.max(t0 + 1.0), HALF_SQUARE_MM)];
    let series = [
        ("½ square", Color::DarkGray, bound),
        ("corrected", CORRECTED, pick(|e| e.corrected_mm)),
        ("odometry", UNCORRECTED, pick(|e| e.uncorrected_mm)),
        ("nearest line", BASELINE, pick(|e| e.baseline_mm)),
    ];
    let hi = series
        .iter()
        .flat_map(|(_, _, d)| d.iter().map(|(_, v)| *v))
        .fold(50.0f64, f64::max);
    let datasets: Vec<Dataset> = series
        .iter()
        .map(|(name, color, d)| {
            Dataset::default()
                .name(*name)
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::new().fg(*color))
                .data(d)
        })
        .collect();
    let chart = Chart::new(datasets)
        .block(block)
        .x_axis(
            Axis::default()
                .bounds([t0, t_end.max(t0 + 1.0)])
                .labels([
                    TLine::from(format!("-{:.0} s", t_end - t0)),
                    TLine::from("now"),
                ])
                .style(Style::new().fg(Color::DarkGray)),
        )
        .y_axis(
            Axis::default()
                .bounds([0.0, hi * 1.05])
                .labels([TLine::from("0"), TLine::from(format!("{hi:.0}"))])
                .style(Style::new().fg(Color::DarkGray)),
        );
    frame.render_widget(chart, area);
}

fn row(label: &str, value: String) -> TLine<'static> {
    TLine::from(vec![
        Span::styled(format!("{label:<10}"), Style::new().fg(Color::DarkGray)),
        Span::raw(value),
    ])
}

fn status(app: &App) -> Paragraph<'static> {
    let l = &app.localization;
    let mut lines = Vec::new();
    if let Some(e) = l.latest_error() {
        lines.push(TLine::from(vec![
            Span::styled(
                format!("{:<10}", "now/max"),
                Style::new().fg(Color::DarkGray),
            ),
            Span::styled(
                format!("{:.0}/{:.0} ", e.corrected_mm, l.max_mm[0]),
                Style::new().fg(CORRECTED),
            ),
            Span::styled(
                format!("{:.0}/{:.0} ", e.uncorrected_mm, l.max_mm[1]),
                Style::new().fg(UNCORRECTED),
            ),
            Span::styled(
                format!("{:.0}/{:.0}", e.baseline_mm, l.max_mm[2]),
                Style::new().fg(BASELINE),
            ),
        ]));
    }
    if let Some(m) = &l.last {
        lines.push(row(
            "lines",
            format!(
                "{} seen, {} used, {} ignored",
                m.lines, m.corrections, m.rejected
            ),
        ));
        lines.push(row(
            "PPD",
            format!(
                "{} mm, bias {:+.2}/{:+.2} %",
                m.ppd_size_mm,
                f64::from(m.bias_mean[0]) / 1000.0,
                f64::from(m.bias_mean[1]) / 1000.0
            ),
        ));
        if let Some(e) = m.last_event {
            let what = match e.verdict {
                LineVerdict::Corrected => format!(
                    "{:?}{} {} mm {:+.1}°",
                    e.axis,
                    e.index,
                    e.moved_mm,
                    f64::from(e.turned_mrad) / 1000.0 * 180.0 / std::f64::consts::PI
                ),
                LineVerdict::Rejected => format!("rejected ({} mm off)", e.moved_mm),
                LineVerdict::Echo => "echo ignored".to_string(),
            };
            lines.push(row(
                "last line",
                format!("{what} at {:.1} s", f64::from(e.time_ms) / 1000.0),
            ));
        }
    }
    lines.push(TLine::from(vec![
        "· ".cyan(),
        "corr ".dark_gray(),
        "· ".yellow(),
        "odo ".dark_gray(),
        "· ".light_red(),
        "near ".dark_gray(),
        "○ ".magenta(),
        "true".dark_gray(),
    ]));
    lines.push(TLine::from(
        "S survey  y odo  i lines  v PPD  f grid".dark_gray(),
    ));
    Paragraph::new(lines).block(Block::bordered().title(" Line correction "))
}
