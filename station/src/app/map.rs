//! The map view's state: the arena shown, the cursor and goal, the layers, zoom and pan.

use super::arena::ArenaOverlay;

/// The map's interactive state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapState {
    pub arena: Option<ArenaOverlay>,
    /// The go-to cursor, metres; shown while `cursor_mode`.
    pub cursor: (f64, f64),
    pub cursor_mode: bool,
    /// The last go-to goal sent (drawn `×`; `Esc` clears it).
    pub goal: Option<(f64, f64)>,
    /// The target the operator chose for plans (`O`/`P` with the cursor shown); `None`: the
    /// map's goal (`app::plan_target`).
    pub plan_target: Option<(f64, f64)>,
    /// Names of hidden layers.
    pub hidden: Vec<&'static str>,
    /// Planning on the station: the map's grid and regions, the last plan.
    pub plan: crate::plan::PlanState,
    /// The view follows the robot (`F`): its centre is the robot, `pan` an offset from it.
    pub follow: bool,
    /// See `zoom()`; 0 (the default) is 1.
    pub(super) zoom: f64,
    /// See `pan()`.
    pub(super) pan: (f64, f64),
}

impl MapState {
    pub fn visible(&self, layer: &str) -> bool {
        !self.hidden.contains(&layer)
    }

    /// Magnification over the whole arena (1: all of it).
    pub fn zoom(&self) -> f64 {
        self.zoom.clamp(1.0, MAX_ZOOM)
    }

    /// The view's centre, as fractions of the whole arena's span from its centre.
    pub fn pan(&self) -> (f64, f64) {
        self.pan
    }

    /// Zooms by `factor` keeping the point `at` where it is on screen (`at`: fractions of the
    /// shown span from the view's centre, x right, y up; (0, 0) zooms about the centre).
    /// Zooming out to the whole arena recentres it.
    pub fn zoom_by(&mut self, factor: f64, at: (f64, f64)) {
        let z = self.zoom();
        let z2 = (z * factor).clamp(1.0, MAX_ZOOM);
        if !z2.is_finite() || z2 <= 1.0 {
            self.zoom = 1.0;
            self.pan = (0.0, 0.0);
            return;
        }
        // The point under `at` is centre + at / z (arena spans); it stays put at zoom z2.
        let k = 1.0 / z - 1.0 / z2;
        self.zoom = z2;
        self.set_pan(self.pan.0 + at.0 * k, self.pan.1 + at.1 * k);
    }

    /// Moves the view by `dx`, `dy` steps of a quarter of what is shown (x right, y up).
    pub fn pan_by(&mut self, dx: i8, dy: i8) {
        let step = PAN_STEP / self.zoom();
        self.set_pan(
            self.pan.0 + f64::from(dx) * step,
            self.pan.1 + f64::from(dy) * step,
        );
    }

    /// Starts following the robot (zoomed in at least to `FOLLOW_ZOOM`: at the whole arena
    /// there is nothing to recentre), or stops, leaving the view at `keep` (the pan that shows
    /// what is shown now), so that it does not jump.
    pub fn toggle_follow(&mut self, keep: (f64, f64)) {
        if self.follow {
            self.follow = false;
            self.set_pan(keep.0, keep.1);
        } else {
            self.follow = true;
            self.pan = (0.0, 0.0);
            self.zoom = self.zoom().max(FOLLOW_ZOOM);
        }
    }

    fn set_pan(&mut self, x: f64, y: f64) {
        // The centre stays over the arena: the view never wanders off into nothing.
        self.pan = (x.clamp(-0.5, 0.5), y.clamp(-0.5, 0.5));
    }
}

/// Largest map magnification.
pub const MAX_ZOOM: f64 = 64.0;
/// One pan step, as a fraction of the shown span.
pub const PAN_STEP: f64 = 0.25;
/// One zoom step (a key press or a wheel notch).
pub const ZOOM_STEP: f64 = 1.5;
/// The least magnification while following the robot: two zoom steps.
pub const FOLLOW_ZOOM: f64 = ZOOM_STEP * ZOOM_STEP;
