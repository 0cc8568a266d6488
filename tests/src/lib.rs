//! Shared helpers for the end-to-end tests: a minimal synchronous station over a real serial
//! port, enough to handshake, send commands and collect what the robot says. The product's
//! station has its own full client; this one keeps the emulator's tests independent of it.

pub mod procs;
pub mod tmux;

use std::time::{Duration, Instant};

use protocol::{
    encode, Command, Feed, FrameDecoder, Hello, Kind, Message, Telemetry, FINGERPRINT, MAX_FRAME,
    PROTOCOL_VERSION,
};

/// What the robot sent, owned, with the time it was read.
#[derive(Clone, Debug, PartialEq)]
pub enum Received {
    HelloReply {
        accepted: bool,
        session: u32,
        capabilities: u32,
    },
    Telemetry(Telemetry),
    Truth(protocol::EmuTruth),
    Ack {
        cmd_seq: u16,
    },
    Nack {
        cmd_seq: u16,
        reason: protocol::NackReason,
    },
    Other(Kind),
}

/// A serial-port station for tests.
pub struct TestStation {
    port: Box<dyn serialport::SerialPort>,
    dec: FrameDecoder,
    seq: u16,
    pub bytes_in: u64,
    /// The robot id of the last `HelloReply` read (issue 17: robots state who they are).
    pub last_robot_id: Option<u8>,
}

impl TestStation {
    /// Opens `path` at `baud` (a pty ignores the rate; the emulator enforces it).
    pub fn open(path: &std::path::Path, baud: u32) -> Result<TestStation, serialport::Error> {
        let port = serialport::new(path.to_string_lossy(), baud)
            .timeout(Duration::from_millis(5))
            .open()?;
        Ok(TestStation {
            port,
            dec: FrameDecoder::new(),
            seq: 0,
            bytes_in: 0,
            last_robot_id: None,
        })
    }

    /// Sends a message; returns its sequence number.
    pub fn send(&mut self, msg: &Message<'_>) -> std::io::Result<u16> {
        let mut buf = [0u8; MAX_FRAME];
        let n =
            encode(self.seq, msg, &mut buf).map_err(|e| std::io::Error::other(e.to_string()))?;
        self.port.write_all(&buf[..n])?;
        let s = self.seq;
        self.seq = self.seq.wrapping_add(1);
        Ok(s)
    }

    /// Writes raw bytes, waiting while the port's buffer is full, for up to `within`;
    /// returns how many were written.
    pub fn write_raw(&mut self, bytes: &[u8], within: Duration) -> usize {
        let end = Instant::now() + within;
        let mut done = 0;
        while done < bytes.len() && Instant::now() < end {
            match self.port.write(&bytes[done..]) {
                Ok(n) => done += n,
                Err(_) => std::thread::sleep(Duration::from_millis(1)),
            }
        }
        done
    }

    pub fn command(&mut self, c: Command) -> std::io::Result<u16> {
        self.send(&Message::Command(c))
    }

    /// Reads for `dur`, collecting frames with their arrival times.
    pub fn collect(&mut self, dur: Duration) -> Vec<(Instant, Received)> {
        let end = Instant::now() + dur;
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        while Instant::now() < end {
            let n = match self.port.read(&mut buf) {
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => 0,
                Err(_) => 0,
            };
            self.bytes_in += n as u64;
            let now = Instant::now();
            let mut input = &buf[..n];
            loop {
                match self.dec.feed(input) {
                    Feed::NeedMore => break,
                    Feed::Error { rest, .. } => input = rest,
                    Feed::Frame { frame, rest } => {
                        if let Message::HelloReply(r) = &frame.message {
                            self.last_robot_id = Some(r.robot_id);
                        }
                        out.push((now, owned(&frame.message)));
                        input = rest;
                    }
                }
            }
        }
        out
    }

    /// Handshakes, retrying every 200 ms for up to `within`; returns the robot's capabilities.
    pub fn handshake(&mut self, within: Duration) -> Option<u32> {
        let end = Instant::now() + within;
        let session = 0x5EED;
        while Instant::now() < end {
            self.port.write_all(&[0]).ok()?;
            self.send(&Message::Hello(Hello {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session,
                station: "e2e",
            }))
            .ok()?;
            for (_, r) in self.collect(Duration::from_millis(200)) {
                if let Received::HelloReply {
                    accepted: true,
                    session: s,
                    capabilities,
                } = r
                {
                    if s == session {
                        return Some(capabilities);
                    }
                }
            }
        }
        None
    }

    pub fn decoder_stats(&self) -> &protocol::DecoderStats {
        self.dec.stats()
    }
}

fn owned(m: &Message<'_>) -> Received {
    match m {
        Message::HelloReply(r) => Received::HelloReply {
            accepted: r.accepted,
            session: r.session,
            capabilities: r.capabilities,
        },
        Message::Telemetry(t) => Received::Telemetry(*t),
        Message::EmuTruth(t) => Received::Truth(*t),
        Message::Ack(a) => Received::Ack { cmd_seq: a.cmd_seq },
        Message::Nack(n) => Received::Nack {
            cmd_seq: n.cmd_seq,
            reason: n.reason,
        },
        other => Received::Other(other.kind()),
    }
}

/// The path of one of the workspace's binaries (`station`, `robot-emulator`), built by the
/// same `cargo test` run: they sit in the target directory beside the `deps` folder this test
/// runs from. A run that did not build it (`cargo test -p e2e-tests` alone) builds it here.
pub fn workspace_bin(name: &str) -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap_or_default();
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .map(std::path::Path::to_path_buf)
        .unwrap_or_default();
    let path = profile_dir.join(name);
    if !path.is_file() {
        let package = if name == "robot-emulator" {
            "emulator"
        } else {
            name
        };
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut build = std::process::Command::new(cargo);
        build.args(["build", "-p", package, "--bin", name]);
        if profile_dir.file_name().is_some_and(|p| p == "release") {
            build.arg("--release");
        }
        // Best effort: a failure shows up as the binary missing when it is run.
        let _ = build.status();
    }
    path
}
