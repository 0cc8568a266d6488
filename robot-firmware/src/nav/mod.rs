//! Navigation: occupancy grid, square segmentation and A* over regions (seed 004 §5-6).
//! Heap-free: every algorithm works in storage the caller provides, so the firmware runs it in
//! fixed arrays and the station in vectors, with the same results.

pub mod grid;
