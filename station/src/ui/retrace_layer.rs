//! The retraced track over the replay's map (`station replay --retrace`): yellow, up to the
//! replay's robot time, beside the recorded believed track (cyan) and the truth (magenta).

use ratatui::style::{Color, Stylize as _};
use ratatui::widgets::canvas::{Context, Points};

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// The retraced robot's believed track.
pub struct RetraceLayer;

impl MapLayer for RetraceLayer {
    fn name(&self) -> &'static str {
        "retrace"
    }

    fn dots(&self, app: &App) -> bool {
        app.retrace.as_ref().is_some_and(|r| !r.track.is_empty())
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(r) = &app.retrace else { return };
        let now = app.telemetry.as_ref().map_or(0, |t| t.time_ms);
        let pts: Vec<(f64, f64)> = r
            .track
            .iter()
            .take_while(|(t, _, _)| *t <= now)
            .map(|&(_, x, y)| (x, y))
            .collect();
        ctx.draw(&Points {
            coords: &pts,
            color: Color::Yellow,
        });
        if let Some(&(x, y)) = pts.last() {
            ctx.print(x, y, "◇".yellow());
        }
    }
}
