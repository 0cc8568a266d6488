//! The simulated world: an arena's walls plus what the robot's sensors can see in it.
//!
//! Layer: std, under the physics and the sensor models, above the arena importers and the
//! geometry. A [`World`] holds the [`Arena`] it was built from, its walls as a [`SegmentSet`]
//! (built once), the beacon (the arena's first; seen over walls lower than itself), the
//! target area (a floor circle the micro-rato's ground sensor sees), the light sources (the
//! arena's plus any the run adds) and an optional floor grid of black lines (seed 003 §2.6.4).
//!
//! Invariants: a `World` is immutable once built, so sensor reads and physics steps never
//! change it; every light has a finite position and a finite, non-negative intensity; a floor
//! grid's lines are thinner than its pitch. What can fail: [`World::new`] with a bad light or
//! grid ([`WorldError`]). Queries never fail; non-finite points answer "not over a line", "not
//! in the target", "blocked".

use thiserror::Error;

use crate::arena::{Arena, Light, Target};
use crate::geometry::{Point, SegmentSet};

/// Floor grid pitch of seed 003 §2.6.4: black lines forming 10 cm squares.
pub const GRID_PITCH_M: f64 = 0.10;
/// Width of a floor grid line. seed 003 gives none; about 1 cm is a strip of black tape.
pub const GRID_LINE_WIDTH_M: f64 = 0.01;

/// What is wrong with a world description.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum WorldError {
    /// A light source with a non-finite position or height, or a negative/non-finite intensity.
    #[error("light {index}: {reason}")]
    BadLight {
        /// Index into the run's light list (the arena's lights first).
        index: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A floor grid whose pitch is not a finite length above its line width.
    #[error(
        "floor grid pitch {pitch_m} m must be finite and larger than its {line_width_m} m lines"
    )]
    BadGrid {
        /// The pitch asked for.
        pitch_m: f64,
        /// The line width asked for.
        line_width_m: f64,
    },
}

/// Black floor lines along x = k * pitch and y = k * pitch (seed 003 §2.6.4), relative to the
/// arena's lower-left corner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorGrid {
    /// Distance between parallel lines, metres.
    pub pitch_m: f64,
    /// Width of each line, metres.
    pub line_width_m: f64,
    /// Where lines cross: the grid's origin, metres.
    pub origin: Point,
}

impl FloorGrid {
    /// A grid with `pitch_m` squares and the default 1 cm lines, from `origin`.
    pub fn new(pitch_m: f64, origin: Point) -> Result<FloorGrid, WorldError> {
        Self::with_width(pitch_m, GRID_LINE_WIDTH_M, origin)
    }

    /// A grid with explicit line width.
    pub fn with_width(
        pitch_m: f64,
        line_width_m: f64,
        origin: Point,
    ) -> Result<FloorGrid, WorldError> {
        let ok = pitch_m.is_finite()
            && line_width_m.is_finite()
            && line_width_m > 0.0
            && pitch_m > line_width_m
            && origin.x.is_finite()
            && origin.y.is_finite();
        if !ok {
            return Err(WorldError::BadGrid {
                pitch_m,
                line_width_m,
            });
        }
        Ok(FloorGrid {
            pitch_m,
            line_width_m,
            origin,
        })
    }

    /// True when `p` is on a line (either direction; the sensor cannot tell them apart,
    /// seed 003 §2.2.3).
    pub fn on_line(&self, p: Point) -> bool {
        let half = self.line_width_m / 2.0;
        let near = |v: f64| {
            let m = v.rem_euclid(self.pitch_m);
            m <= half || self.pitch_m - m <= half
        };
        // rem_euclid of NaN is NaN and every comparison with it is false: not on a line.
        near(p.x - self.origin.x) || near(p.y - self.origin.y)
    }
}

/// The beacon as the world sees it: where, how high, and the walls tall enough to hide it.
#[derive(Clone, Debug)]
pub struct WorldBeacon {
    /// Position, metres.
    pub position: Point,
    /// Height above the floor, metres.
    pub height_m: f64,
    blockers: SegmentSet,
}

impl WorldBeacon {
    /// True when no wall taller than the beacon crosses the line from `from` to the beacon.
    pub fn visible_from(&self, from: Point) -> bool {
        from.x.is_finite() && from.y.is_finite() && !self.blockers.blocks(from, self.position)
    }
}

/// An arena with its walls indexed, plus beacons, targets, lights and floor grid.
#[derive(Clone, Debug)]
pub struct World {
    arena: Arena,
    walls: SegmentSet,
    beacons: Vec<WorldBeacon>,
    lights: Vec<Light>,
    floor: Option<FloorGrid>,
}

