//! The robot's own software. `#![no_std]`, no heap: every piece of state has a size fixed at
//! compile time, so the firmware's memory use is known before it runs. The same code runs on a
//! microcontroller and inside the emulator, which implements the `Hal` trait over a simulated
//! world. Its navigation modules (`nav`) are also linked by the station, so a map segmented or a
//! plan made on either side of the link is the same.
#![no_std]
#![deny(unsafe_code)]

pub mod nav;
pub mod behaviour;
pub mod deadreckon;
pub mod odometry;
