//! The simulation: the unchanged firmware (`Robot`) stepped every simulated millisecond
//! against a `Hal` implemented over the world, the physics, the sensor models and the UART.
//!
//! Layer: std, the top of the emulator's core; the pty front end, the headless scenario
//! runners (`scenarios`) and the station's built-in emulator drive a [`Sim`]. One
//! [`Sim::step`] is one millisecond: `Robot::step` with the clock at `t` (it runs its control
//! cycle itself when due and reads the sensors then; skipped while the robot says it has
//! nothing to do before a later time, `Robot::idle_until_us`, and no byte comes), then the physics from `t` to `t + 1 ms`
//! under the motor command in force, then the UART up to `t + 1 ms`, with a further pass of
//! `Robot::step` at each moment within the step when a frame from the station completes (a
//! real robot's receive path acts on a frame when its delimiter arrives, issue 15).
//!
//! Invariants: the ground truth (pose, collisions, wheel bias) is never given to the
//! firmware: it sees only what `Hal` returns, and the truth leaves the emulator only through
//! the `EmuTruth` channel of the UART and the accessors here. The robot is created with
//! `emulated: true`, so its HelloReply carries `caps::EMULATED`. Determinism: everything
//! random is drawn from streams of `SimConfig::seed`, and no wall-clock time enters, so the
//! same seed and the same inputs give the same run bit for bit.
//!
//! What can fail: [`Sim::new`] with an invalid configuration or a start pose inside (or
//! overlapping) a wall ([`SimError`]). Stepping cannot fail.

use robot_firmware::hal::{GripperCommand, GripperState, CAMERA_PIXELS};
use robot_firmware::odometry::Pose as FwPose;
use robot_firmware::{AnyRobot, BeaconReading, Hal, MotorCommand, Profile, RobotOptions};
use thiserror::Error;

use crate::arena::{Arena, Light, Pose};
use crate::fleet::contact::{Neighbour, RobotContacts};
use crate::forage::{ForageSite, Gripper, LineCamera};
use crate::geometry::{Disc, Point};
use crate::physics::{Body, PhysicsError, PhysicsParams};
use crate::rng::{stream, SimRng};
use crate::sensors::ir::IrArray;
use crate::sensors::light::AmbientLight;
use crate::sensors::line::LineSensor;
use crate::sensors::rato::{Battery, BeaconSensor, Compass};
use crate::sensors::Noise;
use crate::uart::{TruthHistory, TruthSample, Uart, UartError, DEFAULT_BAUD};
use crate::world::{FloorGrid, World, WorldError};

/// One wheel's constant relative speed error for a run: Gaussian with sigma `sigma`, clipped
/// to two sigma. seed 003 §2.3.3 measured the Khepera's wheel speed error as AT MOST ±1 %
/// (sigma = dV/2 = 0.5 %); an unclipped Gaussian exceeds that bound on about 9 % of runs
/// (either wheel), and those runs' odometry drifts faster than any robot the thesis measured.
pub fn wheel_speed_error(rng: &mut SimRng, sigma: f64) -> f64 {
    let limit = 2.0 * sigma;
    rng.gaussian(sigma).clamp(-limit, limit)
}

/// One simulation step, microseconds.
pub const STEP_US: u64 = 1000;
/// Most extra passes of the robot's main loop in one step, one at each frame from the
/// station that completes mid-step (`Sim::step`): at 115200 baud a frame of at least 4 bytes
/// takes 0.35 ms, so real traffic needs 3; the bound keeps a flood of delimiters (untrusted
/// bytes) from multiplying the cost of a step, up to 10 Mbaud's 1000 bytes a millisecond.
pub const PASSES_PER_STEP: usize = 16;
const STEP_S: f64 = 1e-3;