impl World {
    /// Builds the world: the arena's lights come first, then `extra_lights`.
    pub fn new(
        arena: Arena,
        extra_lights: Vec<Light>,
        floor: Option<FloorGrid>,
    ) -> Result<World, WorldError> {
        let mut lights = arena.lights.clone();
        lights.extend(extra_lights);
        for (index, l) in lights.iter().enumerate() {
            if !(l.position.x.is_finite() && l.position.y.is_finite() && l.height_m.is_finite()) {
                return Err(WorldError::BadLight {
                    index,
                    reason: "position and height must be finite",
                });
            }
            if !(l.intensity.is_finite() && l.intensity >= 0.0) {
                return Err(WorldError::BadLight {
                    index,
                    reason: "intensity must be finite and >= 0",
                });
            }
        }
        let beacons = arena
            .beacons
            .iter()
            .map(|b| WorldBeacon {
                position: b.position,
                height_m: b.height_m,
                // CiberRato: walls lower than the beacon do not hide it.
                blockers: arena.segment_set_hiding(b.height_m),
            })
            .collect();
        Ok(World {
            walls: arena.segment_set(),
            arena,
            beacons,
            lights,
            floor,
        })
    }

    /// The arena this world was built from.
    pub fn arena(&self) -> &Arena {
        &self.arena
    }

    /// Every wall edge (and the boundary of an enclosed arena).
    pub fn walls(&self) -> &SegmentSet {
        &self.walls
    }

    /// The first beacon, if the arena has one (what the firmware is told it seeks).
    pub fn beacon(&self) -> Option<&WorldBeacon> {
        self.beacons.first()
    }

    /// Every beacon, in the file's order (CiberRato labs may have several).
    pub fn beacons(&self) -> &[WorldBeacon] {
        &self.beacons
    }

    /// The first target area, if any.
    pub fn target(&self) -> Option<Target> {
        self.arena.target().copied()
    }

    /// The target areas a beacon search may end in ([`Arena::goal_targets`]).
    pub fn goal_targets(&self) -> impl Iterator<Item = &Target> + '_ {
        self.arena.goal_targets()
    }

    /// True when `p` is inside a goal target circle (edge included): what the ground sensor
    /// sees and where a beacon search is judged to have arrived.
    pub fn in_target(&self, p: Point) -> bool {
        self.goal_targets()
            .any(|t| (p - t.centre).norm() <= t.radius_m)
    }

    /// Light sources.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The floor grid, if there is one.
    pub fn floor(&self) -> Option<&FloorGrid> {
        self.floor.as_ref()
    }

    /// True when `p` is over a floor line.
    pub fn on_line(&self, p: Point) -> bool {
        self.floor.as_ref().is_some_and(|g| g.on_line(p))
    }

    /// True when a disc of `radius` at `p` is outside every wall and overlaps none (touching
    /// is allowed: a robot may start against a wall).
    pub fn is_free(&self, p: Point, radius: f64) -> bool {
        if !(p.x.is_finite() && p.y.is_finite()) || self.arena.is_solid(p) {
            return false;
        }
        self.walls
            .nearest(p, radius)
            .is_none_or(|n| n.distance >= radius)
    }

    /// A free spot for a robot of `radius`: the first point, scanning rows upwards from the
    /// lower-left corner in steps of the radius, that keeps half a radius of clearance and is
    /// outside the target area (inside it only if nothing else is free). Deterministic.
    pub fn free_spot(&self, radius: f64) -> Option<Point> {
        self.free_spot_where(radius, |_| true)
    }

    /// [`World::free_spot`] among the points `accept` takes.
    pub fn free_spot_where(&self, radius: f64, accept: impl Fn(Point) -> bool) -> Option<Point> {
        if !(radius.is_finite() && radius > 0.0) {
            return None;
        }
        let b = self.arena.bounds;
        let margin = radius * 1.5;
        let step = radius;
        let nx = ((b.width() - 2.0 * margin) / step).floor().max(0.0) as usize + 1;
        let ny = ((b.height() - 2.0 * margin) / step).floor().max(0.0) as usize + 1;
        // Bounded: an absurdly fine scan would take forever; 4 million candidates is plenty.
        if nx.saturating_mul(ny) > 4_000_000 {
            return None;
        }
        let mut fallback = None;
        for j in 0..ny {
            for i in 0..nx {
                let p = Point::new(
                    b.min.x + margin + i as f64 * step,
                    b.min.y + margin + j as f64 * step,
                );
                if !self.is_free(p, margin) || !accept(p) {
                    continue;
                }
                if !self.in_target(p) {
                    return Some(p);
                }
                fallback = fallback.or(Some(p));
            }
        }
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_lines_are_seen_on_both_axes_and_between_them_is_floor() {
        let g = FloorGrid::new(GRID_PITCH_M, Point::new(0.0, 0.0)).expect("valid grid");
        assert!(g.on_line(Point::new(0.1, 0.05)));
        assert!(g.on_line(Point::new(0.0449, 0.3041)));
        assert!(g.on_line(Point::new(-0.2, 0.05)));
        assert!(!g.on_line(Point::new(0.05, 0.05)));
        assert!(!g.on_line(Point::new(0.106, 0.094)));
        assert!(!g.on_line(Point::new(f64::NAN, 0.05)));
        assert!(FloorGrid::new(0.005, Point::new(0.0, 0.0)).is_err());
        assert!(FloorGrid::new(f64::INFINITY, Point::new(0.0, 0.0)).is_err());
    }
}
