//! Serving the simulated robot on a pseudo-terminal, in real time or faster.
//!
//! Layer: the emulator's I/O loop. It advances the simulation in 1 ms steps against the wall
//! clock (times `speed`), moves bytes between the pty and the robot's UART model through the
//! seeded fault injectors, and can unplug and replug the port to test reconnection. The
//! simulation itself knows nothing of ptys, faults or wall time; the baud rate is enforced by
//! its UART model in simulated time, so in real-time mode the pty carries no more than the
//! configured baud rate.
//!
//! `spawn` runs the loop on a thread and hands back the slave path: the station's built-in
//! default uses it, and so do the end-to-end tests.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::fault::{FaultConfig, FaultInjector, FaultStats};
use crate::pty::{Pty, PtyError, ReadState};

/// A simulated robot as the serving loop sees it.
pub trait Device {
    /// Simulated time, microseconds.
    fn now_us(&self) -> u64;
    /// Advances the simulation by one millisecond.
    fn step_ms(&mut self);
    /// Bytes arriving at the robot's serial port.
    fn push_inbound(&mut self, bytes: &[u8]);
    /// Bytes the robot's serial port has finished sending, appended to `out`.
    fn take_outbound(&mut self, out: &mut Vec<u8>);
    /// Control cycles run so far (for the real-time jitter figure).
    fn cycles(&self) -> u32;
    /// The control-cycle period, microseconds.
    fn cycle_us(&self) -> u32;
    /// Bytes from the station that never reached the robot's software (a burst beyond its
    /// serial port's buffers); 0 for a device that loses none.
    fn to_robot_dropped(&self) -> u64 {
        0
    }
    /// Simulated time (µs) at which the serving loop must run the next step when no byte
    /// arrives from the station. The robot acts at the start of a step (and within it when a
    /// frame from the station completes, `Sim::step`: bytes already on the wire when the step
    /// runs), so a step runs as soon as the clock reaches its start: `now_us()` itself while
    /// bytes are on the wire, else the next thing the robot does on its own (its control
    /// cycle) or `IDLE_LOOK_US` on at the latest.
    fn next_due_us(&self) -> u64 {
        self.now_us()
    }
    /// Moves the bytes on the wire on to `now_us` (at most the start of the next step) without
    /// stepping the robot, so that bytes that completed since the last step reach the robot's
    /// receive FIFO before its next step reads it.
    fn sync_line(&mut self, _now_us: u64) {}
    /// Bytes from the station that reached the line at simulated `at_us`.
    fn push_inbound_at(&mut self, bytes: &[u8], _at_us: u64) {
        self.push_inbound(bytes);
    }
    /// Bytes the robot's serial port had finished sending by `until_us`, appended to `out`
    /// (a step moves the line on to its end, up to a millisecond ahead of the clock).
    fn take_outbound_until(&mut self, _until_us: u64, out: &mut Vec<u8>) {
        self.take_outbound(out);
    }
    /// When the next frame already on its way to the station ends (its delimiter's last bit),
    /// simulated µs; the serving loop hands it over then. `None`: no frame end is pending.
    fn next_frame_end_us(&self) -> Option<u64> {
        None
    }
    /// Gives the robot its link key (PROTOCOL.md §13); `serve` calls it before the first byte.
    fn set_link_key(&mut self, _key: Option<&[u8; protocol::sign::KEY_LEN]>) {}
}

/// How fast simulated time runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speed {
    /// `factor` simulated seconds per wall second; 1.0 is real time.
    Factor(f64),
    /// As fast as the machine allows.
    Max,
}

