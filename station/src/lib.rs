//! The station: terminal UI and command line for a robot on a serial link.
//!
//! Data flows one way: terminal and link events become `action::Action`s, `app::App::update`
//! applies them, `ui::render` draws the app. One task (`link`) owns the serial port.
//!
//! - `link`: the port's owner: handshake, heartbeat, retries, reconnect, statistics.
//! - `action`, `app`, `input`: the UI's state machine and what feeds it; `fleet`: one `App`
//!   per robot when several are driven at once, and the picker.
//! - `ui`: drawing, pure.
//! - `params`: `station params` and its parameter files.
//! - `plan`: planning on the station with the robot's nav code (`station plan`, map layers).
//! - `record`, `replay`, `export`: recordings of both directions of a link, the TUI driven by
//!   one, and their export to MCAP and CSV.
//! - `transfer`: map and plan uploads and downloads (the engine, `station upload-map` ...).
//! - `tui`: the terminal loop; `pace`: the timer grid its periodic work shares; `cli`,
//!   `headless`, `builtin`: the binary's edge.
//! - `terminal_text`: the one sanitiser for wire- and file-supplied text before a terminal;
//!   `json_text`: JSON output by the same rule.
//! - `output_file`: how every file the station writes reaches its name (atomic, O_EXCL
//!   temporary, no special file replaced); `input_file`: how every file a user names is
//!   read (regular files only, a size limit per kind).
#![deny(unsafe_code)]

pub mod action;
pub mod app;
pub mod awaited_replies;
pub mod builtin;
pub mod calibrate;
pub mod calibrate_odometry;
pub mod cli;
pub mod export;
pub mod fleet;
pub mod headless;
pub mod input;
/// Lives in the emulator crate so that the emulator reads its arena and key files the same way.
pub use emulator::input_file;
pub mod link;
/// Lives in the emulator crate so that `robot-emulator arena generate` writes the same way.
pub use emulator::output_file;
pub mod pace;
pub mod params;
pub mod places;
pub mod plan;
pub mod record;
pub mod replay;
pub mod retrace;
/// Lives in the emulator crate so that the emulator's output follows the same rule.
pub use emulator::{json_text, terminal_text};
pub mod transfer;
pub mod tui;
pub mod ui;
