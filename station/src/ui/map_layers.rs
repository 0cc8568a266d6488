//! Map layers for planning: the occupancy grid, the segmentation squares, the raw plan with
//! its waypoints, the smoothed path, and the plan's start and goal.
//!
//! Layer: presentation; each is a [`MapLayer`] reading `app.map.plan` (a [`PlanState`]) and
//! painting in metres on the map's canvas, hidden by name like the others. The grid is filled
//! with half-block cells (one terminal cell = two square pixels), so obstacles show as solid
//! blocks under the braille lines of the layers above; free cells are left empty. Squares too
//! small to see (under two braille dots a side) are not outlined: on a fine grid they would
//! only fill the screen with dots. Waypoints are marked while there are few enough to read.
//! Cannot fail; with no map or no plan a layer paints nothing.
//!
//! [`PlanState`]: crate::plan::PlanState

use ratatui::style::{Color, Style, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::{Line as TLine, Span};
use ratatui::widgets::canvas::{Context, Line, Points, Rectangle};

use robot_firmware::nav::Cell;

use super::layer::{MapLayer, MapView};
use crate::app::App;
use crate::plan::NavMap;

/// Obstacle cells.
pub const OBSTACLE: Color = Color::DarkGray;
/// Unknown cells (treated as obstacles by the planner).
pub const UNKNOWN: Color = Color::Indexed(240);
/// The glyph of an unknown (unexplored) cell: a shade, where an obstacle is a solid block, so
/// the two read apart without colour.
pub const UNKNOWN_GLYPH: char = '░';
/// The legend's names of the grid's glyphs.
pub const WALL_LABEL: &str = "█ wall";
pub const UNKNOWN_LABEL: &str = "░ unexplored";
/// Square outlines.
pub const REGION: Color = Color::Blue;
/// The raw plan through region centres.
pub const RAW: Color = Color::LightYellow;
/// The smoothed path.
pub const SMOOTH: Color = Color::LightGreen;
/// Most waypoints marked individually.
const MAX_WAYPOINT_MARKS: usize = 60;

/// Layer names, with the key that toggles each (see `input.rs` and the help).
pub const GRID: &str = "grid";
pub const REGIONS: &str = "regions";
pub const PLAN: &str = "plan";
pub const SMOOTHED: &str = "smoothed";
pub const ENDS: &str = "ends";

/// Free / obstacle / unknown cells of the planner's grid.
pub struct GridLayer;
/// The segmentation's squares (seed 004 §6, Fig. 6).
pub struct RegionsLayer;
/// The raw plan through region centres and its waypoints.
pub struct PlanLayer;
/// The smoothed path.
pub struct SmoothedLayer;
/// The plan's start and goal (the map's markers before any plan).
pub struct EndsLayer;

fn map(app: &App) -> Option<&NavMap> {
    app.map.plan.map()
}

impl MapLayer for GridLayer {
    fn name(&self) -> &'static str {
        GRID
    }

    fn dots(&self, app: &App) -> bool {
        map(app).is_some()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        let Some(m) = map(app) else { return };
        // Unknown cells one shade glyph per terminal cell, obstacles in half blocks over them.
        ctx.marker(Marker::Custom(UNKNOWN_GLYPH));
        let unknown = pixels_of(m, view, 1, Cell::Unknown);
        ctx.draw(&Points {
            coords: &unknown,
            color: UNKNOWN,
        });
        ctx.marker(Marker::HalfBlock);
        let solid = pixels_of(m, view, 2, Cell::Obstacle);
        ctx.draw(&Points {
            coords: &solid,
            color: OBSTACLE,
        });
        // Back to braille for the layers above (this saves the half-block layer).
        ctx.marker(Marker::Braille);
    }
}

/// The centres of the canvas pixels whose grid cell is `kind`, on a grid of `per_row` pixels
/// down each terminal cell (one across).
fn pixels_of(m: &NavMap, view: &MapView, per_row: usize, kind: Cell) -> Vec<(f64, f64)> {
    let (w, h) = (usize::from(view.cols), usize::from(view.rows) * per_row);
    let (xs, ys) = (view.x[1] - view.x[0], view.y[1] - view.y[0]);
    // The canvas maps x to pixel round((x - left) * (w - 1) / xs): pixel i is centred on
    // left + i * xs / (w - 1) (likewise y, from the top).
    let px = |i: usize| view.x[0] + i as f64 * xs / (w.max(2) - 1) as f64;
    let py = |j: usize| view.y[1] - j as f64 * ys / (h.max(2) - 1) as f64;
    let mut out = Vec::new();
    for j in 0..h {
        let y = py(j).clamp(view.y[0], view.y[1]);
        for i in 0..w {
            let x = px(i).clamp(view.x[0], view.x[1]);
            let Some((cx, cy)) = m.cell_of((x, y)) else {
                continue;
            };
            if m.grid.get(cx.into(), cy.into()) == kind {
                out.push((x, y));
            }
        }
    }
    out
}

