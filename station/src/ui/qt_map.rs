//! The QT world model on the map (`qt` layer): edges shaded by confidence (dark grey for
//! nearly forgotten, white for just confirmed), cells as green dots, the winner (the cell the
//! robot is at) yellow, the model's corrected robot position as a cyan cross. Paints nothing
//! until the model has cells (`app.qt`), so other robots' screens do not change. Cannot fail.

use ratatui::style::Color;
use ratatui::widgets::canvas::{Context, Line, Points};

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// Layer name (key in `input.rs` and the help).
pub const QT: &str = "qt";
/// Cells.
pub const CELL: Color = Color::Green;
/// The winner.
pub const WINNER: Color = Color::Yellow;
/// The model's corrected robot position.
pub const ROBOT: Color = Color::Cyan;

/// The grey for an edge of confidence `c` (0..1): xterm's grey ramp 236 (dark) .. 255.
pub fn edge_color(c: f64) -> Color {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    Color::Indexed(236 + (c * 19.0).round() as u8)
}

/// The legend's item: the model's cell count, while the layer is shown and has cells (the
/// cells' dots alone do not say how many there are).
pub fn legend(app: &App) -> Option<ratatui::text::Span<'static>> {
    use ratatui::style::Stylize;
    let model = app.qt.model.as_ref().filter(|_| app.qt.active())?;
    if !app.map.visible(QT) {
        return None;
    }
    Some(format!("• {} QT cells ", model.network().len()).green())
}

/// The QT network.
pub struct QtLayer;

impl MapLayer for QtLayer {
    fn name(&self) -> &'static str {
        QT
    }

    fn dots(&self, app: &App) -> bool {
        app.qt.active()
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(model) = app.qt.model.as_ref() else {
            return;
        };
        let net = model.network();
        for (a, b, conf) in net.edges() {
            let (pa, pb) = (net.position(a), net.position(b));
            ctx.draw(&Line::new(pa.0, pa.1, pb.0, pb.1, edge_color(conf)));
        }
        let cells: Vec<(f64, f64)> = net.cells().map(|(id, _)| net.position(id)).collect();
        ctx.draw(&Points {
            coords: &cells,
            color: CELL,
        });
        if let Some(w) = model.winner().filter(|w| net.cell(*w).is_some()) {
            ctx.draw(&Points {
                coords: &[net.position(w)],
                color: WINNER,
            });
        }
        let p = model.pose();
        let r = 0.05;
        ctx.draw(&Line::new(p.x - r, p.y, p.x + r, p.y, ROBOT));
        ctx.draw(&Line::new(p.x, p.y - r, p.x, p.y + r, ROBOT));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::app::{App, AppOptions};
    use ratatui::buffer::Buffer;
    use ratatui::layout::Rect;
    use ratatui::widgets::canvas::Canvas;
    use ratatui::widgets::Widget;
    use world_model::{Params, Pose, Sample};

    /// The layer is silent until situations arrive; then it draws the network: cells, the
    /// winner, grey edges.
    #[test]
    fn the_layer_draws_the_fed_network() {
        let mut app = App::new(AppOptions::default());
        assert!(!QtLayer.dots(&app));
        let params = Params::default();
        let mut light = vec![0.1; 24];
        light[3] = 0.9;
        let touch = vec![false; 24];
        for i in 0..40 {
            let odometry = Pose {
                x: 0.5 + 0.05 * f64::from(i),
                y: 0.5,
                heading: 0.0,
            };
            let s = Sample {
                light: &light,
                touch: &touch,
                odometry,
            };
            app.qt.feed(&params, &s).expect("valid situation");
        }
        assert!(QtLayer.dots(&app));
        let net = app.qt.model.as_ref().expect("model").network();
        assert!(
            net.len() >= 2 && net.edges().count() >= 1,
            "{} cells",
            net.len()
        );
        let area = Rect::new(0, 0, 40, 12);
        let mut buf = Buffer::empty(area);
        let view = MapView {
            x: [0.0, 3.0],
            y: [0.0, 1.0],
            cols: 40,
            rows: 12,
        };
        Canvas::default()
            .x_bounds(view.x)
            .y_bounds(view.y)
            .paint(|ctx| QtLayer.paint(&app, &view, ctx))
            .render(area, &mut buf);
        let fg: Vec<Color> = buf
            .content()
            .iter()
            .filter(|c| c.symbol() != " ")
            .map(|c| c.fg)
            .collect();
        assert!(fg.contains(&CELL) || fg.contains(&WINNER), "{fg:?}");
        assert!(
            fg.iter().any(|c| matches!(c, Color::Indexed(236..=255))),
            "{fg:?}"
        );
        // A malformed situation is refused with its reason, and counted.
        let short = Sample {
            light: &light[..3],
            touch: &touch,
            odometry: Pose::default(),
        };
        assert!(app.qt.feed(&params, &short).is_err());
        assert_eq!(app.qt.refused, 1);
    }

    #[test]
    fn confidence_shades_from_dark_to_white() {
        assert_eq!(edge_color(0.0), Color::Indexed(236));
        assert_eq!(edge_color(1.0), Color::Indexed(255));
        assert_eq!(edge_color(f64::NAN), Color::Indexed(236));
        assert_eq!(edge_color(7.0), Color::Indexed(255));
    }
}
