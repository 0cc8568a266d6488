//! Replay in the terminal: a recording drives the app exactly as the live link did, at any
//! speed, with seek. The events a recording replays as, and its summary, are
//! `station_core::replay`'s (re-exported here); `screen` draws the progress bar, `session`
//! holds the apps a replay drives, `tui` is its terminal loop.

pub use station_core::replay::*;

pub mod screen;
pub mod session;
pub mod tui;
