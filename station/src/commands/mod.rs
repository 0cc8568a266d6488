//! The commands that work without the TUI (`station send`, `record`, `export`, ...), one
//! module each: their arguments (clap) and what they print. `cli` names them, `headless`
//! dispatches them; the work itself is `station_core`'s.

pub mod args;
pub mod calibrate;
pub mod calibrate_odometry;
pub mod calibration;
pub mod connect;
pub mod export;
pub mod params;
pub mod plan;
pub mod ports;
pub mod record;
pub mod replay;
pub mod retrace;
pub mod send;
pub mod stats;
pub mod status;
pub mod transfer;
pub mod wait;
pub mod watch;
