//! The qualitative topological (QT) world model of seed 001 (ALICE, chapters 4-5), as one
//! library with no I/O: a growing network of cells over situation vectors (light readings,
//! smoothed touch readings, position; rotated by the heading), winner search within g_search
//! through a spatial index, winner and neighbour adaptation, insertion by rho_s and by
//! accumulated error, edges with confidences, position and orientation correlation, and A*
//! navigation over the cell graph.
//!
//! Where it runs: on the station (and in the emulator's scenarios), fed by the robot's
//! situation messages. It needs a heap and far more memory than a 32 KB robot has: each cell
//! holds a 50-value situation (400 bytes as f64) plus edges and index entries, and a 3 x 3 m
//! arena takes a few hundred cells (ALICE carried 16 MB); the firmware stays heap-free.

pub mod execute;
pub mod index;
pub mod model;
pub mod navigate;
pub mod network;
pub mod params;
pub mod situation;

pub use model::{QtModel, Sample, Stats};
pub use network::{Cell, Network, WinnerChange};
pub use params::{OrMethod, ParamError, Params, PosDistance};
pub use situation::Pose;
