//! A real serial port (or a pty slave) as a `Transport`, opened exclusively.
//!
//! Layer: I/O edge. Opens with tokio-serial over serialport, which sets TIOCEXCL and takes an
//! exclusive `flock`, so a second station (or any flock-aware program) cannot share the port
//! and garble both sessions. When the port cannot be opened the error says why; when it is
//! busy, the holders are found by scanning `/proc/*/fd` for the device and named with their
//! pid and command. What can fail: everything the OS can refuse on open (`OpenError`).

use std::path::{Path, PathBuf};

use super::paced::{PacedSerial, Prompt};
use super::transport::{Connector, OpenError, Transport};

/// Default baud rate (PROTOCOL.md §1).
pub const DEFAULT_BAUD: u32 = 115_200;

/// Opens one serial port path, again after each loss.
#[derive(Clone, Debug)]
pub struct SerialConnector {
    path: PathBuf,
    baud: u32,
    paced: bool,
    /// Shared with the paced port it opens (`Connector::awaiting_reply`).
    prompt: Prompt,
}

impl SerialConnector {
    pub fn new(path: impl Into<PathBuf>, baud: u32) -> Self {
        SerialConnector {
            path: path.into(),
            baud,
            paced: false,
            prompt: Prompt::default(),
        }
    }

    /// Reads the port on the `pace` grid while bytes keep coming (`PacedSerial`): far fewer
    /// wake-ups, up to one slot (25 ms) more latency. For the TUI; tools that want every
    /// byte's own time (recording headless) or the fastest round trips leave it off.
    pub fn paced(mut self, paced: bool) -> Self {
        self.paced = paced;
        self
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Connector for SerialConnector {
    fn name(&self) -> String {
        self.path.display().to_string()
    }

    fn open(&mut self) -> Result<Box<dyn Transport>, OpenError> {
        if !self.paced {
            return open_exclusive(&self.path, self.baud).map(|mut s| {
                discard_pending_input(&mut s);
                Box::new(s) as Box<dyn Transport>
            });
        }
        let builder = builder(&self.path, self.baud)?;
        let mut port =
            mio_serial::SerialStream::open(&builder).map_err(|e| classify(&self.path, &e))?;
        discard_pending_input(&mut port);
        PacedSerial::new(port, self.prompt.clone())
            .map(|s| Box::new(s) as Box<dyn Transport>)
            .map_err(|e| OpenError::Other {
                path: self.path.clone(),
                message: e.to_string(),
            })
    }

    fn present(&self) -> bool {
        // Follows symlinks (the emulator's `--link`, udev's by-id names) to the device.
        self.path.exists()
    }

    fn awaiting_reply(&self, awaiting: bool) {
        self.prompt.set(awaiting);
    }
}

/// Drops what the port received before we opened it (TCIFLUSH; a pty slave's queue too).
/// The robot keeps talking for up to 1.5 s after a station leaves (its link timeout), and a
/// pty keeps those bytes for the next station: telemetry seconds old, or the refusal of the
/// last station's Hello. Read now, they would pass for answers to us. A port that cannot
/// flush still works: the link machine does not act on a backlog (`LinkMachine`), this only
/// spares it the reading.
fn discard_pending_input(port: &mut dyn tokio_serial::SerialPort) {
    let _ = port.clear(tokio_serial::ClearBuffer::Input);
}

/// Opens `path` exclusively at `baud`, 8N1, no flow control. Needs a tokio runtime.
pub fn open_exclusive(path: &Path, baud: u32) -> Result<tokio_serial::SerialStream, OpenError> {
    let builder = builder(path, baud)?;
    tokio_serial::SerialStream::open(&builder).map_err(|e| classify(path, &e))
}

/// The settings `open_exclusive` opens with, once `path` is known to be a device.
fn builder(path: &Path, baud: u32) -> Result<tokio_serial::SerialPortBuilder, OpenError> {
    let p = path.to_path_buf();
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => OpenError::NotFound { path: p.clone() },
        std::io::ErrorKind::PermissionDenied => permission_denied(path),
        _ => OpenError::Other {
            path: p.clone(),
            message: e.to_string(),
        },
    })?;
    if meta.is_dir() || meta.is_file() {
        return Err(OpenError::NotATty {
            path: p,
            message: "it is a regular file or directory".into(),
        });
    }
    let builder = tokio_serial::new(path.to_string_lossy(), baud)
        .data_bits(tokio_serial::DataBits::Eight)
        .parity(tokio_serial::Parity::None)
        .stop_bits(tokio_serial::StopBits::One)
        .flow_control(tokio_serial::FlowControl::None);
    Ok(serialport_exclusive(builder))
}

fn serialport_exclusive(b: tokio_serial::SerialPortBuilder) -> tokio_serial::SerialPortBuilder {
    // TIOCEXCL + exclusive flock (serialport's default, stated here because it matters).
    b.exclusive(true)
}

fn classify(path: &Path, e: &tokio_serial::Error) -> OpenError {
    use tokio_serial::ErrorKind as K;
    let p = path.to_path_buf();
    match e.kind() {
        // serialport reports EBUSY from TIOCEXCL and a held flock as NoDevice.
        K::NoDevice if path.exists() => OpenError::Busy {
            path: p,
            holders: describe_holders(path),
        },
        K::NoDevice => OpenError::NotFound { path: p },
        K::Io(std::io::ErrorKind::NotFound) => OpenError::NotFound { path: p },
        K::Io(std::io::ErrorKind::PermissionDenied) => permission_denied(path),
        K::Unknown if e.description.contains("Inappropriate ioctl") => OpenError::NotATty {
            path: p,
            message: e.description.clone(),
        },
        _ => OpenError::Other {
            path: p,
            message: e.description.clone(),
        },
    }
}

fn permission_denied(path: &Path) -> OpenError {
    OpenError::PermissionDenied {
        path: path.to_path_buf(),
        hint: " (add yourself to the group that owns it, often `dialout`, and log in again)".into(),
    }
}

/// Who holds `path` open, from `/proc/*/fd`: "pid 123 (minicom), pid 456 (station)".
pub fn describe_holders(path: &Path) -> String {
    let holders = holders(path);
    if holders.is_empty() {
        "another process (none visible in /proc; try `fuser` as root)".into()
    } else {
        let me = std::process::id();
        holders
            .iter()
            .map(|(pid, comm)| {
                if *pid == me {
                    format!("this process (pid {pid})")
                } else {
                    format!("pid {pid} ({comm})")
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Processes with an open file descriptor on `path` (after resolving symlinks).
pub fn holders(path: &Path) -> Vec<(u32, String)> {
    let Ok(target) = std::fs::canonicalize(path) else {
        return Vec::new();
    };
    let Ok(procs) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    let mut found = Vec::new();
    for entry in procs.flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|s| s.parse::<u32>().ok())
        else {
            continue;
        };
        let Ok(fds) = std::fs::read_dir(entry.path().join("fd")) else {
            continue;
        };
        let holds = fds
            .flatten()
            .any(|fd| std::fs::read_link(fd.path()).is_ok_and(|t| t == target));
        if holds {
            let comm = std::fs::read_to_string(entry.path().join("comm"))
                .map(|s| s.trim().to_string())
                .unwrap_or_else(|_| "?".into());
            found.push((pid, comm));
        }
    }
    found.sort_unstable();
    found
}
