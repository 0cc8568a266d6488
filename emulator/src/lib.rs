//! The robot emulator: the unchanged robot firmware driven by a simulated world.
#![deny(unsafe_code)]

pub mod alice;
pub mod arena;
pub mod arena_gen;
pub mod bench;
pub mod builtin;
pub mod cli;
pub mod fault;
pub mod fleet;
pub mod fleet_bench;
pub mod forage;
pub mod geometry;
pub mod hil;
pub mod input_file;
pub mod json_text;
pub mod line_correct;
pub mod link;
pub mod output_file;
pub mod physics;
pub mod power_on;
pub mod pty;
pub mod rng;
pub mod scenario;
pub mod sensors;
pub mod sent_bytes;
pub mod sim;
pub mod terminal_text;
pub mod uart;
pub mod unsupervised_places;
pub mod world;
