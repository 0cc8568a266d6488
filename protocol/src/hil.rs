//! Hardware in the loop: the small protocol between a board running the firmware and a
//! simulated world (docs/hil.md). The board's second UART carries the robot's motor commands
//! out and its sensor readings in; the world advances one control period per exchange
//! (lockstep), so a seed gives the same run however fast the board executes.
//!
//! Layer: pure functions over caller buffers, no heap, no panic, like `frame`. A frame is
//! `COBS([kind u8][body][crc32c u32 LE]) 0x00`, the CRC taken over kind and body; every
//! number is little-endian, every float an IEEE-754 `f32` that must be finite.
//! [`HilDecoder`] is fed bytes one at a time and yields whole messages or typed errors,
//! resynchronising at the next 0x00; a frame longer than [`MAX_ENCODED`] is dropped whole.
//!
//! The exchange (docs/hil.md §2): the board sends `PowerOn` (again every half second until
//! answered); the world answers `Setup` (what the robot is told at power-on: its seed, start,
//! arena, link key) and the `Sensors` of time 0. After each control cycle the board answers
//! the `Sensors` it used with `Motors` of the same sequence number; the world then advances
//! one period under them and sends the next `Sensors`. `Report` (the board's own measures)
//! and `Fault` (the board stopped) go board to world at any time.

use crate::frame::crc32c;
use crate::sign::KEY_LEN;
use crate::{Mode, ProfileId};

/// The HIL protocol's version, carried in `PowerOn` and `Setup`.
pub const HIL_VERSION: u8 = 1;
/// Largest decoded frame: kind + body + CRC.
pub const MAX_RAW: usize = 128;
/// Largest COBS-encoded frame without its delimiter.
pub const MAX_ENCODED: usize = MAX_RAW + 1;
/// Largest frame on the wire, with its 0x00 delimiter.
pub const MAX_FRAME: usize = MAX_ENCODED + 1;

const _: () = assert!(cobs::max_encoding_length(MAX_RAW) <= MAX_ENCODED);

/// Message kinds (the first decoded byte).
pub mod kind {
    pub const POWER_ON: u8 = 1;
    pub const SETUP: u8 = 2;
    pub const SENSORS: u8 = 3;
    pub const MOTORS: u8 = 4;
    pub const REPORT: u8 = 5;
    pub const FAULT: u8 = 6;
}

/// Board to world: the board is up and waits for its `Setup`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PowerOn {
    pub version: u8,
    /// The profile the image was built for; the world refuses another.
    pub profile: ProfileId,
}

/// Board to world, world to board: a point, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Xy {
    pub x: f32,
    pub y: f32,
}

/// World to board: what the robot is told at power-on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    pub version: u8,
    pub profile: ProfileId,
    /// The world's control period, µs: the profile's `cycle_us` (checked by the board).
    pub period_us: u32,
    /// Seeds the firmware's own random draws (`RobotOptions::seed`).
    pub firmware_seed: u32,
    /// Where the robot starts (metres, radians), as the emulator tells its robot.
    pub start: [f32; 3],
    /// The goal light's position, when the arena has one.
    pub beacon: Option<Xy>,
    /// The arena's inside: lower-left and upper-right corners.
    pub bounds: [Xy; 2],
    /// A mode to enter at power-on (`Idle`: none), for lockstep runs without a station.
    pub power_on_mode: Mode,
    /// The link key (PROTOCOL.md §13) the image signs with; a real board keeps its own.
    pub key: Option<[u8; KEY_LEN]>,
}

/// World to board: the sensors at `time_us`, in the firmware's `Hal` units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sensors {
    /// Exchange number: 0 for time 0, one more per period.
    pub seq: u32,
    /// World time, µs since power-on: `seq * period_us`.
    pub time_us: u64,
    pub ir: [u16; 8],
    pub ambient: [u16; 8],
    pub compass: Option<f32>,
    pub ground: bool,
    pub line: bool,
    /// Bearing (radians) and strength.
    pub beacon: Option<(f32, u8)>,
    pub battery_mv: u16,
    pub encoders: Option<[i32; 2]>,
    /// Arm position, grip closed, object between the fingers.
    pub gripper: Option<(u8, bool, bool)>,
    pub whiskers: Option<u32>,
    pub photoresistors: Option<[u8; 24]>,
}