/// Link behaviour of a served emulator.
#[derive(Clone, Debug, PartialEq)]
pub struct ServeOptions {
    pub speed: Speed,
    /// Faults on bytes from the station to the robot.
    pub to_robot: FaultConfig,
    /// Faults on bytes from the robot to the station.
    pub from_robot: FaultConfig,
    /// Unplug the port after this many simulated seconds.
    pub disconnect_after_s: Option<f64>,
    /// Plug it back in (a new pty, the `--link` symlink updated) this long after unplugging.
    pub reconnect_after_s: Option<f64>,
    /// A symlink kept pointing at the current pty.
    pub link: Option<PathBuf>,
    pub seed: u64,
    /// The link key (PROTOCOL.md §13): the robot then signs everything and accepts only
    /// frames signed with it.
    pub key: Option<[u8; protocol::sign::KEY_LEN]>,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            speed: Speed::Factor(1.0),
            to_robot: FaultConfig::default(),
            from_robot: FaultConfig::default(),
            disconnect_after_s: None,
            reconnect_after_s: None,
            link: None,
            seed: 0,
            key: None,
        }
    }
}

/// What a serving run measured.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ServeStats {
    pub sim_s: f64,
    pub wall_s: f64,
    pub bytes_to_robot: u64,
    pub bytes_from_robot: u64,
    /// Bytes the pty would not take (no station attached, or its buffer full).
    pub bytes_unsent: u64,
    /// Bytes from the station the robot's serial port dropped: a burst beyond its line buffer
    /// or receive FIFO, as a real UART overrun loses them.
    pub bytes_to_robot_dropped: u64,
    pub to_robot_faults: FaultCounts,
    pub from_robot_faults: FaultCounts,
    pub disconnects: u32,
    /// Real-time mode: wall-clock control-cycle period, microseconds.
    pub cycle_period_us: Jitter,
}

/// Fault counters in serialisable form.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FaultCounts {
    pub bytes_dropped: u64,
    pub bits_flipped: u64,
}

impl From<FaultStats> for FaultCounts {
    fn from(s: FaultStats) -> Self {
        FaultCounts {
            bytes_dropped: s.bytes_dropped,
            bits_flipped: s.bits_flipped,
        }
    }
}

/// Distribution of the wall-clock control-cycle period.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Jitter {
    pub samples: u64,
    pub nominal_us: f64,
    pub mean_us: f64,
    pub p50_us: f64,
    pub p99_us: f64,
    pub max_abs_error_us: f64,
}

impl Jitter {
    fn from_periods(nominal_us: f64, mut periods: Vec<f64>) -> Jitter {
        if periods.is_empty() {
            return Jitter {
                nominal_us,
                ..Jitter::default()
            };
        }
        periods.sort_by(f64::total_cmp);
        let pick = |q: f64| {
            let i = ((periods.len() - 1) as f64 * q).round() as usize;
            periods.get(i).copied().unwrap_or(0.0)
        };
        let mean = periods.iter().sum::<f64>() / periods.len() as f64;
        let max_err = periods
            .iter()
            .map(|p| (p - nominal_us).abs())
            .fold(0.0, f64::max);
        Jitter {
            samples: periods.len() as u64,
            nominal_us,
            mean_us: mean,
            p50_us: pick(0.5),
            p99_us: pick(0.99),
            max_abs_error_us: max_err,
        }
    }
}

/// Longest simulated time between two looks while the wire is idle: the most a frame the
/// robot sends unprompted (telemetry, an event) can leave late, about 46 byte times at
/// 115 200 baud. Bytes from the station wake the loop at once whatever this is.
pub const IDLE_LOOK_US: u64 = 4_000;
/// Simulated milliseconds between pty polls at maximum speed.
pub(crate) const MAX_SPEED_BATCH_MS: u32 = 20;
/// Most simulated steps one tick may catch up, so a stalled host does not freeze the pty.
pub(crate) const MAX_CATCH_UP_MS: u32 = 200;

