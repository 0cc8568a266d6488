//! Playing a hardware trace back: a `Hal` that gives the firmware what the recorded `Hal` gave
//! it, pass by pass, and keeps what the firmware does with it (motor and gripper commands,
//! serial bytes out) for the caller to compare.
//!
//! Layer: the reading half of `hal_trace`, pure over a borrowed stream, `no_std` and
//! heap-free like the recorder, so a host (`station retrace`) and the firmware's own tests
//! share it. The caller calls [`Playback::next_step`] before each `Robot::step`. A value the
//! firmware asks for that the pass did not record (a changed parameter made it read the camera
//! in another cycle, say) is answered with the last value seen, or the sensor's "absent"
//! value, and counted as a miss: with the recorded parameters a miss is a divergence.
//! What can fail: a malformed stream ([`TraceError`], with its byte offset), never a panic;
//! every read is bounded by a length check.

use super::{tag, StartInfo, FORMAT_VERSION};
use crate::hal::{BeaconReading, GripperCommand, GripperState, Hal, MotorCommand, CAMERA_PIXELS};
use crate::odometry::{Point, Pose};

/// Extra clock reads kept per pass.
const CLOCKS: usize = 4;
/// Serial reads kept per pass.
const READS: usize = 16;
/// Motor or gripper commands kept per pass.
const COMMANDS: usize = 4;
/// Serial bytes the firmware may write in one pass (its whole transmit queue).
pub const OUT_CAPACITY: usize = crate::link::TX_QUEUE;

/// Why a trace could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceError {
    /// The stream ends inside an entry.
    Truncated { offset: usize },
    /// An entry tag the format does not have.
    UnknownTag { offset: usize, tag: u8 },
    /// A varint longer than its type, or a value out of its range.
    BadValue { offset: usize, field: &'static str },
    /// The stream does not begin with `START`, or has another format version.
    NoStart { offset: usize },
    /// More entries of one kind in a pass than a pass can make.
    TooMany { offset: usize, what: &'static str },
    /// More passes, or more robot time, between two control cycles than the firmware makes
    /// (see [`Playback`]'s bound): `claimed` against `limit`, in `unit`.
    Implausible {
        offset: usize,
        field: &'static str,
        claimed: u64,
        limit: u64,
        unit: &'static str,
    },
}

impl core::fmt::Display for TraceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            TraceError::Truncated { offset } => {
                write!(f, "trace byte {offset}: the trace ends inside an entry")
            }
            TraceError::UnknownTag { offset, tag } => {
                write!(f, "trace byte {offset}: unknown entry tag {tag}")
            }
            TraceError::BadValue { offset, field } => {
                write!(f, "trace byte {offset}: {field} is not a valid value")
            }
            TraceError::NoStart { offset } => write!(
                f,
                "trace byte {offset}: the trace does not start with a START entry of format {FORMAT_VERSION}"
            ),
            TraceError::TooMany { offset, what } => {
                write!(f, "trace byte {offset}: more {what} in one pass than a pass makes")
            }
            TraceError::Implausible {
                offset,
                field,
                claimed,
                limit,
                unit,
            } => write!(
                f,
                "trace byte {offset}: {field} makes {claimed} {unit} without a control cycle; \
                 the firmware runs one every {period} us and makes at most a pass a \
                 microsecond, so at most {limit} {unit} come between two (two periods)",
                period = limit / 2
            ),
        }
    }
}

