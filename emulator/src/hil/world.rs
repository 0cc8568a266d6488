//! The world's side of the HIL exchange (docs/hil.md §2) over an emulator `Sim`, as a state
//! machine: bytes from the board in, bytes to it out, no I/O and no clock of its own.
//!
//! Lockstep: the world moves only when the board answers a `Sensors` with the `Motors` of
//! the same sequence number; it then advances one control period (the profile's `cycle_us`)
//! in the simulation's 1 ms steps under those motors and sends the next `Sensors`. The world
//! is thus a function of the seed and the motor commands alone, however fast or slow the
//! board runs. The firmware inside `Sim` is never stepped: the board's is the robot.
//!
//! Untrusted input: a frame that fails its CRC or layout is counted and ignored; a `Motors`
//! of another sequence number (a repeat, or one from before a board reset) changes nothing.

use protocol::hil::{self, HilDecoder, Msg, Setup, Xy, HIL_VERSION};
use protocol::sign::KEY_LEN;
use protocol::Mode;
use robot_firmware::hal::GripperCommand;
use robot_firmware::{Hal, MotorCommand};
use serde::Serialize;
use thiserror::Error;

use crate::geometry::Point;
use crate::sim::{firmware_seed, Sim, STEP_US};

/// Why the world cannot go on with this board.
#[derive(Debug, Error, PartialEq)]
pub enum HilWorldError {
    #[error(
        "the board's image is built for profile {board:?}, the world runs {world:?} (build the \
         image with that profile's feature, or run the world with --profile)"
    )]
    ProfileMismatch {
        board: protocol::ProfileId,
        world: protocol::ProfileId,
    },
    #[error("the board speaks HIL version {0}, this world {HIL_VERSION}")]
    Version(u8),
    #[error("the profile's control period {0} µs is not a whole number of milliseconds")]
    Period(u32),
}

/// What a run did, for `--json` and the benches.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct HilSummary {
    /// Exchanges completed (periods the world advanced).
    pub exchanges: u64,
    pub world_time_s: f64,
    /// Times the board powered on (more than one: it was reset).
    pub power_ons: u32,
    /// Frames from the board that failed their CRC or layout.
    pub frame_errors: u32,
    /// `Motors` of another sequence number than the one awaited.
    pub stale_motors: u32,
    /// World time the true position first entered the target area (the beacon's circle).
    pub target_reached_s: Option<f64>,
    pub collisions: u32,
    pub distance_m: f64,
    /// At the end: the true position in the target area, and the motors stopped (the
    /// firmware declared its arrival there: a search ends in `Idle`).
    pub final_in_target: bool,
    pub final_stopped: bool,
    /// Exchanges with the motors running.
    pub moving_exchanges: u64,
    /// The board's last `Report` (its own measures, docs/hil.md §4).
    pub board: Option<hil::Report>,
    /// The fault the board stopped with, if it did.
    pub fault: Option<String>,
    /// A digest of every exchange (sensors sent, motors received): same seed and same motor
    /// commands, same digest.
    pub digest: String,
    /// When the motors stopped (running before, STOP from this exchange), as
    /// `CLOCK_MONOTONIC` seconds on this machine, so a bench on the same machine can time a
    /// Stop from its write to the wheels (the first `MAX_STOPS_KEPT`; `serve` fills it).
    pub motor_stops_monotonic_s: Vec<f64>,
    /// The station link's relay (`--drop-rate`, `--flip-rate`, `--stall`, `--line-baud`),
    /// when it ran through the world.
    pub relay: Option<super::relay::RelayStats>,
}

/// Motor stops timed in a summary, at most.
pub const MAX_STOPS_KEPT: usize = 1000;

/// The world serving one board.
pub struct HilWorld {
    sim: Sim,
    decoder: HilDecoder,
    setup: Setup,
    /// The sequence number whose `Motors` the world waits for; `None` before a `PowerOn`.
    awaiting: Option<u32>,
    /// World time at the board's last power-on, µs: its clock starts from 0 there.
    epoch_us: u64,
    period_steps: u64,
    summary: HilSummary,
    digest: u64,
    /// The motors of the last exchange ran.
    moving: bool,
    /// Exchanges whose motors stopped after running.
    stops: u64,
}

