//! The board-independent part of the robot's Cortex-M4 image (`main.rs` is the image):
//!
//! - `board`: the main loop over a board's `Ports`: `Robot::step` unchanged, its `Hal` made
//!   of the station UART, the lockstep clock and the HIL UART's sensors and motors.
//! - `lockstep`: the clock that keeps the firmware's cycles on the world's time.
//! - `fifo`: the byte FIFOs between the UART interrupts and the loop.
//!
//! `no_std` and heap-free like the firmware; tested on the host against the emulator's world.
#![cfg_attr(not(test), no_std)]

pub mod board;
pub mod fifo;
pub mod lockstep;
