//! The robot emulator: the unchanged robot firmware driven by a simulated world.
//!
//! Two parts and the command line above them:
//! - the world: arenas and their importers (`arena`, `arena_gen`, `builtin`), geometry,
//!   physics, the sensor models, the UART timed at the baud rate, `sim::Sim` (one millisecond
//!   of the firmware against the world), fault injection, several robots in one world
//!   (`fleet`), the pty loop (`link`, `pty`), hardware in the loop (`hil`), and the files and
//!   text they read and write;
//! - [`scenarios`]: the papers' scenarios and the benchmarks, on top of the world. The world
//!   never imports them (`tests/tests/module_layers.rs` checks it).
//!
//! `cli` parses the command line of both; the binary (`main.rs`) runs it.
#![deny(unsafe_code)]

// The world.
pub mod arena;
pub mod arena_gen;
pub mod builtin;
pub mod fault;
pub mod fleet;
pub mod forage;
pub mod geometry;
pub mod hil;
pub mod input_file;
pub mod json_text;
pub mod link;
pub mod output_file;
pub mod physics;
pub mod power_on;
pub mod pty;
pub mod rng;
pub mod sensors;
pub mod sent_bytes;
pub mod sim;
pub mod terminal_text;
pub mod uart;
pub mod world;

// The papers' scenarios, on top of the world.
pub mod scenarios;

// The command line.
pub mod cli;
