//! Serving the world over a port (docs/hil.md §1): a tty (QEMU's `-serial pty`, or a real
//! board's USB serial adapter) or the Unix socket of a QEMU started here (`qemu`).
//!
//! The loop only moves bytes: `HilWorld` decides. It waits on the port with a timeout so that
//! Ctrl-C, the end of QEMU and `--seconds` are noticed while the board is silent (a board
//! that stops answering stops the world with it: lockstep).

use std::io::{Read, Write};
use std::os::fd::AsFd;
use std::os::unix::net::UnixListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use nix::poll::{PollFd, PollFlags, PollTimeout};

use super::qemu::{self, QemuOptions};
use super::relay::{self, RelayOptions};
use super::{HilSummary, HilWorld};

/// Where the board is.
#[derive(Clone, Debug)]
pub enum Port {
    /// A tty path (a pty QEMU made, or a serial adapter).
    Tty(PathBuf),
    /// Start QEMU with this image and serve it over a socket; with a relay, the station's
    /// link goes through the world too (faults, line rate).
    Qemu(QemuOptions, Option<RelayOptions>),
}

/// When to stop.
#[derive(Clone, Copy, Debug, Default)]
pub struct StopWhen {
    /// After this much world time, seconds.
    pub world_seconds: Option<f64>,
    /// Once the true position is in the target area (plus `grace_s` of world time).
    pub target: bool,
    pub grace_s: f64,
    /// When the board has not sent a byte for this long (wall clock), seconds.
    pub silent_s: Option<f64>,
}

/// A byte stream to the board.
trait Stream: Read + Write + AsFd {}
impl<T: Read + Write + AsFd> Stream for T {}

/// Runs the world for the board at `port` until `stop` (Ctrl-C) or `when`; `on_station_port`
/// is told the station's port once there is one (QEMU's pty; for a tty the caller knows it).
pub fn serve(
    world: &mut HilWorld,
    port: &Port,
    stop: &AtomicBool,
    when: StopWhen,
    on_station_port: &mut dyn FnMut(&Path),
) -> Result<HilSummary, String> {
    match port {
        Port::Tty(path) => {
            let file = open_tty(path)?;
            run(world, file, stop, when, None)
        }
        Port::Qemu(opts, relay) => {
            let dir = tempfile::Builder::new()
                .prefix("robot-hil-")
                .tempdir()
                .map_err(|e| format!("cannot make a directory for the HIL socket: {e}"))?;
            let listen = |name: &str| {
                let path = dir.path().join(name);
                UnixListener::bind(&path)
                    .map(|l| (l, path.clone()))
                    .map_err(|e| format!("cannot listen on {}: {e}", path.display()))
            };
            let (hil_listener, hil_sock) = listen("hil.sock")?;
            let station = match relay {
                Some(_) => Some(listen("station.sock")?),
                None => None,
            };
            let mut q = qemu::start(opts, &hil_sock, station.as_ref().map(|(_, p)| p.as_path()))?;
            let stream = accept_within(&hil_listener, Duration::from_secs(10), &mut q.child)?;
            let mut relay_thread = None;
            let relay_stop = Arc::new(AtomicBool::new(false));
            match (station, relay, &q.station_pty) {
                (Some((listener, _)), Some(r), _) => {
                    let board = accept_within(&listener, Duration::from_secs(10), &mut q.child)?;
                    let pty = crate::pty::Pty::open(None).map_err(|e| e.to_string())?;
                    on_station_port(pty.slave_path());
                    relay_thread = Some(relay::spawn(pty, board, *r, Arc::clone(&relay_stop)));
                }
                (_, _, Some(pty)) => on_station_port(pty),
                _ => return Err("QEMU's UART0 has no port".to_string()),
            }
            let result = run(world, stream, stop, when, Some(&mut q.child));
            relay_stop.store(true, Ordering::Relaxed);
            let relay_stats = relay_thread.and_then(|t| t.join().ok());
            let _ = q.child.kill();
            let _ = q.child.wait();
            result.map(|mut s| {
                s.relay = relay_stats;
                s
            })
        }
    }
}

