//! The board's main loop over its ports: the firmware's `Robot` stepped unchanged, its `Hal`
//! made of the station UART, the lockstep clock and the sensors and motors of the HIL UART.
//!
//! Layer: between the firmware and the board's registers. `Ports` is what a board provides
//! (the mps2-an386's in `mps2`, a fake on the host for the tests); everything here is plain
//! code, so the loop that runs on the image is also tested on the host against the emulator's
//! world (`tests`). The loop: take HIL bytes; deliver the next `Sensors` when the clock says
//! its cycle is due; one `Robot::step`; answer a delivered frame with the `Motors` its cycle
//! set; then sleep until the next work (`wake_at`): the next frame, the firmware's own next
//! work (`Robot::idle_until_us`), or a millisecond while a session is open, or a byte.
//!
//! Safety: a motion command is executed or refused by the firmware as everywhere; the motors
//! it sets reach the world at the next exchange, and only then (lockstep), so a Stop takes
//! effect within one control period. A board that stops (panic, fault) sends `Fault`, and the
//! world stops the motors; a real board's fault handler drives its motor pins low.

use core::mem::MaybeUninit;

use protocol::hil::{self, HilDecoder, Msg, Setup, HIL_VERSION};
use protocol::{Command, Mode};
use robot_firmware::deadreckon::Bounds;
use robot_firmware::hal::{BeaconReading, GripperCommand, GripperState};
use robot_firmware::odometry::{Point, Pose};
use robot_firmware::robot::Kit;
use robot_firmware::{Hal, MotorCommand, Profile, Robot, RobotOptions};

use crate::lockstep::{Lockstep, TICKS_PER_US};

/// What a board provides.
pub trait Ports {
    /// The free-running timer, `TICKS_PER_US` ticks a microsecond, never going backwards.
    fn ticks(&mut self) -> u64;
    /// Bytes received from the station (its receive FIFO).
    fn station_read(&mut self, buf: &mut [u8]) -> usize;
    /// Offers bytes to the station transmitter; returns how many it took.
    fn station_write(&mut self, bytes: &[u8]) -> usize;
    /// Bytes received from the world.
    fn hil_read(&mut self, buf: &mut [u8]) -> usize;
    /// Sends bytes to the world (small frames; may block briefly).
    fn hil_write(&mut self, bytes: &[u8]);
    /// Sleeps until `until` ticks (`None`: no deadline) or a byte from either UART.
    fn idle(&mut self, until: Option<u64>);
    /// The station receive FIFO's counters: bytes in, fullest, dropped full.
    fn station_fifo(&self) -> (u32, u32, u32);
    /// Statics, the stack's size and its high-water mark, bytes.
    fn memory(&self) -> (u32, u32, u32);
    /// Times `idle` slept.
    fn sleeps(&self) -> u32;
}

/// How often the board sends its `Report`, control cycles.
pub const REPORT_EVERY: u32 = 20;
/// How often `PowerOn` is repeated until the world answers, µs.
pub const POWER_ON_RETRY_US: u64 = 500_000;
/// A pass every millisecond while a session is open (the emulator's step).
const BUSY_PASS_US: u64 = 1000;

/// The firmware's hardware: the station UART, the lockstep clock, the last `Sensors`.
pub struct BoardHal<P: Ports> {
    pub ports: P,
    pub clock: Lockstep,
    sensors: hil::Sensors,
    motor: MotorCommand,
    gripper: GripperCommand,
    /// Station bytes read in the current pass.
    rx_in_pass: usize,
}

impl<P: Ports> Hal for BoardHal<P> {
    fn now_us(&mut self) -> u64 {
        let t = self.ports.ticks();
        self.clock.now_us(t)
    }
    fn set_motors(&mut self, cmd: MotorCommand) {
        self.motor = cmd;
    }
    fn encoders(&mut self) -> Option<[i32; 2]> {
        self.sensors.encoders
    }
    fn ir(&mut self) -> [u16; 8] {
        self.sensors.ir
    }
    fn ambient(&mut self) -> [u16; 8] {
        self.sensors.ambient
    }
    fn compass(&mut self) -> Option<f32> {
        self.sensors.compass
    }
    fn ground(&mut self) -> bool {
        self.sensors.ground
    }
    fn line(&mut self) -> bool {
        self.sensors.line
    }
    fn beacon(&mut self) -> Option<BeaconReading> {
        self.sensors
            .beacon
            .map(|(bearing_rad, strength)| BeaconReading {
                bearing_rad,
                strength,
            })
    }
    fn battery_mv(&mut self) -> u16 {
        self.sensors.battery_mv
    }
    fn gripper(&mut self) -> Option<GripperState> {
        self.sensors
            .gripper
            .map(|(arm, closed, object)| GripperState {
                arm,
                closed,
                object,
            })
    }
    fn set_gripper(&mut self, cmd: GripperCommand) {
        self.gripper = cmd;
    }
    fn whiskers(&mut self) -> Option<u32> {
        self.sensors.whiskers
    }
    fn photoresistors(&mut self) -> Option<[u8; robot_firmware::alice::SENSORS]> {
        self.sensors.photoresistors
    }
    fn serial_read(&mut self, buf: &mut [u8]) -> usize {
        let n = self.ports.station_read(buf);
        self.rx_in_pass += n;
        n
    }
    fn serial_write(&mut self, bytes: &[u8]) -> usize {
        self.ports.station_write(bytes)
    }
}

