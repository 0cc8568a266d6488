//! A landmark scan with the K213 line camera (seed 000 §6.2, §7): turn on the spot in steps,
//! stop, grab a line, and note each landmark seen near the image centre with its absolute
//! bearing (odometry heading + pixel angle) and its distance (from its width in the image).
//!
//! Layer: pure logic under `robot::forage`, no I/O: the caller feeds the believed heading
//! each cycle and the camera line when asked (`take_frame`), and drives the motor command
//! returned. Two uses: at the start
//! of foraging the three tower landmarks are mapped from the (known) start pose (§7's
//! initialisation phase, Eqs 30-31); at a source after a grasp and at the home base their
//! bearings give the global position and heading by resection (`landmarks::Triple`, Eqs 33-44).
//!
//! Choices the paper leaves open, as documented parameters: 15° steps, a line read after
//! 6 cycles at rest (the K213 gives at most 2 frames per second), landmarks taken within 12°
//! of the image centre (where the pixel angle is best; more than half a step, as a turn
//! overshoots), edges by Eqs 22-23 (gradient, |G| < 20
//! is noise), distance from the angular width of a 4.8 cm tower (the paper trains a SOM on
//! width and minimum pixel; geometry is enough for the emulated camera).
//!
//! Invariants: fixed size (at most `MAX_SIGHTINGS` sightings); a scan ends after one full
//! turn whatever it sees, or as `Stalled` when one step's turn takes more than
//! `ScanParams::stall_cycles` (a robot wedged so it cannot turn would otherwise scan
//! forever). Never a panic.

use crate::hal::{MotorCommand, CAMERA_PIXELS};
use crate::landmarks::{Camera, Triple};
use crate::odometry::{wrap_angle, Point, Pose};

/// Distinct landmarks a scan can hold.
pub const MAX_SIGHTINGS: usize = 4;

/// Scan parameters (none are in the paper).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScanParams {
    /// Turn between two looks, radians: 15°.
    pub step_rad: f32,
    /// Cycles at rest before a line is read: 6 (480 ms, the camera's 2 Hz).
    pub settle_cycles: u8,
    /// Wheel speed while turning, units: 2 (16 mm/s, about 35°/s on a Khepera).
    pub turn_units: i16,
    /// A landmark is taken only this close to the image centre, radians: 12° (more than half
    /// a step: turns overshoot).
    pub centre_rad: f32,
    /// Gradient below which an edge is noise (seed 000 Eq 23: 20).
    pub edge_threshold: i16,
    /// Tower diameter, metres (seed 000 §5.4: about 4.8 cm).
    pub tower_m: f32,
    /// Two sightings closer than this in bearing are the same landmark, radians: 5°.
    pub same_rad: f32,
    /// A step still turning after this many cycles is a stall and ends the scan: 25 (2 s,
    /// more than 4 times the 0.43 s a 15° step takes at 35°/s).
    pub stall_cycles: u16,
}

impl Default for ScanParams {
    fn default() -> Self {
        let deg = core::f32::consts::PI / 180.0;
        ScanParams {
            step_rad: 15.0 * deg,
            settle_cycles: 6,
            turn_units: 2,
            centre_rad: 12.0 * deg,
            edge_threshold: 20,
            tower_m: 0.048,
            same_rad: 5.0 * deg,
            stall_cycles: 25,
        }
    }
}

/// A landmark seen during a scan.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sighting {
    /// Absolute bearing (believed heading + angle in the image), radians.
    pub bearing: f32,
    /// Distance from its width, metres.
    pub distance_m: f32,
    /// How far off the image centre it was, radians (the smallest is kept).
    pub off_axis: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Turning to the next look; cycles spent so far.
    Turning(u16),
    Settling(u8),
    /// Waiting for the camera line (`take_frame`).
    Looking,
    /// The line was taken.
    Looked,
}

/// What the scan wants this cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScanStep {
    /// Drive this (turning, or stopped while settling).
    Drive(MotorCommand),
    /// Stopped; read the camera for the next cycle.
    WantFrame,
    /// One full turn done.
    Done,
    /// A step did not finish turning in `ScanParams::stall_cycles`: the scan is given up
    /// (the robot cannot turn); its sightings are not a full turn's and should not be used.
    Stalled,
}

/// One scan in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LandmarkScan {
    phase: Phase,
    last_heading: f32,
    turned: f32,
    step_turned: f32,
    sightings: [Sighting; MAX_SIGHTINGS],
    len: usize,
}

impl LandmarkScan {
    /// A scan starting at `heading`; it first looks where the robot faces.
    pub fn new(heading: f32) -> Self {
        LandmarkScan {
            phase: Phase::Settling(0),
            last_heading: heading,
            turned: 0.0,
            step_turned: 0.0,
            sightings: [Sighting::default(); MAX_SIGHTINGS],
            len: 0,
        }
    }

    /// The landmarks seen so far.
    pub fn sightings(&self) -> &[Sighting] {
        self.sightings.get(..self.len).unwrap_or(&[])
    }

