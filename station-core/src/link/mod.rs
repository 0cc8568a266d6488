//! The serial link: one task owns the port; everyone else talks to it over channels.
//!
//! Layer: between the transport (bytes) and the app (`LinkEvent`s). `machine` is the protocol
//! state with no I/O (handshake, heartbeat, commands with retries, link timeout, statistics);
//! `task` does the I/O around it and reconnects; `transport` is the byte-stream seam with a
//! real serial implementation (`serial`) and an in-memory one (`memory`); `sim` runs the real
//! robot firmware on the far end of an in-memory port, for tests and demos; `robot_ids` finds
//! two links whose robots state the same id; `line_phase` predicts when the robot's line
//! towards us is quiet, for commands that may wait for it.

pub mod api;
pub mod clock;
pub mod commands;
pub mod line_phase;
pub mod machine;
pub mod memory;
pub mod paced;
pub mod robot_ids;
pub mod serial;
pub mod sim;
pub mod stats;
pub mod task;
pub mod transport;

pub use api::{
    CommandFailure, CommandId, CommandOutcome, Connection, LinkEvent, LinkRequest, PeerInfo,
    SendWhen, TransferIn, TransferOut,
};
pub use machine::{LinkMachine, MachineConfig};
pub use stats::LinkStats;
pub use task::{spawn_link, LinkHandle, LinkOptions, RunningLink, TapDirection, TapRecord};
pub use transport::{Connector, OpenError, Transport};