/// Why the board cannot run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BootError {
    /// The world's `Setup` is for another profile, period or HIL version.
    BadSetup,
}

/// Sends one HIL message.
fn send<P: Ports>(ports: &mut P, msg: &Msg) {
    let mut buf = [0u8; hil::MAX_FRAME];
    if let Ok(n) = hil::encode(msg, &mut buf) {
        ports.hil_write(buf.get(..n).unwrap_or_default());
    }
}

/// Tells the world the board has stopped (`hil::fault`), so it stops the motors. A delimiter
/// goes first: the fault may have cut a frame short, and the world's decoder resynchronises
/// on it (an empty frame is nothing).
pub fn send_fault<P: Ports>(ports: &mut P, code: u8) {
    ports.hil_write(&[0]);
    send(ports, &Msg::Fault(code));
}

/// Power-on: `PowerOn` (repeated until answered), then the world's `Setup` and the `Sensors`
/// of time 0. A `Setup` that does not fit the image is refused with `Fault`.
pub fn power_on<P: Ports>(
    ports: &mut P,
    profile: &'static Profile,
) -> Result<(Setup, hil::Sensors, HilDecoder), BootError> {
    let mut dec = HilDecoder::new();
    let mut setup = None;
    let mut next_try = 0u64;
    loop {
        let now = ports.ticks();
        if now >= next_try {
            send(
                ports,
                &Msg::PowerOn(hil::PowerOn {
                    version: HIL_VERSION,
                    profile: profile.id,
                }),
            );
            next_try = now + POWER_ON_RETRY_US * TICKS_PER_US;
        }
        let mut buf = [0u8; 64];
        let n = ports.hil_read(&mut buf);
        for &b in buf.get(..n).unwrap_or_default() {
            match dec.feed(b) {
                Some(Ok(Msg::Setup(s))) => {
                    if s.version != HIL_VERSION
                        || s.profile != profile.id
                        || s.period_us != profile.cycle_us
                    {
                        send_fault(ports, hil::fault::BAD_SETUP);
                        return Err(BootError::BadSetup);
                    }
                    setup = Some(s);
                }
                Some(Ok(Msg::Sensors(z))) if z.seq == 0 && z.time_us == 0 => {
                    if let Some(s) = setup {
                        return Ok((s, z, dec));
                    }
                }
                _ => {}
            }
        }
        if n == 0 {
            ports.idle(Some(next_try));
        }
    }
}

/// Builds the robot in `slot` as `setup` tells it: its seed, start, arena, key, first mode
/// (what `emulator::sim` tells an emulated robot, and a real board reads from its flash).
pub fn build_robot<'r, K: Kit>(
    slot: &'r mut MaybeUninit<Robot<K>>,
    profile: &'static Profile,
    setup: &Setup,
) -> &'r mut Robot<K> {
    let [x, y, heading] = setup.start;
    let robot = Robot::init(
        slot,
        RobotOptions {
            profile,
            seed: setup.firmware_seed,
            start: Pose::new(x, y, heading),
            // A board is a robot: no truth channel, no EMULATED capability.
            emulated: false,
            firmware_version: env!("CARGO_PKG_VERSION"),
        },
    );
    let dead = &mut robot.core.dead;
    if let Some(b) = setup.beacon {
        dead.params.beacon = Point::new(b.x, b.y);
    }
    let [min, max] = setup.bounds;
    dead.set_bounds(Bounds {
        min: Point::new(min.x, min.y),
        max: Point::new(max.x, max.y),
        ..dead.params.bounds
    });
    robot.link.set_key(setup.key.as_ref());
    if setup.power_on_mode != Mode::Idle {
        let _ = robot.core.apply(Command::SetMode(setup.power_on_mode), 0);
    }
    robot
}

/// The running board.
pub struct Board<'r, K: Kit, P: Ports> {
    pub robot: &'r mut Robot<K>,
    pub hal: BoardHal<P>,
    decoder: HilDecoder,
    /// The next `Sensors` received and not yet delivered.
    pending: Option<hil::Sensors>,
    report: hil::Report,
    rx_frames_seen: u32,
}

impl<'r, K: Kit, P: Ports> Board<'r, K, P> {
    /// The board after `power_on`, with the `Sensors` of time 0 waiting.
    pub fn new(
        robot: &'r mut Robot<K>,
        ports: P,
        setup: &Setup,
        first: hil::Sensors,
        decoder: HilDecoder,
    ) -> Self {
        Board {
            robot,
            hal: BoardHal {
                ports,
                clock: Lockstep::new(setup.period_us),
                sensors: first,
                motor: MotorCommand::STOP,
                gripper: GripperCommand::default(),
                rx_in_pass: 0,
            },
            decoder,
            pending: Some(first),
            report: hil::Report::default(),
            rx_frames_seen: 0,
        }
    }

