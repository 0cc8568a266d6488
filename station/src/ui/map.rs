//! The map: arena walls, the robot's believed pose and track, the emulator's true pose and
//! track, the go-to goal and cursor, drawn with a ratatui `Canvas` in metres.
//!
//! Layer: presentation, built from layers. A `MapLayer` paints one kind of thing from the app
//! state onto the canvas, in `LAYERS` order (later layers on top); the occupancy grid,
//! segmentation regions and plans are layers of `map_layers`. Layers can be hidden
//! by name (`MapState::hidden`). `view_bounds` fits the arena (or the tracks) into the panel
//! with square cells, and `to_world` inverts it for mouse clicks.

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Stylize};
use ratatui::symbols::Marker;
use ratatui::text::Line as TLine;
use ratatui::widgets::canvas::Canvas;
use ratatui::widgets::canvas::{Circle, Context, Line, Points};
use ratatui::widgets::Block;
use ratatui::Frame;

pub use super::layer::{MapLayer, MapView};
use super::map_layers;
use crate::app::App;

/// The arena's walls, targets and beacons.
pub struct ArenaLayer;
/// The true pose and track from `EmuTruth`.
pub struct TruthLayer;
/// The pose and track the robot believes.
pub struct BelievedLayer;
/// The go-to goal and the plan's target.
pub struct GoalLayer;
/// The go-to cursor.
pub struct CursorLayer;

/// Layers in drawing order: the planner's grid and squares under the arena, plans above it,
/// the markers of places (start, goal, targets) under the robots, so that a robot standing on
/// its start or its goal shows itself; the cursor the operator is moving over everything.
pub static LAYERS: [&dyn MapLayer; 19] = [
    &map_layers::GridLayer,
    &map_layers::RegionsLayer,
    &super::localization::FloorLayer,
    &ArenaLayer,
    &super::forage::ForageLayer,
    &map_layers::PlanLayer,
    &map_layers::SmoothedLayer,
    &super::transfer::RobotPlanLayer,
    &super::localization::OdometryLayer,
    &super::qt_map::QtLayer,
    &GoalLayer,
    &map_layers::EndsLayer,
    &TruthLayer,
    &super::fleet::FleetLayer,
    &BelievedLayer,
    // Over the believed robot: the retraced track's marker stays visible where they agree.
    &super::retrace_layer::RetraceLayer,
    &super::localization::LinesLayer,
    &super::localization::PpdLayer,
    &CursorLayer,
];

/// Extra margin around what is shown, metres.
const MARGIN_M: f64 = 0.1;
/// Smallest span shown without an arena, metres.
const MIN_SPAN_M: f64 = 2.0;
/// Smallest marker radius of a robot, metres (about a Khepera); larger maps draw it larger
/// so it stays visible.
const ROBOT_R: f64 = 0.04;
/// Marker radius as a fraction of the shown span.
const ROBOT_FRACTION: f64 = 1.0 / 50.0;

pub fn render(app: &App, frame: &mut Frame, area: Rect) {
    // A wide panel gives its spare columns to a side panel (the same split maps clicks): the
    // line-correction panel while the robot reports it, since planning means nothing on a
    // floor grid, else the plan panel.
    let (area, loc) = super::localization::split(app, area);
    let (area, side) = match loc {
        Some(_) => (area, None),
        None => super::plan_panel::split(app, area),
    };
    if let Some(side) = side {
        super::plan_panel::render(app, frame, side);
    }
    if let Some(loc) = loc {
        super::localization::render_panel(app, frame, loc);
    }
    let name = app
        .map
        .arena
        .as_ref()
        .map(|a| a.name.clone())
        .or_else(|| app.map.plan.map().map(|m| m.name.clone()))
        .unwrap_or_else(|| "no arena".to_string());
    let inner = Block::bordered().inner(area);
    let (xb, yb) = view_bounds(app, inner);
    let title = format!(" Map — {name} ");
    let title_w = title.chars().count() as u16;
    // The title row holds the name, the scale and a status. The plan panel, when drawn, says
    // the status; else it goes where it fits: foraging's progress and a plan's outcome before
    // the scale, the scale before the hint of how to plan.
    // The corners and a border column between each title.
    let room = area.width.saturating_sub(title_w + 3);
    let scale = |room: u16| scale_bar(xb[1] - xb[0], inner.width, room);
    let status = |room: u16| {
        super::forage::status(app)
            .filter(|l| l.width() <= usize::from(room))
            .or_else(|| map_layers::status(app, room))
    };
    let news = super::forage::status(app).is_some()
        || app.map.plan.error.is_some()
        || app.map.plan.result.is_some();
    let (scale, status) = match side {
        Some(_) => (scale(room), None),
        None if news => {
            let st = status(room);
            let left = room.saturating_sub(st.as_ref().map_or(0, |l| l.width() as u16 + 1));
            (scale(left), st)
        }
        None => {
            let sc = scale(room);
            let left = room.saturating_sub(sc.as_ref().map_or(0, |s| s.chars().count() as u16 + 1));
            (sc, status(left))
        }
    };
    let block = Block::bordered()
        .title(title)
        .title(TLine::from(scale.unwrap_or_default().white()))
        .title_top(status.unwrap_or_default().right_aligned())
        .title_bottom(legend(app, area.width.saturating_sub(2)));
    let view = MapView {
        x: xb,
        y: yb,
        cols: inner.width,
        rows: inner.height,
    };
    let canvas = Canvas::default()
        .block(block)
        .marker(Marker::Braille)
        .x_bounds(xb)
        .y_bounds(yb)
        .paint(|ctx| {
            for layer in LAYERS.iter() {
                if app.map.visible(layer.name()) {
                    layer.paint(app, &view, ctx);
                    if layer.dots(app) {
                        ctx.layer();
                    }
                }
            }
        });
    frame.render_widget(canvas, area);
}

