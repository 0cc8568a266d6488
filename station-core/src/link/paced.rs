//! A serial port read once per pace slot while bytes keep coming: a USB adapter's latency
//! timer, on the station's side.
//!
//! Layer: I/O edge (a `Transport`). A UART at 115 200 baud hands the kernel a few bytes every
//! millisecond; an event-driven reader wakes for each handful (about 340 reads and 560 wake-ups
//! a second at 50 Hz telemetry), and those wake-ups were most of an idle TUI's CPU. Here, while
//! bytes keep arriving, the port is not watched at all: it is read on the `pace` grid (every
//! 32 ms, with the TUI's other timers, in the same wake-up). When a look finds nothing, the
//! port is watched again (epoll) so that the first byte after a quiet spell is read at once:
//! a quiet link costs no wake-ups, a busy one one per slot. Writes are non-blocking; a full
//! output buffer is retried every `WRITE_RETRY` (the link task's write timeout notices a
//! wedged port). Flushing does not wait for the bytes to leave (`tcdrain` would block the
//! thread). Costs up to one slot of latency on received bytes, except while a reply is awaited:
//! then (`Prompt` set by the link task, while a command or a Hello is unanswered) the port is
//! read as soon as bytes come, as an unpaced port is, so an ack never waits for the next slot
//! (it used to: every round trip took a slot, p50 33 ms for 2.1-2.4 ms of bytes). The flag is
//! looked at on every poll, and the link task polls the read afresh after each send. What can
//! fail: the port's I/O.

use std::future::Future;
use std::io::{self, Read, Write};
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::task::{ready, Context, Poll};
use std::time::Duration;

use mio_serial::SerialStream;
use tokio::io::unix::AsyncFd;
use tokio::io::{AsyncRead, AsyncWrite, Interest, ReadBuf};
use tokio::time::{sleep_until, Instant, Sleep};

use crate::pace;

/// Wait before trying a write again when the port's output buffer is full.
pub const WRITE_RETRY: Duration = Duration::from_millis(2);

/// Set while a reply is awaited: the paced port then reads bytes as they come. Shared between
/// the link task (which knows what is in flight) and the port (which reads).
#[derive(Clone, Debug, Default)]
pub struct Prompt(Arc<AtomicBool>);

impl Prompt {
    pub fn set(&self, on: bool) {
        self.0.store(on, Ordering::Relaxed);
    }

    pub fn get(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// A non-blocking serial port read on the pace grid while busy; see the module's note.
pub struct PacedSerial {
    state: State,
    prompt: Prompt,
    /// Armed while a write waits for room in the output buffer.
    write_retry: Option<Pin<Box<Sleep>>>,
}

enum State {
    /// The last look found nothing: the port is watched, the first byte wakes the task.
    Watched(AsyncFd<SerialStream>),
    /// Bytes came at the last look: the port is looked at again at `next`, unwatched.
    Paced {
        port: SerialStream,
        next: Pin<Box<Sleep>>,
    },
    /// Only while switching between the two, or after watching failed.
    Broken,
}

impl PacedSerial {
    /// Takes an open port (non-blocking, as `mio_serial` opens it); reads it as bytes come
    /// while `prompt` is set. Needs a tokio runtime.
    pub fn new(port: SerialStream, prompt: Prompt) -> io::Result<PacedSerial> {
        Ok(PacedSerial {
            state: State::Watched(watch(port)?),
            prompt,
            write_retry: None,
        })
    }

    fn port_mut(&mut self) -> io::Result<&mut SerialStream> {
        match &mut self.state {
            State::Watched(fd) => Ok(fd.get_mut()),
            State::Paced { port, .. } => Ok(port),
            State::Broken => Err(broken()),
        }
    }
}

/// Registers the port for input with the runtime.
fn watch(port: SerialStream) -> io::Result<AsyncFd<SerialStream>> {
    // Deprecated because a `T` could hand out an fd it does not own; `SerialStream` owns its
    // fd and keeps it open until dropped, which is what the safe replacement would require.
    #[allow(deprecated)]
    AsyncFd::with_interest(port, Interest::READABLE)
}

fn broken() -> io::Error {
    io::Error::other("the port could not be watched for input")
}

/// Reads what is there now; `Ok(None)` when nothing is.
fn read_now(port: &mut SerialStream, buf: &mut ReadBuf<'_>) -> io::Result<Option<usize>> {
    match port.read(buf.initialize_unfilled()) {
        Ok(n) => {
            buf.advance(n);
            Ok(Some(n))
        }
        Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(None),
        Err(e) => Err(e),
    }
}

impl AsyncRead for PacedSerial {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        loop {
            match &mut this.state {
                State::Watched(fd) => {
                    let got = {
                        let mut guard = ready!(fd.poll_read_ready_mut(cx))?;
                        guard.try_io(|fd| match read_now(fd.get_mut(), buf) {
                            Ok(None) => Err(io::ErrorKind::WouldBlock.into()),
                            other => other,
                        })
                    };
                    match got {
                        Ok(Ok(Some(n))) => {
                            // A reply is awaited: stay watched, read each byte as it comes.
                            if n > 0 && !this.prompt.get() {
                                // Busy: stop watching; look again on the grid.
                                if let State::Watched(fd) =
                                    std::mem::replace(&mut this.state, State::Broken)
                                {
                                    this.state = State::Paced {
                                        port: fd.into_inner(),
                                        next: Box::pin(sleep_until(pace::next_slot())),
                                    };
                                }
                            }
                            return Poll::Ready(Ok(()));
                        }
                        Ok(Ok(None)) | Err(_) => continue,
                        Ok(Err(e)) => return Poll::Ready(Err(e)),
                    }
                }
                State::Paced { port, next } => {
                    // A reply is awaited: look now, not at the next slot.
                    if !this.prompt.get() {
                        ready!(next.as_mut().poll(cx));
                    }
                    let room = buf.remaining();
                    match read_now(port, buf)? {
                        Some(n) => {
                            // A full buffer may have left more behind: look again at once.
                            let at = if n == room {
                                Instant::now()
                            } else {
                                pace::next_slot()
                            };
                            next.as_mut().reset(at);
                            return Poll::Ready(Ok(()));
                        }
                        None => {
                            // Quiet: watch the port so the next byte wakes us at once.
                            if let State::Paced { port, .. } =
                                std::mem::replace(&mut this.state, State::Broken)
                            {
                                this.state = State::Watched(watch(port)?);
                            }
                        }
                    }
                }
                State::Broken => return Poll::Ready(Err(broken())),
            }
        }
    }
}

impl AsyncWrite for PacedSerial {
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        data: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        loop {
            if let Some(retry) = &mut this.write_retry {
                ready!(retry.as_mut().poll(cx));
                this.write_retry = None;
            }
            match this.port_mut()?.write(data) {
                Ok(n) => return Poll::Ready(Ok(n)),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    this.write_retry = Some(Box::pin(sleep_until(Instant::now() + WRITE_RETRY)));
                }
                Err(e) => return Poll::Ready(Err(e)),
            }
        }
    }

    fn poll_flush(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        // Written bytes are the kernel's; waiting for them to leave would block the thread.
        Poll::Ready(Ok(()))
    }

    fn poll_shutdown(self: Pin<&mut Self>, _cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Poll::Ready(Ok(()))
    }
}
