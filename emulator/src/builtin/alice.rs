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
    let mut a = crate::arena::walled_box(
        "ALICE test scene (Zimmer §4.5)",
        BUILTIN_ALICE,
        SIDE_M,
        SIDE_M,
    );
    a.walls = vec![pillar];
    // Spots at the border, of different strengths, 1 m high (the thesis: "two respectively
    // three light sources are mounted at the border").
    a.lights = lamps([(0.15, 2.85, 1.0), (2.85, 2.0, 0.8), (1.0, 0.15, 0.6)]);
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

/// The ALICE arena `name` names (`builtin:alice`, `builtin:alice-navigation`), for
/// `builtin::load`; None for any other name.
pub fn builtin(name: &str) -> Option<Arena> {
    let name = Path::new(name);
    if name == Path::new(BUILTIN_ALICE) {
        Some(alice())
    } else if name == Path::new(BUILTIN_ALICE_NAVIGATION) {
        Some(navigation_scene())
    } else {
        None
    }
}

/// The §5.3 navigation scene, drawn from the thesis's description (its figure 15 is not in
/// the text we have; every measure here is ours): "On the upper left, an asymmetrical narrow
/// corridor prevents any success of straight or imprecise manoeuvres ... On the lower left
/// ... a narrowing corridor ... The right wall is rough ... All other outer borders are
/// straight and smooth. The obstacles on the right are of different sizes and equipped with
/// rough border lines ... One of the three light sources illuminates the whole scene, whereas
/// the others produce sharp shadows in some areas, for example at the asymmetrical corridor.
/// The test-path ... starts between the obstacles on the right via the open space area
/// through the corridor at the upper left and returns to the starting point."
///
/// Ours: 4 x 3 m. The upper-left corridor runs along the top wall from x 2.3 to 1.3 m, its
/// lower side a wall rising from y 2.25 to 2.32 m (0.68-0.75 m wide for the 40 cm body), into
/// a pocket (x 0-1.3, y 1.6-3 m) that only the corridor reaches: the test path's far end is
/// there ([`CORRIDOR_TARGET`]). The lower-left corridor narrows from 0.95 to 0.6 m between
/// the floor wall and an inclined wall. The right wall is a zigzag of 6 cm in 15 cm; three
/// obstacles of 0.1-0.25 m radius have jagged outlines; the start is between them. Lamps: a
/// strong one low on the bottom wall (the open space), one in the pocket's corner shining
/// along the corridor, one in the upper right behind the obstacles.
pub fn navigation_scene() -> Arena {
    let mut a = crate::arena::walled_box(
        "ALICE navigation scene (Zimmer §5.3)",
        BUILTIN_ALICE_NAVIGATION,
        NAV_SCENE_M.0,
        NAV_SCENE_M.1,
    );
    let (w, h) = NAV_SCENE_M;
    let mut walls = vec![
        // The corridor's lower side, then the pocket's right side and floor.
        thick(Point::new(1.3, 2.25), Point::new(2.3, 2.32)),
        thick(Point::new(1.3, 1.6), Point::new(1.3, 2.25)),
        thick(Point::new(0.0, 1.6), Point::new(1.3, 1.6)),
        // The lower-left narrowing corridor's inclined side.
        thick(Point::new(0.5, 0.95), Point::new(1.7, 0.6)),
    ];
    // The rough right wall: a zigzag 6 cm deep in 15 cm steps along the east border.
    let mut rough = vec![Point::new(w, 0.0), Point::new(w, h)];
    let teeth = (h / 0.15).round() as usize;
    for i in 0..=teeth {
        let y = h - i as f64 * h / teeth as f64;
        let x = if i % 2 == 0 { w - 0.04 } else { w - 0.10 };
        rough.push(Point::new(x, y));
    }
    walls.push(Wall {
        corners: rough,
        height_m: None,
    });
    for (cx, cy, r, n) in [
        (3.2, 2.35, 0.25, 10),
        (3.2, 0.6, 0.18, 9),
        (2.6, 1.5, 0.1, 7),
    ] {
        walls.push(Wall {
            corners: (0..n)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / n as f64;
                    // Jagged: every other corner 25 % further in.
                    let r = if i % 2 == 0 { r } else { 0.75 * r };
                    Point::new(cx + r * a.cos(), cy + r * a.sin())
                })
                .collect(),
            height_m: None,
        });
    }
    a.walls = walls;
    a.lights = lamps([(2.2, 0.1, 1.0), (0.1, 2.9, 0.6), (3.85, 2.9, 0.7)]);
    a.starts = vec![Pose {
        x: 3.4,
        y: 1.5,
        heading: std::f64::consts::PI,
    }];
    a
}

