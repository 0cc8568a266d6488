//! The foraging world of seed 000 §7: objects at lit sources, a home base, three landmarks,
//! and the Khepera gripper turret that picks the objects up and puts them down.
//!
//! Layer: std, beside the sensor models: [`ForageSite`] says where things are (the built-in
//! `builtin:forage` arena has a fixed one, any other arena gets one drawn from the run's seed);
//! [`Gripper`] is the simulated turret (`sim::SimHal` steps it every millisecond and answers
//! the firmware's `Hal::gripper` from it), and it owns the objects, since only it moves them.
//!
//! Model (seed 000 §1.1: 256 arm positions, grip open/closed; the paper gives no timings):
//! the arm travels its full range in `arm_travel_s` (1 s) and the grip opens or closes in
//! `grip_s` (0.3 s). The fingers meet `reach_m` (12 mm) ahead of the body's edge. Closing the
//! grip with the arm down picks up a loose object whose centre is within `pick_radius_m`
//! (2 cm) of that point; the object-present sensor (the turret's optical barrier) sees an
//! object between the fingers. Opening the grip puts a carried object down at the fingers; if
//! that point is inside the home base the object is delivered (and leaves play).
//! Objects are small cylinders (2 cm across) under the lamps: they are not obstacles, neither
//! to the IR sensors nor to the body (seed 000 §7.4: gripping is triggered by the light
//! intensity because the lamps disturb the IR sensors, so IR never had to see them).
//! The landmarks are towers outside the arena's walls (seen over them by the K213 camera in
//! the paper; here drawn by the station, the emulated robot has no camera).
//!
//! Invariants: an object is in exactly one state; a delivered object never moves again;
//! everything is deterministic (no random draws after the site is made). Cannot fail.

use robot_firmware::hal::{GripperCommand, GripperState, ARM_DOWN, CAMERA_PIXELS};
use robot_firmware::landmarks::Camera;

use crate::arena::{Arena, Light, Pose, Target};
use crate::geometry::{Point, Vector};
use crate::rng::SimRng;
use crate::world::World;

/// Name of the built-in foraging arena.
pub const BUILTIN_FORAGE: &str = "builtin:forage";
/// Home base radius when the arena marks none: 0.10 m (a 20 cm floor patch).
pub const HOME_RADIUS_M: f64 = 0.10;
/// Light sources drawn for an arena that has none.
pub const DRAWN_SOURCES: usize = 3;
/// Random stream of the site drawing (after the `rng::stream` numbers).
const SITE_STREAM: u64 = 16;
/// Random stream of the camera's noise.
pub const CAMERA_STREAM: u64 = 17;
/// Camera pixel noise, counts (1 sigma). The paper gives none; 2 keeps it well under the
/// edge threshold of 20 (Eq 23).
pub const CAMERA_NOISE_COUNTS: f64 = 2.0;

/// Where the foraging things are.
#[derive(Clone, Debug, PartialEq)]
pub struct ForageSite {
    /// The home base: a floor circle.
    pub home: Target,
    /// Light sources, each with one object under it.
    pub sources: Vec<Light>,
    /// True when `sources` are not in the arena and must be added to the world's lights.
    pub sources_added: bool,
    /// The three global landmarks (seed 000 §6.2, §7: tower-like "skyscrapers").
    pub landmarks: [Point; 3],
}

