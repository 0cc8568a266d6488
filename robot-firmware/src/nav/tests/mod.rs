//! Tests of the navigation pipeline across modules (small unit tests sit beside each module).
//!
//! `util` builds grids from ASCII and runs the pipeline on `Vec` storage (the station's way);
//! `reference` holds deliberately naive re-implementations (Fig. 6 by the letter, O(R^2)
//! adjacency, Dijkstra) that the fast code is checked against.

// Lints denied in product code (workspace lints) are fine for test assertions.
#![allow(clippy::panic, clippy::unwrap_used)]

mod graph;
mod paper;
mod props;
mod reference;
mod search;
mod segmentation;
mod util;
mod wave;
