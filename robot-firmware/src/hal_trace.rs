//! The hardware trace: everything the `Hal` gave the firmware, recorded at the one place the
//! firmware meets its hardware, so a station can feed it to the same code again (retracing,
//! seed 001 §3.1.2; `station retrace`).
//!
//! Layer: between `Robot::step` and its `Hal`. While parameter 34 `hal_trace` is on,
//! `Robot::step` wraps the board's `Hal` in a [`Recorder`], which passes every call through
//! and appends what came back (and the motor and gripper commands that went out) to the
//! robot's [`HalTrace`] as entries (format below, PROTOCOL.md §17). The entries leave as
//! `HalTrace` frames (kind 15) at every control cycle. `no_std`, heap-free: the pending bytes
//! live in a [`TRACE_BUFFER`]-byte queue.
//!
//! When the link cannot keep up (the queue is full), the pass of the main loop being recorded
//! is cut back to its start and it and every later pass are dropped until half the queue is
//! free again; then a `GAP` entry says how many passes are missing, and every frame carries the
//! running count (`dropped_steps`). A retrace stops at a gap: it cannot go on without inputs.
//!
//! Entry format (a byte stream; varint = unsigned LEB128, zigzag for signed):
//! - `START` (1): version u8 (1), profile u8, seed u32 LE, start x, y, heading f32 LE,
//!   steps before tracing varint (the passes made before, 0: from power-up; a robot
//!   idle between control cycles may make none, `Robot::idle_until_us`), emulated u8, beacon x, y f32, bounds
//!   min x, min y, max x, max y f32 — what the robot was started with and told.
//! - `IDLE` (2): n varint, dt varint: n passes of the main loop, each `dt` µs after the one
//!   before, in which the Hal gave nothing but the clock and took all bytes offered.
//! - `STEP` (3): dt varint: one pass, `dt` µs after the one before; its entries follow.
//! - `CLOCK` (4): dt varint: a further clock read in this pass, µs after the pass's first.
//! - `RX` (5): len varint, bytes: serial bytes read.
//! - `TX_SHORT` (6): n varint: the transmitter took only n of the bytes offered in this pass.
//! - `IR` (7), `AMBIENT` (8): 8 varints. `COMPASS` (9): f32; `NO_COMPASS` (10).
//! - `GROUND` (11), `LINE` (12): u8 0/1. `BEACON` (13): bearing f32, strength u8;
//!   `NO_BEACON` (14). `BATTERY` (15): mV varint.
//! - `ENCODERS` (16): left, right zigzag varints, the change since the last `ENCODERS` (from 0
//!   after `START`); `NO_ENCODERS` (17).
//! - `GRIPPER` (18): arm u8, flags u8 (bit 0 closed, bit 1 object); `NO_GRIPPER` (19).
//! - `CAMERA` (20): 64 bytes; `NO_CAMERA` (21).
//! - `MOTORS` (22): left, right zigzag varints (the command given). `GRIP_CMD` (23): arm u8,
//!   closed u8.
//! - `GAP` (24): n varint: n passes are missing here (the pass in progress included).
//! - `WHISKERS` (25): bits varint (ALICE's 24 whiskers); `NO_WHISKERS` (26).
//! - `LIGHT24` (27): 24 bytes (ALICE's photoresistors); `NO_LIGHT24` (28).

pub mod playback;

use heapless::Deque;
use protocol::{HalTrace as TraceMsg, Message, MAX_HAL_TRACE_CHUNK};

use crate::hal::{BeaconReading, GripperCommand, GripperState, Hal, MotorCommand, CAMERA_PIXELS};
use crate::link::Link;
use crate::odometry::{Point, Pose};

/// Bytes of trace the robot holds for the link.
pub const TRACE_BUFFER: usize = 512;
/// Version of the entry format in `START`.
pub const FORMAT_VERSION: u8 = 1;
/// Frames sent at most per pass, so a backlog cannot crowd out replies.
const FRAMES_PER_STEP: usize = 2;
/// Room for the largest single entry (a `START`, 49 bytes) on the stack.
const LARGEST_ENTRY: usize = 72;
const _: () = assert!(TRACE_BUFFER / 2 >= LARGEST_ENTRY);