/// Nice lengths a scale bar shows, metres: 1, 2 and 5 times powers of ten.
const SCALE_STEPS: [f64; 3] = [1.0, 2.0, 5.0];
/// Most columns a scale bar takes, its ends included.
const SCALE_MAX_COLS: f64 = 10.0;

/// A scale bar for a view `span_m` wide over `cols` columns, in at most `room` columns:
/// `┝━━━┥ 0.5 m`, the bar as many columns as the length it names (the longest 1-2-5 length
/// of 3 to `SCALE_MAX_COLS` columns that fits). Drawn in the title row, heavy on the light
/// border, so it never covers the map.
pub fn scale_bar(span_m: f64, cols: u16, room: u16) -> Option<String> {
    let per_col = span_m / f64::from(cols.max(1));
    if !(per_col.is_finite() && per_col > 0.0) {
        return None;
    }
    let text = |len: f64, n: usize| {
        let label = if len >= 1.0 {
            format!("{len:.0} m")
        } else if len >= 0.1 {
            format!("{len:.1} m")
        } else {
            format!("{:.0} cm", len * 100.0)
        };
        format!(" ┝{}┥ {label} ", "━".repeat(n.saturating_sub(2)))
    };
    let mut best = None;
    let mut decade = 10f64.powi(per_col.log10().floor() as i32);
    for _ in 0..3 {
        for step in SCALE_STEPS {
            let len = step * decade;
            let n = (len / per_col).round();
            if (3.0..=SCALE_MAX_COLS).contains(&n) {
                let t = text(len, n as usize);
                if t.chars().count() <= usize::from(room) {
                    best = Some(t);
                }
            }
        }
        decade *= 10.0;
    }
    best
}

/// One mark of the legend: its text, a shorter one for a narrow map, and how much it matters
/// (0 most): what does not fit goes, least important first.
struct Mark {
    full: ratatui::text::Span<'static>,
    short: ratatui::text::Span<'static>,
    rank: u8,
}

fn mark(full: ratatui::text::Span<'static>, short: &'static str, rank: u8) -> Mark {
    let style = full.style;
    Mark {
        short: ratatui::text::Span::styled(short, style),
        full,
        rank,
    }
}

