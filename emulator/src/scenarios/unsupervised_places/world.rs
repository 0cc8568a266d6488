//! The scenario's world: a generated arena of walls, obstacles and lamps, and the line camera
//! that sees it (64 pixels over 36 degrees; its features as §3.3.2).

use super::{ArenaKind, ARENA_DIAMETERS, CAMERA_FOV_DEG, CAMERA_PIXELS, DIAMETER_M};
use crate::arena::{Light, Pose};
use crate::geometry::{point_in_polygon, polygon_edges, Point, Segment, SegmentSet, Vector};
use crate::rng::SimRng;

/// A generated arena.
#[derive(Clone, Debug)]
pub struct World {
    /// Walls.
    pub walls: SegmentSet,
    /// Reflectance of each wall segment (camera), 0..1.
    pub reflectance: Vec<f64>,
    /// Lamps.
    pub lights: Vec<Light>,
    /// Obstacle outlines (for tests and views).
    pub obstacles: Vec<Vec<Point>>,
    /// Outer boundary.
    pub boundary: Vec<Point>,
    /// Start pose.
    pub start: Pose,
}

/// Generate the `kind` arena of `seed` (side `ARENA_DIAMETERS` diameters).
pub fn generate(kind: ArenaKind, seed: u64, lamps: usize) -> World {
    let mut rng = SimRng::new(seed, 101);
    let side = ARENA_DIAMETERS * DIAMETER_M;
    let boundary: Vec<Point> = match kind {
        ArenaKind::Structured => vec![
            Point::new(0.0, 0.0),
            Point::new(side, 0.0),
            Point::new(side, side),
            Point::new(0.0, side),
        ],
        ArenaKind::Unstructured => {
            // Six points a side, each pushed inwards by up to 1.2 diameters.
            let mut b = Vec::new();
            let corners = [(0.0, 0.0), (side, 0.0), (side, side), (0.0, side)];
            let inward = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0)];
            for k in 0..4 {
                let (a, c) = (corners[k], corners[(k + 1) % 4]);
                for i in 0..6 {
                    let t = i as f64 / 6.0;
                    let push = if i == 0 {
                        0.0
                    } else {
                        rng.uniform() * 1.2 * DIAMETER_M
                    };
                    b.push(Point::new(
                        a.0 + (c.0 - a.0) * t + inward[k].0 * push,
                        a.1 + (c.1 - a.1) * t + inward[k].1 * push,
                    ));
                }
            }
            b
        }
    };
    let mut obstacles: Vec<Vec<Point>> = Vec::new();
    let mut centres: Vec<(Point, f64)> = Vec::new();
    let gap = 1.6 * DIAMETER_M; // a passage the robot fits through
    let mut tries = 0;
    while obstacles.len() < 7 && tries < 500 {
        tries += 1;
        let r = 0.03 + rng.uniform() * 0.04;
        let margin = r + gap + 1.2 * DIAMETER_M;
        let c = Point::new(
            margin + rng.uniform() * (side - 2.0 * margin),
            margin + rng.uniform() * (side - 2.0 * margin),
        );
        if centres.iter().any(|(o, ro)| (o - c).norm() < r + ro + gap) {
            continue;
        }
        let poly: Vec<Point> = match kind {
            ArenaKind::Structured => {
                let (w, h) = (
                    r * (0.6 + rng.uniform() * 0.4),
                    r * (0.6 + rng.uniform() * 0.4),
                );
                vec![
                    Point::new(c.x - w, c.y - h),
                    Point::new(c.x + w, c.y - h),
                    Point::new(c.x + w, c.y + h),
                    Point::new(c.x - w, c.y + h),
                ]
            }
            ArenaKind::Unstructured => {
                let n = 3 + (rng.next_u64() % 4) as usize;
                let phase = rng.uniform() * std::f64::consts::TAU;
                (0..n)
                    .map(|i| {
                        let a = phase
                            + std::f64::consts::TAU * (i as f64 + 0.3 * rng.uniform()) / n as f64;
                        let rr = r * (0.6 + 0.4 * rng.uniform());
                        Point::new(c.x + rr * a.cos(), c.y + rr * a.sin())
                    })
                    .collect()
            }
        };
        centres.push((c, r));
        obstacles.push(poly);
    }
    let mut segments: Vec<Segment> = polygon_edges(&boundary).collect();
    for o in &obstacles {
        segments.extend(polygon_edges(o));
    }
    let reflectance = segments
        .iter()
        .map(|_| match kind {
            ArenaKind::Structured => 0.8,
            ArenaKind::Unstructured => 0.2 + 0.8 * rng.uniform(),
        })
        .collect();
    let walls = SegmentSet::new(segments);
    let free = |p: Point, clearance: f64| {
        point_in_polygon(p, &boundary)
            && !obstacles.iter().any(|o| point_in_polygon(p, o))
            && walls.nearest(p, clearance).is_none()
    };
    let mut lights = Vec::new();
    let mut start = Pose {
        x: side / 2.0,
        y: side / 2.0,
        heading: 0.0,
    };
    for _ in 0..2000 {
        let p = Point::new(rng.uniform() * side, rng.uniform() * side);
        if !free(p, 1.5 * DIAMETER_M) {
            continue;
        }
        if lights.len() < lamps {
            lights.push(Light {
                position: p,
                height_m: 0.0,
                intensity: 1.0,
            });
        } else {
            start = Pose {
                x: p.x,
                y: p.y,
                heading: rng.uniform() * std::f64::consts::TAU - std::f64::consts::PI,
            };
            break;
        }
    }
    World {
        walls,
        reflectance,
        lights,
        obstacles,
        boundary,
        start,
    }
}