impl ForageSite {
    /// The site for `arena`: its lights and first target if `start` is inside it (the
    /// built-in forage arena has both), else drawn from `seed`: home at `start`, [`DRAWN_SOURCES`] lamps at free spots
    /// at least 0.3 m from home and from each other. Landmarks: three towers 6 cm outside the
    /// arena's left edge, at 30 %, 55 % and 95 % of its height (the paper's towers share an x
    /// and are 20 and 30 cm apart in its 80 cm arena).
    pub fn for_arena(world: &World, start: Point, seed: u64) -> ForageSite {
        let arena = world.arena();
        // The firmware takes the start as its home base (it does not look for one), so the
        // arena's target is the home only when the robot starts inside it. A generated box's
        // target is the go-to goal, metres away: home there had the firmware put every
        // object down at its start, outside the "home" (bench: 0 of 54 delivered, the
        // firmware's count differing in every run).
        let home = arena
            .target()
            .copied()
            .filter(|t| (start - t.centre).norm() <= t.radius_m)
            .unwrap_or(Target {
                centre: start,
                radius_m: HOME_RADIUS_M,
            });
        let (sources, sources_added) = if arena.lights.is_empty() {
            (draw_sources(world, home.centre, seed), true)
        } else {
            (arena.lights.clone(), false)
        };
        ForageSite {
            home,
            sources,
            sources_added,
            landmarks: landmarks_for(arena),
        }
    }

    /// The site of the built-in forage arena, or `None` for any other arena.
    pub fn builtin(world: &World) -> Option<ForageSite> {
        Self::of_builtin(world.arena())
    }

    /// As [`ForageSite::builtin`], from the arena alone (the station draws it).
    pub fn of_builtin(arena: &Arena) -> Option<ForageSite> {
        if arena.source.as_os_str() != BUILTIN_FORAGE {
            return None;
        }
        let home = arena.target().copied()?;
        Some(ForageSite {
            home,
            sources: arena.lights.clone(),
            sources_added: false,
            landmarks: landmarks_for(arena),
        })
    }

    /// Where each source's object starts: under its lamp.
    pub fn object_positions(&self) -> Vec<Point> {
        self.sources.iter().map(|l| l.position).collect()
    }
}

fn landmarks_for(arena: &Arena) -> [Point; 3] {
    let b = arena.bounds;
    let x = b.min.x - 0.06;
    let y = |f: f64| b.min.y + f * b.height();
    [
        Point::new(x, y(0.3)),
        Point::new(x, y(0.55)),
        Point::new(x, y(0.95)),
    ]
}

/// Lamps at free spots, deterministic for `seed`; fewer if the arena is too cramped.
fn draw_sources(world: &World, home: Point, seed: u64) -> Vec<Light> {
    let mut rng = SimRng::new(seed, SITE_STREAM);
    let b = world.arena().bounds;
    let mut out: Vec<Light> = Vec::new();
    // Bounded: a crowded arena gets fewer lamps rather than an endless search.
    for _ in 0..10_000 {
        if out.len() == DRAWN_SOURCES {
            break;
        }
        let p = Point::new(
            b.min.x + rng.uniform() * b.width(),
            b.min.y + rng.uniform() * b.height(),
        );
        let far = (p - home).norm() >= 0.3 && out.iter().all(|l| (p - l.position).norm() >= 0.3);
        if far && world.is_free(p, 0.12) {
            out.push(Light {
                position: p,
                height_m: 0.05,
                intensity: 1.0,
            });
        }
    }
    out
}

/// Where an object is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectState {
    /// On the floor.
    Loose,
    /// In the gripper.
    Carried,
    /// Put down inside the home base.
    Delivered,
}

/// One object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForageObject {
    /// Where it is (for a carried one, at the fingers).
    pub position: Point,
    pub state: ObjectState,
}

/// An object put down: when, where, and whether inside the home base.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drop {
    /// Simulated time, ms.
    pub time_ms: u64,
    /// Where it landed.
    pub position: Point,
    /// Inside the home base.
    pub delivered: bool,
}

/// Gripper timings and geometry (the paper gives none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GripperParams {
    /// Full arm travel, seconds.
    pub arm_travel_s: f64,
    /// Grip opening or closing, seconds.
    pub grip_s: f64,
    /// Fingers ahead of the body's edge, metres.
    pub reach_m: f64,
    /// Largest distance from the fingers to an object's centre that still grips it, metres.
    pub pick_radius_m: f64,
}

