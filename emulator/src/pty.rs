//! The emulator's end of a pseudo-terminal: the robot's serial port as a real tty.
//!
//! Layer: host I/O at the edge. `Pty::open` creates a master/slave pair in raw mode (no echo,
//! no line editing, 8 bits), so the station opens the slave path exactly as it would open
//! /dev/ttyUSB0. The emulator keeps only the master: while no one has the slave open, Linux
//! answers reads on the master with EIO and the robot's bytes go nowhere, as they would on a
//! wire with nothing plugged in; when the station (re)opens the slave, bytes flow again. The
//! master is non-blocking, and a full pty buffer drops bytes instead of stalling the
//! simulation. A pty ignores baud rates: the emulator's UART model throttles the bytes.
//!
//! Can fail: creating the pair (no free ptys), naming the slave, creating the `--link`
//! symlink (a non-link file already there is never overwritten).

use std::io;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};

use nix::fcntl::{fcntl, FcntlArg, OFlag};
use nix::pty::openpty;
use nix::sys::termios::{cfmakeraw, tcgetattr, tcsetattr, SetArg};

/// Why a pty could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    #[error("cannot create a pseudo-terminal: {0}")]
    Open(nix::Error),
    #[error("cannot configure the pseudo-terminal: {0}")]
    Configure(nix::Error),
    #[error("cannot name the pseudo-terminal's slave: {0}")]
    Name(nix::Error),
    #[error("--link {path}: {message}")]
    Link { path: PathBuf, message: String },
}

/// An open pseudo-terminal master and the path of its slave.
pub struct Pty {
    master: OwnedFd,
    slave_path: PathBuf,
    link: Option<PathBuf>,
}

/// The outcome of a read on the master.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadState {
    /// `n` bytes were read.
    Data(usize),
    /// Nothing waiting now.
    Idle,
    /// No process has the slave open.
    NoPeer,
}

impl Pty {
    /// Creates a raw-mode pty pair; with `link`, also a symlink to the slave (as socat's
    /// `link=` does), replacing an old symlink but never a regular file.
    pub fn open(link: Option<&Path>) -> Result<Pty, PtyError> {
        let pair = openpty(None, None).map_err(PtyError::Open)?;
        // Raw mode on the slave: the station would set it too, but bytes written before it
        // opens the port must not be echoed back or mangled by the line discipline.
        let mut t = tcgetattr(pair.slave.as_fd()).map_err(PtyError::Configure)?;
        cfmakeraw(&mut t);
        tcsetattr(pair.slave.as_fd(), SetArg::TCSANOW, &t).map_err(PtyError::Configure)?;
        let slave_path = nix::unistd::ttyname(pair.slave.as_fd()).map_err(PtyError::Name)?;
        let flags = fcntl(pair.master.as_fd(), FcntlArg::F_GETFL).map_err(PtyError::Configure)?;
        let flags = OFlag::from_bits_truncate(flags) | OFlag::O_NONBLOCK;
        fcntl(pair.master.as_fd(), FcntlArg::F_SETFL(flags)).map_err(PtyError::Configure)?;
        // Our slave fd closes here; the termios settings stay with the pty while the
        // master lives.
        drop(pair.slave);
        let link = match link {
            Some(p) => Some(make_link(p, &slave_path)?),
            None => None,
        };
        Ok(Pty {
            master: pair.master,
            slave_path,
            link,
        })
    }

    /// The path the station opens.
    pub fn slave_path(&self) -> &Path {
        &self.slave_path
    }

    /// The `--link` symlink, if one was made.
    pub fn link_path(&self) -> Option<&Path> {
        self.link.as_deref()
    }

    /// Reads what the station wrote, without blocking.
    pub fn read(&self, buf: &mut [u8]) -> ReadState {
        match nix::unistd::read(&self.master, buf) {
            Ok(0) => ReadState::Idle,
            Ok(n) => ReadState::Data(n),
            Err(nix::Error::EAGAIN) | Err(nix::Error::EINTR) => ReadState::Idle,
            // EIO: the slave is closed (no station attached); other errors are treated the
            // same way, since all the emulator can do is wait for a peer.
            Err(_) => ReadState::NoPeer,
        }
    }

