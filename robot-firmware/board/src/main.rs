//! The robot's firmware as an image for a Cortex-M4 board: QEMU's mps2-an386 (docs/porting.md
//! walks through it as the worked example of a port).
//!
//! - `mps2`: the board's registers: UARTs, timers, interrupts, sleep, the stack's high-water
//!   mark, as the `Ports` of `robot_board::board`.
//! - `image`: reset, the robot in a static, the main loop, panics and faults.
//! - `profile`: the robot the image is built for (a cargo feature).
//!
//! Built for the host, the image is a stub that says how to build it.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod image;
#[cfg(target_os = "none")]
mod mps2;
#[cfg(target_os = "none")]
mod profile;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "robot-board is a Cortex-M4 image: cargo build -p robot-board --release --target \
         thumbv7em-none-eabihf, then robot-firmware/board/run.sh (docs/porting.md)"
    );
    std::process::exit(2);
}
