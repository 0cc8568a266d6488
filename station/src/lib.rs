//! The station: terminal UI and command line for a robot on a serial link.
//!
//! Layers, each importing only from those below it (`tests/tests/module_layers.rs` checks):
//! 1. `station_core` (its own crate: no terminal, no command line): the link, transfers,
//!    recordings, replay events, export, planning, retracing, calibration, formatting. Its
//!    modules are re-exported here under their own names (`station::link`, ...).
//! 2. The application: `action` (everything that can change the app, as data) and `app` (the
//!    state and `App::update`). No drawing, no terminal, no I/O.
//! 3. The views: `ui` (draw only) and `replay::screen`.
//! 4. The terminal and the command line: `tui` (the terminal loop), `input` (keys and mouse to
//!    actions), `fleet` (one app per robot), `replay` (a recording driving the app), `places`;
//!    `cli` (the clap definitions), `headless` (their dispatch), `commands` (one module per
//!    command that works without the TUI).
//!
//! Data flows one way: terminal and link events become `action::Action`s, `app::App::update`
//! applies them, `ui::render` draws the app. One task (`link`) owns the serial port.
#![deny(unsafe_code)]

pub mod action;
pub mod app;
pub mod cli;
pub mod commands;
pub mod fleet;
pub mod headless;
pub mod input;
pub mod places;
pub mod replay;
pub mod tui;
pub mod ui;

pub use station_core::{
    arena, awaited_replies, builtin, calibrate, export, format, input_file, json_text, link,
    output_file, pace, param_file, plan, qt_state, record, retrace, share, task_end, terminal_text,
    transfer, watch,
};