    /// Waits up to `timeout` for the station to write something (returns at once if it has).
    /// With no station attached the master reports a hang-up at once: then this just sleeps,
    /// so the serving loop does not spin.
    pub fn wait_input(&self, timeout: std::time::Duration) {
        use nix::poll::{PollFd, PollFlags};
        let mut fds = [PollFd::new(self.master.as_fd(), PollFlags::POLLIN)];
        let ready = poll_for(&mut fds, timeout);
        let hung_up = fds
            .first()
            .and_then(PollFd::revents)
            .is_some_and(|r| r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR));
        if ready.is_err() || hung_up {
            std::thread::sleep(timeout);
        }
    }

    /// Waits up to `timeout` for a station to write to any of `ptys` (a fleet's ports).
    /// Ports with no station attached report a hang-up at once; they are left out of the
    /// wait, and with none left this just sleeps, so the serving loop does not spin.
    pub fn wait_any(ptys: &[&Pty], timeout: std::time::Duration) {
        use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
        let mut fds: Vec<PollFd> = ptys
            .iter()
            .map(|p| PollFd::new(p.master.as_fd(), PollFlags::POLLIN))
            .collect();
        // A hung-up port answers at once: look once without waiting, then wait on the rest.
        let _ = poll(&mut fds, PollTimeout::ZERO);
        let input = |f: &PollFd| f.revents().is_some_and(|r| r.contains(PollFlags::POLLIN));
        if fds.iter().any(input) {
            return;
        }
        let hung = |f: &PollFd| {
            f.revents()
                .is_some_and(|r| r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR))
        };
        let mut live: Vec<PollFd> = ptys
            .iter()
            .zip(&fds)
            .filter(|(_, f)| !hung(f))
            .map(|(p, _)| PollFd::new(p.master.as_fd(), PollFlags::POLLIN))
            .collect();
        if live.is_empty() || poll_for(&mut live, timeout).is_err() {
            std::thread::sleep(timeout);
        }
    }

    /// Writes bytes for the station; returns how many the pty took (the rest are dropped by
    /// the caller, as a UART with a full buffer would).
    pub fn write(&self, bytes: &[u8]) -> usize {
        // EAGAIN (buffer full) and EIO (no station) both mean "took nothing".
        nix::unistd::write(&self.master, bytes).unwrap_or_default()
    }
}

impl Drop for Pty {
    fn drop(&mut self) {
        if let Some(link) = &self.link {
            // Only remove the link if it still points at our slave.
            if std::fs::read_link(link).ok().as_deref() == Some(self.slave_path.as_path()) {
                let _ = std::fs::remove_file(link);
            }
        }
    }
}

fn make_link(link: &Path, target: &Path) -> Result<PathBuf, PtyError> {
    let err = |message: String| PtyError::Link {
        path: link.to_path_buf(),
        message,
    };
    match std::fs::symlink_metadata(link) {
        Ok(meta) if meta.file_type().is_symlink() => {
            std::fs::remove_file(link).map_err(|e| err(format!("cannot replace old link: {e}")))?
        }
        Ok(_) => {
            return Err(err(
                "exists and is not a symlink; refusing to overwrite it".to_string()
            ))
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(err(e.to_string())),
    }
    std::os::unix::fs::symlink(target, link).map_err(|e| err(e.to_string()))?;
    Ok(link.to_path_buf())
}

/// `poll` with a timeout to the microsecond (`ppoll`): the serving loop wakes when a byte's
/// last bit leaves the line, and a timeout in whole milliseconds (`poll`'s) cut waits under
/// one to none at all and others by up to a millisecond.
fn poll_for(fds: &mut [nix::poll::PollFd], timeout: std::time::Duration) -> nix::Result<i32> {
    let t = nix::sys::time::TimeSpec::from_duration(timeout);
    nix::poll::ppoll(fds, Some(t), None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    #[test]
    fn bytes_cross_the_pty_in_both_directions_raw() {
        let pty = Pty::open(None).expect("pty");
        let mut slave = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(pty.slave_path())
            .expect("open slave");
        // Every byte value, zero and newline included, arrives unchanged (raw mode).
        let all: Vec<u8> = (0..=255u8).collect();
        assert_eq!(pty.write(&all), 256);
        let mut got = vec![0u8; 256];
        slave.read_exact(&mut got).expect("read");
        assert_eq!(got, all);
        slave.write_all(&[0, 1, 2, b'\n', 0xFF]).expect("write");
        std::thread::sleep(std::time::Duration::from_millis(20));
        let mut buf = [0u8; 16];
        assert_eq!(pty.read(&mut buf), ReadState::Data(5));
        assert_eq!(&buf[..5], &[0, 1, 2, b'\n', 0xFF]);
    }

    #[test]
    fn a_closed_slave_reads_as_no_peer_and_reopening_works() {
        let pty = Pty::open(None).expect("pty");
        let mut buf = [0u8; 16];
        assert_eq!(pty.read(&mut buf), ReadState::NoPeer);
        {
            let mut slave = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(pty.slave_path())
                .expect("open slave");
            slave.write_all(b"hi").expect("write");
            std::thread::sleep(std::time::Duration::from_millis(20));
            assert_eq!(pty.read(&mut buf), ReadState::Data(2));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert_eq!(pty.read(&mut buf), ReadState::NoPeer);
        let mut again = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(pty.slave_path())
            .expect("reopen slave");
        again.write_all(b"x").expect("write");
        std::thread::sleep(std::time::Duration::from_millis(20));
        assert_eq!(pty.read(&mut buf), ReadState::Data(1));
    }

    #[test]
    fn link_replaces_an_old_symlink_but_never_a_file() {
        let dir = std::env::temp_dir().join(format!("pty-link-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let link = dir.join("robot");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink("/nonexistent", &link).expect("old link");
        let pty = Pty::open(Some(&link)).expect("pty");
        assert_eq!(std::fs::read_link(&link).expect("link"), pty.slave_path());
        drop(pty);
        assert!(
            std::fs::symlink_metadata(&link).is_err(),
            "link removed on drop"
        );
        std::fs::write(&link, b"precious").expect("file");
        assert!(matches!(Pty::open(Some(&link)), Err(PtyError::Link { .. })));
        assert_eq!(std::fs::read(&link).expect("file kept"), b"precious");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
