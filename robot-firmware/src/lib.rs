//! The robot's own software. `#![no_std]`, no heap: every piece of state has a size fixed at
//! compile time, so the firmware's memory use is known before it runs. The same code runs on a
//! microcontroller and inside the emulator, which implements the `Hal` trait over a simulated
//! world. Its navigation modules (`nav`) are also linked by the station, so a map segmented or a
//! plan made on either side of the link is the same.
//!
//! - `robot`: `Robot::step`, the main loop over a `Hal`; `robot::kit`, which capabilities'
//!   state each profile's robot carries.
//! - `hal`, `profile`: the hardware boundary and the three robots of the papers.
//! - `alice`: seed 001's ALICE: its situations (kind 16) and its wandering.
//! - `hal_trace`: the hardware trace, recorded at that boundary, for retracing a run.
//! - `link`, `params`, `robot::telemetry`: the robot's side of the protocol.
//! - `transfer`: the robot's map, plan and regions objects, their uploads and downloads.
//! - `odometry`, `deadreckon`: position (seed 000 §3; seed 004 §4).
//! - `behaviour`, `guided`: reflexive behaviours (seed 000 §4) and guided motion (seed 004 §7).
//! - `nav`: occupancy grid, square segmentation, A* (seed 004 §5-6).
//! - `scripted`: a scripted `Hal` for host tests and benchmarks.
#![no_std]
#![deny(unsafe_code)]

pub mod alice;
pub mod behaviour;
pub mod deadreckon;
pub mod execute;
pub mod explore;
pub mod guided;
pub mod hal;
pub mod hal_trace;
pub mod landmarks;
pub mod light_calibration;
pub mod link;
pub mod localize;
pub mod motion_progress;
pub mod nav;
pub mod odometry;
pub mod odometry_calibration;
pub mod odometry_manoeuvre;
pub mod odometry_stretch;
pub mod params;
pub mod profile;
pub mod robot;
pub mod scripted;
pub mod som;
pub mod transfer;
pub mod unsupervised;
pub mod wall_holder;

pub use hal::{BeaconReading, Hal, MotorCommand};
pub use profile::{Profile, ALICE, KHEPERA, MICRO_RATO};
pub use robot::{AnyRobot, Robot, RobotOptions};

/// Side of the square map the firmware holds, in cells (seed 004 used 17 x 17).
pub const MAP_CAPACITY: usize = 64;