    /// Whether the scan is waiting for a camera line.
    pub fn wants_frame(&self) -> bool {
        self.phase == Phase::Looking
    }

    /// One control cycle: the believed heading and, when asked for, the camera line.
    pub fn step(&mut self, heading: f32, p: &ScanParams) -> ScanStep {
        let d = wrap_angle(heading - self.last_heading);
        self.last_heading = heading;
        self.turned += libm::fabsf(d);
        self.step_turned += libm::fabsf(d);
        match self.phase {
            Phase::Turning(n) => {
                if self.step_turned >= p.step_rad {
                    self.phase = Phase::Settling(0);
                    return ScanStep::Drive(MotorCommand::STOP);
                }
                if n >= p.stall_cycles {
                    return ScanStep::Stalled;
                }
                self.phase = Phase::Turning(n.saturating_add(1));
                let u = p.turn_units;
                ScanStep::Drive(MotorCommand::new(-u, u))
            }
            Phase::Settling(n) => {
                if n + 1 >= p.settle_cycles {
                    self.phase = Phase::Looking;
                    return ScanStep::WantFrame;
                }
                self.phase = Phase::Settling(n + 1);
                ScanStep::Drive(MotorCommand::STOP)
            }
            Phase::Looking => ScanStep::WantFrame,
            Phase::Looked => self.next_step(),
        }
    }

    /// The camera line asked for by `WantFrame` (`None`: no camera, nothing seen), grabbed
    /// at `heading`.
    pub fn take_frame(
        &mut self,
        heading: f32,
        frame: Option<&[u8; CAMERA_PIXELS]>,
        p: &ScanParams,
    ) {
        if self.phase != Phase::Looking {
            return;
        }
        self.phase = Phase::Looked;
        if let Some(line) = frame {
            let mut blobs = [Blob::default(); MAX_SIGHTINGS];
            let n = find_blobs(line, p.edge_threshold, &mut blobs);
            for b in blobs.iter().take(n) {
                self.note(heading, b, p);
            }
        }
    }

    fn next_step(&mut self) -> ScanStep {
        if self.turned >= 2.0 * core::f32::consts::PI {
            return ScanStep::Done;
        }
        self.phase = Phase::Turning(0);
        self.step_turned = 0.0;
        ScanStep::Drive(MotorCommand::STOP)
    }

    fn note(&mut self, heading: f32, b: &Blob, p: &ScanParams) {
        let cam = Camera::K213;
        let angle = cam.pixel_angle(b.centre);
        if libm::fabsf(angle) > p.centre_rad {
            return;
        }
        let width = b.width * cam.fov_rad / f32::from(cam.pixels);
        let distance_m = p.tower_m / 2.0 / libm::tanf((width / 2.0).max(1e-3));
        let s = Sighting {
            bearing: wrap_angle(heading + angle),
            distance_m,
            off_axis: libm::fabsf(angle),
        };
        let same = self
            .sightings
            .iter_mut()
            .take(self.len)
            .find(|o| libm::fabsf(wrap_angle(o.bearing - s.bearing)) < p.same_rad);
        match same {
            Some(o) if s.off_axis < o.off_axis => *o = s,
            Some(_) => {}
            None => {
                if let Some(slot) = self.sightings.get_mut(self.len) {
                    *slot = s;
                    self.len += 1;
                }
            }
        }
    }
}

/// A dark object in a camera line: centre pixel (fractional) and width in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Blob {
    pub centre: f32,
    pub width: f32,
}

/// Seed 000 Eqs 22-23: `G_i = B_i - B_(i+1)`, zero where `|G_i| < threshold`; a falling edge
/// (G > 0, brighter to darker) opens an object, a rising one closes it. Objects cut by the
/// image's border are not reported (their centre is unknown). Returns how many were found.
pub fn find_blobs(line: &[u8; CAMERA_PIXELS], threshold: i16, out: &mut [Blob]) -> usize {
    let mut n = 0;
    let mut open: Option<usize> = None;
    for i in 0..CAMERA_PIXELS - 1 {
        let g = i16::from(line[i]) - i16::from(line[i + 1]);
        if g >= threshold {
            open = Some(i + 1);
        } else if g <= -threshold {
            if let (Some(start), Some(slot)) = (open.take(), out.get_mut(n)) {
                let end = i;
                *slot = Blob {
                    centre: (start + end) as f32 / 2.0,
                    width: (end + 1 - start) as f32,
                };
                n += 1;
            }
        }
    }
    n
}

/// Three sightings ordered left to right (decreasing counter-clockwise bearing): sorted by
/// bearing, the widest gap between neighbours is behind the robot (the landmarks span less
/// than 180°, §6.2), so the right-most is the one after it. `None` unless exactly three.
pub fn left_to_right(seen: &[Sighting]) -> Option<[Sighting; 3]> {
    let mut s = <[Sighting; 3]>::try_from(seen).ok()?;
    s.sort_unstable_by(|x, y| x.bearing.total_cmp(&y.bearing));
    let gaps = [
        s[1].bearing - s[0].bearing,
        s[2].bearing - s[1].bearing,
        s[0].bearing + 2.0 * core::f32::consts::PI - s[2].bearing,
    ];
    let mut widest = 0;
    for (i, g) in gaps.iter().enumerate() {
        if *g > gaps[widest] {
            widest = i;
        }
    }
    let right = (widest + 1) % 3;
    Some([s[(right + 2) % 3], s[(right + 1) % 3], s[right]])
}