/// Which of the grid's glyphs the map shows now: (walls, unexplored cells).
pub fn grid_glyphs(app: &App) -> (bool, bool) {
    let Some(m) = map(app).filter(|_| app.map.visible(GRID)) else {
        return (false, false);
    };
    let (_, obstacle, unknown) = m.counts();
    (obstacle > 0, unknown > 0)
}

impl MapLayer for RegionsLayer {
    fn name(&self) -> &'static str {
        REGIONS
    }

    fn dots(&self, app: &App) -> bool {
        app.map.plan.planner().is_some()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        let Some(p) = app.map.plan.planner() else {
            return;
        };
        let m = p.map();
        let (ox, oy) = m.origin();
        let c = m.cell_m();
        let dots_per_m = f64::from(view.cols) * 2.0 / (view.x[1] - view.x[0]).max(1e-9);
        for s in p.squares() {
            let side = f64::from(s.size) * c;
            if side * dots_per_m < 2.0 {
                continue;
            }
            ctx.draw(&Rectangle {
                x: ox + f64::from(s.x) * c,
                y: oy + f64::from(s.y) * c,
                width: side,
                height: side,
                color: REGION,
            });
        }
    }
}

/// Straight segments through `points`.
fn polyline(ctx: &mut Context<'_>, points: &[(f64, f64)], color: Color) {
    for w in points.windows(2) {
        ctx.draw(&Line {
            x1: w[0].0,
            y1: w[0].1,
            x2: w[1].0,
            y2: w[1].1,
            color,
        });
    }
}

impl MapLayer for PlanLayer {
    fn name(&self) -> &'static str {
        PLAN
    }

    fn dots(&self, app: &App) -> bool {
        app.map.plan.result.is_some()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(r) = &app.map.plan.result else {
            return;
        };
        polyline(ctx, &r.waypoints, RAW);
        let inner = r.waypoints.get(1..r.waypoints.len().saturating_sub(1));
        if let Some(centres) = inner.filter(|c| c.len() <= MAX_WAYPOINT_MARKS) {
            for (x, y) in centres {
                ctx.print(*x, *y, Span::styled("•", Style::new().fg(RAW)));
            }
        }
    }
}

impl MapLayer for SmoothedLayer {
    fn name(&self) -> &'static str {
        SMOOTHED
    }

    fn dots(&self, app: &App) -> bool {
        app.map
            .plan
            .result
            .as_ref()
            .is_some_and(|r| r.smoothed.is_some())
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        if let Some(s) = app
            .map
            .plan
            .result
            .as_ref()
            .and_then(|r| r.smoothed.as_ref())
        {
            polyline(ctx, &s.waypoints, SMOOTH);
        }
    }
}

impl MapLayer for EndsLayer {
    fn name(&self) -> &'static str {
        ENDS
    }

    fn dots(&self, _app: &App) -> bool {
        false
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let (start, goal) = match (&app.map.plan.result, map(app)) {
            (Some(r), _) => (Some(r.start()), Some(r.goal())),
            (None, Some(m)) => (m.start, m.goal.map(|g| g.centre)),
            (None, None) => return,
        };
        if let Some((x, y)) = start {
            ctx.print(x, y, "S".white().bold());
        }
        if let Some((x, y)) = goal {
            ctx.print(x, y, "G".light_red().bold());
        }
    }
}

/// The map title's planning part in at most `room` columns: the last plan, the last failure,
/// or how to plan; shorter forms on narrow panels, nothing when even those do not fit.
pub fn status(app: &App, room: u16) -> Option<TLine<'static>> {
    let full = status_line(app)?;
    if full.width() <= usize::from(room) {
        return Some(full);
    }
    let state = &app.map.plan;
    let short = match (&state.error, &state.result) {
        (Some(_), _) => TLine::from(" plan failed: see log ".red()),
        (None, Some(r)) => TLine::from(Span::styled(
            format!(" plan {:.2} m ", r.length_m),
            Style::new().fg(RAW),
        )),
        (None, None) => TLine::from(" P: plan ".dark_gray()),
    };
    (short.width() <= usize::from(room)).then_some(short)
}

fn status_line(app: &App) -> Option<TLine<'static>> {
    let state = &app.map.plan;
    if let Some(e) = &state.error {
        return Some(TLine::from(format!(" {e} ").red()));
    }
    let p = state.planner()?;
    Some(match &state.result {
        Some(r) => {
            let mut spans = vec![
                Span::styled(format!(" plan {:.2} m", r.length_m), Style::new().fg(RAW)),
                Span::raw(format!(" · {} regions", r.path.len())),
            ];
            if let Some(s) = &r.smoothed {
                spans.push(Span::styled(
                    format!(" · smoothed {:.2} m", s.length_m),
                    Style::new().fg(SMOOTH),
                ));
            }
            spans.push(Span::raw(" "));
            TLine::from(spans)
        }
        None => TLine::from(
            format!(
                " {}x{} · {} squares · P: plan ",
                p.map().grid.width(),
                p.map().grid.height(),
                p.squares().len()
            )
            .dark_gray(),
        ),
    })
}