/// The legend in at most `room` columns: the marks on the map now, each with the glyph drawn,
/// so it reads without colour (short names on a narrow map, the least important left out when
/// even those do not fit); the map's state (cursor, zoom, following); then the keys that
/// work, as far as they fit.
fn legend(app: &App, room: u16) -> TLine<'static> {
    let mut marks = Vec::new();
    // In a fleet the robots are their numbers (`ui::fleet`), the selected one reversed.
    match &app.fleet {
        Some(f) if app.in_fleet() => {
            let text = format!(" 1-{} robots ", f.robots.len());
            marks.push(Mark {
                short: text.clone().white(),
                full: text.white(),
                rank: 0,
            })
        }
        _ => marks.push(mark(" ● believed ".cyan(), " ● robot ", 0)),
    }
    if app.truth.is_some() {
        marks.push(mark("○ true ".magenta(), "○ true ", 1));
    }
    // A go-to cursor's coordinates: where Enter would send the robot.
    if app.map.cursor_mode {
        let (x, y) = app.map.cursor;
        let at = format!("+ {x:.2}, {y:.2} m ");
        marks.push(Mark {
            short: at.clone().green(),
            full: at.green(),
            rank: 0,
        });
    }
    let (wall, unknown) = map_layers::grid_glyphs(app);
    if unknown {
        marks.push(mark(
            format!("{} ", map_layers::UNKNOWN_LABEL).dark_gray(),
            "░ unexplored ",
            1,
        ));
    }
    if wall {
        marks.push(mark(
            format!("{} ", map_layers::WALL_LABEL).dark_gray(),
            "█ wall ",
            2,
        ));
    }
    if app.map.goal.is_some() && !app.replaying {
        marks.push(mark("× go-to ".yellow(), "× go-to ", 2));
    }
    if app.plan_target().point().is_some() {
        marks.push(mark("◎ plan target ".light_red(), "◎ plan ", 3));
    }
    // The map's goal letter (`map_layers`), when one is drawn.
    if app.map.plan.result.is_some() || app.map.plan.map().is_some_and(|m| m.goal.is_some()) {
        marks.push(mark("G goal ".light_red(), "G goal ", 3));
    }
    if app
        .map
        .arena
        .as_ref()
        .is_some_and(|a| !a.beacons.is_empty())
    {
        marks.push(mark("B beacon ".yellow(), "B beacon ", 4));
    }
    // The QT world model (seed 001), once it has cells and while its layer is shown.
    if let Some(label) = super::qt_map::legend(app) {
        marks.push(Mark {
            short: label.clone(),
            full: label,
            rank: 3,
        });
    }
    // The map's state: room is kept for it before the hints.
    let zoom = app.map.zoom();
    let mut state = Vec::new();
    if app.map.follow {
        state.push("⊙ follow ".white());
    }
    if zoom > 1.0 && !app.map.cursor_mode {
        state.push(format!("×{zoom:.1} ").white());
    }
    let state_w: usize = state.iter().map(|s| s.width()).sum();
    let room = usize::from(room).saturating_sub(state_w);
    let width = |marks: &[Mark], short: bool| -> usize {
        marks
            .iter()
            .map(|m| {
                if short {
                    m.short.width()
                } else {
                    m.full.width()
                }
            })
            .sum()
    };
    let short = width(&marks, false) > room;
    while width(&marks, short) > room {
        let Some(i) = marks
            .iter()
            .enumerate()
            .max_by_key(|(_, m)| m.rank)
            .map(|(i, _)| i)
            .filter(|_| marks.len() > 1)
        else {
            break;
        };
        marks.remove(i);
    }
    let mut items: Vec<ratatui::text::Span<'static>> = marks
        .into_iter()
        .map(|m| if short { m.short } else { m.full })
        .collect();
    items.extend(state);
    let extra: Vec<ratatui::text::Span<'static>> = if app.map.cursor_mode {
        vec!["Enter: go ".dark_gray()]
    } else {
        let mut v = Vec::new();
        if !app.replaying {
            v.push("g/click: go-to ".dark_gray());
        }
        v.push("z/Z/wheel: zoom hjkl: pan F: follow ".dark_gray());
        v
    };
    let mut used: usize = items.iter().map(|s| s.width()).sum();
    for e in extra {
        if used + e.width() <= room + state_w {
            used += e.width();
            items.push(e);
        }
    }
    TLine::from(items)
}

/// The map's own part of the map panel `area`: without the plan or line-correction panel.
pub fn map_area(app: &App, area: Rect) -> Rect {
    match super::localization::split(app, area) {
        (a, Some(_)) => a,
        (a, None) => super::plan_panel::split(app, a).0,
    }
}

/// Splits a map panel `area` into the map, as wide as `bounds` ([x0, y0, x1, y1], metres,
/// with the view's margin) needs at square braille dots, and a side panel of the columns left
/// over (at most `max_width`); no side panel when fewer than `min_width` are left.
pub fn split_beside(
    area: Rect,
    bounds: [f64; 4],
    min_width: u16,
    max_width: u16,
) -> (Rect, Option<Rect>) {
    let [x0, y0, x1, y1] = bounds;
    let (xs, ys) = (x1 - x0 + 2.0 * MARGIN_M, y1 - y0 + 2.0 * MARGIN_M);
    // Braille dots are square when a cell is twice as tall as wide: 2 columns per row of span.
    let inner_h = f64::from(area.height.saturating_sub(2));
    // A long thin arena (from a file) asks for more columns than a u16 holds: saturate.
    let need = ((2.0 * inner_h * xs / ys.max(1e-9))
        .ceil()
        .min(f64::from(u16::MAX)) as u16)
        .saturating_add(2);
    let spare = area.width.saturating_sub(need);
    if spare < min_width {
        return (area, None);
    }
    let [map, side] = Layout::horizontal([
        Constraint::Fill(1),
        Constraint::Length(spare.min(max_width)),
    ])
    .areas(area);
    (map, Some(side))
}

