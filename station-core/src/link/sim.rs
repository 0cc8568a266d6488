//! The real robot firmware on the far end of a port, in-process: for tests and demos.
//!
//! Layer: a test bench, not a simulation of the world. `SimCore` is a `robot_firmware::AnyRobot`
//! stepped every simulated millisecond with a `ScriptedHal`; wheel motion is integrated into
//! encoder counts, compass heading and a "true" pose (an ideal unicycle: no walls, no slip),
//! which it reports as `EmuTruth` frames on their own sequence counter when `emulated` is set,
//! as the emulator does. Frame-level faults (drop the next N frames in either direction) let
//! tests exercise retries. `FirmwareSim` runs a `SimCore` on a tokio task against a
//! `MemoryPeer`; `SimCore` also implements the emulator's `Device`, so it can be served on a
//! real pty. Cannot fail: bytes that do not fit a buffer are dropped, as a UART would.

use std::pin::Pin;
use std::sync::{Arc, Mutex, MutexGuard};
use std::task::{Context, Poll, Waker};
use std::time::Duration;

use protocol::{caps, encode, EmuTruth, Message, Pose, MAX_FRAME};
use robot_firmware::odometry::Pose as FwPose;
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{AnyRobot, Profile, RobotOptions};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

use super::memory::MemoryPeer;

/// How the bench robot is built.
#[derive(Clone, Copy, Debug)]
pub struct SimOptions {
    pub profile: &'static Profile,
    /// Start pose, metres and radians.
    pub start: (f32, f32, f32),
    /// Declare itself emulated and send `EmuTruth`.
    pub emulated: bool,
    pub seed: u32,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            profile: &robot_firmware::KHEPERA,
            start: (0.5, 0.5, 0.0),
            emulated: true,
            seed: 1,
        }
    }
}

/// Faults applied to whole frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameFaults {
    /// Frames still to drop on the way to the robot.
    pub drop_to_robot: u32,
    /// Frames still to drop on the way to the station.
    pub drop_from_robot: u32,
}

/// Period of `EmuTruth` frames, ms (the emulator sends one per telemetry frame; 10 Hz here).
const TRUTH_PERIOD_MS: u64 = 100;

/// The robot, its scripted hardware and the integrated motion.
pub struct SimCore {
    pub robot: AnyRobot,
    pub hal: ScriptedHal,
    pub faults: FrameFaults,
    /// The true pose: x, y metres, heading radians.
    pub truth: (f64, f64, f64),
    profile: &'static Profile,
    emulated: bool,
    encoder_pulses: [f64; 2],
    truth_seq: u16,
    next_truth_ms: u64,
    outbound: Vec<u8>,
    to_robot: FaultState,
    from_robot: FaultState,
}

#[derive(Clone, Copy, Debug, Default)]
struct FaultState {
    /// At the start of a frame (after a delimiter).
    at_start: bool,
    /// Inside a frame being dropped.
    dropping: bool,
}

impl SimCore {
    pub fn new(opts: SimOptions) -> Self {
        let (x, y, h) = opts.start;
        let robot = AnyRobot::new(RobotOptions {
            profile: opts.profile,
            seed: opts.seed,
            start: FwPose::new(x, y, h),
            emulated: opts.emulated,
            firmware_version: env!("CARGO_PKG_VERSION"),
        });
        let hal = ScriptedHal {
            encoders: opts.profile.has(caps::ENCODERS).then_some([0, 0]),
            compass: opts.profile.has(caps::COMPASS).then_some(h),
            battery_mv: if opts.profile.has(caps::BATTERY) {
                8000
            } else {
                0
            },
            ..ScriptedHal::default()
        };
        SimCore {
            robot,
            hal,
            faults: FrameFaults::default(),
            truth: (f64::from(x), f64::from(y), f64::from(h)),
            profile: opts.profile,
            emulated: opts.emulated,
            encoder_pulses: [0.0; 2],
            truth_seq: 0,
            next_truth_ms: 0,
            outbound: Vec::new(),
            to_robot: FaultState {
                at_start: true,
                dropping: false,
            },
            from_robot: FaultState {
                at_start: true,
                dropping: false,
            },
        }
    }

    /// Bytes from the station; frames selected by `faults` are dropped whole.
    pub fn push_inbound(&mut self, bytes: &[u8]) {
        let kept = filter_frames(bytes, &mut self.to_robot, &mut self.faults.drop_to_robot);
        // A full receive buffer drops the rest, as a UART's FIFO would.
        let _ = self.hal.push_rx(&kept);
    }