/// The line camera: 64 pixels over 36 degrees, brightness of the wall each pixel sees by a
/// Lambertian first approximation (§3.3.2, Fig. 3-6): reflectance x |cos incidence| /
/// (1 + (d / 0.2 m)^2); nothing within 1 m is black.
pub fn camera(world: &World, pose: Pose) -> [f64; CAMERA_PIXELS] {
    let mut img = [0.0; CAMERA_PIXELS];
    let o = Point::new(pose.x, pose.y);
    let fov = CAMERA_FOV_DEG.to_radians();
    for (i, px) in img.iter_mut().enumerate() {
        let a = pose.heading + fov / 2.0 - fov * (i as f64 + 0.5) / CAMERA_PIXELS as f64;
        let d = Vector::new(a.cos(), a.sin());
        if let Some(hit) = world.walls.ray_cast(o, d, 1.0) {
            let seg = &world.walls.segments()[hit.segment];
            let t = seg.direction();
            let n = t.norm();
            let cos_inc = if n > 0.0 {
                (t.x * d.y - t.y * d.x).abs() / n
            } else {
                1.0
            };
            *px = world.reflectance[hit.segment] * cos_inc / (1.0 + (hit.distance / 0.2).powi(2));
        }
    }
    img
}

/// Camera preprocessing (§3.3.2, Fig. 3-7): edges from the second derivative, the image
/// stretched so the outer edges touch the borders; returns the Gaussian neuron distribution
/// (8 neurons) and the group neuron distribution (groups of 1..4 inner edges, 10 neurons).
pub fn camera_features(img: &[f64; CAMERA_PIXELS]) -> ([f32; 8], [f32; 10]) {
    let mut edges = Vec::new();
    let mut prev_edge = false;
    for i in 1..CAMERA_PIXELS - 1 {
        let dd = (img[i - 1] - 2.0 * img[i] + img[i + 1]).abs();
        let e = dd > 0.03;
        if e && !prev_edge {
            edges.push(i as f64);
        }
        prev_edge = e;
    }
    let mut gauss = [0.0f32; 8];
    let mut group = [0.0f32; 10];
    if edges.len() >= 2 {
        let (lo, hi) = (edges[0], edges[edges.len() - 1]);
        let pos: Vec<f64> = edges.iter().map(|e| (e - lo) / (hi - lo)).collect();
        for (k, g) in gauss.iter_mut().enumerate() {
            let c = k as f64 / 7.0;
            let s: f64 = pos
                .iter()
                .map(|p| (-(p - c).powi(2) / (2.0 * 0.08f64.powi(2))).exp())
                .sum();
            *g = s.min(1.0) as f32;
        }
        let inner = &pos[1..pos.len() - 1];
        let n = inner.len().min(4);
        if n > 0 {
            let base = n * (n - 1) / 2; // groups 1, 2, 3, 4 start at 0, 1, 3, 6
            for (j, p) in inner.iter().take(n).enumerate() {
                group[base + j] = *p as f32;
            }
        }
    } else if edges.len() == 1 {
        gauss[(edges[0] / CAMERA_PIXELS as f64 * 8.0) as usize % 8] = 1.0;
    }
    (gauss, group)
}
