//! Hardware in the loop: the world served to a board that runs the firmware itself (docs/hil.md).
//!
//! - `world`: the exchange as a state machine over bytes (no I/O): the same `Sim` world,
//!   physics, noise and faults as `serve`, advanced one control period per `Motors` (lockstep).
//! - `serve`: the port it runs on (a tty such as QEMU's `-serial pty`, or a socket to a QEMU
//!   it starts itself, `qemu`), and the summary a run prints.
//! - `relay`: the station's link through the world, with the emulator's link faults and a
//!   line rate (optional).
//! - `qemu`: starting `qemu-system-arm -M mps2-an386` with the board image.
//!
//! Its command line is `cli::HilArgs`.

pub mod qemu;
pub mod relay;
pub mod serve;
pub mod world;

pub use world::{HilSummary, HilWorld, HilWorldError};