fn accept_within(
    listener: &UnixListener,
    limit: Duration,
    child: &mut std::process::Child,
) -> Result<std::os::unix::net::UnixStream, String> {
    listener
        .set_nonblocking(true)
        .map_err(|e| format!("socket: {e}"))?;
    let deadline = Instant::now() + limit;
    loop {
        match listener.accept() {
            Ok((s, _)) => {
                s.set_nonblocking(false)
                    .map_err(|e| format!("socket: {e}"))?;
                return Ok(s);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => return Err(format!("socket: {e}")),
        }
        if let Ok(Some(status)) = child.try_wait() {
            return Err(format!("QEMU exited before connecting its UART1: {status}"));
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            return Err("QEMU did not connect its UART1 within 10 s".to_string());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Opens a tty for reading and writing, raw, 8N1, no echo (the baud rate does not matter for
/// a pty; a real adapter is set to 115200 like the station link).
fn open_tty(path: &Path) -> Result<std::fs::File, String> {
    use nix::sys::termios::{self, BaudRate, SetArg};
    use std::os::unix::fs::OpenOptionsExt;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::fcntl::OFlag::O_NOCTTY.bits())
        .open(path)
        .map_err(|e| format!("cannot open the HIL port {}: {e}", path.display()))?;
    if let Ok(mut t) = termios::tcgetattr(&file) {
        termios::cfmakeraw(&mut t);
        let _ = termios::cfsetspeed(&mut t, BaudRate::B115200);
        termios::tcsetattr(&file, SetArg::TCSANOW, &t)
            .map_err(|e| format!("cannot set {} raw: {e}", path.display()))?;
    }
    Ok(file)
}

fn run(
    world: &mut HilWorld,
    mut port: impl Stream,
    stop: &AtomicBool,
    when: StopWhen,
    mut qemu: Option<&mut std::process::Child>,
) -> Result<HilSummary, String> {
    let mut buf = [0u8; 512];
    let mut out = Vec::with_capacity(512);
    let mut last_byte = Instant::now();
    while !stop.load(Ordering::Relaxed) {
        let s = world.summary();
        if when
            .world_seconds
            .is_some_and(|limit| s.world_time_s >= limit)
        {
            break;
        }
        if when.target
            && s.target_reached_s
                .is_some_and(|t| s.world_time_s >= t + when.grace_s)
        {
            break;
        }
        if s.fault.is_some() {
            break;
        }
        if when
            .silent_s
            .is_some_and(|limit| last_byte.elapsed().as_secs_f64() > limit)
        {
            return Err(format!(
                "the board sent nothing for {:.0} s (world time {:.2} s)",
                when.silent_s.unwrap_or_default(),
                s.world_time_s
            ));
        }
        if let Some(child) = qemu.as_deref_mut() {
            if let Ok(Some(status)) = child.try_wait() {
                return Err(format!("QEMU exited: {status}"));
            }
        }
        let ready = {
            let mut fds = [PollFd::new(port.as_fd(), PollFlags::POLLIN)];
            nix::poll::poll(&mut fds, PollTimeout::from(100u16)).unwrap_or(0) > 0
        };
        if !ready {
            continue;
        }
        let n = match port.read(&mut buf) {
            Ok(0) if stop.load(Ordering::Relaxed) => break,
            Ok(0) => return Err("the board's port closed".to_string()),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            // A pty whose other side is not open yet reads EIO: wait for it.
            Err(e) if e.raw_os_error() == Some(nix::libc::EIO) => {
                std::thread::sleep(Duration::from_millis(50));
                continue;
            }
            Err(e) => return Err(format!("reading the board's port: {e}")),
        };
        last_byte = Instant::now();
        out.clear();
        let stops = world.stops();
        world.feed(&buf[..n], &mut out).map_err(|e| e.to_string())?;
        if world.stops() != stops {
            if let Ok(t) = nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC) {
                world.note_stop_time(t.tv_sec() as f64 + t.tv_nsec() as f64 * 1e-9);
            }
        }
        if !out.is_empty() {
            port.write_all(&out)
                .and_then(|()| port.flush())
                .map_err(|e| format!("writing the board's port: {e}"))?;
        }
    }
    Ok(world.summary())
}
