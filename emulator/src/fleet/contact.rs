//! Robots against robots: the physics of several round bodies in one arena.
//!
//! Layer: std, beside `physics` (which knows walls only). After a robot's own step (walls
//! resolved), [`RobotContacts::resolve`] moves it out of any other robot it now overlaps,
//! along the line between the centres, as a wall contact pushes a body out along its normal:
//! motion into the other robot is removed, motion along it remains (round robots slide off
//! each other), the wheels keep turning. Robots do not push each other: the one that moves
//! is stopped by the other, which stays where it is (a robot is heavy against its motors;
//! the papers give no masses or friction to do better). A push that would end in a wall, or
//! still overlapping, is not taken: the robot stays where the step began, which was free.
//!
//! Contacts are counted per robot and per other robot, separately from wall contacts: a
//! contact starts when the bodies touch and ends when they are more than
//! `physics::CONTACT_RELEASE_M` apart (the same hysteresis as walls), so two robots sliding
//! past each other are one collision for each of them.
//!
//! Invariants: with every robot resolved after its own step, no two bodies overlap (beyond
//! rounding); nothing here allocates. Cannot fail.

use crate::geometry::{Disc, Point};
use crate::physics::{Body, CONTACT_RELEASE_M};
use crate::world::World;

/// Most robots one world holds: ids are bits of a `u64` contact mask. A Micro-Rato contest
/// runs three (seed 004 §2).
pub const MAX_ROBOTS: usize = 16;
/// Gap under which two bodies touch, metres (push-outs leave a hair of rounding).
const TOUCH_M: f64 = 1e-6;
/// Largest number of push-outs per step (wedged between two robots needs two).
const MAX_PUSHES: usize = 4;

/// Another robot as one robot's sensors and physics see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Its index in the fleet (0-based), below [`MAX_ROBOTS`].
    pub id: usize,
    /// Its body now.
    pub body: Disc,
}

/// One robot's contacts with the others.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RobotContacts {
    /// Bit `id` set while touching robot `id`.
    touching: u64,
    collisions: u32,
}

impl RobotContacts {
    /// Contacts with other robots so far (each contact once, whoever drove into whom).
    pub fn collisions(&self) -> u32 {
        self.collisions
    }

    /// Whether this robot is touching (or has just left) another robot.
    pub fn in_contact(&self) -> bool {
        self.touching != 0
    }

    /// Moves `body` (just stepped from `step_from`) out of the `neighbours` it overlaps and
    /// counts new contacts. With no neighbours it does nothing.
    pub fn resolve(
        &mut self,
        body: &mut Body,
        step_from: Point,
        neighbours: &[Neighbour],
        world: &World,
    ) {
        if neighbours.is_empty() {
            return;
        }
        let r = body.params().radius_m;
        let pose = body.pose();
        let at = Point::new(pose.x, pose.y);
        let mut q = at;
        let mut pushed: u64 = 0;
        for _ in 0..MAX_PUSHES {
            let me = Disc {
                centre: q,
                radius: r,
            };
            let worst = neighbours
                .iter()
                .map(|n| (n, me.gap(&n.body)))
                .filter(|(_, gap)| *gap < 0.0)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let Some((n, _)) = worst else { break };
            pushed |= bit(n.id);
            let away = q - n.body.centre;
            let dist = away.norm();
            if dist < 1e-12 {
                q = step_from; // centres coincide: no sensible direction, undo the step
                break;
            }
            let reach = (r + n.body.radius) * (1.0 + 1e-12);
            q = n.body.centre + away * (reach / dist);
        }
        if q != at {
            let me = Disc {
                centre: q,
                radius: r,
            };
            let overlaps = neighbours.iter().any(|n| me.gap(&n.body) < -TOUCH_M);
            if overlaps || !world.is_free(q, r) {
                q = step_from;
            }
            body.displace_to(q, step_from);
        }
        let me = Disc {
            centre: q,
            radius: r,
        };
        for n in neighbours {
            let b = bit(n.id);
            let gap = me.gap(&n.body);
            if gap <= TOUCH_M || pushed & b != 0 {
                if self.touching & b == 0 {
                    self.collisions = self.collisions.saturating_add(1);
                    self.touching |= b;
                }
            } else if gap > CONTACT_RELEASE_M {
                self.touching &= !b;
            }
        }
    }
}

fn bit(id: usize) -> u64 {
    1u64.checked_shl(id as u32).unwrap_or(0)
}
