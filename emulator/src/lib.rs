//! The robot emulator: the unchanged robot firmware driven by a simulated world.
#![deny(unsafe_code)]

pub mod arena;
pub mod geometry;
pub mod pty;
pub mod fault;
pub mod link;