/// Board to world: the motors (and gripper) the cycle of `Sensors::seq` left in force.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Motors {
    pub seq: u32,
    pub left: i16,
    pub right: i16,
    /// Gripper arm and grip (ignored without a gripper).
    pub arm: u8,
    pub closed: bool,
}

/// Board to world: the board's own measures (docs/hil.md §4), sent every few seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Report {
    /// RAM taken by statics (.data + .bss), bytes.
    pub static_ram: u32,
    /// The stack's reserved size and its high-water mark since boot, bytes.
    pub stack_size: u32,
    pub stack_used: u32,
    /// Station UART: bytes received, the receive FIFO's fullest, bytes it dropped full.
    pub rx_bytes: u32,
    pub rx_fifo_max: u32,
    pub rx_dropped: u32,
    /// Control cycles run, their last and largest cost in timer ticks (40 ns each).
    pub cycles: u32,
    pub cycle_ticks_last: u32,
    pub cycle_ticks_max: u32,
    /// Their ticks summed (wrapping; with `cycles`, the mean).
    pub cycle_ticks_sum: u32,
    /// Passes without a control cycle that read station bytes, the frames they decoded and
    /// their ticks summed and largest.
    pub rx_passes: u32,
    pub rx_frames: u32,
    pub rx_pass_ticks_sum: u32,
    pub rx_pass_ticks_max: u32,
    /// Times the board slept (WFI) and HIL frames it refused.
    pub sleeps: u32,
    pub hil_errors: u32,
}

const REPORT_FIELDS: usize = 16;

/// Why the board stopped (`Fault`).
pub mod fault {
    /// A Rust panic.
    pub const PANIC: u8 = 1;
    /// A HardFault (or another fault escalated to it).
    pub const HARD_FAULT: u8 = 2;
    /// The world's `Setup` did not fit the image (profile, period, version).
    pub const BAD_SETUP: u8 = 3;
}

/// One HIL message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Msg {
    PowerOn(PowerOn),
    Setup(Setup),
    Sensors(Sensors),
    Motors(Motors),
    Report(Report),
    Fault(u8),
}

/// What is wrong with a frame or a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HilError {
    /// The output buffer is smaller than `MAX_FRAME`.
    OutputTooSmall,
    /// Longer than `MAX_ENCODED` before its delimiter.
    Oversize,
    BadCobs,
    /// Shorter than a kind and a CRC.
    TooShort,
    BadCrc,
    UnknownKind(u8),
    /// The body's length is not the kind's.
    BadLength,
    /// A float that is NaN or infinite.
    NotFinite,
    /// A profile, mode or flag value this version does not know.
    BadValue,
}

impl core::fmt::Display for HilError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HilError::OutputTooSmall => write!(f, "output buffer too small"),
            HilError::Oversize => write!(f, "frame longer than {MAX_ENCODED} bytes"),
            HilError::BadCobs => write!(f, "bad COBS encoding"),
            HilError::TooShort => write!(f, "frame too short"),
            HilError::BadCrc => write!(f, "bad CRC"),
            HilError::UnknownKind(k) => write!(f, "unknown message kind {k}"),
            HilError::BadLength => write!(f, "message body of the wrong length"),
            HilError::NotFinite => write!(f, "a number is NaN or infinite"),
            HilError::BadValue => write!(f, "a profile, mode or flag value out of range"),
        }
    }
}

/// Profile ids on the HIL wire (the `ProfileId` order).
fn profile_byte(p: ProfileId) -> u8 {
    match p {
        ProfileId::Khepera => 0,
        ProfileId::MicroRato => 1,
        ProfileId::Alice => 2,
    }
}

fn profile_from(b: u8) -> Result<ProfileId, HilError> {
    match b {
        0 => Ok(ProfileId::Khepera),
        1 => Ok(ProfileId::MicroRato),
        2 => Ok(ProfileId::Alice),
        _ => Err(HilError::BadValue),
    }
}

/// Power-on modes on the wire: only those a robot can run without a station's command data.
fn mode_byte(m: Mode) -> u8 {
    match m {
        Mode::Wander => 1,
        Mode::Explore => 2,
        _ => 0,
    }
}

fn mode_from(b: u8) -> Result<Mode, HilError> {
    match b {
        0 => Ok(Mode::Idle),
        1 => Ok(Mode::Wander),
        2 => Ok(Mode::Explore),
        _ => Err(HilError::BadValue),
    }
}