/// Serves `dev` until `stop` is set. The pty is created here, so the slave path is reported
/// through `on_ready` (called again with the new path after each replug).
pub fn serve<D: Device>(
    dev: &mut D,
    opts: &ServeOptions,
    stop: &AtomicBool,
    on_ready: &mut dyn FnMut(&Path),
) -> Result<ServeStats, PtyError> {
    dev.set_link_key(opts.key.as_ref());
    let mut end = Endpoint::open(opts, on_ready)?;
    let wall0 = Instant::now();
    let sim0 = dev.now_us();
    let mut clock = CycleClock::new(dev.cycles());
    let real_time = match opts.speed {
        Speed::Factor(f) => {
            precise_wake_ups();
            Some(RealTime::new(wall0, sim0, f))
        }
        Speed::Max => None,
    };

    while !stop.load(Ordering::Relaxed) {
        // 1. Advance simulated time: in real time, every step whose start the clock has
        // reached (the robot acts at a step's start), moving the wire on to it first.
        let now_us = match &real_time {
            Some(rt) => {
                let now = rt.sim_now();
                step_until(dev, now, &mut |d| clock.observe(d.cycles()));
                now
            }
            None => {
                for _ in 0..MAX_SPEED_BATCH_MS {
                    dev.step_ms();
                }
                dev.now_us()
            }
        };
        let t_s = (dev.now_us() - sim0) as f64 * 1e-6;
        // 2. Unplug / replug; 3. station -> robot; 4. robot -> station.
        end.plug(t_s, on_ready)?;
        let (line_us, take_until) = exchange_clock(real_time.as_ref(), now_us);
        end.exchange(dev, t_s, line_us, take_until);

        if let Some(rt) = &real_time {
            // Driven by the next event (a step due, a frame's last byte leaving the line, or
            // bytes from the station, which wake the wait at once): an idle link costs a few
            // wake-ups, a command is read as it comes and its answer handed over as its last
            // bit leaves.
            let wait = rt
                .wall_at(next_look_us(dev))
                .saturating_duration_since(Instant::now());
            match end.pty() {
                Some(p) => p.wait_input(wait),
                None => std::thread::sleep(wait),
            }
        }
    }
    let mut stats = end.finish(dev);
    stats.sim_s = (dev.now_us() - sim0) as f64 * 1e-6;
    stats.wall_s = wall0.elapsed().as_secs_f64();
    stats.cycle_period_us = clock.jitter(dev.cycle_us());
    Ok(stats)
}

/// The simulated moments of an exchange with the pty: when the station's bytes read now
/// reached the line, and until when the robot's bytes may be handed over. In real time the
/// clock is read again after the steps (catching up can take a fraction of a millisecond
/// under load): bytes read then were stamped with the moment before the steps, so a
/// command seemed to arrive before it was written and was answered faster than its bytes
/// allow (a minimal client saw 1.74 ms for 2.0 ms of bytes, issue 15). At maximum speed: the
/// step reached, and everything sent.
pub(crate) fn exchange_clock(real_time: Option<&RealTime>, now_us: u64) -> (u64, u64) {
    match real_time {
        Some(rt) => {
            let t = rt.sim_now().max(now_us);
            (t, t)
        }
        None => (now_us, u64::MAX),
    }
}

/// Runs every step of `dev` whose start simulated `now_us` has reached (the robot acts at a
/// step's start), moving the wire on to each start first so the robot reads what completed by
/// then; at most `MAX_CATCH_UP_MS` steps. `after_step` sees the device after each.
pub(crate) fn step_until<D: Device>(dev: &mut D, now_us: u64, after_step: &mut dyn FnMut(&D)) {
    let mut steps = 0;
    while dev.now_us() <= now_us && steps < MAX_CATCH_UP_MS {
        dev.sync_line(dev.now_us());
        dev.step_ms();
        after_step(dev);
        steps += 1;
    }
}

/// When the serving loop must look next, simulated µs: the next step due, or the moment the
/// next frame towards the station ends, whichever comes first.
pub(crate) fn next_look_us<D: Device>(dev: &D) -> u64 {
    dev.next_due_us()
        .min(dev.next_frame_end_us().unwrap_or(u64::MAX))
}