/// The world rectangle shown in `inner` (x bounds, y bounds), with square braille dots.
pub fn view_bounds(app: &App, inner: Rect) -> ([f64; 2], [f64; 2]) {
    let ((bx, by), (xs, ys)) = whole_view(app, inner);
    let (zoom, (px, py)) = (app.map.zoom(), app.map.pan());
    // Zoomed: a 1/zoom part of that, centred where the operator panned to, or, following the
    // robot, on the robot (the pan then an offset from it).
    let (ox, oy) = match app.pose() {
        Some((x, y, _)) if app.map.follow => (x, y),
        _ => (bx, by),
    };
    let (cx, cy) = (ox + px * xs, oy + py * ys);
    let (hx, hy) = (xs / (2.0 * zoom), ys / (2.0 * zoom));
    ([cx - hx, cx + hx], [cy - hy, cy + hy])
}

/// The pan (`MapState::pan`, not following) that shows the view shown now in `inner`: where
/// the view stays when following stops.
pub fn pan_of_view(app: &App, inner: Rect) -> (f64, f64) {
    let ((bx, by), (xs, ys)) = whole_view(app, inner);
    let ([x0, x1], [y0, y1]) = view_bounds(app, inner);
    (
        ((x0 + x1) / 2.0 - bx) / xs.max(1e-12),
        ((y0 + y1) / 2.0 - by) / ys.max(1e-12),
    )
}

/// The whole map's view in `inner` at zoom 1: its centre and its spans, metres, the arena
/// (or what there is to show) grown to square braille dots.
fn whole_view(app: &App, inner: Rect) -> ((f64, f64), (f64, f64)) {
    let [mut x0, mut y0, mut x1, mut y1] = match &app.map.arena {
        Some(a) => a.bounds,
        None => app
            .map
            .plan
            .map()
            .map_or_else(|| content_bounds(app), |m| m.bounds()),
    };
    x0 -= MARGIN_M;
    y0 -= MARGIN_M;
    x1 += MARGIN_M;
    y1 += MARGIN_M;
    let (w, h) = (
        f64::from(inner.width.max(1)),
        f64::from(inner.height.max(1)),
    );
    // A braille cell is 2 x 4 dots and about 1 x 2 in shape: world span per dot equal in x and y.
    let want = w / (2.0 * h); // x span / y span
    let (xs, ys) = (x1 - x0, y1 - y0);
    if xs / ys < want {
        let grow = (ys * want - xs) / 2.0;
        x0 -= grow;
        x1 += grow;
    } else {
        let grow = (xs / want - ys) / 2.0;
        y0 -= grow;
        y1 += grow;
    }
    (((x0 + x1) / 2.0, (y0 + y1) / 2.0), (x1 - x0, y1 - y0))
}

/// The cell at `col`, `row` of the terminal as a world point, if it is inside the map.
pub fn to_world(app: &App, inner: Rect, col: u16, row: u16) -> Option<(f64, f64)> {
    let inside = col >= inner.x
        && col < inner.x + inner.width
        && row >= inner.y
        && row < inner.y + inner.height;
    if !inside {
        return None;
    }
    let ([x0, x1], [y0, y1]) = view_bounds(app, inner);
    let fx = (f64::from(col - inner.x) + 0.5) / f64::from(inner.width);
    let fy = (f64::from(row - inner.y) + 0.5) / f64::from(inner.height);
    Some((x0 + fx * (x1 - x0), y1 - fy * (y1 - y0)))
}

/// The terminal cell (column, row) a label printed at `p` lands on, as the canvas places
/// labels.
fn label_cell(view: &MapView, (x, y): (f64, f64)) -> (i64, i64) {
    let (w, h) = (view.x[1] - view.x[0], view.y[1] - view.y[0]);
    let col = (x - view.x[0]) * f64::from(view.cols.saturating_sub(1)) / w.max(1e-12);
    let row = (view.y[1] - y) * f64::from(view.rows.saturating_sub(1)) / h.max(1e-12);
    (col.floor() as i64, row.floor() as i64)
}

