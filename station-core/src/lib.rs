//! The station's core: everything the station does that is not a terminal or a command line.
//!
//! Layer: the lowest of the station's three (this crate; then `station`'s application state
//! and views; then its TUI loop and commands). It has no ratatui, crossterm or clap: its
//! `Cargo.toml` lists none, so the compiler keeps it so. What is here:
//!
//! - `link`: the port's owner: handshake, heartbeat, retries, reconnect, statistics; `pace`:
//!   the timer grid periodic work shares; `awaited_replies`: commands a caller waits on.
//! - `transfer`: map, plan and calibration uploads and downloads (the engine and its client).
//! - `record`, `replay`, `export`: recordings of both directions of a link, the events a
//!   recording replays as, their summary, and their export to MCAP and CSV.
//! - `plan`: planning on the station with the robot's own nav code.
//! - `retrace`: re-running a recorded run through the firmware's code over its hardware trace.
//! - `calibrate`: the Khepera's light -> angle map, trained from a recording.
//! - `param_file`: parameter files; `param_names`: parameters as users name them, with the
//!   closest names for a typo; `format`: values, modes, parameters and objects in words.
//! - `arena`: what the map draws of an arena; `qt_state`: ALICE's world model as the station
//!   runs it; `builtin`: the built-in emulator the station starts without `--port`.
//! - `watch`: the robot as JSON lines for scripts (`station watch`, `status`) and when a link
//!   counts as lost; `task_end`: how a task the station started ended (`send --wait`).
//! - `terminal_text`, `json_text`, `input_file`, `output_file`: the one sanitiser for text
//!   reaching a terminal, the one JSON writer, the one file reader and the one file writer
//!   (in the emulator crate, which writes and reads files the same way).
#![deny(unsafe_code)]

pub mod arena;
pub mod awaited_replies;
pub mod builtin;
pub mod calibrate;
pub mod export;
pub mod format;
pub use emulator::{input_file, json_text, output_file, terminal_text};
pub mod link;
pub mod pace;
pub mod param_file;
pub mod param_names;
pub mod plan;
pub mod qt_feed;
pub mod qt_state;
pub mod record;
pub mod replay;
pub mod retrace;
pub mod share;
pub mod task_end;
pub mod transfer;
pub mod watch;
