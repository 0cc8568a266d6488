//! ALICE (seed 001 §3.1): the robot's side of the QT world model. ALICE carried 24 binary
//! whiskers and 24 photoresistors around a 40 cm body and drove at 25 cm/s; three times a
//! second it sampled its situation (its readings and its odometry's pose), and the world model
//! (chapters 4-5) learned from it. The model needs a heap and far more memory than this
//! firmware has (ALICE carried 16 MB), so the robot streams its situations (message kind 16)
//! and the station builds the network (`world-model`, `station::app::qt_feed`).
//!
//! - `situation`: the wire form of one sample and its 3 Hz schedule: the one place a kind-16
//!   frame is built, on the robot and in the emulator's scenarios alike.
//! - `wander`: what ALICE did while the model learned: straight until a whisker touches,
//!   turn away from the touch, stochastic turns (§6.2's instincts fused by priority).
//!
//! `no_std`, heap-free; the robot side (`robot::alice`) runs them in `Mode::Wander` on the
//! ALICE composition (`robot::kit::Alice`).

pub mod situation;
pub mod wander;

/// Sensors of each kind (seed 001 §3.1), sensor `i` looking `i * 15` degrees anticlockwise
/// from the robot's forward axis.
pub const SENSORS: usize = protocol::ALICE_SENSORS;

/// Direction of sensor `i` from the robot's forward axis, radians anticlockwise.
pub fn sensor_angle_rad(i: usize) -> f32 {
    i as f32 * core::f32::consts::TAU / SENSORS as f32
}