fn content_bounds(app: &App) -> [f64; 4] {
    let mut pts: Vec<(f64, f64)> = app
        .believed
        .points()
        .chain(app.true_track.points())
        .copied()
        .collect();
    pts.extend(app.pose().map(|(x, y, _)| (x, y)));
    // In a fleet, the other robots too: a map without an arena shows them all.
    if let Some(f) = app.fleet.as_ref() {
        pts.extend(
            f.robots
                .iter()
                .filter_map(|r| r.pose.map(|(x, y, _)| (x, y))),
        );
    }
    pts.extend(app.map.goal);
    pts.extend(app.map.plan_target);
    if app.map.cursor_mode {
        pts.push(app.map.cursor);
    }
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for (x, y) in &pts {
        x0 = x0.min(*x);
        y0 = y0.min(*y);
        x1 = x1.max(*x);
        y1 = y1.max(*y);
    }
    if pts.is_empty() {
        (x0, y0, x1, y1) = (0.0, 0.0, 0.0, 0.0);
    }
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let half_x = ((x1 - x0) / 2.0).max(MIN_SPAN_M / 2.0);
    let half_y = ((y1 - y0) / 2.0).max(MIN_SPAN_M / 2.0);
    [cx - half_x, cy - half_y, cx + half_x, cy + half_y]
}

fn robot(ctx: &mut Context<'_>, view: &MapView, (x, y, h): (f64, f64, f64), color: Color) {
    let r = ROBOT_R.max((view.x[1] - view.x[0]) * ROBOT_FRACTION);
    ctx.draw(&Circle {
        x,
        y,
        radius: r,
        color,
    });
    ctx.draw(&Line {
        x1: x,
        y1: y,
        x2: x + 2.0 * r * h.cos(),
        y2: y + 2.0 * r * h.sin(),
        color,
    });
}

impl MapLayer for ArenaLayer {
    fn name(&self) -> &'static str {
        "arena"
    }

    fn dots(&self, app: &App) -> bool {
        app.map.arena.is_some()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        let Some(a) = &app.map.arena else { return };
        let [x0, y0, x1, y1] = a.bounds;
        let edge = |ctx: &mut Context<'_>, (ax, ay): (f64, f64), (bx, by): (f64, f64)| {
            ctx.draw(&Line {
                x1: ax,
                y1: ay,
                x2: bx,
                y2: by,
                color: Color::Gray,
            });
        };
        let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)];
        for i in 0..4 {
            edge(ctx, corners[i], corners[(i + 1) % 4]);
        }
        for wall in &a.walls {
            for (i, p) in wall.iter().enumerate() {
                if let Some(q) = wall.get((i + 1) % wall.len()) {
                    edge(ctx, *p, *q);
                }
            }
        }
        for ((x, y), r) in &a.targets {
            ctx.draw(&Circle {
                x: *x,
                y: *y,
                radius: *r,
                color: Color::Green,
            });
        }
        // The beacon usually marks the goal: when the goal's letter would cover it, it moves
        // one cell away from the goal, so both read.
        let goal = app
            .map
            .plan
            .result
            .as_ref()
            .map(|r| r.goal())
            .or_else(|| app.map.plan.map().and_then(|m| m.goal.map(|g| g.centre)));
        for (x, y) in &a.beacons {
            let covered = goal.is_some_and(|g| {
                label_cell(view, g) == label_cell(view, (*x, *y))
                    && app.map.visible(map_layers::ENDS)
            });
            // One cell towards the side the goal is not on.
            let step = (view.x[1] - view.x[0]) / f64::from(view.cols.saturating_sub(1).max(1));
            let x = match goal {
                Some((gx, _)) if covered && gx > *x => x - step,
                Some(_) if covered => x + step,
                _ => *x,
            };
            ctx.print(x, *y, "B".yellow().bold());
        }
    }
}

impl MapLayer for TruthLayer {
    fn name(&self) -> &'static str {
        "truth"
    }

    fn dots(&self, app: &App) -> bool {
        app.true_track.points().next().is_some() || app.true_pose().is_some()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        let pts: Vec<(f64, f64)> = app.true_track.points().copied().collect();
        ctx.draw(&Points {
            coords: &pts,
            color: Color::Magenta,
        });
        if let Some(p) = app.true_pose() {
            robot(ctx, view, p, Color::Magenta);
            ctx.print(p.0, p.1, "○".magenta());
        }
    }
}

