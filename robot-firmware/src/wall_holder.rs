//! A wall holder for the odometry calibration's manoeuvre: keeps the side IR sensor at a
//! constant reading inside its useful band, slowly, so the robot runs parallel to a wall.
//!
//! Why not seed 000's edge follower (`behaviour::edge`): it only ever curves TOWARDS the wall
//! and leaves moving away to obstacle avoidance, so on a Khepera it rides the wall with the
//! side sensor saturated (1023 below 1.7 cm): the reading then says nothing about the
//! distance, and the robot's true heading turns slowly against the wall while the encoders
//! report a straight line (traces of the generated boxes). The straight-wall estimate
//! (`odometry_stretch`) needs the distance, so the sensor must stay in its band.
//!
//! The controller, once per observation (25 Hz), wall on the right (mirrored for the left):
//! - a wall ahead (front or diagonal sensor on the wall's side above `front_level`): turn on
//!   the spot away from it until clear (an inside corner, a block);
//! - the wall lost (side and diagonal below `lost_level`): curve towards it with radius
//!   `lost_radius_mm` (round the end of a wall); after a whole turn without finding it (the
//!   robot is in the open: at the start, or it left a small block), cross: straight on
//!   until a wall is ahead, then the rules above (the caller also has the robot leave an
//!   island it went round: a quarter turn away, then across);
//! - otherwise hold: the wanted heading relative to the wall is proportional to the distance
//!   error (reading minus `set_level`, over the band's counts a millimetre), clamped; the
//!   heading relative to the wall is the believed heading minus its slow average (the wall's
//!   direction as the robot has been moving along it); the wheel speed difference is
//!   proportional to the heading error, dithered onto whole motor units (sigma-delta), as the
//!   robot's motors take whole units.
//!
//! Output: wheel speeds in whole motor units as a `Command::Teleop` (the robot's teleop turns
//! `v`, `w` back into exactly those units). Layer: pure, no I/O, no clock, no heap.

use protocol::Command;

/// The holder's settings. Not from the papers; each says why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HolderParams {
    /// Side reading to hold, counts: the middle of a Khepera's useful band (1.7-3.3 cm), far
    /// from saturation and from the floor.
    pub set_level: f32,
    /// Counts a millimetre near `set_level` (only the loop gain depends on it).
    pub counts_per_mm: f32,
    /// Wanted heading change per millimetre of distance error, radians.
    pub heading_per_mm: f32,
    /// Largest wanted heading relative to the wall, radians (a gentle approach).
    pub max_heading: f32,
    /// Wheel-speed difference per radian of heading error, motor units.
    pub units_per_rad: f32,
    /// Forward speed, motor units a wheel (slow: more samples a millimetre, less lag).
    pub base_units: i16,
    /// Front or diagonal reading that means a wall ahead, counts.
    pub front_level: u16,
    /// Below this on the side and diagonal sensors the wall is lost, counts.
    pub lost_level: u16,
    /// Radius of the curve towards a lost wall, mm.
    pub lost_radius_mm: f32,
    /// Turn rate on the spot at a wall ahead, mrad/s.
    pub spin_mrad_s: i16,
    /// Weight of each new heading in the wall direction's average (1 / samples).
    pub wall_gain: f32,
}

impl Default for HolderParams {
    fn default() -> Self {
        Self {
            set_level: 450.0,
            counts_per_mm: 60.0,
            heading_per_mm: 0.03,
            max_heading: 0.08,
            units_per_rad: 12.0,
            base_units: 4,
            front_level: 200,
            lost_level: 40,
            lost_radius_mm: 55.0,
            spin_mrad_s: 600,
            wall_gain: 0.05,
        }
    }
}

/// Which of the holder's rules drove this observation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HolderPhase {
    /// Holding the side reading along a wall.
    Holding,
    /// Turning on the spot away from a wall ahead.
    Spinning,
    /// Curving towards a lost wall.
    Seeking,
    /// Straight on across the open until a wall is ahead.
    Crossing,
    /// Turning away from an island (a block the robot went round) by a quarter turn; the
    /// believed heading where the turn began.
    Leaving,
}

/// The holder's state (a few words).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallHolder {
    params: HolderParams,
    /// +1: wall on the right; -1: on the left.
    sign: f32,
    right: bool,
    wall_dir: Option<f32>,
    acc: f32,
    phase: HolderPhase,
    /// The believed heading where the current seeking curve began.
    seek_from: Option<f32>,
    unit_mm_s: f32,
    half_base_mm: f32,
}

impl WallHolder {
    /// A holder for a wall on the right (`right`) or left, for a robot whose motor unit is
    /// `unit_mm_s` and nominal wheel distance `wheel_distance_mm`.
    pub fn new(params: HolderParams, right: bool, unit_mm_s: f32, wheel_distance_mm: f32) -> Self {
        Self {
            params,
            sign: if right { 1.0 } else { -1.0 },
            right,
            wall_dir: None,
            acc: 0.0,
            phase: HolderPhase::Crossing,
            seek_from: None,
            unit_mm_s,
            half_base_mm: wheel_distance_mm / 2.0,
        }
    }

    /// Leave the wall being held (the caller found it is an island: a lap went round it the
    /// wrong way): a quarter turn away from it, then straight on to the next wall ahead.
    pub fn leave(&mut self, heading: f32) {
        self.phase = HolderPhase::Leaving;
        self.seek_from = Some(heading);
        self.wall_dir = None;
    }