/// A cursor over the stream.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn u8(&mut self) -> Result<u8, TraceError> {
        let b = *self
            .bytes
            .get(self.at)
            .ok_or(TraceError::Truncated { offset: self.at })?;
        self.at += 1;
        Ok(b)
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], TraceError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(TraceError::Truncated { offset: self.at })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn varint(&mut self, field: &'static str) -> Result<u64, TraceError> {
        let start = self.at;
        let mut v = 0u64;
        for i in 0..10 {
            let b = self.u8()?;
            v |= u64::from(b & 0x7f) << (7 * i);
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(TraceError::BadValue {
            offset: start,
            field,
        })
    }
    fn small(&mut self, field: &'static str, max: u64) -> Result<u64, TraceError> {
        let start = self.at;
        let v = self.varint(field)?;
        if v > max {
            return Err(TraceError::BadValue {
                offset: start,
                field,
            });
        }
        Ok(v)
    }
    fn zigzag(&mut self, field: &'static str) -> Result<i32, TraceError> {
        let v = self.small(field, u64::from(u32::MAX))? as u32;
        Ok(((v >> 1) as i32) ^ -((v & 1) as i32))
    }
    fn f32(&mut self) -> Result<f32, TraceError> {
        let b = self.take(4)?;
        Ok(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn eight(&mut self, field: &'static str) -> Result<[u16; 8], TraceError> {
        let mut v = [0u16; 8];
        for x in v.iter_mut() {
            *x = self.small(field, u64::from(u16::MAX))? as u16;
        }
        Ok(v)
    }
    fn flag(&mut self, field: &'static str) -> Result<bool, TraceError> {
        let start = self.at;
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(TraceError::BadValue {
                offset: start,
                field,
            }),
        }
    }
}

/// What one recorded pass gave and took.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepInputs<'a> {
    pub clock_us: u64,
    extra_clocks: [u64; CLOCKS],
    n_clocks: usize,
    reads: [&'a [u8]; READS],
    n_reads: usize,
    /// Bytes the transmitter took in all, when it took fewer than offered.
    pub tx_short: Option<u32>,
    ir: Option<[u16; 8]>,
    ambient: Option<[u16; 8]>,
    compass: Option<Option<f32>>,
    ground: Option<bool>,
    line: Option<bool>,
    beacon: Option<Option<BeaconReading>>,
    battery: Option<u16>,
    encoders: Option<Option<[i32; 2]>>,
    gripper: Option<Option<GripperState>>,
    camera: Option<Option<&'a [u8]>>,
    whiskers: Option<Option<u32>>,
    light24: Option<Option<&'a [u8]>>,
    /// The motor commands the recorded firmware gave in this pass, in order.
    pub motors: [MotorCommand; COMMANDS],
    pub n_motors: usize,
    pub grips: [GripperCommand; COMMANDS],
    pub n_grips: usize,
    /// The pass ran a control cycle (its sensors were read).
    pub cycle: bool,
}

/// Where the stream stands after a pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// A pass is ready.
    Step,
    /// The stream ends (the pass before the end may be incomplete and is not played).
    End,
    /// A gap: `steps` passes are missing here; the stream cannot be followed past it.
    Gap { steps: u32, offset: usize },
    /// A new `START` (tracing was switched off and on): a new stream begins here.
    Restart { offset: usize },
}

/// The `Hal` that plays a trace back.
pub struct Playback<'a> {
    cur: Cursor<'a>,
    pub start: StartInfo,
    step: StepInputs<'a>,
    /// Idle passes still to play from an `IDLE` entry, and their spacing.
    idle: (u64, u64),
    /// The profile `START` names.
    profile: &'static crate::profile::Profile,
    /// Most passes, and most µs of robot time, between two control cycles (`between_cycles`).
    bound: u64,
    /// The clock of the last control cycle (or of the first pass, before one), and the passes
    /// since it.
    since_cycle: Option<(u64, u64)>,
    /// Where the entry that began the pass just loaded is in the stream.
    pass_at: usize,
    /// Where the next pass's entries begin.
    next_pass: Option<usize>,
    clock: u64,
    encoders: [i32; 2],
    clocks_used: usize,
    reads_used: usize,
    read_off: usize,
    tx_left: Option<u32>,
    /// Passes played, control cycles among them.
    pub steps: u64,
    pub cycles: u64,
    /// What the firmware did in the pass just played.
    pub motors_out: [MotorCommand; COMMANDS],
    pub n_motors_out: usize,
    pub grips_out: [GripperCommand; COMMANDS],
    pub n_grips_out: usize,
    out: [u8; OUT_CAPACITY],
    n_out: usize,
    /// Values the firmware asked for that the pass had not recorded.
    pub misses: u64,
    /// The first of them: the Hal call.
    pub first_miss: Option<(u64, &'static str)>,
    last: StepInputs<'a>,
}