/// Entry tags.
pub mod tag {
    pub const START: u8 = 1;
    pub const IDLE: u8 = 2;
    pub const STEP: u8 = 3;
    pub const CLOCK: u8 = 4;
    pub const RX: u8 = 5;
    pub const TX_SHORT: u8 = 6;
    pub const IR: u8 = 7;
    pub const AMBIENT: u8 = 8;
    pub const COMPASS: u8 = 9;
    pub const NO_COMPASS: u8 = 10;
    pub const GROUND: u8 = 11;
    pub const LINE: u8 = 12;
    pub const BEACON: u8 = 13;
    pub const NO_BEACON: u8 = 14;
    pub const BATTERY: u8 = 15;
    pub const ENCODERS: u8 = 16;
    pub const NO_ENCODERS: u8 = 17;
    pub const GRIPPER: u8 = 18;
    pub const NO_GRIPPER: u8 = 19;
    pub const CAMERA: u8 = 20;
    pub const NO_CAMERA: u8 = 21;
    pub const MOTORS: u8 = 22;
    pub const GRIP_CMD: u8 = 23;
    pub const GAP: u8 = 24;
    pub const WHISKERS: u8 = 25;
    pub const NO_WHISKERS: u8 = 26;
    pub const LIGHT24: u8 = 27;
    pub const NO_LIGHT24: u8 = 28;
}

/// What the robot was started with and told, as `START` carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartInfo {
    pub profile: u8,
    pub seed: u32,
    pub start: Pose,
    /// Passes of the main loop before tracing was switched on (0: the trace is complete).
    pub steps_before: u32,
    pub emulated: bool,
    pub beacon: Point,
    pub bounds_min: Point,
    pub bounds_max: Point,
}

/// A small encoder for one entry, on the stack.
struct Entry {
    buf: [u8; LARGEST_ENTRY],
    len: usize,
}

impl Entry {
    fn new(tag: u8) -> Entry {
        let mut e = Entry {
            buf: [0; LARGEST_ENTRY],
            len: 0,
        };
        e.u8(tag);
        e
    }
    fn u8(&mut self, b: u8) {
        if let Some(slot) = self.buf.get_mut(self.len) {
            *slot = b;
            self.len += 1;
        }
    }
    fn varint(&mut self, mut v: u64) {
        loop {
            let b = (v & 0x7f) as u8;
            v >>= 7;
            if v == 0 {
                self.u8(b);
                return;
            }
            self.u8(b | 0x80);
        }
    }
    fn zigzag(&mut self, v: i32) {
        self.varint(u64::from(((v << 1) ^ (v >> 31)) as u32));
    }
    fn f32(&mut self, v: f32) {
        for b in v.to_le_bytes() {
            self.u8(b);
        }
    }
    fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }
}

/// The trace's state in the robot.
pub struct HalTrace {
    on: bool,
    /// Bytes not yet sent.
    pending: Deque<u8, TRACE_BUFFER>,
    /// Stream offset of `pending`'s front.
    head: u32,
    /// Passes dropped since tracing was switched on.
    dropped_steps: u32,
    /// Passes dropped in the gap in progress (not yet marked).
    gap_steps: u32,
    /// Stream offset where the pass in progress started (its entries may be cut back to it).
    step_mark: u32,
    /// Whether the pass in progress has written an entry (then it is not idle).
    step_open: bool,
    /// The pass in progress: its first clock read, and whether the clock was read yet.
    step_clock: Option<u64>,
    /// The previous pass's first clock read.
    last_clock: Option<u64>,
    /// Idle passes not yet written: count and their spacing.
    idle: (u32, u64),
    last_encoders: [i32; 2],
    /// Passes of the main loop since power-up.
    steps: u32,
    /// Transmitter: bytes taken in this pass, and whether it took fewer than offered.
    tx_taken: u32,
    tx_short: bool,
    seed: u32,
    start: Pose,
}

impl HalTrace {
    /// Off, for a robot started with `seed` at `start`.
    pub const fn new(seed: u32, start: Pose) -> HalTrace {
        HalTrace {
            on: false,
            pending: Deque::new(),
            head: 0,
            dropped_steps: 0,
            gap_steps: 0,
            step_mark: 0,
            step_open: false,
            step_clock: None,
            last_clock: None,
            idle: (0, 0),
            last_encoders: [0, 0],
            steps: 0,
            tx_taken: 0,
            tx_short: false,
            seed,
            start,
        }
    }