impl Default for GripperParams {
    fn default() -> Self {
        GripperParams {
            arm_travel_s: 1.0,
            grip_s: 0.3,
            reach_m: 0.012,
            pick_radius_m: 0.02,
        }
    }
}

/// The simulated gripper turret and the objects it can move.
#[derive(Clone, Debug)]
pub struct Gripper {
    present: bool,
    params: GripperParams,
    body_radius_m: f64,
    home: Option<Target>,
    cmd: GripperCommand,
    /// Arm position 0 (up) ..= 255 (down), continuous.
    arm: f64,
    /// 0 open ..= 1 closed.
    grip: f64,
    objects: Vec<ForageObject>,
    carried: Option<usize>,
    drops: Vec<Drop>,
}

impl Gripper {
    /// A gripper for a robot of `body_radius_m`; absent unless `present`.
    pub fn new(present: bool, body_radius_m: f64, site: Option<&ForageSite>) -> Gripper {
        Gripper {
            present,
            params: GripperParams::default(),
            body_radius_m,
            home: site.map(|s| s.home),
            cmd: GripperCommand::default(),
            arm: 0.0,
            grip: 0.0,
            objects: site
                .map(|s| {
                    s.object_positions()
                        .into_iter()
                        .map(|position| ForageObject {
                            position,
                            state: ObjectState::Loose,
                        })
                        .collect()
                })
                .unwrap_or_default(),
            carried: None,
            drops: Vec::new(),
        }
    }

    /// Whether the robot has a gripper.
    pub fn present(&self) -> bool {
        self.present
    }

    /// The firmware's command.
    pub fn command(&mut self, cmd: GripperCommand) {
        if self.present {
            self.cmd = cmd;
        }
    }

    /// The turret's report (the object-present sensor included).
    pub fn read(&self, pose: Pose) -> Option<GripperState> {
        if !self.present {
            return None;
        }
        let object = self.carried.is_some()
            || (self.arm_down() && self.grip < 1.0 && self.loose_at(self.fingers(pose)).is_some());
        Some(GripperState {
            arm: self.arm.round().clamp(0.0, 255.0) as u8,
            closed: self.grip >= 1.0,
            object,
        })
    }

    /// Advances `dt_s` with the robot at `pose`, `heading` being the unit vector of
    /// `pose.heading` (the body keeps one: a carried object follows the fingers every step, and
    /// a `sin_cos` per step was 8 % of a foraging run); `now_ms` stamps drops.
    pub fn step(&mut self, pose: Pose, heading: Vector, dt_s: f64, now_ms: u64) {
        if !self.present {
            return;
        }
        // At rest (arm and grip where commanded, nothing held) a step changes nothing: most
        // of a run, so it returns before any arithmetic.
        if self.carried.is_none()
            && self.arm == f64::from(self.cmd.arm)
            && self.grip == if self.cmd.closed { 1.0 } else { 0.0 }
        {
            return;
        }
        let arm_rate = 255.0 / self.params.arm_travel_s.max(1e-3);
        self.arm = approach(self.arm, f64::from(self.cmd.arm), arm_rate * dt_s);
        let was_closed = self.grip >= 1.0;
        let target = if self.cmd.closed { 1.0 } else { 0.0 };
        self.grip = approach(self.grip, target, dt_s / self.params.grip_s.max(1e-3));
        // Where the fingers are only matters when they close on something or carry it: an
        // idle gripper (most of a run) does not pay a sin_cos every step.
        if !was_closed && self.grip >= 1.0 && self.carried.is_none() && self.arm_down() {
            if let Some(i) = self.loose_at(self.fingers_along(pose, heading)) {
                self.carried = Some(i);
                if let Some(o) = self.objects.get_mut(i) {
                    o.state = ObjectState::Carried;
                }
            }
        }
        if let Some(i) = self.carried {
            let fingers = self.fingers_along(pose, heading);
            let Some(o) = self.objects.get_mut(i) else {
                return;
            };
            o.position = fingers;
            if self.grip < 0.5 {
                let delivered = self
                    .home
                    .is_some_and(|h| (fingers - h.centre).norm() <= h.radius_m);
                o.state = if delivered {
                    ObjectState::Delivered
                } else {
                    ObjectState::Loose
                };
                self.carried = None;
                self.drops.push(Drop {
                    time_ms: now_ms,
                    position: fingers,
                    delivered,
                });
            }
        }
    }