impl<'a> Playback<'a> {
    /// Reads the stream's `START`.
    pub fn new(bytes: &'a [u8]) -> Result<Self, TraceError> {
        let mut cur = Cursor { bytes, at: 0 };
        if cur.u8()? != tag::START {
            return Err(TraceError::NoStart { offset: 0 });
        }
        let start = read_start(&mut cur)?;
        let at = cur.at;
        let profile =
            crate::profile::Profile::by_trace_code(start.profile).ok_or(TraceError::BadValue {
                offset: 2,
                field: "START profile",
            })?;
        Ok(Playback {
            cur,
            start,
            step: StepInputs::default(),
            idle: (0, 0),
            profile,
            bound: between_cycles(profile),
            since_cycle: None,
            pass_at: at,
            next_pass: Some(at),
            clock: 0,
            encoders: [0, 0],
            clocks_used: 0,
            reads_used: 0,
            read_off: 0,
            tx_left: None,
            steps: 0,
            cycles: 0,
            motors_out: [MotorCommand::STOP; COMMANDS],
            n_motors_out: 0,
            grips_out: [GripperCommand::default(); COMMANDS],
            n_grips_out: 0,
            out: [0; OUT_CAPACITY],
            n_out: 0,
            misses: 0,
            first_miss: None,
            last: StepInputs::default(),
        })
    }

    /// Byte offset in the stream of the pass about to be played.
    pub fn offset(&self) -> usize {
        self.cur.at
    }

