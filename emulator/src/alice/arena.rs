//! The thesis's test scene (seed 001 §4.5): about 3 x 3 m, straight 1 m wall segments, a round
//! pillar 45 cm across slightly off centre, three lamps at the border (the fourth source,
//! sunlight, is left out: it changes with the time of day, which the scenarios do not model).
//! `builtin:alice` is this arena; the dynamic experiment adds [`gap_wall`] below the pillar.

use std::path::Path;

use crate::arena::{Arena, Light, Pose, Wall};
use crate::geometry::{Aabb, Point};

/// Name of the built-in ALICE arena.
pub const BUILTIN_ALICE: &str = "builtin:alice";
/// Side of the square arena, metres (§4.5: "approximately three times three metres").
pub const SIDE_M: f64 = 3.0;
/// Pillar centre, metres: slightly off the arena's centre (§4.5 "slightly asymmetrical").
pub const PILLAR_CENTRE: (f64, f64) = (1.65, 1.4);
/// Pillar radius, metres (45 cm diameter).
pub const PILLAR_RADIUS_M: f64 = 0.225;
/// Corners of the polygon standing for the round pillar.
const PILLAR_SIDES: usize = 16;

/// The arena: walls of 1 m segments around a 3 x 3 m floor (each side is three collinear
/// segments, which for a ray or a whisker is one straight wall), the pillar, three lamps.
pub fn alice() -> Arena {
    let (cx, cy) = PILLAR_CENTRE;
    // The circumscribed polygon, so the solid is at least the 45 cm disc.
    let r = PILLAR_RADIUS_M / (std::f64::consts::PI / PILLAR_SIDES as f64).cos();
    let pillar = Wall {
        corners: (0..PILLAR_SIDES)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / PILLAR_SIDES as f64;
                Point::new(cx + r * a.cos(), cy + r * a.sin())
            })
            .collect(),
        height_m: None,
    };
    let mut a =
        crate::builtin::walled_box("ALICE test scene (seed 001)", BUILTIN_ALICE, SIDE_M, SIDE_M);
    a.walls = vec![pillar];
    // Spots at the border, of different strengths, 1 m high (the thesis: "two respectively
    // three light sources are mounted at the border").
    a.lights = [(0.15, 2.85, 1.0), (2.85, 2.0, 0.8), (1.0, 0.15, 0.6)]
        .into_iter()
        .map(|(x, y, i)| Light {
            position: Point::new(x, y),
            height_m: 1.0,
            intensity: i,
        })
        .collect();
    a.starts = vec![Pose {
        x: 0.6,
        y: 0.6,
        heading: 0.5,
    }];
    a
}

/// The wall of the dynamic experiment (§4.5.4): it cuts the circle around the pillar at the
/// lower end, from the pillar down to the lower border, 4 cm thick.
pub fn gap_wall() -> Wall {
    let (cx, cy) = PILLAR_CENTRE;
    Wall::rectangle(
        Aabb::from_corners(
            Point::new(cx - 0.02, 0.0),
            Point::new(cx + 0.02, cy - PILLAR_RADIUS_M + 0.01),
        ),
        None,
    )
}

/// The same name resolves in `builtin::load`.
pub fn is_builtin(name: &str) -> bool {
    Path::new(name) == Path::new(BUILTIN_ALICE)
}
