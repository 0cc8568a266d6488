//! A robot powered on by the station: `robot-emulator --hal-trace` holds the simulation at
//! power-up until the first byte from the station arrives, so the robot's hardware trace
//! (`robot_firmware::hal_trace`, on from power-up) reaches the station whole and
//! `station retrace` can start from the robot's first pass of the main loop.
//!
//! Layer: a `Device` wrapper for the serving loop. While held, simulated time runs on for the
//! loop's pacing only (an offset), the robot does not step; from the first byte on, every call
//! goes to the robot, its clock counting from its own 0.

use crate::link::Device;

/// A device that powers on at the station's first byte.
pub struct PoweredByStation<D: Device> {
    dev: D,
    /// Simulated time that passed before power-on, µs.
    held_us: u64,
    on: bool,
}

impl<D: Device> PoweredByStation<D> {
    pub fn new(dev: D) -> Self {
        PoweredByStation {
            dev,
            held_us: 0,
            on: false,
        }
    }
}

impl<D: Device> Device for PoweredByStation<D> {
    fn now_us(&self) -> u64 {
        self.held_us + self.dev.now_us()
    }
    fn step_ms(&mut self) {
        if self.on {
            self.dev.step_ms();
        } else {
            self.held_us += 1000;
        }
    }
    fn push_inbound(&mut self, bytes: &[u8]) {
        self.on |= !bytes.is_empty();
        self.dev.push_inbound(bytes);
    }
    fn take_outbound(&mut self, out: &mut Vec<u8>) {
        self.dev.take_outbound(out);
    }
    // The robot's own clock counts from power-on: times from the loop lose the held span.
    fn push_inbound_at(&mut self, bytes: &[u8], at_us: u64) {
        self.on |= !bytes.is_empty();
        self.dev
            .push_inbound_at(bytes, at_us.saturating_sub(self.held_us));
    }
    fn take_outbound_until(&mut self, until_us: u64, out: &mut Vec<u8>) {
        self.dev
            .take_outbound_until(until_us.saturating_sub(self.held_us), out);
    }
    fn sync_line(&mut self, now_us: u64) {
        if self.on {
            self.dev.sync_line(now_us.saturating_sub(self.held_us));
        }
    }
    fn next_frame_end_us(&self) -> Option<u64> {
        self.dev.next_frame_end_us().map(|t| t + self.held_us)
    }
    fn cycles(&self) -> u32 {
        self.dev.cycles()
    }
    fn cycle_us(&self) -> u32 {
        self.dev.cycle_us()
    }
    fn to_robot_dropped(&self) -> u64 {
        self.dev.to_robot_dropped()
    }
    fn next_due_us(&self) -> u64 {
        self.held_us + self.dev.next_due_us()
    }
    fn set_link_key(&mut self, key: Option<&[u8; protocol::sign::KEY_LEN]>) {
        self.dev.set_link_key(key);
    }
}