    /// The robot's profile, as `START` names it (a profile this firmware lacks is refused).
    pub fn profile(&self) -> &'static crate::profile::Profile {
        self.profile
    }

    /// Byte offset in the stream of the entry that began the pass just loaded (its `STEP`, or
    /// the `IDLE` it is one of).
    pub fn pass_offset(&self) -> usize {
        self.pass_at
    }

    /// Checks that a run of `n` passes ending at robot time `end` (µs), the first at `first`,
    /// keeps within the bound since the last control cycle; `entry` and the fields name the
    /// claim. The run's passes are not control cycles.
    fn within_bound(
        &mut self,
        entry: usize,
        (n, first, end): (u64, u64, u64),
        (passes_field, time_field): (&'static str, &'static str),
    ) -> Result<(), TraceError> {
        let (since, before) = *self.since_cycle.get_or_insert((first, 0));
        let passes = before.saturating_add(n);
        let time = end.saturating_sub(since);
        let refuse = |field, claimed, unit| TraceError::Implausible {
            offset: entry,
            field,
            claimed,
            limit: self.bound,
            unit,
        };
        if passes > self.bound {
            return Err(refuse(passes_field, passes, "passes"));
        }
        if time > self.bound {
            return Err(refuse(time_field, time, "us of robot time"));
        }
        self.since_cycle = Some((since, passes));
        Ok(())
    }

    /// Loads the next pass. `Next::Step`: call `Robot::step` with this `Hal` now.
    pub fn next_step(&mut self) -> Result<Next, TraceError> {
        self.clocks_used = 0;
        self.reads_used = 0;
        self.read_off = 0;
        self.n_motors_out = 0;
        self.n_grips_out = 0;
        self.n_out = 0;
        if self.step.cycle {
            self.last = self.step;
        }
        if self.idle.0 > 0 {
            self.idle.0 -= 1;
            self.clock = self.clock.wrapping_add(self.idle.1);
            self.step = StepInputs {
                clock_us: self.clock,
                ..StepInputs::default()
            };
            self.tx_left = None;
            self.steps += 1;
            return Ok(Next::Step);
        }
        let Some(at) = self.next_pass else {
            return Ok(Next::End);
        };
        self.cur.at = at;
        let entry_at = self.cur.at;
        let t = match self.cur.u8() {
            Ok(t) => t,
            Err(_) => return Ok(Next::End),
        };
        match t {
            tag::IDLE => {
                let n = self.cur.small("IDLE count", u64::from(u32::MAX))?;
                let dt = self.cur.varint("IDLE spacing")?;
                if n == 0 {
                    return Err(TraceError::BadValue {
                        offset: entry_at + 1,
                        field: "IDLE count",
                    });
                }
                // Refused before a pass is played: 2^32 - 1 passes 0 µs apart took 95 s.
                let first = self.clock.wrapping_add(dt);
                let end = self.clock.saturating_add(n.saturating_mul(dt));
                self.within_bound(entry_at, (n, first, end), ("IDLE count", "IDLE spacing"))?;
                self.next_pass = Some(self.cur.at);
                self.idle = (n, dt);
                self.pass_at = entry_at;
                self.next_step()
            }
            tag::STEP => {
                let dt = self.cur.varint("STEP time")?;
                // A pass is played only when the entry after it has arrived: the recording
                // may have ended with the pass half sent.
                let mut step = StepInputs {
                    clock_us: self.clock.wrapping_add(dt),
                    ..StepInputs::default()
                };
                match self.read_pass(&mut step)? {
                    Some(next) => {
                        if step.cycle {
                            self.since_cycle = Some((step.clock_us, 0));
                        } else {
                            let t = step.clock_us;
                            self.within_bound(entry_at, (1, t, t), ("STEP", "STEP time"))?;
                        }
                        self.pass_at = entry_at;
                        self.next_pass = Some(next);
                        self.clock = step.clock_us;
                        self.tx_left = step.tx_short;
                        self.step = step;
                        self.steps += 1;
                        if step.cycle {
                            self.cycles += 1;
                        }
                        Ok(Next::Step)
                    }
                    None => Ok(Next::End),
                }
            }
            tag::GAP => {
                let steps = self.cur.small("GAP count", u64::from(u32::MAX))? as u32;
                Ok(Next::Gap {
                    steps,
                    offset: entry_at,
                })
            }
            tag::START => Ok(Next::Restart { offset: entry_at }),
            tag => Err(TraceError::UnknownTag {
                offset: entry_at,
                tag,
            }),
        }
    }

    /// Reads a pass's entries up to the next pass; `None` when the stream ends first.
    fn read_pass(&mut self, s: &mut StepInputs<'a>) -> Result<Option<usize>, TraceError> {
        loop {
            let at = self.cur.at;
            let Ok(t) = self.cur.u8() else {
                return Ok(None);
            };
            let r = self.read_entry(t, at, s);
            match r {
                Ok(true) => {}
                Ok(false) => return Ok(Some(at)),
                // The stream may end inside the last pass's entry: not an error at the end.
                // Only the stream's end truncates: the recording stopped inside this pass.
                Err(TraceError::Truncated { .. }) => return Ok(None),
                Err(e) => return Err(e),
            }
        }
    }

    /// One entry of a pass; false when `t` begins the next pass (not consumed).
    fn read_entry(&mut self, t: u8, at: usize, s: &mut StepInputs<'a>) -> Result<bool, TraceError> {
        let c = &mut self.cur;
        let too_many = |what| TraceError::TooMany { offset: at, what };
        match t {
            tag::IDLE | tag::STEP | tag::GAP | tag::START => return Ok(false),
            tag::CLOCK => {
                let dt = c.varint("CLOCK time")?;
                let slot = s
                    .extra_clocks
                    .get_mut(s.n_clocks)
                    .ok_or(too_many("clock reads"))?;
                *slot = s.clock_us.wrapping_add(dt);
                s.n_clocks += 1;
            }
            tag::RX => {
                let n = c.small("RX length", crate::link::TX_QUEUE as u64 * 4)? as usize;
                let bytes = c.take(n)?;
                let slot = s.reads.get_mut(s.n_reads).ok_or(too_many("serial reads"))?;
                *slot = bytes;
                s.n_reads += 1;
            }
            tag::TX_SHORT => {
                s.tx_short = Some(c.small("TX_SHORT count", u64::from(u32::MAX))? as u32)
            }
            tag::IR => s.ir = Some(c.eight("IR reading")?),
            tag::AMBIENT => s.ambient = Some(c.eight("AMBIENT reading")?),
            tag::COMPASS => s.compass = Some(Some(c.f32()?)),
            tag::NO_COMPASS => s.compass = Some(None),
            tag::GROUND => s.ground = Some(c.flag("GROUND")?),
            tag::LINE => s.line = Some(c.flag("LINE")?),
            tag::BEACON => {
                let bearing_rad = c.f32()?;
                let strength = c.u8()?;
                s.beacon = Some(Some(BeaconReading {
                    bearing_rad,
                    strength,
                }));
            }
            tag::NO_BEACON => s.beacon = Some(None),
            tag::BATTERY => s.battery = Some(c.small("BATTERY", u64::from(u16::MAX))? as u16),
            tag::ENCODERS => {
                let dl = c.zigzag("ENCODERS left")?;
                let dr = c.zigzag("ENCODERS right")?;
                self.encoders = [
                    self.encoders[0].wrapping_add(dl),
                    self.encoders[1].wrapping_add(dr),
                ];
                s.encoders = Some(Some(self.encoders));
            }
            tag::NO_ENCODERS => s.encoders = Some(None),
            tag::GRIPPER => {
                let arm = c.u8()?;
                let flags = c.u8()?;
                if flags > 3 {
                    return Err(TraceError::BadValue {
                        offset: at + 2,
                        field: "GRIPPER flags",
                    });
                }
                s.gripper = Some(Some(GripperState {
                    arm,
                    closed: flags & 1 != 0,
                    object: flags & 2 != 0,
                }));
            }
            tag::NO_GRIPPER => s.gripper = Some(None),
            tag::CAMERA => s.camera = Some(Some(c.take(CAMERA_PIXELS)?)),
            tag::NO_CAMERA => s.camera = Some(None),
            tag::WHISKERS => {
                let bits = c.small("WHISKERS", u64::from(u32::MAX))? as u32;
                s.whiskers = Some(Some(bits));
            }
            tag::NO_WHISKERS => s.whiskers = Some(None),
            tag::LIGHT24 => s.light24 = Some(Some(c.take(crate::alice::SENSORS)?)),
            tag::NO_LIGHT24 => s.light24 = Some(None),
            tag::MOTORS => {
                let l = c.zigzag("MOTORS left")?;
                let r = c.zigzag("MOTORS right")?;
                let (Ok(left), Ok(right)) = (i16::try_from(l), i16::try_from(r)) else {
                    return Err(TraceError::BadValue {
                        offset: at + 1,
                        field: "MOTORS",
                    });
                };
                let slot = s
                    .motors
                    .get_mut(s.n_motors)
                    .ok_or(too_many("motor commands"))?;
                *slot = MotorCommand::new(left, right);
                s.n_motors += 1;
            }
            tag::GRIP_CMD => {
                let arm = c.u8()?;
                let closed = c.flag("GRIP_CMD closed")?;
                let slot = s
                    .grips
                    .get_mut(s.n_grips)
                    .ok_or(too_many("gripper commands"))?;
                *slot = GripperCommand { arm, closed };
                s.n_grips += 1;
            }
            tag => return Err(TraceError::UnknownTag { offset: at, tag }),
        }
        if matches!(t, tag::IR) {
            s.cycle = true;
        }
        Ok(true)
    }

    /// The serial bytes the firmware wrote in the pass just played (as the recorded
    /// transmitter took them).
    pub fn written(&self) -> &[u8] {
        &self.out[..self.n_out]
    }

    /// The pass just loaded (what the recorded firmware gave back in it).
    pub fn recorded(&self) -> &StepInputs<'a> {
        &self.step
    }

    fn miss(&mut self, what: &'static str) {
        self.misses += 1;
        if self.first_miss.is_none() {
            self.first_miss = Some((self.steps, what));
        }
    }

    fn value<T: Copy>(
        &mut self,
        now: Option<T>,
        last: Option<T>,
        absent: T,
        what: &'static str,
    ) -> T {
        match now {
            Some(v) => v,
            None => {
                self.miss(what);
                last.unwrap_or(absent)
            }
        }
    }
}