/// How a run is set up. [`SimConfig::new`] gives the defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct SimConfig {
    /// Which robot.
    pub profile: &'static Profile,
    /// Seeds every random draw of the run (and the firmware's own).
    pub seed: u64,
    /// Sensor and motor noise levels.
    pub noise: Noise,
    /// Start pose; default the arena's first start pose, else [`World::free_spot`].
    pub start: Option<Pose>,
    /// True wheel distance; default the profile's nominal one (seed 000 §3: 0.0533 m
    /// reproduces Tables 1-2 with a nominal-52 mm odometry).
    pub true_wheel_distance_m: Option<f64>,
    /// Per-wheel relative speed bias; default drawn from `seed` with sigma `noise.motors`,
    /// clipped to two sigma ([`wheel_speed_error`]).
    pub wheel_bias: Option<[f64; 2]>,
    /// Slip: standard deviation of the fraction of ground travel lost, redrawn every 100 ms
    /// per wheel (0 = none).
    pub slip: f64,
    /// Floor grid pitch (seed 003: 0.10 m); `None` = no grid. Lines are 1 cm wide from the
    /// arena's lower-left corner.
    pub floor_grid_m: Option<f64>,
    /// Light sources added to the arena's.
    pub lights: Vec<Light>,
    /// Seed 000 §7 foraging: objects, home base, landmarks; default the built-in forage
    /// arena's own site, none elsewhere. Its drawn sources (if any) join the lights. Objects
    /// need a robot with a gripper.
    pub forage: Option<ForageSite>,
    /// Serial line rate.
    pub baud: u32,
}

impl SimConfig {
    /// Defaults for `profile`: seed 0, the papers' noise, 115200 baud, nothing else.
    pub fn new(profile: &'static Profile) -> SimConfig {
        SimConfig {
            profile,
            seed: 0,
            noise: Noise::default(),
            start: None,
            true_wheel_distance_m: None,
            wheel_bias: None,
            slip: 0.0,
            floor_grid_m: None,
            lights: Vec::new(),
            forage: None,
            baud: DEFAULT_BAUD,
        }
    }
}

