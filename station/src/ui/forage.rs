//! Foraging on the map (seed 000 §7): lamps, the objects under them (dimmed once taken), the
//! home base, the three landmarks, and a status for the map's title: what the gripper holds
//! and how many objects are home.
//!
//! Layer: presentation, a [`MapLayer`] over `app.map.arena` (lamps, `forage` site) and
//! `app.forage` (progress from the robot's events). Paints nothing for an arena without lamps
//! or a foraging site. Cannot fail.

use ratatui::style::{Color, Stylize};
use ratatui::text::{Line as TLine, Span};
use ratatui::widgets::canvas::{Circle, Context};

use super::layer::{MapLayer, MapView};
use crate::app::App;

/// Layer name (hidden like the others).
pub const FORAGE: &str = "forage";

/// Lamps, objects, home base, landmarks.
pub struct ForageLayer;

impl MapLayer for ForageLayer {
    fn name(&self) -> &'static str {
        FORAGE
    }

    fn dots(&self, app: &App) -> bool {
        app.map.arena.as_ref().is_some_and(|a| a.forage.is_some())
    }

    fn paint(&self, app: &App, _view: &MapView, ctx: &mut Context<'_>) {
        let Some(a) = &app.map.arena else { return };
        if let Some(site) = &a.forage {
            let ((hx, hy), r) = site.home;
            ctx.draw(&Circle {
                x: hx,
                y: hy,
                radius: r,
                color: Color::LightGreen,
            });
            ctx.print(hx, hy, "H".light_green().bold());
            for (i, (x, y)) in site.landmarks.iter().enumerate() {
                ctx.print(*x, *y, format!("L{}", i + 1).light_blue());
            }
        }
        for (x, y) in &a.lights {
            ctx.print(*x, *y, "*".light_yellow().bold());
        }
        if let Some(site) = &a.forage {
            for (i, (x, y)) in site.objects.iter().enumerate() {
                // Drawn beside the lamp (both cannot share a cell at this scale).
                let mark = if app.forage.is_taken(i) {
                    "o".dark_gray()
                } else {
                    "o".white().bold()
                };
                ctx.print(*x + 0.03, *y - 0.03, mark);
            }
        }
    }
}

/// The map title's status while foraging: gripper and objects home.
pub fn status(app: &App) -> Option<TLine<'static>> {
    let site = app.map.arena.as_ref()?.forage.as_ref()?;
    let f = &app.forage;
    let grip = if f.carrying {
        Span::from(" gripper: carrying ").light_yellow()
    } else {
        Span::from(" gripper: empty ").dark_gray()
    };
    Some(TLine::from(vec![
        grip,
        Span::from(format!("· home {}/{} ", f.delivered, site.objects.len())).light_green(),
    ]))
}
