//! Where the robots of a fleet start: the arena's start areas.
//!
//! Seed 004 §2: the robots go "from a start area"; CiberRato grid files list several start
//! positions (the 2005 final's has three) and the arena generator writes one to three. The
//! rule, deterministic and checked here:
//! 1. a robot given a pose (`--robot P@X,Y,DEG`, `--start` for robot 1) starts there;
//! 2. the others take the arena's start positions in order, each one not yet taken and
//!    clear of the robots already placed (robot 1 alone gets exactly the single-robot start:
//!    the arena's first, else the first free spot);
//! 3. when the arena has fewer starts than robots, the rest are set down beside a start
//!    (the start area around it), in its heading, one body diameter plus [`SPACING_M`] away
//!    per ring, trying its sides first, then behind, then the diagonals, then ahead, out to
//!    [`RINGS`] rings; a spot must keep [`WALL_MARGIN_M`] from walls and lie outside the goal.
//!
//! What can fail: two given poses overlapping, or no room for a robot ([`StartError`]).

use thiserror::Error;

use crate::arena::Pose;
use crate::geometry::{Disc, Point};
use crate::sim::SimError;
use crate::world::World;

/// Least gap between two robots' bodies at the start, metres (they must not touch).
pub const SPACING_M: f64 = 0.10;
/// Least gap between a robot set down beside a start and a wall, metres.
pub const WALL_MARGIN_M: f64 = 0.05;
/// Rings of spots tried around each start.
pub const RINGS: u32 = 3;
/// Directions tried around a start, relative to its heading, degrees: sides, behind,
/// diagonals, ahead last (ahead is the way it will drive).
const AROUND_DEG: [f64; 8] = [90.0, -90.0, 180.0, 135.0, -135.0, 45.0, -45.0, 0.0];

/// Why the robots cannot all be placed.
#[derive(Debug, Error)]
pub enum StartError {
    /// A robot's start is not a valid single-robot start (in a wall, not finite, no room).
    #[error("robot {robot}: {source}")]
    Robot {
        /// 1-based robot number.
        robot: usize,
        /// Why.
        source: SimError,
    },
    /// Two robots would start overlapping or closer than [`SPACING_M`].
    #[error(
        "robots {a} and {b} would start {gap_m:.3} m apart (edge to edge); robots need at \
         least {SPACING_M} m between them: give them other poses (--robot PROFILE@X,Y,DEG)"
    )]
    Overlap {
        /// 1-based robot number.
        a: usize,
        /// 1-based robot number.
        b: usize,
        /// Gap between their bodies.
        gap_m: f64,
    },
    /// No start position and no free spot near one.
    #[error(
        "robot {robot}: arena {arena:?} has {starts} start position(s) and no free spot \
         beside them for another robot; give its pose (--robot PROFILE@X,Y,DEG)"
    )]
    NoRoom {
        /// 1-based robot number.
        robot: usize,
        /// Arena name.
        arena: String,
        /// The arena's start positions.
        starts: usize,
    },
}

/// The start pose of each robot; `given[i]` and `radii[i]` describe robot `i`.
pub fn start_poses(
    world: &World,
    given: &[Option<Pose>],
    radii: &[f64],
) -> Result<Vec<Pose>, StartError> {
    let n = given.len().min(radii.len());
    let mut placed: Vec<Option<Pose>> = vec![None; n];
    // 1. Given poses, checked as a single robot's start is.
    for i in 0..n {
        if let Some(p) = given[i] {
            let pose = crate::sim::start_pose(world, Some(p), radii[i]).map_err(|source| {
                StartError::Robot {
                    robot: i + 1,
                    source,
                }
            })?;
            placed[i] = Some(pose);
        }
    }
    for i in 0..n {
        for j in 0..i {
            if let (Some(a), Some(b)) = (placed[j], placed[i]) {
                let gap = disc(a, radii[j]).gap(&disc(b, radii[i]));
                if gap < SPACING_M {
                    return Err(StartError::Overlap {
                        a: j + 1,
                        b: i + 1,
                        gap_m: gap,
                    });
                }
            }
        }
    }
    // 2. The arena's starts, in order.
    let starts = &world.arena().starts;
    let mut next_start = 0;
    for i in 0..n {
        if placed[i].is_some() {
            continue;
        }
        if starts.is_empty() && i == 0 {
            // As a single robot: the first free spot.
            let pose = crate::sim::start_pose(world, None, radii[0])
                .map_err(|source| StartError::Robot { robot: 1, source })?;
            if clear_of(&placed, radii, pose, radii[0]) {
                placed[0] = Some(pose);
            }
            continue;
        }
        while next_start < starts.len() {
            let s = starts[next_start];
            next_start += 1;
            let Ok(pose) = crate::sim::start_pose(world, Some(s), radii[i]) else {
                continue;
            };
            if clear_of(&placed, radii, pose, radii[i]) {
                placed[i] = Some(pose);
                break;
            }
        }
    }
    // 3. Beside a start (the arena's, else a robot's already placed).
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let mut anchors: Vec<Pose> = starts.clone();
    anchors.extend(placed.iter().flatten().copied());
    for i in 0..n {
        if placed[i].is_some() {
            continue;
        }
        let spot = anchors.iter().find_map(|a| {
            (1..=RINGS).find_map(|ring| {
                AROUND_DEG.iter().find_map(|deg| {
                    let dir = a.heading + deg.to_radians();
                    let d = f64::from(ring) * (2.0 * r_max + SPACING_M);
                    let p = Point::new(a.x + d * dir.cos(), a.y + d * dir.sin());
                    let pose = Pose {
                        x: p.x,
                        y: p.y,
                        heading: a.heading,
                    };
                    let ok = world.is_free(p, radii[i] + WALL_MARGIN_M)
                        && !world.in_target(p)
                        && clear_of(&placed, radii, pose, radii[i]);
                    ok.then_some(pose)
                })
            })
        });
        match spot {
            Some(p) => placed[i] = Some(p),
            None => {
                return Err(StartError::NoRoom {
                    robot: i + 1,
                    arena: world.arena().name.clone(),
                    starts: starts.len(),
                })
            }
        }
    }
    Ok(placed.into_iter().flatten().collect())
}

fn disc(p: Pose, r: f64) -> Disc {
    Disc {
        centre: Point::new(p.x, p.y),
        radius: r,
    }
}

/// True when a robot of radius `r` at `pose` keeps [`SPACING_M`] from every placed robot.
fn clear_of(placed: &[Option<Pose>], radii: &[f64], pose: Pose, r: f64) -> bool {
    placed
        .iter()
        .zip(radii)
        .all(|(p, &rp)| p.is_none_or(|p| disc(p, rp).gap(&disc(pose, r)) >= SPACING_M))
}