/// Asks the kernel to wake this thread on time: its timer slack (50 µs by default on Linux,
/// by which a timed wait may end late so wake-ups can be grouped) becomes 1 µs. The real-time
/// serving loops sleep until a reply's last bit leaves the line; the default slack made the
/// hand-over of every answer about 50 µs late (issue 15). Best effort: elsewhere, or if the
/// kernel refuses, waits stay as they were.
pub(crate) fn precise_wake_ups() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1_000);
}

/// Simulated time against the wall clock, to the microsecond, at `factor` times real time.
/// The serving loops run a step as soon as the clock reaches its start and hand bytes over as
/// they complete: in whole milliseconds the robot acted up to 1 ms late, and its bytes were
/// held to the next millisecond (issue 15).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RealTime {
    wall0: Instant,
    sim0: u64,
    factor: f64,
}

impl RealTime {
    pub(crate) fn new(wall0: Instant, sim0: u64, factor: f64) -> RealTime {
        RealTime {
            wall0,
            sim0,
            factor,
        }
    }

    /// Simulated µs now.
    pub(crate) fn sim_now(&self) -> u64 {
        self.sim0 + (self.wall0.elapsed().as_secs_f64() * self.factor * 1e6) as u64
    }

    /// The wall-clock moment of simulated `sim_us`.
    pub(crate) fn wall_at(&self, sim_us: u64) -> Instant {
        let us = sim_us.saturating_sub(self.sim0) as f64 / self.factor;
        self.wall0 + Duration::from_secs_f64(us.clamp(0.0, 1e12) * 1e-6)
    }
}

/// The wall-clock period of a robot's control cycles, for the real-time jitter figure.
pub(crate) struct CycleClock {
    last: (u32, Instant),
    periods: Vec<f64>,
}

impl CycleClock {
    pub(crate) fn new(cycles: u32) -> CycleClock {
        CycleClock {
            last: (cycles, Instant::now()),
            periods: Vec::new(),
        }
    }

    /// Called after each step with the robot's cycle count: a new cycle records its period.
    pub(crate) fn observe(&mut self, cycles: u32) {
        if cycles != self.last.0 {
            let now = Instant::now();
            self.periods
                .push(now.duration_since(self.last.1).as_secs_f64() * 1e6);
            self.last = (cycles, now);
        }
    }

    /// The distribution, without the first period (it includes the pty setup).
    pub(crate) fn jitter(self, cycle_us: u32) -> Jitter {
        let periods = self.periods.into_iter().skip(1).collect();
        Jitter::from_periods(f64::from(cycle_us), periods)
    }
}

/// One robot's end of the link: its pty (absent while unplugged), its fault injectors and
/// its byte counters. The single-robot loop has one; a fleet's has one per robot.
pub(crate) struct Endpoint {
    pty: Option<Pty>,
    link: Option<PathBuf>,
    disconnect_after_s: Option<f64>,
    reconnect_after_s: Option<f64>,
    unplugged_at: Option<f64>,
    to_robot: FaultInjector,
    from_robot: FaultInjector,
    stats: ServeStats,
    buf: Vec<u8>,
    inbound: Vec<u8>,
    outbound: Vec<u8>,
    faulted: Vec<u8>,
}

impl Endpoint {
    /// Opens the pty (and `opts.link`) and reports its path through `on_ready`.
    pub(crate) fn open(
        opts: &ServeOptions,
        on_ready: &mut dyn FnMut(&Path),
    ) -> Result<Endpoint, PtyError> {
        let pty = Pty::open(opts.link.as_deref())?;
        on_ready(pty.slave_path());
        Ok(Endpoint {
            pty: Some(pty),
            link: opts.link.clone(),
            disconnect_after_s: opts.disconnect_after_s,
            reconnect_after_s: opts.reconnect_after_s,
            unplugged_at: None,
            to_robot: FaultInjector::new(opts.to_robot, opts.seed, 1),
            from_robot: FaultInjector::new(opts.from_robot, opts.seed, 2),
            stats: ServeStats::default(),
            buf: vec![0u8; 4096],
            inbound: Vec::with_capacity(4096),
            outbound: Vec::with_capacity(4096),
            faulted: Vec::with_capacity(4096),
        })
    }