    /// The objects.
    pub fn objects(&self) -> &[ForageObject] {
        &self.objects
    }

    /// Every object put down so far, in order.
    pub fn drops(&self) -> &[Drop] {
        &self.drops
    }

    /// Objects delivered to the home base.
    pub fn delivered(&self) -> usize {
        self.objects
            .iter()
            .filter(|o| o.state == ObjectState::Delivered)
            .count()
    }

    /// Whether an object is held.
    pub fn carrying(&self) -> bool {
        self.carried.is_some()
    }

    fn arm_down(&self) -> bool {
        self.arm >= f64::from(ARM_DOWN) - 5.0
    }

    fn fingers(&self, pose: Pose) -> Point {
        let (s, c) = pose.heading.sin_cos();
        self.fingers_along(pose, Vector::new(c, s))
    }

    fn fingers_along(&self, pose: Pose, heading: Vector) -> Point {
        Point::new(pose.x, pose.y) + heading * (self.body_radius_m + self.params.reach_m)
    }

    /// The nearest loose object within reach of `fingers`.
    fn loose_at(&self, fingers: Point) -> Option<usize> {
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.state == ObjectState::Loose)
            .map(|(i, o)| (i, (o.position - fingers).norm()))
            .filter(|&(_, d)| d <= self.params.pick_radius_m)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }
}

/// Landmark tower diameter, metres (seed 000 §5.4: about 4.8 cm).
pub const TOWER_M: f64 = 0.048;
/// Camera background (the bright wall behind the towers), 8-bit.
const BACKGROUND: f64 = 190.0;

/// The K213 line camera (seed 000 §1.1: 64 pixels, 8 bit, 36 deg) seeing the landmark towers
/// over the arena's low walls; nothing else is drawn (lamps, walls and objects are below its
/// line of sight). Each pixel is the ray through its centre (`Camera::pixel_angle`) from the
/// robot's centre (the paper's 5 mm offset is left out: Eq 29 makes it at most 1.5 mm). A
/// tower reads darker the nearer it is (§5.4: the minimum pixel value carries distance),
/// the background 190, plus Gaussian noise.
#[derive(Clone, Debug)]
pub struct LineCamera {
    present: bool,
    towers: Vec<Point>,
    sigma: f64,
    rng: SimRng,
}

impl LineCamera {
    /// A camera seeing `towers`; absent unless `present`.
    pub fn new(present: bool, towers: &[Point], sigma: f64, rng: SimRng) -> LineCamera {
        LineCamera {
            present,
            towers: towers.to_vec(),
            sigma,
            rng,
        }
    }

    /// One line from `pose`; false without a camera.
    pub fn read(&mut self, pose: Pose, image: &mut [u8; CAMERA_PIXELS]) -> bool {
        if !self.present {
            return false;
        }
        let cam = Camera::K213;
        let o = Point::new(pose.x, pose.y);
        for (i, px) in image.iter_mut().enumerate() {
            let a = pose.heading + f64::from(cam.pixel_angle(i as f32));
            let d = Vector::new(a.cos(), a.sin());
            let hit = self
                .towers
                .iter()
                .filter_map(|t| ray_circle(o, d, *t, TOWER_M / 2.0))
                .fold(f64::INFINITY, f64::min);
            // A tower is dark against the background, darker the nearer: 30 close up, 130
            // from 1 m on, still 60 below the background (the firmware's edge threshold is 20).
            let v = if hit.is_finite() {
                30.0 + 100.0 * hit.min(1.0)
            } else {
                BACKGROUND
            };
            *px = (v + self.rng.gaussian(self.sigma))
                .round()
                .clamp(0.0, 255.0) as u8;
        }
        true
    }
}