    /// Whether tracing is on.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// Passes dropped since tracing was switched on.
    pub fn dropped_steps(&self) -> u32 {
        self.dropped_steps
    }

    /// Bytes waiting to be sent.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    /// Follows the switch at the start of a pass; on switching on, starts a new stream with
    /// `START` (`told`: the beacon and arena bounds the robot holds now).
    pub fn switch(&mut self, on: bool, profile: u8, emulated: bool, told: [Point; 3]) {
        if on && !self.on {
            let steps = self.steps;
            *self = HalTrace::new(self.seed, self.start);
            self.steps = steps;
            self.on = true;
            let mut e = Entry::new(tag::START);
            e.u8(FORMAT_VERSION);
            e.u8(profile);
            for b in self.seed.to_le_bytes() {
                e.u8(b);
            }
            e.f32(self.start.x);
            e.f32(self.start.y);
            e.f32(self.start.heading);
            e.varint(u64::from(steps));
            e.u8(u8::from(emulated));
            for p in told {
                e.f32(p.x);
                e.f32(p.y);
            }
            self.put(e.bytes());
        } else if !on && self.on {
            self.close_idle();
            self.on = false;
        }
        self.steps = self.steps.wrapping_add(1);
    }

    /// Counts a pass made with tracing off.
    pub fn count_untraced(&mut self) {
        self.steps = self.steps.wrapping_add(1);
    }

    fn in_gap(&self) -> bool {
        self.gap_steps > 0
    }

    fn end_offset(&self) -> u32 {
        self.head.wrapping_add(self.pending.len() as u32)
    }

    /// Appends bytes whole, or starts (or continues) a gap.
    fn put(&mut self, bytes: &[u8]) {
        if self.in_gap() {
            return;
        }
        if self.pending.capacity() - self.pending.len() < bytes.len() {
            // Cut the pass in progress back to its start (what of it was already sent stays:
            // the reader drops the pass before a gap).
            let keep = self.step_mark.wrapping_sub(self.head) as usize;
            while self.pending.len() > keep.min(self.pending.len()) {
                self.pending.pop_back();
            }
            self.gap_steps = 1;
            self.dropped_steps = self.dropped_steps.wrapping_add(1);
            return;
        }
        for &b in bytes {
            let _ = self.pending.push_back(b);
        }
    }

    fn close_idle(&mut self) {
        let (n, dt) = self.idle;
        if n > 0 {
            let mut e = Entry::new(tag::IDLE);
            e.varint(u64::from(n));
            e.varint(dt);
            self.put(e.bytes());
            self.idle = (0, 0);
        }
    }

    /// The pass's first entry: the idle passes before it, then its `STEP`.
    fn open_step(&mut self) {
        if self.step_open {
            return;
        }
        self.step_open = true;
        self.close_idle();
        self.step_mark = self.end_offset();
        let mut e = Entry::new(tag::STEP);
        e.varint(self.step_dt());
        self.put(e.bytes());
    }

    fn step_dt(&self) -> u64 {
        match (self.step_clock, self.last_clock) {
            (Some(now), Some(last)) => now.saturating_sub(last),
            (Some(now), None) => now,
            _ => 0,
        }
    }

    fn entry(&mut self, e: &Entry) {
        self.open_step();
        self.put(e.bytes());
    }

    /// The start of a pass (before its first Hal call).
    fn begin_step(&mut self) {
        self.step_open = false;
        self.step_clock = None;
        self.tx_taken = 0;
        self.tx_short = false;
        self.step_mark = self.end_offset();
        if self.in_gap() {
            let free = self.pending.capacity() - self.pending.len();
            if free >= TRACE_BUFFER / 2 {
                let n = self.gap_steps;
                self.gap_steps = 0;
                self.idle = (0, 0);
                let mut e = Entry::new(tag::GAP);
                e.varint(u64::from(n));
                self.put(e.bytes());
                self.step_mark = self.end_offset();
            } else {
                self.gap_steps = self.gap_steps.saturating_add(1);
                self.dropped_steps = self.dropped_steps.wrapping_add(1);
            }
        }
    }