impl MapLayer for BelievedLayer {
    fn name(&self) -> &'static str {
        "believed"
    }

    fn dots(&self, app: &App) -> bool {
        app.believed.points().next().is_some() || app.pose().is_some()
    }

    fn paint(&self, app: &App, view: &MapView, ctx: &mut Context<'_>) {
        let pts: Vec<(f64, f64)> = app.believed.points().copied().collect();
        // In a fleet: the selected robot in its fleet colour, its number reversed.
        let (color, glyph) = super::fleet::selected_mark(app).unwrap_or((Color::Cyan, "●".cyan()));
        ctx.draw(&Points {
            coords: &pts,
            color,
        });
        if let Some(p) = app.pose() {
            robot(ctx, view, p, color);
            ctx.print(p.0, p.1, glyph);
        }
    }
}

impl MapLayer for GoalLayer {
    fn name(&self) -> &'static str {
        "goal"
    }

    fn dots(&self, _app: &App) -> bool {
        false
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        if let Some((x, y)) = app.map.goal {
            ctx.print(x, y, "×".yellow());
        }
        // Where O and P plan to: the chosen target, else the map's goal.
        if let Some((x, y)) = app.plan_target().point() {
            ctx.print(x, y, "◎".light_red().bold());
        }
    }
}

impl MapLayer for CursorLayer {
    fn name(&self) -> &'static str {
        "cursor"
    }

    fn dots(&self, _app: &App) -> bool {
        false
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        if app.map.cursor_mode {
            let (x, y) = app.map.cursor;
            ctx.print(x, y, "+".green().bold());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::Action;
    use crate::app::AppOptions;
    use crate::link::LinkEvent;

    fn at(app: &mut App, x_mm: i32, y_mm: i32) {
        app.update(Action::Link(LinkEvent::Telemetry(protocol::Telemetry {
            pose: protocol::Pose {
                x_mm,
                y_mm,
                heading_mrad: 0,
            },
            ..protocol::Telemetry::default()
        })));
    }

    fn centre(app: &App, inner: Rect) -> (f64, f64) {
        let ([x0, x1], [y0, y1]) = view_bounds(app, inner);
        ((x0 + x1) / 2.0, (y0 + y1) / 2.0)
    }

    #[test]
    fn following_keeps_the_robot_in_the_middle_and_stopping_keeps_the_view() {
        let mut app = App::new(AppOptions::default());
        let inner = Rect::new(0, 0, 40, 20);
        at(&mut app, 500, 500);
        at(&mut app, 4000, 3000);
        app.update(Action::MapFollow {
            keep: pan_of_view(&app, inner),
        });
        assert!(app.map.follow && app.map.zoom() > 1.0);
        let c = centre(&app, inner);
        assert!(
            (c.0 - 4.0).abs() < 1e-9 && (c.1 - 3.0).abs() < 1e-9,
            "{c:?}"
        );
        at(&mut app, 4500, 2500);
        let c = centre(&app, inner);
        assert!(
            (c.0 - 4.5).abs() < 1e-9 && (c.1 - 2.5).abs() < 1e-9,
            "{c:?}"
        );
        // F again: the view stays where it is, the robot may then leave it.
        let keep = pan_of_view(&app, inner);
        app.update(Action::MapFollow { keep });
        assert!(!app.map.follow);
        let c2 = centre(&app, inner);
        assert!(
            (c2.0 - c.0).abs() < 1e-6 && (c2.1 - c.1).abs() < 1e-6,
            "{c2:?}"
        );
    }

    #[test]
    fn the_scale_bar_names_a_round_length_as_long_as_its_columns() {
        // 5 m over 40 columns: 0.125 m a column; 1 m is 8 columns.
        assert_eq!(scale_bar(5.0, 40, 80).as_deref(), Some(" ┝━━━━━━┥ 1 m "));
        // Less room: a shorter length.
        assert_eq!(scale_bar(5.0, 40, 12).as_deref(), Some(" ┝━━┥ 0.5 m "));
        // 0.4 m over 40 columns: 1 cm a column; 0.1 m is 10 columns.
        assert_eq!(
            scale_bar(0.4, 40, 80).as_deref(),
            Some(" ┝━━━━━━━━┥ 0.1 m ")
        );
        assert_eq!(scale_bar(0.0, 40, 80), None);
        assert_eq!(scale_bar(5.0, 40, 5), None);
    }
}