/// The bound on a trace between two control cycles for `profile`, µs of robot time and passes
/// alike: two control periods. The firmware runs a control cycle (its sensors read, so a `STEP`, never `IDLE`)
/// in the first pass at least a period after the last, so a genuine trace has less than one
/// period of passes between two, and a main loop that reads its clock, its port and its link
/// takes more than a microsecond a pass on these robots (the emulator makes one a
/// millisecond). A claim past the bound is refused before it is played: playing is a
/// `Robot::step` a pass, and one 8-byte `IDLE` entry can claim 2^32 - 1 passes. Retracing is
/// then work in proportion to the trace: at most two periods of passes per control cycle,
/// whose entries take at least 11 bytes.
fn between_cycles(profile: &crate::profile::Profile) -> u64 {
    2 * u64::from(profile.cycle_us)
}

fn read_start(c: &mut Cursor<'_>) -> Result<StartInfo, TraceError> {
    if c.u8()? != FORMAT_VERSION {
        return Err(TraceError::NoStart { offset: 1 });
    }
    let profile = c.u8()?;
    let s = c.take(4)?;
    let seed = u32::from_le_bytes([s[0], s[1], s[2], s[3]]);
    let start = Pose::new(c.f32()?, c.f32()?, c.f32()?);
    let steps_before = c.small("START steps before", u64::from(u32::MAX))? as u32;
    let emulated = c.flag("START emulated")?;
    let mut told = [Point::new(0.0, 0.0); 3];
    for p in told.iter_mut() {
        *p = Point::new(c.f32()?, c.f32()?);
    }
    Ok(StartInfo {
        profile,
        seed,
        start,
        steps_before,
        emulated,
        beacon: told[0],
        bounds_min: told[1],
        bounds_max: told[2],
    })
}