/// FNV-1a, 64 bits: a stable digest of the exchange (not a security measure).
fn fnv(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01B3);
    }
    h
}

impl HilWorld {
    /// Serves `sim`'s world to a board; `key` is handed to the image at power-on (the
    /// stand-in for a key provisioned in a real board's flash), `power_on_mode` a mode it
    /// enters at once (lockstep runs without a station).
    pub fn new(
        sim: Sim,
        key: Option<[u8; KEY_LEN]>,
        power_on_mode: Mode,
    ) -> Result<HilWorld, HilWorldError> {
        let profile = sim.robot().profile();
        let period_us = profile.cycle_us;
        if period_us == 0 || u64::from(period_us) % STEP_US != 0 {
            return Err(HilWorldError::Period(period_us));
        }
        let start = sim.truth();
        let world = sim.world();
        let b = world.arena().bounds;
        let xy = |p: Point| Xy {
            x: p.x as f32,
            y: p.y as f32,
        };
        // What `sim::tell_the_arena` tells an emulated robot: the beacon only to a robot
        // with a beacon sensor.
        let beacon = world
            .beacon()
            .filter(|_| profile.has(protocol::caps::BEACON))
            .map(|b| xy(b.position));
        let setup = Setup {
            version: HIL_VERSION,
            profile: profile.id,
            period_us,
            firmware_seed: firmware_seed(sim.seed()),
            start: [start.x as f32, start.y as f32, start.heading as f32],
            beacon,
            bounds: [xy(b.min), xy(b.max)],
            power_on_mode,
            key,
        };
        Ok(HilWorld {
            sim,
            decoder: HilDecoder::new(),
            setup,
            awaiting: None,
            epoch_us: 0,
            period_steps: u64::from(period_us) / STEP_US,
            summary: HilSummary::default(),
            digest: 0xCBF2_9CE4_8422_2325,
            moving: false,
            stops: 0,
        })
    }

