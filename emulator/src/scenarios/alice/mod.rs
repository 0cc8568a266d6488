//! Seed 001 (ALICE) chapters 4-5: the QT world model (`world_model`) fed by a simulated ALICE
//! in the thesis's test scene, and the thesis's experiments as scenarios with JSON reports
//! (`robot-emulator run --task alice-equilibrium|alice-eps-o|alice-correlation|alice-dynamic|
//! alice-eps-o-continued --seed N --json`), and §5.3's navigation (`--task alice-navigation`,
//! `navigation`).
//!
//! Layer: std, beside `unsupervised_places`. The world is its own small kinematic model (no
//! `Sim`: the firmware's `Robot` has no ALICE profile with 24 + 24 sensors), like the seed 003
//! scenario's. The model sees only the sensors and the drifting odometry; the truth is used for
//! the report only. Sampling as the thesis: 3 situations per second at 25 cm/s.
//!
//! The thesis's scenes are built-in arenas (`builtin::alice`) and ALICE's whiskers and
//! photoresistors a sensor model of the world (`sensors::alice`): the served ALICE
//! (`robot-emulator --profile alice`) reads the same ones.

pub mod body;
pub mod experiments;
pub mod explore;
pub mod metrics;
pub mod navigation;
pub mod scenario;
pub mod stream;

/// Angle wrapped to (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    world_model::model::wrap(a)
}