    /// Bytes for the station since the last call, appended to `out`.
    pub fn take_outbound(&mut self, out: &mut Vec<u8>) {
        out.append(&mut self.outbound);
    }

    /// Simulated time, ms.
    pub fn now_ms(&self) -> u64 {
        self.hal.now_us / 1000
    }

    /// One millisecond: a robot step, motion, and the robot's output collected.
    pub fn step_ms(&mut self) {
        self.robot.step(&mut self.hal);
        self.hal.now_us += 1000;
        self.integrate(0.001);
        // Robot bytes and truth frames share the port, so faults apply to both alike.
        let mut raw = Vec::new();
        let mut buf = [0u8; 1024];
        loop {
            let n = self.hal.take_tx(&mut buf);
            if n == 0 {
                break;
            }
            raw.extend_from_slice(buf.get(..n).unwrap_or(&[]));
        }
        let now_ms = self.now_ms();
        let between_frames = raw.last().is_none_or(|&b| b == 0);
        if self.emulated
            && self.robot.link().connected()
            && now_ms >= self.next_truth_ms
            && between_frames
        {
            self.next_truth_ms = now_ms + TRUTH_PERIOD_MS;
            self.truth_frame(now_ms, &mut raw);
        }
        let kept = filter_frames(&raw, &mut self.from_robot, &mut self.faults.drop_from_robot);
        self.outbound.extend_from_slice(&kept);
    }

    fn truth_frame(&mut self, now_ms: u64, out: &mut Vec<u8>) {
        let (x, y, h) = self.truth;
        let truth = EmuTruth {
            time_ms: now_ms as u32,
            pose: Pose {
                // The simulated world is the built-in arena, well inside the wire's range.
                x_mm: protocol::units::mm_from_m_clamped(x),
                y_mm: protocol::units::mm_from_m_clamped(y),
                heading_mrad: (h * 1000.0).round() as i16,
            },
            collisions: 0,
            robot_id: 1,
        };
        let mut buf = [0u8; MAX_FRAME];
        if let Ok(n) = encode(self.truth_seq, &Message::EmuTruth(truth), &mut buf) {
            self.truth_seq = self.truth_seq.wrapping_add(1);
            out.extend_from_slice(buf.get(..n).unwrap_or(&[]));
        }
    }

    /// Ideal differential drive from the motor command in force.
    fn integrate(&mut self, dt: f64) {
        let unit = f64::from(self.profile.motor_unit_mm_s) / 1000.0;
        let vl = f64::from(self.hal.motors.left) * unit;
        let vr = f64::from(self.hal.motors.right) * unit;
        let (x, y, h) = self.truth;
        let v = (vl + vr) / 2.0;
        let w = (vr - vl) / f64::from(self.profile.wheel_distance_m);
        let h2 = wrap(h + w * dt);
        self.truth = (x + v * h.cos() * dt, y + v * h.sin() * dt, h2);
        if self.hal.encoders.is_some() && self.profile.pulse_m > 0.0 {
            let pulse = f64::from(self.profile.pulse_m);
            self.encoder_pulses[0] += vl * dt / pulse;
            self.encoder_pulses[1] += vr * dt / pulse;
            self.hal.encoders = Some([
                self.encoder_pulses[0].round() as i32,
                self.encoder_pulses[1].round() as i32,
            ]);
        }
        if self.hal.compass.is_some() {
            self.hal.compass = Some(h2 as f32);
        }
    }
}

fn wrap(a: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let r = a.rem_euclid(tau);
    if r > std::f64::consts::PI {
        r - tau
    } else {
        r
    }
}

/// Copies `bytes`, leaving out whole frames while `drop` is non-zero.
fn filter_frames(bytes: &[u8], st: &mut FaultState, drop: &mut u32) -> Vec<u8> {
    let mut kept = Vec::with_capacity(bytes.len());
    for &b in bytes {
        if st.at_start && b != 0 && *drop > 0 {
            *drop -= 1;
            st.dropping = true;
        }
        st.at_start = b == 0;
        if st.dropping {
            if b == 0 {
                st.dropping = false;
            }
            continue;
        }
        kept.push(b);
    }
    kept
}

impl emulator::link::Device for SimCore {
    fn now_us(&self) -> u64 {
        self.hal.now_us
    }