    /// The end of a pass: its transmitter entry, or an idle pass counted.
    fn end_step(&mut self) {
        if self.tx_short {
            let mut e = Entry::new(tag::TX_SHORT);
            e.varint(u64::from(self.tx_taken));
            self.entry(&e);
        }
        if !self.step_open && !self.in_gap() {
            let dt = self.step_dt();
            if self.idle.0 > 0 && self.idle.1 != dt {
                self.close_idle();
            }
            self.idle = (self.idle.0 + 1, dt);
            if self.idle.0 == u32::MAX {
                self.close_idle();
            }
        }
        if self.step_clock.is_some() {
            self.last_clock = self.step_clock;
        }
    }

    /// Hands pending bytes to the link as `HalTrace` frames: after a control cycle (`cycle`),
    /// or whenever a frame's worth is waiting. Low priority: replies keep their reserve.
    pub fn emit(&mut self, link: &mut Link, now_ms: u32, cycle: bool) {
        if !link.connected() || !(cycle || self.pending.len() >= MAX_HAL_TRACE_CHUNK) {
            return;
        }
        for _ in 0..FRAMES_PER_STEP {
            let n = self.pending.len().min(MAX_HAL_TRACE_CHUNK);
            if n == 0 {
                return;
            }
            let mut chunk = [0u8; MAX_HAL_TRACE_CHUNK];
            for (slot, b) in chunk.iter_mut().zip(self.pending.iter()) {
                *slot = *b;
            }
            let msg = Message::HalTrace(TraceMsg {
                offset: self.head,
                dropped_steps: self.dropped_steps,
                data: &chunk[..n],
            });
            if !link.send_low_priority(&msg, now_ms) {
                return;
            }
            for _ in 0..n {
                self.pending.pop_front();
            }
            self.head = self.head.wrapping_add(n as u32);
        }
    }
}

/// The `Hal` as the firmware sees it while tracing: every call passed through and recorded.
pub struct Recorder<'a, H: Hal> {
    hal: &'a mut H,
    trace: &'a mut HalTrace,
}

impl<'a, H: Hal> Recorder<'a, H> {
    /// Starts recording one pass of the main loop.
    pub fn new(hal: &'a mut H, trace: &'a mut HalTrace) -> Self {
        trace.begin_step();
        Recorder { hal, trace }
    }

    /// The trace, to send it.
    pub fn trace(&mut self) -> &mut HalTrace {
        self.trace
    }

    /// Ends the pass.
    pub fn finish(self) {
        self.trace.end_step();
    }

    fn eight(&mut self, t: u8, v: &[u16; 8]) {
        let mut e = Entry::new(t);
        for &x in v {
            e.varint(u64::from(x));
        }
        self.trace.entry(&e);
    }

    fn flag(&mut self, t: u8, v: bool) {
        let mut e = Entry::new(t);
        e.u8(u8::from(v));
        self.trace.entry(&e);
    }
}