    /// The pty, while plugged in.
    pub(crate) fn pty(&self) -> Option<&Pty> {
        self.pty.as_ref()
    }

    /// Unplugs the port at `disconnect_after_s` and plugs a new one in `reconnect_after_s`
    /// later (`t_s`: simulated seconds since serving began).
    pub(crate) fn plug(
        &mut self,
        t_s: f64,
        on_ready: &mut dyn FnMut(&Path),
    ) -> Result<(), PtyError> {
        if let (Some(after), None) = (self.disconnect_after_s, self.unplugged_at) {
            if t_s >= after && self.pty.is_some() {
                self.pty = None;
                self.unplugged_at = Some(t_s);
                self.stats.disconnects += 1;
            }
        }
        if let (Some(at), Some(re)) = (self.unplugged_at, self.reconnect_after_s) {
            if self.pty.is_none() && t_s >= at + re {
                let p = Pty::open(self.link.as_deref())?;
                on_ready(p.slave_path());
                self.pty = Some(p);
            }
        }
        Ok(())
    }

    /// Moves bytes both ways between the pty and `dev` through the fault injectors: what the
    /// station wrote reaches the line at simulated `now_us`, and what the robot's port had
    /// finished sending by `take_until_us` goes to the station.
    pub(crate) fn exchange<D: Device>(
        &mut self,
        dev: &mut D,
        t_s: f64,
        now_us: u64,
        take_until_us: u64,
    ) {
        // Station -> robot.
        self.inbound.clear();
        if let Some(p) = &self.pty {
            while let ReadState::Data(n) = p.read(&mut self.buf) {
                self.inbound
                    .extend_from_slice(self.buf.get(..n).unwrap_or(&[]));
            }
        }
        self.stats.bytes_to_robot += self.inbound.len() as u64;
        // Called even with no new bytes, so bytes held by a stall that has ended go through.
        self.faulted.clear();
        self.to_robot.apply(&self.inbound, t_s, &mut self.faulted);
        if !self.faulted.is_empty() {
            dev.push_inbound_at(&self.faulted, now_us);
        }

        // Robot -> station.
        self.outbound.clear();
        dev.take_outbound_until(take_until_us, &mut self.outbound);
        self.faulted.clear();
        self.from_robot
            .apply(&self.outbound, t_s, &mut self.faulted);
        self.stats.bytes_from_robot += self.outbound.len() as u64;
        let sent = self
            .pty
            .as_ref()
            .map_or(0, |p| write_all_possible(p, &self.faulted));
        self.stats.bytes_unsent += (self.faulted.len() - sent) as u64;
    }

    /// The counters (times and jitter are the caller's).
    pub(crate) fn finish<D: Device>(self, dev: &D) -> ServeStats {
        let mut stats = self.stats;
        stats.bytes_to_robot_dropped = dev.to_robot_dropped();
        stats.to_robot_faults = self.to_robot.stats().into();
        stats.from_robot_faults = self.from_robot.stats().into();
        stats
    }
}

fn write_all_possible(pty: &Pty, bytes: &[u8]) -> usize {
    let mut sent = 0;
    while sent < bytes.len() {
        let n = pty.write(bytes.get(sent..).unwrap_or(&[]));
        if n == 0 {
            break;
        }
        sent += n;
    }
    sent
}

/// A serving loop running on its own thread. Dropping it stops the loop and removes the pty.
pub struct Running {
    path: PathBuf,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<ServeStats, PtyError>>>,
    paths: std::sync::mpsc::Receiver<PathBuf>,
}

impl Running {
    /// The slave path to open (the newest one after a replug).
    pub fn path(&mut self) -> &Path {
        while let Ok(p) = self.paths.try_recv() {
            self.path = p;
        }
        &self.path
    }

