//! The robot's firmware as an image for a Cortex-M4 board: QEMU's mps2-an386 (docs/porting.md
//! walks through it as the worked example of a port).
//!
//! - `board`: the main loop over a board's `Ports`: `Robot::step` unchanged, its `Hal` made
//!   of the station UART, the lockstep clock and the HIL UART's sensors and motors.
//! - `lockstep`: the clock that keeps the firmware's cycles on the world's time.
//! - `fifo`: the byte FIFOs between the UART interrupts and the loop.
//! - `mps2` (the image only): the board's registers: UARTs, timers, interrupts, sleep, the
//!   stack's high-water mark; `image`: reset, the robot in a static, panics and faults.
//!
//! Built for the host, the image is a stub that says how to build it; the plain modules are
//! tested there against the emulator's world (`board::tests`).
#![cfg_attr(target_os = "none", no_std, no_main)]

mod board;
mod fifo;
mod lockstep;
mod profile;

#[cfg(target_os = "none")]
mod image;
#[cfg(target_os = "none")]
mod mps2;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "robot-board is a Cortex-M4 image: cargo build -p robot-board --release --target \
         thumbv7em-none-eabihf, then robot-firmware/board/run.sh (docs/porting.md)"
    );
    std::process::exit(2);
}