    /// Takes bytes from the board, appends the world's answers to `out`. A board whose image
    /// does not fit this world is an error (the run cannot go on).
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<u8>) -> Result<(), HilWorldError> {
        for &b in bytes {
            match self.decoder.feed(b) {
                None => {}
                Some(Err(_)) => self.summary.frame_errors += 1,
                Some(Ok(msg)) => self.handle(msg, out)?,
            }
        }
        Ok(())
    }

    fn handle(&mut self, msg: Msg, out: &mut Vec<u8>) -> Result<(), HilWorldError> {
        match msg {
            Msg::PowerOn(p) => {
                if p.version != HIL_VERSION {
                    return Err(HilWorldError::Version(p.version));
                }
                if p.profile != self.setup.profile {
                    return Err(HilWorldError::ProfileMismatch {
                        board: p.profile,
                        world: self.setup.profile,
                    });
                }
                // A board reset: the body stays where it is, the motors stop (a board
                // resetting drops its motor outputs) and the board's clock restarts from 0.
                self.summary.power_ons += 1;
                self.epoch_us = self.sim.now_us();
                self.sim.hardware_mut().set_motors(MotorCommand::STOP);
                send(&Msg::Setup(self.setup), out);
                self.awaiting = Some(0);
                self.send_sensors(0, out);
            }
            Msg::Motors(m) => {
                if self.awaiting != Some(m.seq) {
                    self.summary.stale_motors += 1;
                    return Ok(());
                }
                self.digest = fnv(self.digest, &m.seq.to_le_bytes());
                self.digest = fnv(self.digest, &m.left.to_le_bytes());
                self.digest = fnv(self.digest, &m.right.to_le_bytes());
                let hw = self.sim.hardware_mut();
                let cmd = MotorCommand {
                    left: m.left,
                    right: m.right,
                };
                hw.set_motors(cmd);
                hw.set_gripper(GripperCommand {
                    arm: m.arm,
                    closed: m.closed,
                });
                let moving = cmd != MotorCommand::STOP;
                if moving {
                    self.summary.moving_exchanges += 1;
                } else if self.moving {
                    self.stops += 1;
                }
                self.moving = moving;
                for _ in 0..self.period_steps {
                    self.sim.advance_hardware();
                    self.check_target();
                }
                self.summary.exchanges += 1;
                let next = m.seq.wrapping_add(1);
                self.awaiting = Some(next);
                self.send_sensors(next, out);
            }
            Msg::Report(r) => self.summary.board = Some(r),
            Msg::Fault(code) => {
                self.summary.fault = Some(
                    match code {
                        hil::fault::PANIC => "panic",
                        hil::fault::HARD_FAULT => "hard fault",
                        hil::fault::BAD_SETUP => "the setup did not fit the image",
                        _ => "unknown fault",
                    }
                    .to_string(),
                );
                // A stopped board drives nothing.
                self.sim.hardware_mut().set_motors(MotorCommand::STOP);
                self.awaiting = None;
            }
            // World-to-board messages from the board: ignored, counted.
            Msg::Setup(_) | Msg::Sensors(_) => self.summary.frame_errors += 1,
        }
        Ok(())
    }

    fn check_target(&mut self) {
        if self.summary.target_reached_s.is_none() {
            let p = self.sim.truth();
            if self.sim.world().in_target(Point::new(p.x, p.y)) {
                self.summary.target_reached_s = Some(self.sim.now_us() as f64 * 1e-6);
            }
        }
    }

    /// Reads every sensor the firmware reads in a control cycle (`Robot::read_sensors`), once.
    fn send_sensors(&mut self, seq: u32, out: &mut Vec<u8>) {
        let time_us = self.sim.now_us() - self.epoch_us;
        let alice = self.setup.profile == protocol::ProfileId::Alice;
        let hw = self.sim.hardware_mut();
        let s = hil::Sensors {
            seq,
            time_us,
            ir: hw.ir(),
            ambient: hw.ambient(),
            compass: hw.compass(),
            ground: hw.ground(),
            line: hw.line(),
            beacon: hw.beacon().map(|b| (b.bearing_rad, b.strength)),
            battery_mv: hw.battery_mv(),
            encoders: hw.encoders(),
            gripper: hw.gripper().map(|g| (g.arm, g.closed, g.object)),
            whiskers: if alice { hw.whiskers() } else { None },
            photoresistors: if alice { hw.photoresistors() } else { None },
        };
        let start = out.len();
        send(&Msg::Sensors(s), out);
        self.digest = fnv(self.digest, &out[start..]);
    }

    /// The run so far.
    pub fn summary(&self) -> HilSummary {
        let mut s = self.summary.clone();
        s.world_time_s = self.sim.now_us() as f64 * 1e-6;
        s.collisions = self.sim.collisions();
        s.distance_m = self.sim.distance_m();
        let p = self.sim.truth();
        s.final_in_target = self.sim.world().in_target(Point::new(p.x, p.y));
        s.final_stopped = !self.moving;
        s.digest = format!("{:016x}", self.digest);
        s
    }

    /// Times the motors have stopped after running (`serve` times each).
    pub fn stops(&self) -> u64 {
        self.stops
    }

    /// Records the time of a stop (`serve`).
    pub fn note_stop_time(&mut self, monotonic_s: f64) {
        if self.summary.motor_stops_monotonic_s.len() < MAX_STOPS_KEPT {
            self.summary.motor_stops_monotonic_s.push(monotonic_s);
        }
    }

    /// The simulation (truth, world).
    pub fn sim(&self) -> &Sim {
        &self.sim
    }

    /// World time, µs.
    pub fn now_us(&self) -> u64 {
        self.sim.now_us()
    }
}

fn send(msg: &Msg, out: &mut Vec<u8>) {
    let mut buf = [0u8; hil::MAX_FRAME];
    // Every message fits MAX_FRAME (protocol::hil's sizes); an error would be a bug there,
    // and the message is then not sent rather than sent cut.
    if let Ok(n) = hil::encode(msg, &mut buf) {
        out.extend_from_slice(&buf[..n]);
    }
}

#[cfg(test)]
mod tests;