/// Distance along the ray `o + t d` (|d| = 1, t > 0) to a circle, if it hits.
fn ray_circle(o: Point, d: Vector, c: Point, r: f64) -> Option<f64> {
    let oc = c - o;
    let t = oc.dot(&d);
    let miss2 = oc.dot(&oc) - t * t;
    (t > 0.0 && miss2 <= r * r).then(|| t - (r * r - miss2).sqrt())
}

/// `from` moved towards `to` by at most `step`.
fn approach(from: f64, to: f64, step: f64) -> f64 {
    if (to - from).abs() <= step {
        to
    } else {
        from + step.copysign(to - from)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn site() -> ForageSite {
        ForageSite {
            home: Target {
                centre: Point::new(0.0, 0.0),
                radius_m: 0.1,
            },
            sources: vec![Light {
                position: Point::new(0.5, 0.0),
                height_m: 0.05,
                intensity: 1.0,
            }],
            sources_added: false,
            landmarks: [Point::new(0.0, 0.0); 3],
        }
    }

    fn run(g: &mut Gripper, pose: Pose, cmd: GripperCommand, ms: u64) {
        g.command(cmd);
        let heading = Vector::new(pose.heading.cos(), pose.heading.sin());
        for t in 0..ms {
            g.step(pose, heading, 1e-3, t);
        }
    }

    const DOWN_OPEN: GripperCommand = GripperCommand {
        arm: ARM_DOWN,
        closed: false,
    };
    const DOWN_CLOSED: GripperCommand = GripperCommand {
        arm: ARM_DOWN,
        closed: true,
    };
    const UP_CLOSED: GripperCommand = GripperCommand {
        arm: 0,
        closed: true,
    };

    #[test]
    fn an_object_at_the_fingers_is_picked_carried_and_delivered_at_home() {
        let mut g = Gripper::new(true, 0.0275, Some(&site()));
        // Fingers 3.95 cm ahead of the centre: the object at 0.5 m is within reach.
        let at_object = Pose {
            x: 0.5 - 0.0395,
            y: 0.005,
            heading: 0.0,
        };
        run(&mut g, at_object, DOWN_OPEN, 1200);
        assert!(g.read(at_object).is_some_and(|s| s.object && !s.closed));
        run(&mut g, at_object, DOWN_CLOSED, 400);
        run(&mut g, at_object, UP_CLOSED, 1200);
        let s = g.read(at_object).expect("present");
        assert!(s.object && s.closed && s.arm == 0);
        assert!(g.carrying());
        let home = Pose {
            x: -0.03,
            y: 0.0,
            heading: 0.0,
        };
        run(&mut g, home, DOWN_CLOSED, 1200);
        run(&mut g, home, DOWN_OPEN, 400);
        assert_eq!(g.delivered(), 1);
        assert!(g.drops()[0].delivered);
        assert!(!g.read(home).expect("present").object);
    }

    #[test]
    fn closing_away_from_an_object_grips_nothing_and_a_drop_outside_home_stays_loose() {
        let mut g = Gripper::new(true, 0.0275, Some(&site()));
        let away = Pose {
            x: 0.3,
            y: 0.0,
            heading: 0.0,
        };
        run(&mut g, away, DOWN_CLOSED, 1500);
        assert!(!g.read(away).expect("present").object);
        let at_object = Pose {
            x: 0.5 - 0.0395,
            y: 0.0,
            heading: 0.0,
        };
        run(&mut g, at_object, DOWN_OPEN, 400);
        run(&mut g, at_object, DOWN_CLOSED, 400);
        assert!(g.carrying());
        run(&mut g, away, DOWN_OPEN, 400);
        assert_eq!(g.delivered(), 0);
        assert_eq!(g.objects()[0].state, ObjectState::Loose);
        assert!(Gripper::new(false, 0.0275, None).read(away).is_none());
    }
}
