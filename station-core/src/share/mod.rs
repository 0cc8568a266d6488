//! A shared link: the station that holds a robot's port serves it to the user's other station
//! programs over a local socket, as MAVProxy's `--out` and mavlink-router do, so `station
//! send`, `watch`, `status` and the rest work while the TUI holds the port.
//!
//! `hub` is the state machine (what each client is told, which commands go to the robot for
//! whom), `server` the socket and the client's connector, `path` where the socket lives.

pub mod hub;
pub mod path;
pub mod server;

pub use path::{runtime_dir, socket_path};
pub use server::{serving, share_link, ShareConnector, Shared};