impl<H: Hal> Hal for Recorder<'_, H> {
    fn now_us(&mut self) -> u64 {
        let now = self.hal.now_us();
        match self.trace.step_clock {
            None => self.trace.step_clock = Some(now),
            Some(first) => {
                let mut e = Entry::new(tag::CLOCK);
                e.varint(now.saturating_sub(first));
                self.trace.entry(&e);
            }
        }
        now
    }

    fn set_motors(&mut self, cmd: MotorCommand) {
        self.hal.set_motors(cmd);
        let mut e = Entry::new(tag::MOTORS);
        e.zigzag(i32::from(cmd.left));
        e.zigzag(i32::from(cmd.right));
        self.trace.entry(&e);
    }

    fn encoders(&mut self) -> Option<[i32; 2]> {
        let v = self.hal.encoders();
        match v {
            Some(c) => {
                let last = self.trace.last_encoders;
                let mut e = Entry::new(tag::ENCODERS);
                e.zigzag(c[0].wrapping_sub(last[0]));
                e.zigzag(c[1].wrapping_sub(last[1]));
                self.trace.entry(&e);
                self.trace.last_encoders = c;
            }
            None => self.trace.entry(&Entry::new(tag::NO_ENCODERS)),
        }
        v
    }

    fn ir(&mut self) -> [u16; 8] {
        let v = self.hal.ir();
        self.eight(tag::IR, &v);
        v
    }

    fn ambient(&mut self) -> [u16; 8] {
        let v = self.hal.ambient();
        self.eight(tag::AMBIENT, &v);
        v
    }

    fn compass(&mut self) -> Option<f32> {
        let v = self.hal.compass();
        match v {
            Some(h) => {
                let mut e = Entry::new(tag::COMPASS);
                e.f32(h);
                self.trace.entry(&e);
            }
            None => self.trace.entry(&Entry::new(tag::NO_COMPASS)),
        }
        v
    }

    fn ground(&mut self) -> bool {
        let v = self.hal.ground();
        self.flag(tag::GROUND, v);
        v
    }

    fn line(&mut self) -> bool {
        let v = self.hal.line();
        self.flag(tag::LINE, v);
        v
    }

    fn beacon(&mut self) -> Option<BeaconReading> {
        let v = self.hal.beacon();
        match v {
            Some(b) => {
                let mut e = Entry::new(tag::BEACON);
                e.f32(b.bearing_rad);
                e.u8(b.strength);
                self.trace.entry(&e);
            }
            None => self.trace.entry(&Entry::new(tag::NO_BEACON)),
        }
        v
    }

    fn battery_mv(&mut self) -> u16 {
        let v = self.hal.battery_mv();
        let mut e = Entry::new(tag::BATTERY);
        e.varint(u64::from(v));
        self.trace.entry(&e);
        v
    }

    fn gripper(&mut self) -> Option<GripperState> {
        let v = self.hal.gripper();
        match v {
            Some(g) => {
                let mut e = Entry::new(tag::GRIPPER);
                e.u8(g.arm);
                e.u8(u8::from(g.closed) | (u8::from(g.object) << 1));
                self.trace.entry(&e);
            }
            None => self.trace.entry(&Entry::new(tag::NO_GRIPPER)),
        }
        v
    }

    fn set_gripper(&mut self, cmd: GripperCommand) {
        self.hal.set_gripper(cmd);
        let mut e = Entry::new(tag::GRIP_CMD);
        e.u8(cmd.arm);
        e.u8(u8::from(cmd.closed));
        self.trace.entry(&e);
    }

    fn camera(&mut self, image: &mut [u8; CAMERA_PIXELS]) -> bool {
        let ok = self.hal.camera(image);
        if ok {
            self.trace.open_step();
            self.trace.put(&[tag::CAMERA]);
            self.trace.put(image);
        } else {
            self.trace.entry(&Entry::new(tag::NO_CAMERA));
        }
        ok
    }

    fn whiskers(&mut self) -> Option<u32> {
        let v = self.hal.whiskers();
        match v {
            Some(bits) => {
                let mut e = Entry::new(tag::WHISKERS);
                e.varint(u64::from(bits));
                self.trace.entry(&e);
            }
            None => self.trace.entry(&Entry::new(tag::NO_WHISKERS)),
        }
        v
    }

    fn photoresistors(&mut self) -> Option<[u8; crate::alice::SENSORS]> {
        let v = self.hal.photoresistors();
        match v {
            Some(light) => {
                self.trace.open_step();
                self.trace.put(&[tag::LIGHT24]);
                self.trace.put(&light);
            }
            None => self.trace.entry(&Entry::new(tag::NO_LIGHT24)),
        }
        v
    }

    fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        let n = self.hal.serial_read(buf).min(buf.len());
        if n > 0 {
            let mut e = Entry::new(tag::RX);
            e.varint(n as u64);
            self.trace.entry(&e);
            self.trace.put(&buf[..n]);
        }
        n
    }

    fn serial_write(&mut self, bytes: &[u8]) -> usize {
        let n = self.hal.serial_write(bytes);
        if n < bytes.len() {
            self.trace.tx_short = true;
        }
        self.trace.tx_taken = self
            .trace
            .tx_taken
            .saturating_add(n.min(bytes.len()) as u32);
        n
    }
}