/// A little-endian writer over a fixed buffer; writes past its end are dropped and flagged.
struct Writer<'a> {
    buf: &'a mut [u8],
    len: usize,
    overflow: bool,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        match self.buf.get_mut(self.len..self.len + b.len()) {
            Some(dst) => {
                dst.copy_from_slice(b);
                self.len += b.len();
            }
            None => self.overflow = true,
        }
    }
    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }
    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn i32(&mut self, v: i32) {
        self.bytes(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
}

/// A little-endian reader; reading past the end is an error, never a panic.
struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], HilError> {
        let s = self
            .buf
            .get(self.at..self.at + N)
            .ok_or(HilError::BadLength)?;
        self.at += N;
        let mut out = [0u8; N];
        out.copy_from_slice(s);
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, HilError> {
        Ok(self.take::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16, HilError> {
        Ok(u16::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> Result<u32, HilError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, HilError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn i16(&mut self) -> Result<i16, HilError> {
        Ok(i16::from_le_bytes(self.take()?))
    }
    fn i32(&mut self) -> Result<i32, HilError> {
        Ok(i32::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Result<f32, HilError> {
        let v = f32::from_le_bytes(self.take()?);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(HilError::NotFinite)
        }
    }
    fn xy(&mut self) -> Result<Xy, HilError> {
        Ok(Xy {
            x: self.f32()?,
            y: self.f32()?,
        })
    }
    fn end(&self) -> Result<(), HilError> {
        if self.at == self.buf.len() {
            Ok(())
        } else {
            Err(HilError::BadLength)
        }
    }
}

// Sensors flags.
const S_COMPASS: u16 = 1 << 0;
const S_GROUND: u16 = 1 << 1;
const S_LINE: u16 = 1 << 2;
const S_BEACON: u16 = 1 << 3;
const S_ENCODERS: u16 = 1 << 4;
const S_GRIPPER: u16 = 1 << 5;
const S_WHISKERS: u16 = 1 << 6;
const S_PHOTO: u16 = 1 << 7;
const S_KNOWN: u16 = 0xFF;
// Setup flags.
const SETUP_BEACON: u8 = 1 << 0;
const SETUP_KEY: u8 = 1 << 1;

fn body(msg: &Msg, w: &mut Writer<'_>) {
    match msg {
        Msg::PowerOn(p) => {
            w.u8(kind::POWER_ON);
            w.u8(p.version);
            w.u8(profile_byte(p.profile));
        }
        Msg::Setup(s) => {
            w.u8(kind::SETUP);
            w.u8(s.version);
            w.u8(profile_byte(s.profile));
            let flags = if s.beacon.is_some() { SETUP_BEACON } else { 0 }
                | if s.key.is_some() { SETUP_KEY } else { 0 };
            w.u8(flags);
            w.u32(s.period_us);
            w.u32(s.firmware_seed);
            for v in s.start {
                w.f32(v);
            }
            let b = s.beacon.unwrap_or_default();
            w.f32(b.x);
            w.f32(b.y);
            for c in s.bounds {
                w.f32(c.x);
                w.f32(c.y);
            }
            w.u8(mode_byte(s.power_on_mode));
            w.bytes(&s.key.unwrap_or([0; KEY_LEN]));
        }
        Msg::Sensors(s) => {
            w.u8(kind::SENSORS);
            w.u32(s.seq);
            w.bytes(&s.time_us.to_le_bytes());
            let flag = |on: bool, bit: u16| if on { bit } else { 0 };
            let flags = flag(s.compass.is_some(), S_COMPASS)
                | flag(s.ground, S_GROUND)
                | flag(s.line, S_LINE)
                | flag(s.beacon.is_some(), S_BEACON)
                | flag(s.encoders.is_some(), S_ENCODERS)
                | flag(s.gripper.is_some(), S_GRIPPER)
                | flag(s.whiskers.is_some(), S_WHISKERS)
                | flag(s.photoresistors.is_some(), S_PHOTO);
            w.u16(flags);
            for v in s.ir.iter().chain(s.ambient.iter()) {
                w.u16(*v);
            }
            w.f32(s.compass.unwrap_or(0.0));
            let (bearing, strength) = s.beacon.unwrap_or((0.0, 0));
            w.f32(bearing);
            w.u8(strength);
            w.u16(s.battery_mv);
            let [l, r] = s.encoders.unwrap_or([0, 0]);
            w.i32(l);
            w.i32(r);
            if let Some((arm, closed, object)) = s.gripper {
                w.u8(arm);
                w.u8(u8::from(closed));
                w.u8(u8::from(object));
            }
            if let Some(bits) = s.whiskers {
                w.u32(bits);
            }
            if let Some(p) = s.photoresistors {
                w.bytes(&p);
            }
        }
        Msg::Motors(m) => {
            w.u8(kind::MOTORS);
            w.u32(m.seq);
            w.bytes(&m.left.to_le_bytes());
            w.bytes(&m.right.to_le_bytes());
            w.u8(m.arm);
            w.u8(u8::from(m.closed));
        }
        Msg::Report(r) => {
            w.u8(kind::REPORT);
            for v in report_fields(r) {
                w.u32(v);
            }
        }
        Msg::Fault(code) => {
            w.u8(kind::FAULT);
            w.u8(*code);
        }
    }
}

fn report_fields(r: &Report) -> [u32; REPORT_FIELDS] {
    [
        r.static_ram,
        r.stack_size,
        r.stack_used,
        r.rx_bytes,
        r.rx_fifo_max,
        r.rx_dropped,
        r.cycles,
        r.cycle_ticks_last,
        r.cycle_ticks_max,
        r.cycle_ticks_sum,
        r.rx_passes,
        r.rx_frames,
        r.rx_pass_ticks_sum,
        r.rx_pass_ticks_max,
        r.sleeps,
        r.hil_errors,
    ]
}

/// Encodes `msg` as one frame, delimiter included, into `out` (at least `MAX_FRAME` bytes
/// are always enough); returns the frame's length.
pub fn encode(msg: &Msg, out: &mut [u8]) -> Result<usize, HilError> {
    let mut raw = [0u8; MAX_RAW];
    let mut w = Writer {
        buf: &mut raw,
        len: 0,
        overflow: false,
    };
    body(msg, &mut w);
    let len = w.len;
    let crc = crc32c(raw.get(..len).ok_or(HilError::OutputTooSmall)?);
    let end = len + 4;
    raw.get_mut(len..end)
        .ok_or(HilError::OutputTooSmall)?
        .copy_from_slice(&crc.to_le_bytes());
    let n = cobs::try_encode(&raw[..end], out).map_err(|_| HilError::OutputTooSmall)?;
    *out.get_mut(n).ok_or(HilError::OutputTooSmall)? = 0;
    Ok(n + 1)
}

/// Parses one decoded frame (COBS removed, no delimiter): checks the CRC and the kind's body.
pub fn parse(raw: &[u8]) -> Result<Msg, HilError> {
    if raw.len() < 5 {
        return Err(HilError::TooShort);
    }
    let (data, crc) = raw.split_at(raw.len() - 4);
    let mut c = [0u8; 4];
    c.copy_from_slice(crc);
    if crc32c(data) != u32::from_le_bytes(c) {
        return Err(HilError::BadCrc);
    }
    let (&k, rest) = data.split_first().ok_or(HilError::TooShort)?;
    let mut r = Reader { buf: rest, at: 0 };
    let msg = match k {
        kind::POWER_ON => Msg::PowerOn(PowerOn {
            version: r.u8()?,
            profile: profile_from(r.u8()?)?,
        }),
        kind::SETUP => {
            let version = r.u8()?;
            let profile = profile_from(r.u8()?)?;
            let flags = r.u8()?;
            if flags & !(SETUP_BEACON | SETUP_KEY) != 0 {
                return Err(HilError::BadValue);
            }
            let period_us = r.u32()?;
            let firmware_seed = r.u32()?;
            let start = [r.f32()?, r.f32()?, r.f32()?];
            let beacon = r.xy()?;
            let bounds = [r.xy()?, r.xy()?];
            let power_on_mode = mode_from(r.u8()?)?;
            let key = r.take::<KEY_LEN>()?;
            Msg::Setup(Setup {
                version,
                profile,
                period_us,
                firmware_seed,
                start,
                beacon: (flags & SETUP_BEACON != 0).then_some(beacon),
                bounds,
                power_on_mode,
                key: (flags & SETUP_KEY != 0).then_some(key),
            })
        }
        kind::SENSORS => {
            let seq = r.u32()?;
            let time_us = r.u64()?;
            let flags = r.u16()?;
            if flags & !S_KNOWN != 0 {
                return Err(HilError::BadValue);
            }
            let mut ir = [0u16; 8];
            for v in ir.iter_mut() {
                *v = r.u16()?;
            }
            let mut ambient = [0u16; 8];
            for v in ambient.iter_mut() {
                *v = r.u16()?;
            }
            let compass = r.f32()?;
            let bearing = r.f32()?;
            let strength = r.u8()?;
            let battery_mv = r.u16()?;
            let encoders = [r.i32()?, r.i32()?];
            let on = |bit: u16| flags & bit != 0;
            let gripper = if on(S_GRIPPER) {
                Some((r.u8()?, r.u8()? != 0, r.u8()? != 0))
            } else {
                None
            };
            let whiskers = if on(S_WHISKERS) { Some(r.u32()?) } else { None };
            let photoresistors = if on(S_PHOTO) {
                Some(r.take::<24>()?)
            } else {
                None
            };
            Msg::Sensors(Sensors {
                seq,
                time_us,
                ir,
                ambient,
                compass: on(S_COMPASS).then_some(compass),
                ground: on(S_GROUND),
                line: on(S_LINE),
                beacon: on(S_BEACON).then_some((bearing, strength)),
                battery_mv,
                encoders: on(S_ENCODERS).then_some(encoders),
                gripper,
                whiskers,
                photoresistors,
            })
        }
        kind::MOTORS => Msg::Motors(Motors {
            seq: r.u32()?,
            left: r.i16()?,
            right: r.i16()?,
            arm: r.u8()?,
            closed: r.u8()? != 0,
        }),
        kind::REPORT => {
            let mut f = [0u32; REPORT_FIELDS];
            for v in f.iter_mut() {
                *v = r.u32()?;
            }
            let [static_ram, stack_size, stack_used, rx_bytes, rx_fifo_max, rx_dropped, cycles, cycle_ticks_last, cycle_ticks_max, cycle_ticks_sum, rx_passes, rx_frames, rx_pass_ticks_sum, rx_pass_ticks_max, sleeps, hil_errors] =
                f;
            Msg::Report(Report {
                static_ram,
                stack_size,
                stack_used,
                rx_bytes,
                rx_fifo_max,
                rx_dropped,
                cycles,
                cycle_ticks_last,
                cycle_ticks_max,
                cycle_ticks_sum,
                rx_passes,
                rx_frames,
                rx_pass_ticks_sum,
                rx_pass_ticks_max,
                sleeps,
                hil_errors,
            })
        }
        kind::FAULT => Msg::Fault(r.u8()?),
        other => return Err(HilError::UnknownKind(other)),
    };
    r.end()?;
    Ok(msg)
}

/// Counters of what the decoder saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HilStats {
    pub frames_ok: u32,
    pub errors: u32,
}

/// Byte-at-a-time frame decoder with one fixed buffer.
pub struct HilDecoder {
    buf: [u8; MAX_ENCODED],
    len: usize,
    /// The frame being received overflowed the buffer: drop it at its delimiter.
    overflow: bool,
    stats: HilStats,
}

impl Default for HilDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl HilDecoder {
    pub const fn new() -> Self {
        HilDecoder {
            buf: [0; MAX_ENCODED],
            len: 0,
            overflow: false,
            stats: HilStats {
                frames_ok: 0,
                errors: 0,
            },
        }
    }

    pub fn stats(&self) -> HilStats {
        self.stats
    }

    /// Takes one byte; at a delimiter, the message it ended (or why it was refused). Empty
    /// frames (two delimiters in a row, or a leading one) yield nothing.
    pub fn feed(&mut self, byte: u8) -> Option<Result<Msg, HilError>> {
        if byte != 0 {
            match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => self.overflow = true,
            }
            return None;
        }
        let (len, overflow) = (self.len, self.overflow);
        self.len = 0;
        self.overflow = false;
        if len == 0 && !overflow {
            return None;
        }
        let result = if overflow {
            Err(HilError::Oversize)
        } else {
            match self.buf.get_mut(..len).map(cobs::decode_in_place) {
                Some(Ok(n)) => self.buf.get(..n).map_or(Err(HilError::BadCobs), parse),
                _ => Err(HilError::BadCobs),
            }
        };
        match result {
            Ok(_) => self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1),
            Err(_) => self.stats.errors = self.stats.errors.wrapping_add(1),
        }
        Some(result)
    }
}

#[cfg(test)]
mod tests;
