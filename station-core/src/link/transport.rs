//! The byte-stream seam between the link task and a port.
//!
//! Layer: I/O boundary. A `Transport` is any async byte stream (a serial port, one end of an
//! in-memory pipe); a `Connector` opens one on demand and says whether the port is present, so
//! the link task can reopen after the port disappears and comes back. Opening is synchronous:
//! it is one system call on a serial port. What can fail is described by `OpenError`, which
//! says as precisely as it can why a port cannot be opened (absent, busy and who holds it,
//! permissions).

use std::path::PathBuf;

use tokio::io::{AsyncRead, AsyncWrite};

/// A bidirectional byte stream the link task can own.
pub trait Transport: AsyncRead + AsyncWrite + Unpin + Send {}

impl<T: AsyncRead + AsyncWrite + Unpin + Send> Transport for T {}

/// Opens transports for one port, again and again.
pub trait Connector: Send + Sync + 'static {
    /// The port's name for messages ("/dev/ttyUSB0", "memory").
    fn name(&self) -> String;
    /// Opens the port now.
    fn open(&mut self) -> Result<Box<dyn Transport>, OpenError>;
    /// Whether the port still exists; polled while it is open, to notice an unplug that the
    /// stream itself does not report.
    fn present(&self) -> bool {
        true
    }
    /// Whether a reply is awaited now (a command or a Hello unanswered): a port that delays
    /// its reads to save wake-ups (`paced`) reads at once meanwhile. Others ignore it.
    fn awaiting_reply(&self, _awaiting: bool) {}
}

/// Why a port could not be opened.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OpenError {
    #[error("{path} does not exist (unplugged?)")]
    NotFound { path: PathBuf },
    #[error("{path} is in use by {holders}")]
    Busy { path: PathBuf, holders: String },
    #[error("permission denied on {path}{hint}")]
    PermissionDenied { path: PathBuf, hint: String },
    #[error("{path} is not a serial port: {message}")]
    NotATty { path: PathBuf, message: String },
    #[error("cannot open {path}: {message}")]
    Other { path: PathBuf, message: String },
    #[error("the in-memory port is unplugged")]
    Unplugged,
}