    /// Reads the world's bytes; keeps the next `Sensors` if it is the one the clock expects.
    fn take_hil(&mut self) {
        let mut buf = [0u8; 64];
        loop {
            let n = self.hal.ports.hil_read(&mut buf);
            if n == 0 {
                return;
            }
            for &b in buf.get(..n).unwrap_or_default() {
                match self.decoder.feed(b) {
                    None => {}
                    Some(Ok(Msg::Sensors(s)))
                        if self.pending.is_none()
                            && s.time_us == self.hal.clock.next_frame_us() =>
                    {
                        self.pending = Some(s)
                    }
                    // A frame out of turn (its time not the next period's) or of another
                    // kind: refused, counted in the report.
                    Some(_) => self.report.hil_errors = self.report.hil_errors.wrapping_add(1),
                }
            }
        }
    }

    /// One pass of the main loop.
    pub fn pass(&mut self) {
        self.take_hil();
        let now = self.hal.ports.ticks();
        let mut delivered = None;
        if let Some(s) = self.pending.filter(|_| self.hal.clock.is_due(now)) {
            self.pending = None;
            self.hal.clock.deliver(s.time_us, now);
            self.hal.sensors = s;
            delivered = Some(s.seq);
        }
        let cycles = self.robot.core.timing.cycles;
        self.hal.rx_in_pass = 0;
        let t0 = self.hal.ports.ticks();
        self.robot.step(&mut self.hal);
        let ticks = u32::try_from(self.hal.ports.ticks().saturating_sub(t0)).unwrap_or(u32::MAX);
        let frames = self.robot.link.decoder_stats().frames_ok;
        let r = &mut self.report;
        if self.robot.core.timing.cycles != cycles {
            r.cycles = r.cycles.wrapping_add(1);
            r.cycle_ticks_last = ticks;
            r.cycle_ticks_max = r.cycle_ticks_max.max(ticks);
            r.cycle_ticks_sum = r.cycle_ticks_sum.wrapping_add(ticks);
        } else if self.hal.rx_in_pass > 0 {
            r.rx_passes = r.rx_passes.wrapping_add(1);
            r.rx_frames = r
                .rx_frames
                .wrapping_add(frames.wrapping_sub(self.rx_frames_seen));
            r.rx_pass_ticks_sum = r.rx_pass_ticks_sum.wrapping_add(ticks);
            r.rx_pass_ticks_max = r.rx_pass_ticks_max.max(ticks);
        }
        self.rx_frames_seen = frames;
        if let Some(seq) = delivered {
            let m = hil::Motors {
                seq,
                left: self.hal.motor.left,
                right: self.hal.motor.right,
                arm: self.hal.gripper.arm,
                closed: self.hal.gripper.closed,
            };
            send(&mut self.hal.ports, &Msg::Motors(m));
            if seq % REPORT_EVERY == 0 {
                self.send_report();
            }
        }
    }

    /// Sends the board's measures (`hil::Report`).
    pub fn send_report(&mut self) {
        let ports = &mut self.hal.ports;
        let (rx_bytes, rx_fifo_max, rx_dropped) = ports.station_fifo();
        let (static_ram, stack_size, stack_used) = ports.memory();
        let r = &mut self.report;
        r.rx_bytes = rx_bytes;
        r.rx_fifo_max = rx_fifo_max;
        r.rx_dropped = rx_dropped;
        r.static_ram = static_ram;
        r.stack_size = stack_size;
        r.stack_used = stack_used;
        r.sleeps = ports.sleeps();
        let msg = Msg::Report(*r);
        send(ports, &msg);
    }

    /// When the next pass has work (ticks; `None`: only when a byte comes).
    pub fn wake_at(&mut self) -> Option<u64> {
        let now = self.hal.ports.ticks();
        let clock = &self.hal.clock;
        let frame = self.pending.map(|_| clock.due_ticks());
        let firmware = match self.robot.idle_until_us() {
            // Quiet until the next cycle: that is the next frame's delivery.
            Some(t) if t >= clock.next_frame_us() => None,
            Some(t) => Some(clock.ticks_at(t, now)),
            None => Some(now + BUSY_PASS_US * TICKS_PER_US),
        };
        match (frame, firmware) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// One pass, then sleep until the next has work.
    pub fn pass_and_sleep(&mut self) {
        self.pass();
        let until = self.wake_at();
        self.hal.ports.idle(until);
    }

    /// Passes forever, sleeping between them.
    #[cfg(target_os = "none")]
    pub fn run(&mut self) -> ! {
        loop {
            self.pass_and_sleep();
        }
    }
}

#[cfg(test)]
mod tests;