/// Why a simulation cannot start.
#[derive(Debug, Error)]
pub enum SimError {
    /// The start pose puts the body inside or across a wall.
    #[error(
        "start pose ({x:.3} m, {y:.3} m) is inside a wall or closer to one than the robot's \
         radius ({radius_m:.3} m); start at a free spot (--start X,Y[,DEG]) or with a smaller \
         robot (--profile khepera)"
    )]
    StartInWall {
        /// Start x.
        x: f64,
        /// Start y.
        y: f64,
        /// Robot radius.
        radius_m: f64,
    },
    /// A start pose with a non-finite coordinate.
    #[error("start pose has a non-finite coordinate")]
    StartNotFinite,
    /// The arena reaches beyond the positions the link can carry.
    #[error("{arena}: {source}")]
    OutOfLinkRange {
        /// The arena's file (or built-in name).
        arena: String,
        /// The corner that does not fit.
        source: protocol::units::OutOfRange,
    },
    /// No start pose given, none in the arena, and no free spot found.
    #[error("arena {arena:?} has no start pose and no free spot for a {diameter_m} m robot")]
    NoFreeSpot {
        /// Arena name.
        arena: String,
        /// Robot diameter.
        diameter_m: f64,
    },
    /// No start pose given, none in the arena, and no free spot that reaches the goal.
    #[error(
        "arena {arena:?} gives no start pose (no grid file found with it) and no free spot \
         outside its goal area from which a {diameter_m} m robot can reach the goal; give \
         --start X,Y[,DEG] or --grid FILE"
    )]
    NoReachableStart {
        /// Arena name.
        arena: String,
        /// Robot diameter.
        diameter_m: f64,
    },
    /// Bad lights or floor grid.
    #[error(transparent)]
    World(#[from] WorldError),
    /// Bad wheel distance, bias or slip.
    #[error(transparent)]
    Physics(#[from] PhysicsError),
    /// Bad baud rate.
    #[error(transparent)]
    Uart(#[from] UartError),
}

/// The simulated hardware: everything `Hal` reads and writes.
pub struct SimHal {
    now_us: u64,
    profile: &'static Profile,
    world: World,
    body: Body,
    motor: MotorCommand,
    ir: IrArray,
    ambient: AmbientLight,
    line: LineSensor,
    compass: Compass,
    beacon: BeaconSensor,
    battery: Battery,
    uart: Uart,
    slip_rng: SimRng,
    gripper: Gripper,
    camera: LineCamera,
    /// The other robots in the world now (a fleet's; empty alone), for the physics.
    neighbours: Vec<Neighbour>,
    /// Their bodies, for the sensors.
    others: Vec<Disc>,
    robot_contacts: RobotContacts,
    /// ALICE's whiskers and photoresistors (seed 001), on the ALICE profile only.
    alice: Option<crate::sensors::alice::Sensors>,
}

impl Hal for SimHal {
    fn now_us(&mut self) -> u64 {
        self.now_us
    }

    fn set_motors(&mut self, cmd: MotorCommand) {
        self.motor = cmd;
    }

    fn encoders(&mut self) -> Option<[i32; 2]> {
        self.body.encoders()
    }

    fn ir(&mut self) -> [u16; 8] {
        self.ir
            .read_among(self.world.walls(), &self.others, self.body.pose())
    }

    fn ambient(&mut self) -> [u16; 8] {
        let lights = self.world.lights();
        self.ambient
            .read(self.world.walls(), lights, self.body.pose())
    }

    fn compass(&mut self) -> Option<f32> {
        self.compass.read(self.now_us, self.body.pose().heading)
    }

    fn ground(&mut self) -> bool {
        let p = self.body.pose();
        self.profile.has(protocol::caps::GROUND_SENSOR)
            && self.world.in_target(Point::new(p.x, p.y))
    }

    fn line(&mut self) -> bool {
        self.line.read()
    }

    /// The goal beacon's channel: the lab's first beacon, whose position the robot is told
    /// (parameters 21/22); the others, told apart, are not its.
    fn beacon(&mut self) -> Option<BeaconReading> {
        self.beacon
            .read_channel(self.world.beacons(), 0, &self.others, self.body.pose())
    }

    fn battery_mv(&mut self) -> u16 {
        self.battery.read()
    }

    fn gripper(&mut self) -> Option<GripperState> {
        self.gripper.read(self.body.pose())
    }

    fn set_gripper(&mut self, cmd: GripperCommand) {
        self.gripper.command(cmd);
    }

    fn camera(&mut self, image: &mut [u8; CAMERA_PIXELS]) -> bool {
        self.camera.read(self.body.pose(), image)
    }

    fn whiskers(&mut self) -> Option<u32> {
        let p = self.body.pose();
        let touch =
            self.alice
                .as_mut()?
                .whiskers(self.world.walls(), Point::new(p.x, p.y), p.heading);
        Some(crate::sensors::alice::whisker_bits(&touch))
    }

    fn photoresistors(&mut self) -> Option<[u8; robot_firmware::alice::SENSORS]> {
        let p = self.body.pose();
        let (walls, lights) = (self.world.walls(), self.world.lights());
        let light = self
            .alice
            .as_mut()?
            .light(walls, lights, Point::new(p.x, p.y), p.heading);
        Some(crate::sensors::alice::light_bytes(&light))
    }

    fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        self.uart.serial_read(buf)
    }

    fn serial_write(&mut self, bytes: &[u8]) -> usize {
        self.uart.serial_write(bytes)
    }
}

impl SimHal {
    /// Advances the physical world by one step under the motor command in force.
    fn advance(&mut self) {
        let level = self.battery.level();
        let before = self.body.pose();
        self.body.step(
            self.motor,
            level,
            self.world.walls(),
            STEP_S,
            &mut self.slip_rng,
        );
        self.robot_contacts.resolve(
            &mut self.body,
            Point::new(before.x, before.y),
            &self.neighbours,
            &self.world,
        );
        let max = f64::from(self.profile.motor_max.max(1));
        let effort = (f64::from(self.motor.left.unsigned_abs())
            + f64::from(self.motor.right.unsigned_abs()))
            / (2.0 * max);
        self.battery.drain(STEP_S, effort);
        if self.gripper.present() {
            self.gripper.step(
                self.body.pose(),
                self.body.heading_vector(),
                STEP_S,
                self.now_us / 1000 + 1,
            );
        }
        if self.line.present() {
            let p = self.body.pose();
            self.line.update(self.world.on_line(Point::new(p.x, p.y)));
        }
        self.now_us += STEP_US;
    }
}

/// What a robot is told about the arena it is put in, as it is told its
/// start: the goal light's position (seed 004 §5: known from the start) and the arena's
/// bounds (§4: the dead reckoning's validation rectangle). Without this the firmware keeps
/// its defaults, the seed 004 arena (a 5 x 5 m square, the beacon at its centre): in
/// Micro-Rato'99 the beacon is at (3.0, 2.571), so exploration headed for (2.5, 2.5) and every
/// beacon calibration pulled the believed position towards the wrong point. Every robot, with
/// a beacon sensor or not, is told the bounds: they also limit where go-to may send it.
fn tell_the_arena(robot: &mut AnyRobot, world: &World) {
    let fw = |p: Point| robot_firmware::odometry::Point::new(p.x as f32, p.y as f32);
    let beacon = robot.profile().has(protocol::caps::BEACON);
    let dead = robot.dead_mut();
    if let (Some(b), true) = (world.beacon(), beacon) {
        dead.params.beacon = fw(b.position);
    }
    let b = world.arena().bounds;
    // `set_bounds` validates the start again as given: the robot was built with the default
    // 5 x 5 m bounds, which had clamped a start beyond them (8 x 4 m lab: x 7.00 -> 4.88).
    dead.set_bounds(robot_firmware::deadreckon::Bounds {
        min: fw(b.min),
        max: fw(b.max),
        ..dead.params.bounds
    });
}

/// The seed of the firmware's own random draws in a run of `seed` (a board in the loop is
/// told the same, `hil`).
pub fn firmware_seed(seed: u64) -> u32 {
    SimRng::new(seed, stream::FIRMWARE).next_u64() as u32
}

/// The firmware instance of one simulated robot: the one place the emulator constructs a
/// `Robot` (a single robot and every robot of a fleet alike), told its start and its arena.
fn build_robot(profile: &'static Profile, seed: u64, start: Pose, world: &World) -> AnyRobot {
    let mut robot = AnyRobot::new(RobotOptions {
        profile,
        seed: firmware_seed(seed),
        // The robot is told where it starts (seed 004 §5: the start pose is known).
        start: FwPose::new(start.x as f32, start.y as f32, start.heading as f32),
        emulated: true,
        firmware_version: env!("CARGO_PKG_VERSION"),
    });
    tell_the_arena(&mut robot, world);
    robot
}

/// A running simulation.
pub struct Sim {
    /// The composition the profile uses (`robot_firmware::robot::kit`).
    robot: AnyRobot,
    /// Until when the robot's passes have nothing to do unless a byte comes
    /// (`AnyRobot::idle_until_us`; 0: a pass every step). Passes before then are skipped,
    /// which changes nothing but the time a run takes.
    robot_idle_until_us: u64,
    hal: SimHal,
    truth: TruthHistory,
    seed: u64,
    wheel_bias: [f64; 2],
    forage: Option<ForageSite>,
}

impl Sim {
    /// Builds the world, the body at its start pose and the robot (believing that pose).
    pub fn new(arena: Arena, cfg: SimConfig) -> Result<Sim, SimError> {
        // Every pose reported is whole millimetres in an i32 (PROTOCOL.md §6): an arena
        // beyond them could only be reported clamped, so it is refused here, by its corner.
        let b = arena.bounds;
        for (field, m) in [
            ("arena min x", b.min.x),
            ("arena min y", b.min.y),
            ("arena max x", b.max.x),
            ("arena max y", b.max.y),
        ] {
            protocol::units::mm_from_m(field, m).map_err(|source| SimError::OutOfLinkRange {
                arena: arena.source.display().to_string(),
                source,
            })?;
        }
        let profile = cfg.profile;
        let noise = cfg.noise.sanitised();
        let floor = match cfg.floor_grid_m {
            Some(pitch) => Some(FloorGrid::new(pitch, arena.bounds.min)?),
            None => None,
        };
        let mut lights = cfg.lights.clone();
        if let Some(site) = cfg.forage.as_ref().filter(|s| s.sources_added) {
            lights.extend(site.sources.iter().copied());
        }
        let world = World::new(arena, lights, floor)?;
        let forage = cfg.forage.clone().or_else(|| ForageSite::builtin(&world));
        let radius = f64::from(profile.body_diameter_m) / 2.0;
        let start = start_pose(&world, cfg.start, radius)?;

        let mut run_rng = SimRng::new(cfg.seed, stream::RUN);
        let drawn = [
            wheel_speed_error(&mut run_rng, noise.motors),
            wheel_speed_error(&mut run_rng, noise.motors),
        ];
        let wheel_bias = cfg.wheel_bias.unwrap_or(drawn);
        let mut params = PhysicsParams::for_profile(profile);
        params.wheel_bias = wheel_bias;
        params.slip_sigma = cfg.slip;
        if let Some(d) = cfg.true_wheel_distance_m {
            params.wheel_distance_m = d;
        }
        params.validate()?;

        let has = |bits| profile.has(bits);
        let seed = cfg.seed;
        let hal = SimHal {
            now_us: 0,
            profile,
            body: Body::new(params, start),
            motor: MotorCommand::STOP,
            ir: IrArray::new(
                profile,
                noise.obstacle_counts,
                noise.obstacle_gain_spread,
                &mut run_rng,
                SimRng::new(seed, stream::IR),
            ),
            ambient: AmbientLight::new(
                profile,
                noise.light_counts,
                SimRng::new(seed, stream::LIGHT),
            ),
            line: LineSensor::new(
                has(protocol::caps::LINE_SENSOR) && world.floor().is_some(),
                noise.line_miss,
                noise.line_double,
                SimRng::new(seed, stream::LINE),
            ),
            compass: Compass::new(
                has(protocol::caps::COMPASS),
                noise.compass_deg,
                SimRng::new(seed, stream::COMPASS),
            ),
            beacon: BeaconSensor::new(
                has(protocol::caps::BEACON),
                noise.beacon_deg,
                noise.beacon_strength,
                SimRng::new(seed, stream::BEACON),
            ),
            battery: Battery::for_profile(
                profile,
                noise.battery_mv,
                SimRng::new(seed, stream::BATTERY),
            ),
            uart: Uart::new(cfg.baud, true)?,
            slip_rng: SimRng::new(seed, stream::SLIP),
            gripper: Gripper::new(has(protocol::caps::GRIPPER), radius, forage.as_ref()),
            camera: LineCamera::new(
                has(protocol::caps::CAMERA),
                forage.as_ref().map_or(&[], |s| &s.landmarks[..]),
                // With the other sensors' noise on (`Noise::none` leaves it exact).
                if noise.light_counts > 0.0 {
                    crate::forage::CAMERA_NOISE_COUNTS
                } else {
                    0.0
                },
                SimRng::new(seed, crate::forage::CAMERA_STREAM),
            ),
            world,
            neighbours: Vec::new(),
            others: Vec::new(),
            robot_contacts: RobotContacts::default(),
            // Seed 001's sensor models, the same as the ALICE scenarios' (`sensors::alice`).
            alice: (profile.id == protocol::ProfileId::Alice)
                .then(|| crate::sensors::alice::Sensors::new(SimRng::new(seed, stream::ALICE))),
        };
        let robot = build_robot(profile, seed, start, &hal.world);
        let mut sim = Sim {
            robot,
            robot_idle_until_us: 0,
            hal,
            truth: TruthHistory::default(),
            seed,
            wheel_bias,
            forage,
        };
        sim.record_truth();
        Ok(sim)
    }

    /// Advances one millisecond.
    pub fn step(&mut self) {
        let start = self.hal.now_us;
        if start >= self.robot_idle_until_us || !self.hal.uart.nothing_for_robot() {
            self.robot_pass();
        }
        self.hal.advance();
        self.record_truth();
        let end = self.hal.now_us;
        if !self.hal.uart.nothing_for_robot() {
            self.pass_at_frame_ends(start, end);
        }
        self.hal.uart.tick(end, &self.truth);
    }

    /// Runs a pass of the robot's main loop (`Robot::step`, which services the link on every
    /// call and runs the control cycle only when due) at each moment within the step
    /// `(start, end)` when a frame from the station completes: a real robot's receive path
    /// acts on a frame when its delimiter arrives (an RX interrupt, or a main loop polling
    /// the UART far faster than the control cycle), not at the next millisecond (issue 15:
    /// that added 0.5 ms on average to every command's round trip). The line is moved on to
    /// that moment first, so the reply starts on the wire then. Times come from the UART's
    /// bit clock, so the run stays a function of the simulated clock and its inputs. The
    /// physics moves in whole steps, already done for this one: a motor command given
    /// mid-step takes effect at its end, within the simulation's 1 ms resolution. A station
    /// sending delimiters faster than frames (a flood of zeros) gets at most
    /// `PASSES_PER_STEP` such passes a step; the rest wait for the next step's start.
    fn pass_at_frame_ends(&mut self, start: u64, end: u64) {
        for _ in 0..PASSES_PER_STEP {
            let Some(at) = self
                .hal
                .uart
                .next_inbound_frame_end_us()
                .filter(|&t| t > start && t < end)
            else {
                return;
            };
            self.hal.uart.tick(at, &self.truth);
            self.hal.now_us = at;
            self.robot_pass();
            self.hal.now_us = end;
        }
    }

    /// One pass of the robot's main loop, and when the next one has work.
    fn robot_pass(&mut self) {
        self.robot.step(&mut self.hal);
        self.robot_idle_until_us = self.robot.idle_until_us().unwrap_or(0);
        // The id in force now (an operator may set it), so truth names the robot as it does;
        // only a pass (or `robot_mut`, which a pass follows) changes it.
        self.truth.robot_id = self.robot.config().robot_id;
        self.truth.binding = self.robot.link().binding();
    }

    /// Moves the wire on to `now_us` (at most this step's start), the robot not stepping: the
    /// serving loop calls it before each step, so the robot reads what completed by then
    /// (bytes from the station reach the line when they come, after the last step moved the
    /// wire to its end). A second call for the same time changes nothing.
    pub fn sync_line(&mut self, now_us: u64) {
        self.hal.uart.tick(now_us, &self.truth);
    }

    /// Tells this robot where the other robots of its world are now (a fleet does, before
    /// each step): its sensors see them and its body cannot enter them. Alone: none.
    pub fn set_neighbours(&mut self, neighbours: impl IntoIterator<Item = Neighbour>) {
        let hal = &mut self.hal;
        hal.neighbours.clear();
        hal.neighbours.extend(neighbours);
        hal.others.clear();
        hal.others.extend(hal.neighbours.iter().map(|n| n.body));
    }

    /// This robot's body as the others see it.
    pub fn disc(&self) -> Disc {
        let p = self.hal.body.pose();
        Disc {
            centre: Point::new(p.x, p.y),
            radius: self.hal.body.params().radius_m,
        }
    }

    /// Contacts with other robots so far (counted apart from wall contacts).
    pub fn robot_collisions(&self) -> u32 {
        self.hal.robot_contacts.collisions()
    }

    /// Advances `ms` milliseconds.
    pub fn run_for(&mut self, ms: u64) {
        for _ in 0..ms {
            self.step();
        }
    }

    fn record_truth(&mut self) {
        self.truth.push(TruthSample {
            time_ms: (self.hal.now_us / 1000) as u32,
            pose: self.hal.body.pose(),
            collisions: self.hal.body.collisions(),
        });
    }

    /// Simulated time, microseconds.
    pub fn now_us(&self) -> u64 {
        self.hal.now_us
    }

    /// Carries the robot to `pose` and sets it down at rest (between two runs, as an
    /// operator does). Only the world changes: what the robot believes is the robot's
    /// business (a station would tell it with `SetPose`).
    pub fn place(&mut self, pose: Pose) -> Result<(), SimError> {
        let radius = f64::from(self.hal.profile.body_diameter_m) / 2.0;
        let pose = start_pose(&self.hal.world, Some(pose), radius)?;
        self.hal.body.place(pose);
        Ok(())
    }

    /// The true pose.
    pub fn truth(&self) -> Pose {
        self.hal.body.pose()
    }

    /// The pose the firmware believes in.
    pub fn believed(&self) -> Pose {
        let p = self.robot.pose();
        Pose {
            x: f64::from(p.x),
            y: f64::from(p.y),
            heading: f64::from(p.heading),
        }
    }

    /// Distance between the true and the believed position, metres.
    pub fn pose_error_m(&self) -> f64 {
        let (t, b) = (self.truth(), self.believed());
        (t.x - b.x).hypot(t.y - b.y)
    }

    /// Wall contacts so far.
    pub fn collisions(&self) -> u32 {
        self.hal.body.collisions()
    }

    /// Ground distance travelled, metres.
    pub fn distance_m(&self) -> f64 {
        self.hal.body.distance_m()
    }

    /// The true physical state (wheel rotation, encoders, contact).
    pub fn body(&self) -> &Body {
        &self.hal.body
    }

    /// The wheel bias in force (drawn or given).
    pub fn wheel_bias(&self) -> [f64; 2] {
        self.wheel_bias
    }

    /// The run's seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The motor command the firmware last set.
    pub fn motor(&self) -> MotorCommand {
        self.hal.motor
    }

    /// True battery voltage, millivolts.
    pub fn battery_mv(&self) -> f64 {
        self.hal.battery.true_mv()
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.hal.world
    }

    /// The gripper turret and the objects (seed 000 §7).
    pub fn gripper(&self) -> &Gripper {
        &self.hal.gripper
    }

    /// The foraging site, if the run has one.
    pub fn forage_site(&self) -> Option<&ForageSite> {
        self.forage.as_ref()
    }

    /// The firmware.
    pub fn robot(&self) -> &AnyRobot {
        &self.robot
    }

    /// The firmware, mutably (headless runs command it directly).
    pub fn robot_mut(&mut self) -> &mut AnyRobot {
        // What the caller changes may give the next pass work.
        self.robot_idle_until_us = 0;
        &mut self.robot
    }

    /// The simulated hardware, for hardware in the loop (`hil`): a board's firmware reads
    /// these sensors and sets these motors through the HIL port; the firmware here is then
    /// never stepped.
    pub fn hardware_mut(&mut self) -> &mut SimHal {
        &mut self.hal
    }

    /// One step of the world without a pass of the firmware (`hil`): the physics under the
    /// motors in force, and the truth recorded.
    pub fn advance_hardware(&mut self) {
        self.hal.advance();
        self.record_truth();
    }

    /// The serial port (host side: `push_inbound`, `take_outbound`).
    pub fn uart(&self) -> &Uart {
        &self.hal.uart
    }

    /// The serial port, mutably.
    pub fn uart_mut(&mut self) -> &mut Uart {
        &mut self.hal.uart
    }
}

/// A start for an arena that gives none: [`World::free_spot`]'s first spot from which a robot
/// of `radius` reaches a goal target or the arena's goal point, outside every goal target
/// (the first free spot if the arena has no goal). A lab's lower-left corner can be a sealed pocket (issue 32: a start
/// there could never reach the beacon); no such spot at all is an error that says so.
fn start_reaching_goal(world: &World, radius: f64) -> Result<Point, SimError> {
    let arena = world.arena();
    let targets: Vec<(Point, f64)> = world
        .goal_targets()
        .map(|t| (t.centre, t.radius_m))
        .collect();
    let goal = arena.goal;
    let no_spot = || SimError::NoFreeSpot {
        arena: arena.name.clone(),
        diameter_m: 2.0 * radius,
    };
    if targets.is_empty() && goal.is_none() {
        return world.free_spot(radius).ok_or_else(no_spot);
    }
    let in_goal = |c: Point| {
        targets.iter().any(|&(t, r)| (c - t).norm() <= r)
            || goal.is_some_and(|g| (c - g).norm() <= radius)
    };
    let reach = crate::arena::reach::Reach::from(arena, radius, in_goal).map_err(|_| no_spot())?;
    // Outside the goal area: a start inside it has nothing to search for.
    world
        .free_spot_where(radius, |p| reach.holds(p) && !world.in_target(p))
        .ok_or_else(|| SimError::NoReachableStart {
            arena: arena.name.clone(),
            diameter_m: 2.0 * radius,
        })
}

/// The start pose: given, the arena's first, or (an arena without a start pose, e.g. a lab
/// whose grid file is missing) the first free spot from which the robot can reach the goal;
/// checked free.
pub fn start_pose(world: &World, given: Option<Pose>, radius: f64) -> Result<Pose, SimError> {
    let pose = match given.or_else(|| world.arena().starts.first().copied()) {
        Some(p) => p,
        None => {
            let p = start_reaching_goal(world, radius)?;
            Pose {
                x: p.x,
                y: p.y,
                heading: 0.0,
            }
        }
    };
    if !(pose.x.is_finite() && pose.y.is_finite() && pose.heading.is_finite()) {
        return Err(SimError::StartNotFinite);
    }
    if !world.is_free(Point::new(pose.x, pose.y), radius) {
        return Err(SimError::StartInWall {
            x: pose.x,
            y: pose.y,
            radius_m: radius,
        });
    }
    Ok(Pose {
        heading: crate::physics::wrap_pi(pose.heading),
        ..pose
    })
}