    /// Stops the loop and returns what it measured.
    pub fn stop(mut self) -> Option<Result<ServeStats, PtyError>> {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().and_then(|t| t.join().ok())
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Runs `serve` for a device built by `make` on a new thread; returns once the pty exists.
pub fn spawn_device<D, F>(make: F, opts: ServeOptions) -> Result<Running, SpawnError>
where
    D: Device,
    F: FnOnce() -> Result<D, SpawnError> + Send + 'static,
{
    let stop = Arc::new(AtomicBool::new(false));
    let (path_tx, path_rx) = std::sync::mpsc::channel::<PathBuf>();
    let (err_tx, err_rx) = std::sync::mpsc::channel::<SpawnError>();
    let stop2 = Arc::clone(&stop);
    let thread = std::thread::Builder::new()
        .name("robot-emulator".into())
        .spawn(move || {
            let mut dev = match make() {
                Ok(d) => d,
                Err(e) => {
                    let _ = err_tx.send(e);
                    return Ok(ServeStats::default());
                }
            };
            let result = serve(&mut dev, &opts, &stop2, &mut |p| {
                let _ = path_tx.send(p.to_path_buf());
            });
            if let Err(e) = &result {
                let _ = err_tx.send(SpawnError::Pty(e.to_string()));
            }
            result
        })
        .map_err(|e| SpawnError::Thread(e.to_string()))?;
    // Wait for the first path or an error.
    loop {
        if let Ok(path) = path_rx.recv_timeout(Duration::from_millis(10)) {
            return Ok(Running {
                path,
                stop,
                thread: Some(thread),
                paths: path_rx,
            });
        }
        if let Ok(e) = err_rx.try_recv() {
            let _ = thread.join();
            return Err(e);
        }
        if thread.is_finished() {
            return Err(SpawnError::Thread(
                "the emulator thread ended before opening its pty".into(),
            ));
        }
    }
}

/// Why an emulator could not be started.
#[derive(Debug, thiserror::Error)]
pub enum SpawnError {
    #[error("{0}")]
    Arena(String),
    #[error("{0}")]
    Sim(String),
    #[error("{0}")]
    Pty(String),
    #[error("cannot start the emulator thread: {0}")]
    Thread(String),
}

impl Device for crate::sim::Sim {
    fn now_us(&self) -> u64 {
        crate::sim::Sim::now_us(self)
    }

    fn step_ms(&mut self) {
        self.step();
    }

    fn push_inbound(&mut self, bytes: &[u8]) {
        // The UART's line buffer is bounded; what it refuses is counted there, as a UART
        // overrun would be.
        self.uart_mut().push_inbound(bytes);
    }

    fn to_robot_dropped(&self) -> u64 {
        self.uart().stats().to_robot_dropped()
    }

    fn take_outbound(&mut self, out: &mut Vec<u8>) {
        self.take_outbound_until(u64::MAX, out);
    }

    fn take_outbound_until(&mut self, until_us: u64, out: &mut Vec<u8>) {
        let mut buf = [0u8; 1024];
        loop {
            let n = self.uart_mut().take_outbound_until(until_us, &mut buf);
            if n == 0 {
                return;
            }
            out.extend_from_slice(buf.get(..n).unwrap_or(&[]));
        }
    }

    fn push_inbound_at(&mut self, bytes: &[u8], at_us: u64) {
        self.uart_mut().push_inbound_at(bytes, at_us);
    }

    fn sync_line(&mut self, now_us: u64) {
        crate::sim::Sim::sync_line(self, now_us);
    }

    fn next_frame_end_us(&self) -> Option<u64> {
        self.uart().next_frame_end_us()
    }

    fn cycles(&self) -> u32 {
        self.robot().timing().cycles
    }

    fn cycle_us(&self) -> u32 {
        self.robot().profile().cycle_us
    }

    fn next_due_us(&self) -> u64 {
        let now = self.now_us();
        if !self.uart().idle() {
            return now;
        }
        let cycle = self.robot().timing().next_cycle_us;
        cycle.clamp(now, now + IDLE_LOOK_US)
    }

    fn set_link_key(&mut self, key: Option<&[u8; protocol::sign::KEY_LEN]>) {
        self.robot_mut().link_mut().set_key(key);
        self.uart_mut()
            .set_truth_key(key.map(protocol::LinkKey::new));
    }
}

/// Everything needed to start a served emulator.
#[derive(Clone, Debug)]
pub struct EmulatorOptions {
    /// A built-in arena name (`builtin::MICRO_RATO_99`) or a file path.
    pub arena: String,
    pub load: crate::arena::LoadOptions,
    pub sim: crate::sim::SimConfig,
    pub serve: ServeOptions,
}

impl EmulatorOptions {
    /// The station's built-in default: Micro-Rato'99, the micro-rato profile, real time.
    pub fn builtin_default() -> EmulatorOptions {
        EmulatorOptions {
            arena: crate::builtin::MICRO_RATO_99.to_string(),
            load: crate::arena::LoadOptions::for_simulation(),
            sim: crate::sim::SimConfig::new(&robot_firmware::MICRO_RATO),
            serve: ServeOptions::default(),
        }
    }
}

/// A served emulator on its own thread; dropping it stops the robot and removes the pty.
pub type RunningEmulator = Running;

/// Loads the arena, builds the simulation and serves it on a new pty.
pub fn spawn(opts: EmulatorOptions) -> Result<RunningEmulator, SpawnError> {
    let EmulatorOptions {
        arena,
        load,
        sim,
        serve,
    } = opts;
    // Load here, not on the thread, so a bad arena is reported before anything starts.
    let arena =
        crate::builtin::load(&arena, &load).map_err(|e| SpawnError::Arena(e.to_string()))?;
    let sim = crate::sim::Sim::new(arena, sim).map_err(|e| SpawnError::Sim(e.to_string()))?;
    spawn_device(move || Ok(sim), serve)
}

/// Reads a link key file: 64 hex digits (surrounding white space ignored). The error names
/// the file and what is wrong with it. A regular file that group or others may access is
/// refused, as ssh refuses such a private key: whoever can read the key can drive the robot.
pub fn read_key_file(path: &Path) -> Result<[u8; protocol::sign::KEY_LEN], String> {
    let file = crate::input_file::InputFile::open(path, &KEY_FILE).map_err(|e| key_error(&e))?;
    // The open file's mode, not the path's: no window for a swap in between. Only regular
    // files: a pipe (`--key-file <(pass show robot)`) is the caller's own.
    if let Some(mode) = loose_mode(file.metadata()) {
        return Err(format!(
            "key file {p} is accessible by group or others (mode {mode:04o}); a link key must \
             be private, as an ssh private key must: run `chmod 600 {p}`",
            p = path.display()
        ));
    }
    // Bounded: a key is 64 digits, and a pipe that never ends must not hang.
    let bytes = file.read_all().map_err(|e| key_error(&e))?;
    let text = String::from_utf8_lossy(&bytes);
    protocol::sign::parse_key_hex(&text).map_err(|e| format!("key file {}: {e}", path.display()))
}

/// A key file's read error, naming it as one.
fn key_error(e: &crate::input_file::InputError) -> String {
    format!("key file {}: {}", e.path().display(), e.reason())
}

/// What a key file may be: 64 hex digits with room for white space and line endings; a pipe
/// is read (up to the limit).
const KEY_FILE: crate::input_file::InputKind = crate::input_file::InputKind {
    what: "key files",
    max_bytes: 4096,
    pipes: true,
};

/// The permission bits of a regular file that group or others may read, write or execute.
#[cfg(unix)]
fn loose_mode(meta: &std::fs::Metadata) -> Option<u32> {
    use std::os::unix::fs::PermissionsExt as _;
    let mode = meta.permissions().mode() & 0o7777;
    (meta.is_file() && mode & 0o077 != 0).then_some(mode)
}

#[cfg(not(unix))]
fn loose_mode(_: &std::fs::Metadata) -> Option<u32> {
    None
}

#[cfg(test)]
mod tests;
