//! The station link through the world (optional): the board's UART0 on a socket, the station
//! on a pty of the emulator's own, and between them the emulator's link faults (`fault`: drops,
//! bit flips, stalls, seeded per direction) and a line rate, as `serve` gives an emulated
//! robot's link. Without it the station opens QEMU's pty directly: no faults, and QEMU's UART
//! sends bytes as fast as they are written.
//!
//! A thread moves bytes both ways every millisecond or sooner; with a line rate, no more than
//! `baud / 10` bytes a second go either way (8N1), the rest waiting their turn as on a wire.

use std::io::{Read, Write};
use std::os::fd::AsFd;
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use nix::poll::{PollFd, PollFlags, PollTimeout};
use serde::Serialize;

use crate::fault::{FaultConfig, FaultInjector, FaultStats};
use crate::pty::{Pty, ReadState};

/// Bytes a direction holds for its line before it stops reading its source: a USB-serial
/// adapter's FIFO. Beyond it the writer is held back (the pty's buffer, the socket, QEMU's UART
/// and so the board's own transmit FIFO fill), as a real line does, rather than the relay
/// queueing without end and delaying everything behind it.
const LINE_BUFFER: usize = 64;

/// The relay's faults and line rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RelayOptions {
    pub to_robot: FaultConfig,
    pub from_robot: FaultConfig,
    /// The line rate, baud (8N1); `None`: as fast as the bytes come.
    pub baud: Option<u32>,
    /// Seeds the faults (the run's seed).
    pub seed: u64,
}

impl RelayOptions {
    /// Whether the link needs the relay at all.
    pub fn wanted(&self) -> bool {
        !self.to_robot.is_clean() || !self.from_robot.is_clean() || self.baud.is_some()
    }
}

/// What the relay did, for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RelayStats {
    pub to_robot_bytes: u64,
    pub to_robot_dropped: u64,
    pub to_robot_flipped: u64,
    pub from_robot_bytes: u64,
    pub from_robot_dropped: u64,
    pub from_robot_flipped: u64,
}

fn stats(to: FaultStats, from: FaultStats) -> RelayStats {
    RelayStats {
        to_robot_bytes: to.bytes_in,
        to_robot_dropped: to.bytes_dropped,
        to_robot_flipped: to.bits_flipped,
        from_robot_bytes: from.bytes_in,
        from_robot_dropped: from.bytes_dropped,
        from_robot_flipped: from.bits_flipped,
    }
}

/// One direction: the faults, then the bytes waiting for the line.
struct Direction {
    faults: FaultInjector,
    line: Vec<u8>,
    sent: u64,
}

impl Direction {
    /// Bytes the line may carry now (all of them without a rate).
    fn due(&self, baud: Option<u32>, elapsed_s: f64) -> usize {
        match baud {
            None => self.line.len(),
            Some(b) => {
                let allowed = (elapsed_s * f64::from(b) / 10.0) as u64;
                let n = allowed.saturating_sub(self.sent) as usize;
                n.min(self.line.len())
            }
        }
    }
}

/// Relays between `pty` (the station's) and `board` (QEMU's UART0) until `stop`; returns the
/// counts when it ends.
pub fn spawn(
    pty: Pty,
    mut board: UnixStream,
    opts: RelayOptions,
    stop: Arc<AtomicBool>,
) -> JoinHandle<RelayStats> {
    std::thread::spawn(move || {
        let start = Instant::now();
        let mut to = Direction {
            faults: FaultInjector::new(opts.to_robot, opts.seed, 1),
            line: Vec::new(),
            sent: 0,
        };
        let mut from = Direction {
            faults: FaultInjector::new(opts.from_robot, opts.seed, 2),
            line: Vec::new(),
            sent: 0,
        };
        let _ = board.set_nonblocking(true);
        // A small socket buffer: the board's bytes wait in its own transmit FIFO, as behind a
        // real UART, not by the hundred kilobytes in the kernel.
        let _ = nix::sys::socket::setsockopt(&board, nix::sys::socket::sockopt::RcvBuf, &2048);
        let mut buf = [0u8; LINE_BUFFER];
        while !stop.load(Ordering::Relaxed) {
            if from.line.len() < LINE_BUFFER {
                let mut fds = [PollFd::new(board.as_fd(), PollFlags::POLLIN)];
                let _ = nix::poll::poll(&mut fds, PollTimeout::from(1u8));
            } else {
                // The board's bytes wait for the line: polling for them would spin (the
                // socket stays readable) and take the CPU QEMU needs.
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
            let t = start.elapsed().as_secs_f64();
            // From the station (the pty never blocks).
            let mut got = Vec::new();
            let room = |d: &Direction| LINE_BUFFER.saturating_sub(d.line.len());
            let n = room(&to);
            if n > 0 {
                if let ReadState::Data(n) = pty.read(&mut buf[..n]) {
                    got.extend_from_slice(&buf[..n]);
                }
            }
            to.faults.apply(&got, t, &mut to.line);
            // From the board.
            got.clear();
            let n = room(&from);
            if n > 0 {
                match board.read(&mut buf[..n]) {
                    Ok(0) => break,
                    Ok(n) => got.extend_from_slice(&buf[..n]),
                    Err(_) => {}
                }
            }
            from.faults.apply(&got, t, &mut from.line);
            // Onto the lines.
            let n = to.due(opts.baud, t);
            if n > 0 {
                let w = board.write(&to.line[..n]).unwrap_or(0);
                let _ = board.flush();
                to.line.drain(..w);
                to.sent += w as u64;
            }
            let n = from.due(opts.baud, t);
            if n > 0 {
                // What the pty does not take (no station attached, or its buffer full) is
                // lost, as on an unplugged cable or an overrun.
                let _ = pty.write(&from.line[..n]);
                from.line.drain(..n);
                from.sent += n as u64;
            }
            if let Some(b) = opts.baud {
                // An idle line does not bank time for a later burst.
                let allowed = (t * f64::from(b) / 10.0) as u64;
                for d in [&mut to, &mut from] {
                    if d.line.is_empty() {
                        d.sent = d.sent.max(allowed);
                    }
                }
            }
        }
        stats(to.faults.stats(), from.faults.stats())
    })
}