/// Name of the §5.3 scene (`navigation_scene`).
pub const BUILTIN_ALICE_NAVIGATION: &str = "builtin:alice-navigation";
/// Its size, metres.
pub const NAV_SCENE_M: (f64, f64) = (4.0, 3.0);
/// The far end of its test path: the pocket beyond the upper-left corridor (truth: the
/// experimenter's choice of the path, never the robot's).
pub const CORRIDOR_TARGET: (f64, f64) = (0.65, 2.3);

/// Spots 1 m high at (x, y) with their relative intensities.
fn lamps<const N: usize>(at: [(f64, f64, f64); N]) -> Vec<Light> {
    at.into_iter()
        .map(|(x, y, i)| Light {
            position: Point::new(x, y),
            height_m: 1.0,
            intensity: i,
        })
        .collect()
}

/// A wall 4 cm thick along `a`-`b`.
fn thick(a: Point, b: Point) -> Wall {
    let d = b - a;
    let n = d.norm().max(1e-9);
    let off = crate::geometry::Vector::new(-d.y / n, d.x / n) * 0.02;
    Wall {
        corners: vec![a + off, b + off, b - off, a - off],
        height_m: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::alice::BODY_RADIUS_M;

    /// Grid cells (5 cm) where the 40 cm body fits, reachable from the start.
    fn reachable(a: &Arena) -> Vec<Point> {
        let walls = a.segment_set();
        let pitch = 0.05;
        let (nx, ny) = (
            (NAV_SCENE_M.0 / pitch) as i64,
            (NAV_SCENE_M.1 / pitch) as i64,
        );
        let at = |i: i64, j: i64| Point::new((i as f64 + 0.5) * pitch, (j as f64 + 0.5) * pitch);
        let fits = |p: Point| !a.is_solid(p) && !walls.circle_collides(p, BODY_RADIUS_M);
        let s = a.starts[0];
        let first = ((s.x / pitch) as i64, (s.y / pitch) as i64);
        assert!(fits(at(first.0, first.1)), "the start is free");
        let mut seen = std::collections::HashSet::from([first]);
        let mut todo = vec![first];
        while let Some((i, j)) = todo.pop() {
            for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let n = (i + di, j + dj);
                if (0..nx).contains(&n.0)
                    && (0..ny).contains(&n.1)
                    && !seen.contains(&n)
                    && fits(at(n.0, n.1))
                {
                    seen.insert(n);
                    todo.push(n);
                }
            }
        }
        seen.into_iter().map(|(i, j)| at(i, j)).collect()
    }

    /// The §5.3 scene's test path is there: the body can drive from the start into the pocket
    /// beyond the upper-left corridor, and only through the corridor (a wall across it cuts
    /// the pocket off).
    #[test]
    fn the_pocket_is_reached_through_the_corridor_only() {
        let near_target = |ps: &[Point]| {
            ps.iter()
                .any(|p| (p.x - CORRIDOR_TARGET.0).hypot(p.y - CORRIDOR_TARGET.1) < 0.1)
        };
        let scene = navigation_scene();
        assert!(
            near_target(&reachable(&scene)),
            "the pocket is out of reach"
        );
        let mut closed = scene.clone();
        closed
            .walls
            .push(thick(Point::new(1.8, 2.2), Point::new(1.8, NAV_SCENE_M.1)));
        assert!(!near_target(&reachable(&closed)), "a second way in");
        // The body fits in the corridor's middle, not 30 cm lower (its lower side).
        let walls = scene.segment_set();
        let mut p = Point::new(1.8, 2.6);
        assert!(!walls.circle_collides(p, BODY_RADIUS_M));
        p.y = 2.3;
        assert!(
            walls.circle_collides(p, BODY_RADIUS_M),
            "room below the corridor"
        );
    }
}
