//! The simulated ALICE's situations as the wire carries them (PROTOCOL.md §6 kind 16): the
//! scenarios' body, sensors and wandering (`body`, `sensors`, `explore`) in `builtin:alice`,
//! one `protocol::AliceSituation` per sample (3 a second, the thesis's rate), quantised as an
//! ALICE sends them: light 0..=255, whisker bits, the odometry pose in mm and mrad.
//!
//! Layer: std, no I/O; a link (or a test) sends what `next` gives. The model is not run here:
//! the station builds it from these (`station::app::qt_feed`).

use protocol::{AliceSituation, ALICE_SENSORS};

use super::body::{Body, SPEED_M_S, SUBSTEPS, TURN_RAD_S};
use super::explore::{decide, Move};
use super::scenario::SAMPLES_PER_S;
use crate::arena::Light;
use crate::builtin::alice::alice;
use crate::geometry::{Point, SegmentSet};
use crate::rng::SimRng;
use crate::sensors::alice::Sensors;

/// A simulated ALICE wandering in `builtin:alice`, with the drifting odometry the thesis gives.
pub struct AliceStream {
    walls: SegmentSet,
    lights: Vec<Light>,
    /// The body: true and odometry poses.
    pub body: Body,
    sensors: Sensors,
    rng: SimRng,
    pending_turn: f64,
    seq: u16,
    time_ms: u32,
}

impl AliceStream {
    /// The run of `seed` (the same streams as the scenarios' seeds draw: drift on).
    pub fn new(seed: u64) -> Self {
        let arena = alice();
        let start = arena.starts[0];
        AliceStream {
            walls: arena.segment_set(),
            lights: arena.lights.clone(),
            body: Body::new(
                Point::new(start.x, start.y),
                start.heading,
                SimRng::new(seed, 101),
                true,
            ),
            sensors: Sensors::new(SimRng::new(seed, 102)),
            rng: SimRng::new(seed, 103),
            pending_turn: 0.0,
            seq: 0,
            time_ms: 0,
        }
    }

    /// Moves one sample period and returns the situation sensed at its end.
    pub fn next_situation(&mut self) -> AliceSituation {
        let dt = 1.0 / SAMPLES_PER_S / SUBSTEPS as f64;
        for _ in 0..SUBSTEPS {
            if self.pending_turn.abs() > 1e-9 {
                let step = self.pending_turn.clamp(-TURN_RAD_S * dt, TURN_RAD_S * dt);
                self.body.turn(step);
                self.pending_turn -= step;
            } else if !self.body.forward(&self.walls, SPEED_M_S * dt) {
                // Blocked before a whisker told: turn away at random (the reflex layer).
                self.pending_turn =
                    super::wrap(std::f64::consts::PI + (2.0 * self.rng.uniform() - 1.0) * 1.2);
            }
        }
        let touch = self
            .sensors
            .whiskers(&self.walls, self.body.at, self.body.heading);
        let light = self
            .sensors
            .light(&self.walls, &self.lights, self.body.at, self.body.heading);
        if self.pending_turn.abs() <= 1e-9 {
            if let Move::Turn(a) = decide(&touch, &mut self.rng) {
                self.pending_turn = a;
            }
        }
        self.time_ms = self
            .time_ms
            .wrapping_add((1000.0 / SAMPLES_PER_S).round() as u32);
        let s = situation(self.seq, self.time_ms, &touch, &light, self.body.odo);
        self.seq = self.seq.wrapping_add(1);
        s
    }
}

/// The wire's form of one sample: the readings as the robot's ports give them
/// (`sensors::whisker_bits`, `sensors::light_bytes`), built by the firmware's own
/// `robot_firmware::alice::situation::situation`, the one place a kind-16 frame is made.
pub fn situation(
    seq: u16,
    time_ms: u32,
    touch: &[bool; ALICE_SENSORS],
    light: &[f64; ALICE_SENSORS],
    odo: (f64, f64, f64),
) -> AliceSituation {
    robot_firmware::alice::situation::situation(
        seq,
        time_ms,
        crate::sensors::alice::whisker_bits(touch),
        crate::sensors::alice::light_bytes(light),
        robot_firmware::odometry::Pose::new(odo.0 as f32, odo.1 as f32, odo.2 as f32),
    )
}