impl Hal for Playback<'_> {
    fn now_us(&mut self) -> u64 {
        let i = self.clocks_used;
        self.clocks_used += 1;
        if i == 0 {
            return self.step.clock_us;
        }
        match self
            .step
            .extra_clocks
            .get(i - 1)
            .filter(|_| i - 1 < self.step.n_clocks)
        {
            Some(&t) => t,
            None => {
                self.miss("now_us");
                self.step.clock_us
            }
        }
    }

    fn set_motors(&mut self, cmd: MotorCommand) {
        if let Some(slot) = self.motors_out.get_mut(self.n_motors_out) {
            *slot = cmd;
            self.n_motors_out += 1;
        }
    }

    fn encoders(&mut self) -> Option<[i32; 2]> {
        let (now, last) = (self.step.encoders, self.last.encoders);
        self.value(now, last, None, "encoders")
    }

    fn ir(&mut self) -> [u16; 8] {
        let (now, last) = (self.step.ir, self.last.ir);
        self.value(now, last, [0; 8], "ir")
    }

    fn ambient(&mut self) -> [u16; 8] {
        let (now, last) = (self.step.ambient, self.last.ambient);
        self.value(now, last, [0; 8], "ambient")
    }

    fn compass(&mut self) -> Option<f32> {
        let (now, last) = (self.step.compass, self.last.compass);
        self.value(now, last, None, "compass")
    }

    fn ground(&mut self) -> bool {
        let (now, last) = (self.step.ground, self.last.ground);
        self.value(now, last, false, "ground")
    }

    fn line(&mut self) -> bool {
        let (now, last) = (self.step.line, self.last.line);
        self.value(now, last, false, "line")
    }

    fn beacon(&mut self) -> Option<BeaconReading> {
        let (now, last) = (self.step.beacon, self.last.beacon);
        self.value(now, last, None, "beacon")
    }

    fn battery_mv(&mut self) -> u16 {
        let (now, last) = (self.step.battery, self.last.battery);
        self.value(now, last, 0, "battery_mv")
    }

    fn gripper(&mut self) -> Option<GripperState> {
        let (now, last) = (self.step.gripper, self.last.gripper);
        self.value(now, last, None, "gripper")
    }

    fn set_gripper(&mut self, cmd: GripperCommand) {
        if let Some(slot) = self.grips_out.get_mut(self.n_grips_out) {
            *slot = cmd;
            self.n_grips_out += 1;
        }
    }

    fn camera(&mut self, image: &mut [u8; CAMERA_PIXELS]) -> bool {
        match self.step.camera {
            Some(Some(line)) => {
                image.copy_from_slice(line);
                true
            }
            Some(None) => false,
            None => {
                self.miss("camera");
                false
            }
        }
    }

    fn whiskers(&mut self) -> Option<u32> {
        let (now, last) = (self.step.whiskers, self.last.whiskers);
        self.value(now, last, None, "whiskers")
    }

    fn photoresistors(&mut self) -> Option<[u8; crate::alice::SENSORS]> {
        let (now, last) = (self.step.light24, self.last.light24);
        let bytes = self.value(now, last, None, "photoresistors")?;
        let mut out = [0u8; crate::alice::SENSORS];
        // `take` gave exactly SENSORS bytes.
        out.iter_mut().zip(bytes).for_each(|(o, b)| *o = *b);
        Some(out)
    }

    fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        // One recorded read per call, as the recorded port gave them.
        let Some(&chunk) = self
            .step
            .reads
            .get(self.reads_used)
            .filter(|_| self.reads_used < self.step.n_reads)
        else {
            return 0;
        };
        let rest = chunk.get(self.read_off..).unwrap_or(&[]);
        let k = rest.len().min(buf.len());
        buf[..k].copy_from_slice(&rest[..k]);
        self.read_off += k;
        if self.read_off >= chunk.len() {
            self.reads_used += 1;
            self.read_off = 0;
        }
        k
    }

    fn serial_write(&mut self, bytes: &[u8]) -> usize {
        let mut n = bytes.len();
        if let Some(left) = self.tx_left.as_mut() {
            n = n.min(*left as usize);
            *left -= n as u32;
        }
        let room = self.out.len() - self.n_out;
        let n = n.min(room);
        self.out[self.n_out..self.n_out + n].copy_from_slice(&bytes[..n]);
        self.n_out += n;
        n
    }
}