    fn step_ms(&mut self) {
        SimCore::step_ms(self);
    }

    fn push_inbound(&mut self, bytes: &[u8]) {
        SimCore::push_inbound(self, bytes);
    }

    fn take_outbound(&mut self, out: &mut Vec<u8>) {
        SimCore::take_outbound(self, out);
    }

    fn cycles(&self) -> u32 {
        self.robot.timing().cycles
    }

    fn cycle_us(&self) -> u32 {
        self.profile.cycle_us
    }
}

/// A `SimCore` running on a tokio task, one step per millisecond of tokio time (so tests with
/// paused time run it as fast as the CPU allows, deterministically).
pub struct FirmwareSim {
    core: Arc<Mutex<SimCore>>,
    task: tokio::task::JoinHandle<()>,
}

impl FirmwareSim {
    /// Starts the robot behind `peer`. Needs a tokio runtime.
    pub fn spawn(peer: MemoryPeer, core: SimCore) -> Self {
        let core = Arc::new(Mutex::new(core));
        let task = tokio::spawn(run(peer, Arc::clone(&core)));
        FirmwareSim { core, task }
    }

    /// Looks at or changes the robot between steps.
    pub fn with<R>(&self, f: impl FnOnce(&mut SimCore) -> R) -> R {
        f(&mut lock(&self.core))
    }
}

impl Drop for FirmwareSim {
    fn drop(&mut self) {
        self.task.abort();
    }
}

fn lock(m: &Mutex<SimCore>) -> MutexGuard<'_, SimCore> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

async fn run(mut peer: MemoryPeer, core: Arc<Mutex<SimCore>>) {
    let mut tick = tokio::time::interval(Duration::from_millis(1));
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Burst);
    let mut buf = vec![0u8; 4096];
    let mut out = Vec::new();
    loop {
        tick.tick().await;
        let mut c = lock(&core);
        while let Some(end) = peer.end() {
            match poll_now_read(end, &mut buf) {
                Some(Ok(0)) | Some(Err(_)) => peer.drop_end(),
                Some(Ok(n)) => c.push_inbound(buf.get(..n).unwrap_or(&[])),
                None => break,
            }
        }
        c.step_ms();
        out.clear();
        c.take_outbound(&mut out);
        drop(c);
        let mut rest = out.as_slice();
        while !rest.is_empty() {
            let Some(end) = peer.end() else { break };
            match poll_now_write(end, rest) {
                Some(Ok(n)) if n > 0 => rest = rest.get(n..).unwrap_or(&[]),
                Some(Err(_)) => peer.drop_end(),
                // A full pipe drops the rest, as a UART with nobody reading would.
                _ => break,
            }
        }
    }
}

/// One non-blocking read: `None` when nothing is waiting.
fn poll_now_read<R: AsyncRead + Unpin>(
    r: &mut R,
    buf: &mut [u8],
) -> Option<std::io::Result<usize>> {
    let mut cx = Context::from_waker(Waker::noop());
    let mut rb = ReadBuf::new(buf);
    match Pin::new(r).poll_read(&mut cx, &mut rb) {
        Poll::Ready(Ok(())) => Some(Ok(rb.filled().len())),
        Poll::Ready(Err(e)) => Some(Err(e)),
        Poll::Pending => None,
    }
}

/// One non-blocking write: `None` when the pipe is full.
fn poll_now_write<W: AsyncWrite + Unpin>(
    w: &mut W,
    bytes: &[u8],
) -> Option<std::io::Result<usize>> {
    let mut cx = Context::from_waker(Waker::noop());
    match Pin::new(w).poll_write(&mut cx, bytes) {
        Poll::Ready(r) => Some(r),
        Poll::Pending => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_filter_drops_whole_frames_and_keeps_lone_delimiters() {
        let mut st = FaultState {
            at_start: true,
            dropping: false,
        };
        let mut drop = 1;
        let kept = filter_frames(&[0, 1, 2, 0, 3, 4, 0], &mut st, &mut drop);
        assert_eq!(kept, vec![0, 3, 4, 0]);
        assert_eq!(drop, 0);
        // Split across calls.
        let mut drop = 1;
        let a = filter_frames(&[5, 6], &mut st, &mut drop);
        let b = filter_frames(&[7, 0, 8, 0], &mut st, &mut drop);
        assert!(a.is_empty());
        assert_eq!(b, vec![8, 0]);
    }
}