/// Seed 000 §7's initialisation: exactly three landmarks seen from the known position `at`
/// become the triple, ordered left to right as the resection wants (Eqs 30-31).
pub fn map_triple(at: Point, seen: &[Sighting]) -> Option<Triple> {
    let [l1, l2, l3] = left_to_right(seen)?.map(|x| {
        Point::new(
            at.x + x.distance_m * libm::cosf(x.bearing),
            at.y + x.distance_m * libm::sinf(x.bearing),
        )
    });
    Some(Triple::new(l1, l2, l3))
}

/// The pose from a scan at the home base (Eqs 33-44). The three towers are told apart by
/// their left-to-right order, which a heading error cannot change (matching by predicted
/// bearing fails once the heading error nears the angle between two towers). `believed` is
/// the pose whose heading the bearings were computed with. `None` unless exactly three were
/// seen and the geometry has an answer.
pub fn resect(triple: &Triple, believed: Pose, seen: &[Sighting]) -> Option<Pose> {
    let rel = left_to_right(seen)?.map(|s| wrap_angle(s.bearing - believed.heading));
    // `rel` are the angles in the image (bearing minus the heading they were added to), so
    // the resected heading is absolute: the direction to L3 minus its angle.
    let fix = triple.resect_pose(rel).ok()?;
    Some(Pose::new(fix.x, fix.y, wrap_angle(fix.heading)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line_with(objects: &[(usize, usize)]) -> [u8; CAMERA_PIXELS] {
        let mut l = [180u8; CAMERA_PIXELS];
        for &(a, b) in objects {
            for px in l.iter_mut().take(b + 1).skip(a) {
                *px = 40;
            }
        }
        l
    }

    #[test]
    fn blobs_are_found_between_a_falling_and_a_rising_edge_and_border_cuts_are_ignored() {
        let mut out = [Blob::default(); 4];
        let n = find_blobs(&line_with(&[(0, 5), (20, 29), (40, 41)]), 20, &mut out);
        assert_eq!(n, 2);
        assert_eq!(
            out[0],
            Blob {
                centre: 24.5,
                width: 10.0
            }
        );
        assert_eq!(
            out[1],
            Blob {
                centre: 40.5,
                width: 2.0
            }
        );
    }

    #[test]
    fn a_scan_whose_turn_makes_no_progress_gives_up_and_a_turning_one_finishes() {
        let p = ScanParams::default();
        let run = |turn_rate: f32| {
            let mut heading = 0.0f32;
            let mut s = LandmarkScan::new(heading);
            for cycle in 0..10_000u32 {
                match s.step(heading, &p) {
                    ScanStep::Drive(cmd) if cmd != MotorCommand::STOP => heading += turn_rate,
                    ScanStep::Drive(_) => {}
                    ScanStep::WantFrame => s.take_frame(heading, None, &p),
                    end => return (end, cycle),
                }
            }
            (ScanStep::Drive(MotorCommand::STOP), u32::MAX)
        };
        // About 2.8° a cycle: a Khepera at 2 units, 80 ms cycles.
        assert_eq!(run(0.049).0, ScanStep::Done);
        let (end, cycles) = run(0.0);
        assert_eq!(end, ScanStep::Stalled);
        assert!(cycles < 100, "gave up after {cycles} cycles");
    }

    #[test]
    fn a_mapped_triple_resects_the_pose_it_was_mapped_from() {
        // Landmarks at 150°, 120° and 105° from the origin, exact distances.
        let deg = core::f32::consts::PI / 180.0;
        let seen = [105.0f32, 150.0, 120.0].map(|b| Sighting {
            bearing: b * deg,
            distance_m: 0.4,
            off_axis: 0.0,
        });
        let t = map_triple(Point::new(0.0, 0.0), &seen).expect("three");
        // Left to right: 150°, 120°, 105°.
        assert!((t.landmarks[0].y - 0.4 * libm::sinf(150.0 * deg)).abs() < 1e-5);
        assert!((t.landmarks[2].x - 0.4 * libm::cosf(105.0 * deg)).abs() < 1e-5);
        // The robot believes it is 5 cm off and 10° turned: the fix puts it back.
        let believed = Pose::new(0.05, -0.03, 10.0 * deg);
        let p = resect(&t, believed, &seen).expect("fix");
        assert!(p.x.abs() < 1e-3 && p.y.abs() < 1e-3, "{p:?}");
        assert!(
            libm::fabsf(wrap_angle(p.heading - 10.0 * deg)) < 1e-3,
            "{p:?}"
        );
        assert!(map_triple(Point::new(0.0, 0.0), &seen[..2]).is_none());
    }
}