    /// The rule that drove the last observation.
    pub fn phase(&self) -> HolderPhase {
        self.phase
    }

    /// The command for this observation: the IR readings (S0 left .. S5 right) and the
    /// believed heading (unwrapped, radians).
    pub fn step(&mut self, ir: &[u16; 8], heading: f32) -> Command {
        let p = self.params;
        let (side, diag, front) = if self.right {
            (ir[5], ir[4], ir[3].max(ir[2]))
        } else {
            (ir[0], ir[1], ir[2].max(ir[3]))
        };
        let away = if self.right {
            p.spin_mrad_s
        } else {
            -p.spin_mrad_s
        };
        if self.phase == HolderPhase::Leaving {
            let from = self.seek_from.unwrap_or(heading);
            if libm::fabsf(heading - from) < core::f32::consts::FRAC_PI_2 {
                return Command::Teleop {
                    v_mm_s: 0,
                    w_mrad_s: away,
                };
            }
            self.phase = HolderPhase::Crossing;
            self.seek_from = None;
        }
        if front >= p.front_level || diag >= p.front_level {
            self.phase = HolderPhase::Spinning;
            self.wall_dir = None;
            self.seek_from = None;
            // Away from the wall: left for a wall on the right.
            return Command::Teleop {
                v_mm_s: 0,
                w_mrad_s: away,
            };
        }
        let v = f32::from(p.base_units) * self.unit_mm_s;
        // Crossing ends at a wall ahead (the spin above), not at one beside: the island just
        // left, or the wall lost, may still be in the side sensor's view.
        if self.phase == HolderPhase::Crossing {
            return Command::Teleop {
                v_mm_s: v as i16,
                w_mrad_s: 0,
            };
        }
        if side < p.lost_level && diag < p.lost_level {
            self.wall_dir = None;
            let from = *self.seek_from.get_or_insert(heading);
            if libm::fabsf(heading - from) > 2.0 * core::f32::consts::PI {
                self.phase = HolderPhase::Crossing;
                self.seek_from = None;
                return Command::Teleop {
                    v_mm_s: v as i16,
                    w_mrad_s: 0,
                };
            }
            self.phase = HolderPhase::Seeking;
            let w = v / p.lost_radius_mm * 1000.0;
            return Command::Teleop {
                v_mm_s: v as i16,
                w_mrad_s: (-self.sign * w) as i16,
            };
        }
        self.phase = HolderPhase::Holding;
        self.seek_from = None;
        let dir = *self.wall_dir.get_or_insert(heading);
        let rel = heading - dir;
        self.wall_dir = Some(dir + p.wall_gain * rel);
        // Too close (reading above the set level): head away from the wall, which is left
        // (positive) for a wall on the right.
        let err_mm = (f32::from(side) - p.set_level) / p.counts_per_mm;
        let want = (self.sign * p.heading_per_mm * err_mm).clamp(-p.max_heading, p.max_heading);
        self.acc += p.units_per_rad * (want - rel);
        let diff = libm::roundf(self.acc).clamp(-3.0, 3.0);
        self.acc = (self.acc - diff).clamp(-1.0, 1.0);
        let d = diff as i16;
        // Right minus left = d, about the base: whole units on each wheel.
        let right = p.base_units + (d + 1).div_euclid(2);
        let left = p.base_units - d.div_euclid(2);
        self.units_command(left, right)
    }

    /// The teleop command whose kinematics give exactly these wheel units.
    fn units_command(&self, left: i16, right: i16) -> Command {
        let u = self.unit_mm_s;
        let v = (f32::from(left) + f32::from(right)) * u / 2.0;
        let w = (f32::from(right) - f32::from(left)) * u / 2.0 / self.half_base_mm * 1000.0;
        Command::Teleop {
            v_mm_s: libm::roundf(v) as i16,
            w_mrad_s: libm::roundf(w) as i16,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_by_whole_units_and_turns_away_from_a_close_wall() {
        let mut h = WallHolder::new(HolderParams::default(), true, 8.0, 52.0);
        // In the open: straight on.
        let mut ir = [0u16; 8];
        assert_eq!(
            h.step(&ir, 0.0),
            Command::Teleop {
                v_mm_s: 32,
                w_mrad_s: 0
            }
        );
        // A wall ahead: spin left on the spot.
        ir[3] = 500;
        assert_eq!(
            h.step(&ir, 0.0),
            Command::Teleop {
                v_mm_s: 0,
                w_mrad_s: 600
            }
        );
        assert_eq!(h.phase(), HolderPhase::Spinning);
        // Far too close on the right: turn left (right wheel faster), by whole units.
        ir[3] = 0;
        ir[5] = 900;
        let mut sum = 0i32;
        for _ in 0..10 {
            match h.step(&ir, 0.0) {
                Command::Teleop { v_mm_s, w_mrad_s } => {
                    assert_eq!(v_mm_s % 4, 0);
                    assert_eq!(i32::from(w_mrad_s) % 154, 0, "{w_mrad_s}");
                    sum += i32::from(w_mrad_s);
                }
                c => panic!("{c:?}"),
            }
        }
        assert!(sum > 0, "{sum}");
        assert_eq!(h.phase(), HolderPhase::Holding);
        // Nothing in view: curve right, towards where the wall was.
        let ir = [0u16; 8];
        match h.step(&ir, 0.0) {
            Command::Teleop { v_mm_s, w_mrad_s } => assert!(v_mm_s > 0 && w_mrad_s < 0),
            c => panic!("{c:?}"),
        }
    }
}
