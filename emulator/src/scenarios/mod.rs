//! The papers' scenarios: headless runs of the simulated world that reproduce an experiment
//! and report on it, as fast as the host allows.
//!
//! Layer: above the world (the arenas, physics, sensor models, the UART, `Sim`, fleets), which
//! they may import; nothing of the world imports them (`tests/tests/module_layers.rs` checks
//! it). The command line (`cli`) is above both.
//!
//! - [`task`]: one task in one arena through the firmware's own command path (go-to, explore,
//!   explore-then-plan, reach-beacon), the runner the next ones share.
//! - [`contest`]: the Micro-Rato contest, several robots in one arena (seed 004).
//! - [`forage`]: foraging (seed 000 §7).
//! - [`lightmap`]: the light map of a Khepera box (seed 000 §5).
//! - [`odometry_laps`]: the odometry laps (seed 000 Tables 1-2).
//! - [`calibrate_odometry`]: the odometry calibration manoeuvre.
//! - [`line_correct`]: floor-grid line correction (seed 003).
//! - [`unsupervised_places`]: landmarks and places (seed 003 chapter 3).
//! - [`alice`]: ALICE's QT world model and the thesis's experiments (seed 001).
//! - [`bench`], [`fleet_bench`]: one task over many arenas and seeds; the contest over many
//!   arenas.

pub mod alice;
pub mod bench;
pub mod calibrate_odometry;
pub mod contest;
pub mod fleet_bench;
pub mod forage;
pub mod lightmap;
pub mod line_correct;
pub mod odometry_laps;
pub mod task;
pub mod unsupervised_places;
