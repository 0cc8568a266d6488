//! The station's link state machine: handshake, heartbeat, commands, link timeout, statistics.
//!
//! Layer: protocol state with no I/O and no clock (smoltcp's `poll(timestamp)`, rumqttc's
//! `state.rs`, with time passed in). The link task feeds it received bytes, port open/close
//! notices, submitted commands and the time in milliseconds; it answers with bytes to write
//! (`take_output`) and `LinkEvent`s (`take_events`), and says when it next needs a `poll`
//! (`next_deadline`). Invariants:
//! - commands are sent only in a handshaken session; one submitted otherwise fails at once
//!   with `NotConnected`, and the ones in flight when the session ends fail with `LinkLost`;
//! - every submitted command produces exactly one `CommandDone`;
//! - a command submitted `SendWhen::QuietLine` (a teleop repeat) may wait until the robot's
//!   periodic burst has left the line (`line_phase`), `line_phase::MAX_HOLD_US` at most, and
//!   only while the robot's clock is measured to run at ours (`RobotClock::runs_at_our_rate`);
//!   the others never wait for it;
//! - no two commands of one session share a sequence number, so the robot's remembered reply
//!   to one can never answer another (PROTOCOL.md §7): once `RENEW_AFTER_FRAMES` frames have
//!   gone out since the handshake, new commands wait, and when none is in flight the station
//!   handshakes again (a renewal), which clears the robot's memory, then sends them;
//! - a fingerprint or protocol mismatch is reported once with both builds named, and retried
//!   only slowly (the robot may be reflashed), never every 200 ms;
//! - with a key (`set_key`, PROTOCOL.md §13) every frame sent is signed and a received frame
//!   is acted on only once it verifies; a key on one side only, or two different keys, ends
//!   the handshake in `Refused` with a message naming --key-file, never in a silent timeout.
//!
//! Cannot fail: encoding errors are impossible for the messages it builds (all fit a frame)
//! and are counted, not raised, if they ever happen.

use std::collections::VecDeque;

use protocol::sign::{
    ticks_from_unix_us, AuthError, Binding, LinkAuth, LinkKey, ANY_ROBOT, STATION_LINK,
};
use protocol::timing::LINK_TIMEOUT_MS;
use protocol::{
    Command, EventCode, Feed, FrameDecoder, FrameError, Heartbeat, Hello, HelloReply, Kind,
    Message, NackReason, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION,
};

use super::api::{
    CommandFailure, CommandId, CommandOutcome, Connection, LinkEvent, PeerInfo, SendWhen,
    TransferIn, TransferOut,
};
use super::clock::RobotClock;
use super::commands::{CommandTable, InFlight};
use super::line_phase::{LinePhase, Periodic};
use super::stats::{LinkStats, StatsCollector};
use crate::terminal_text::printable;

/// Time between two `Hello`s while handshaking (PROTOCOL.md §4).
pub const HELLO_RETRY_MS: u64 = 200;
/// Time between two `Hello`s after a refusal: a mismatch heals only by reflashing.
pub const REFUSED_RETRY_MS: u64 = 2000;
/// How often a statistics snapshot is published.
pub const STATS_PERIOD_MS: u64 = 250;
/// Frames sent in one session after which new commands wait for a renewed handshake: the
/// 16-bit counter has 4,096 numbers left before it could reach the session's first command
/// (PROTOCOL.md §7), far more than the frames sent while the commands in flight finish.
pub const RENEW_AFTER_FRAMES: u32 = 65_536 - 4_096;

/// Settings of one link.
#[derive(Clone, Debug)]
pub struct MachineConfig {
    /// The station's name in `Hello` (at most 32 bytes; longer is cut).
    pub station: String,
    /// Seeds the session nonces; pass something random outside tests.
    pub nonce_seed: u64,
}

#[derive(Clone, Debug, PartialEq)]
enum State {
    Closed,
    Handshaking { session: u32, next_hello_ms: u64 },
    Connected { session: u32, since_ms: u64 },
    Refused { session: u32, next_hello_ms: u64 },
}

/// The state machine. See the module documentation.
pub struct LinkMachine {
    cfg: MachineConfig,
    state: State,
    connection: Connection,
    port: String,
    decoder: FrameDecoder,
    tx_seq: u16,
    /// Sequence numbers used since the session's handshake (PROTOCOL.md §7).
    session_frames: u32,
    /// When a renewal handshake started: commands submitted meanwhile wait instead of failing.
    renewal_since_ms: Option<u64>,
    rng: u64,
    out: Vec<u8>,
    events: VecDeque<LinkEvent>,
    commands: CommandTable,
    stats: StatsCollector,
    last_rx_ms: u64,
    last_tx_ms: u64,
    next_stats_ms: u64,
    /// The robot's clock rate: heartbeats go out every 250 ms of the robot's time.
    robot_clock: RobotClock,
    /// When the robot's line towards us is next quiet, for `SendWhen::QuietLine` commands.
    line_phase: LinePhase,
    auth: LinkAuth,
    /// Signed frames are decoded without a key and not verified (replaying a recording).
    trust_signatures: bool,
    /// The wall clock at `now_ms` = 0, in signing ticks (PROTOCOL.md §13).
    epoch_ticks: u64,
    /// The time of the call being handled, µs (the `_us` entry points give it whole; the
    /// others in milliseconds): round trips are timed with it.
    now_us: u64,
}

impl LinkMachine {
    pub fn new(mut cfg: MachineConfig) -> Self {
        truncate_utf8(&mut cfg.station, protocol::MAX_NAME);
        let rng = cfg.nonce_seed;
        LinkMachine {
            cfg,
            state: State::Closed,
            connection: Connection::Closed {
                reason: "not opened yet".into(),
            },
            port: String::new(),
            decoder: FrameDecoder::new(),
            tx_seq: 0,
            session_frames: 0,
            renewal_since_ms: None,
            rng,
            out: Vec::new(),
            events: VecDeque::new(),
            commands: CommandTable::default(),
            stats: StatsCollector::default(),
            last_rx_ms: 0,
            last_tx_ms: 0,
            next_stats_ms: 0,
            robot_clock: RobotClock::default(),
            line_phase: LinePhase::default(),
            auth: LinkAuth::new(None, STATION_LINK),
            trust_signatures: false,
            epoch_ticks: 0,
            now_us: 0,
        }
    }

    /// Signs every frame with `key` and accepts only frames that verify with it; `None` turns
    /// authentication off. Timestamps start from the wall clock now.
    pub fn set_key(&mut self, key: Option<LinkKey>) {
        let unix_us = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| u64::try_from(d.as_micros()).unwrap_or(u64::MAX))
            .unwrap_or(0);
        self.set_key_at(key, ticks_from_unix_us(unix_us));
    }

    /// `set_key` with the wall clock given: `epoch_ticks` is the time at `now_ms` = 0.
    pub fn set_key_at(&mut self, key: Option<LinkKey>, epoch_ticks: u64) {
        self.auth = LinkAuth::new(key, STATION_LINK);
        self.epoch_ticks = epoch_ticks;
    }

    /// Decodes signed frames without checking them: for replaying a recording, whose key the
    /// replayer need not have and whose timestamps are old by nature.
    pub fn trust_signatures(&mut self) {
        self.trust_signatures = true;
    }

    /// Whether frames are signed and verified.
    pub fn keyed(&self) -> bool {
        self.auth.keyed()
    }

    /// The current connection state.
    pub fn connection(&self) -> &Connection {
        &self.connection
    }

    /// Whether a handshaken session exists.
    pub fn connected(&self) -> bool {
        matches!(self.state, State::Connected { .. })
    }

    /// Whether an answer is awaited: a command unanswered, or a Hello (the port should then be
    /// read as bytes come, not on a timer grid).
    pub fn awaiting_reply(&self) -> bool {
        self.commands.in_flight() > 0 || matches!(self.state, State::Handshaking { .. })
    }

    /// Bytes to write to the port, in order; empties the buffer.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// Events produced so far, in order; empties the queue.
    pub fn take_events(&mut self) -> Vec<LinkEvent> {
        self.events.drain(..).collect()
    }

    /// The port could not be opened (or is absent): records why, once per distinct reason.
    pub fn port_unavailable(&mut self, reason: String) {
        self.state = State::Closed;
        self.set_connection(Connection::Closed { reason });
    }

    /// The port was opened: flush the peer's decoder and start a handshake.
    pub fn port_opened(&mut self, now_ms: u64, port: &str) {
        self.port = port.to_string();
        self.stats.port_opens = self.stats.port_opens.saturating_add(1);
        self.decoder.reset();
        self.last_rx_ms = now_ms;
        // A lone delimiter ends whatever half-frame the robot holds (PROTOCOL.md §2).
        self.out.push(0);
        self.stats.bytes_out += 1;
        self.start_handshake(now_ms);
    }

    /// The port closed or vanished: everything in flight is lost.
    pub fn port_closed(&mut self, reason: String) {
        self.fail_all(CommandFailure::LinkLost);
        self.state = State::Closed;
        self.stats.robot_seq.reset();
        self.stats.truth_seq.reset();
        self.set_connection(Connection::Closed { reason });
    }

    /// Submits a command. Its outcome arrives as a `CommandDone` event.
    pub fn submit(&mut self, now_ms: u64, id: CommandId, command: Command) {
        self.submit_when(now_ms.saturating_mul(1000), id, command, SendWhen::Now);
    }

    /// `submit` at `now_us` microseconds, the command going out `when` says: a `QuietLine` one may be held until
    /// the robot's next periodic burst has passed (`line_phase`); `poll_us` sends it then
    /// (`next_release_us`).
    pub fn submit_when(&mut self, now_us: u64, id: CommandId, command: Command, when: SendWhen) {
        let now_ms = self.at(now_us);
        self.stats.commands.submitted += 1;
        if !self.connected() && self.renewal_since_ms.is_none() {
            self.finish(
                id,
                command,
                CommandOutcome::Failed(CommandFailure::NotConnected),
            );
            return;
        }
        let not_before_us = match when {
            SendWhen::Now => 0,
            // The burst is predicted from the robot's stamps: on a robot whose clock runs
            // faster than ours (an emulator at `--speed 10`) they mislead, and the repeat
            // goes at once, as it did before the line was timed.
            SendWhen::QuietLine if self.robot_clock.runs_at_our_rate() => {
                self.line_phase.quiet_at(now_us)
            }
            SendWhen::QuietLine => now_us,
        };
        for (old, c) in self.commands.enqueue_at(id, command, not_before_us) {
            self.finish(old, c, CommandOutcome::Failed(CommandFailure::Superseded));
        }
        self.pump(now_ms);
    }

    /// Sends a transfer frame if the port is open.
    pub fn send_transfer(&mut self, now_ms: u64, t: &TransferOut) {
        if matches!(self.state, State::Closed) {
            return;
        }
        let msg = match t {
            TransferOut::Begin(b) => Message::TransferBegin(*b),
            TransferOut::Chunk { tag, offset, data } => {
                Message::TransferData(protocol::TransferData {
                    tag: *tag,
                    offset: *offset,
                    data,
                })
            }
            TransferOut::Ack(a) => Message::TransferAck(*a),
        };
        self.send(now_ms, &msg);
    }

    /// Feeds bytes read from the port.
    pub fn receive(&mut self, now_ms: u64, bytes: &[u8]) {
        self.receive_us(now_ms.saturating_mul(1000), bytes);
    }

    /// `receive` at `now_us` microseconds: round trips are then timed to the microsecond.
    pub fn receive_us(&mut self, now_us: u64, bytes: &[u8]) {
        let now_ms = self.at(now_us);
        self.stats.bytes_in += bytes.len() as u64;
        let mut input = bytes;
        loop {
            let owned = match self.decoder.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { error, rest } => {
                    input = rest;
                    self.on_bad_frame(now_ms, error);
                    continue;
                }
                Feed::Frame { frame, rest } => {
                    input = rest;
                    if !self.trust_signatures {
                        if let Err(e) = self.auth.verify(&frame) {
                            let refusal = is_handshake_refusal(&frame.message);
                            self.on_auth_error(e, refusal);
                            continue;
                        }
                    }
                    let kind = frame.header.kind;
                    let seq = frame.header.seq;
                    (kind, seq, Owned::from(frame.message))
                }
            };
            self.on_frame(now_ms, owned.0, owned.1, owned.2);
        }
    }

    /// Runs the timers: hello retries, heartbeats, command retries, link timeout, statistics.
    pub fn poll(&mut self, now_ms: u64) {
        self.poll_us(now_ms.saturating_mul(1000));
    }

    /// `poll` at `now_us` microseconds.
    pub fn poll_us(&mut self, now_us: u64) {
        let now_ms = self.at(now_us);
        if self
            .renewal_since_ms
            .is_some_and(|t| now_ms.saturating_sub(t) >= u64::from(LINK_TIMEOUT_MS))
        {
            // The robot did not answer the renewal: the waiting commands fail like any
            // others on a lost link; the handshake goes on.
            self.renewal_since_ms = None;
            self.stats.link_timeouts = self.stats.link_timeouts.saturating_add(1);
            self.fail_all(CommandFailure::LinkLost);
        }
        match self.state.clone() {
            State::Closed => {}
            State::Handshaking {
                session,
                next_hello_ms,
            } if now_ms >= next_hello_ms => {
                self.send_hello(now_ms, session);
                self.state = State::Handshaking {
                    session,
                    next_hello_ms: now_ms + HELLO_RETRY_MS,
                };
            }
            State::Refused {
                session,
                next_hello_ms,
            } if now_ms >= next_hello_ms => {
                self.send_hello(now_ms, session);
                self.state = State::Refused {
                    session,
                    next_hello_ms: now_ms + REFUSED_RETRY_MS,
                };
            }
            State::Connected { .. } => self.poll_connected(now_ms),
            State::Handshaking { .. } | State::Refused { .. } => {}
        }
        if now_ms >= self.next_stats_ms {
            self.next_stats_ms = now_ms + STATS_PERIOD_MS;
            let s = self.stats(now_ms);
            self.events.push_back(LinkEvent::Stats(Box::new(s)));
        }
    }

    /// Takes the time of the call being handled; returns it in whole milliseconds.
    fn at(&mut self, now_us: u64) -> u64 {
        self.now_us = now_us;
        now_us / 1000
    }

    /// When `poll` next has work (absolute ms).
    pub fn next_deadline(&self) -> u64 {
        let mut t = self.next_stats_ms;
        match &self.state {
            State::Closed => {}
            State::Handshaking { next_hello_ms, .. } | State::Refused { next_hello_ms, .. } => {
                t = t.min(*next_hello_ms);
            }
            State::Connected { .. } => {
                t = t
                    .min(self.last_rx_ms + u64::from(LINK_TIMEOUT_MS))
                    .min(self.last_tx_ms + self.robot_clock.heartbeat_period_ms());
                if let Some(c) = self.commands.next_deadline() {
                    t = t.min(c);
                }
            }
        }
        t
    }

    /// When a queued command may go (µs; past if it may already), if one waits only for
    /// its time (a command held for a quiet line): `poll_us` sends it then. Exact, not on any
    /// timer grid: its moment is the point. `None` while commands wait for a slot or a
    /// renewal instead (an answer or the renewal's handshake sends them).
    pub fn next_release_us(&self) -> Option<u64> {
        if !self.connected() || self.session_frames >= RENEW_AFTER_FRAMES {
            return None;
        }
        self.commands.next_release_us()
    }

    /// A statistics snapshot now.
    pub fn stats(&mut self, now_ms: u64) -> LinkStats {
        self.stats.commands.in_flight = u32::try_from(self.commands.in_flight()).unwrap_or(0);
        self.stats.commands.queued = u32::try_from(self.commands.queued()).unwrap_or(0);
        let session_ms = match self.state {
            State::Connected { since_ms, .. } => now_ms.saturating_sub(since_ms),
            _ => 0,
        };
        let mut s = self.stats.snapshot(
            now_ms,
            self.connection.name(),
            session_ms,
            self.decoder.stats(),
        );
        s.auth = super::stats::AuthCounts::new(self.auth.keyed(), self.auth.stats());
        s
    }

    /// Ends every command (the task is shutting down).
    pub fn shutdown(&mut self) {
        self.fail_all(CommandFailure::Shutdown);
    }

    fn poll_connected(&mut self, now_ms: u64) {
        if now_ms.saturating_sub(self.last_rx_ms) >= u64::from(LINK_TIMEOUT_MS) {
            self.stats.link_timeouts = self.stats.link_timeouts.saturating_add(1);
            self.fail_all(CommandFailure::LinkLost);
            self.start_handshake(now_ms);
            return;
        }
        let (resend, expired) = self.commands.due(now_ms);
        for f in resend {
            self.stats.commands.resends += 1;
            self.send_with_seq(now_ms, f.seq, &Message::Command(f.command));
        }
        for f in expired {
            let failure = CommandFailure::Timeout { sends: f.sends };
            self.finish(f.id, f.command, CommandOutcome::Failed(failure));
        }
        self.pump(now_ms);
        if !self.connected() {
            return; // a renewal began
        }
        if now_ms.saturating_sub(self.last_tx_ms) >= self.robot_clock.heartbeat_period_ms() {
            let time_ms = now_ms as u32; // the wire's clock wraps (PROTOCOL.md §6 kind 2)
            self.send(now_ms, &Message::Heartbeat(Heartbeat { time_ms }));
        }
    }

    fn on_bad_frame(&mut self, now_ms: u64, error: FrameError) {
        // A good CRC with another version is a real peer, not noise: say so (PROTOCOL.md §3).
        if let FrameError::UnsupportedVersion { version } = error {
            if !self.connected() {
                let message = format!(
                    "the robot speaks protocol version {version}; this station speaks \
                     {PROTOCOL_VERSION}: rebuild one of them"
                );
                self.refuse(now_ms, message);
            }
        }
    }

    fn on_frame(&mut self, now_ms: u64, kind: Kind, seq: u16, msg: Owned) {
        self.stats.frames_in += 1;
        self.last_rx_ms = now_ms;
        if kind == Kind::EmuTruth {
            self.stats.truth_seq.observe(seq);
        } else {
            self.stats.robot_seq.observe(seq);
        }
        match msg {
            Owned::HelloReply(r) => self.on_hello_reply(now_ms, r),
            Owned::Telemetry(t) => {
                self.observe_robot_clock(t.time_ms, now_ms);
                self.observe_burst(Periodic::Telemetry, t.time_ms);
                self.stats.telemetry(now_ms);
                self.events.push_back(LinkEvent::Telemetry(t));
            }
            Owned::Truth(t) => {
                self.observe_robot_clock(t.time_ms, now_ms);
                self.observe_burst(Periodic::Truth, t.time_ms);
                self.events.push_back(LinkEvent::Truth(t));
            }
            Owned::Heartbeat(time_ms) => self.observe_robot_clock(time_ms, now_ms),
            Owned::Localization(l) => self.events.push_back(LinkEvent::Localization(l)),
            Owned::Progress(p) => self.events.push_back(LinkEvent::Progress(p)),
            Owned::Situation(s) => self.events.push_back(LinkEvent::Situation(s)),
            Owned::Ack(a) => match self.commands.answer(a.cmd_seq) {
                Some(f) => {
                    let rtt_ms = now_ms.saturating_sub(f.last_sent_ms);
                    if f.sends == 1 {
                        self.stats
                            .rtt_sample_us(self.now_us.saturating_sub(f.first_sent_us));
                    }
                    let outcome = CommandOutcome::Acked {
                        info: a.info,
                        sends: f.sends,
                        rtt_ms,
                    };
                    self.finish(f.id, f.command, outcome);
                    self.pump(now_ms);
                }
                None => self.stats.commands.unmatched_replies += 1,
            },
            Owned::Nack(n) => self.on_nack(now_ms, n),
            Owned::Event(e) => {
                if e.code == EventCode::HandshakeRefused && e.value < 0 && !self.connected() {
                    self.on_robot_auth_refusal(e.value);
                }
                self.events.push_back(LinkEvent::Robot(e));
            }
            Owned::Log { level, text } => self.events.push_back(LinkEvent::Log { level, text }),
            Owned::Transfer(t) => self.events.push_back(LinkEvent::Transfer(t)),
            Owned::Other => {}
        }
    }

    /// Only frames of our own session time the robot's clock. What comes before our
    /// `HelloReply` may be a backlog: the robot's frames to a station that left, queued in
    /// the port while no one read it and all read now in one instant, seconds old. Timed
    /// against our clock they make the robot's look hundreds of times fast, and heartbeats
    /// would go out every `MIN_HEARTBEAT_MS` until the span diluted the error. The reply
    /// is sent after the robot read our `Hello`, and a port keeps order, so every frame
    /// after it is current.
    fn observe_robot_clock(&mut self, robot_ms: u32, now_ms: u64) {
        if self.connected() {
            self.robot_clock.observe(robot_ms, now_ms);
        }
    }

    /// The robot's periodic frames time its bursts (`line_phase`); only our session's, as
    /// for the clock: a backlog read in one instant would say nothing of the line.
    fn observe_burst(&mut self, kind: Periodic, robot_ms: u32) {
        if self.connected() {
            self.line_phase.observe(kind, robot_ms, self.now_us);
        }
    }

    fn on_nack(&mut self, now_ms: u64, n: protocol::Nack) {
        let Some(f) = self.commands.answer(n.cmd_seq) else {
            self.stats.commands.unmatched_replies += 1;
            return;
        };
        let InFlight {
            id, command, sends, ..
        } = f;
        let outcome = CommandOutcome::Nacked {
            reason: n.reason,
            sends,
        };
        self.finish(id, command, outcome);
        if n.reason == NackReason::NoHandshake && self.connected() {
            // The robot forgot the session (reboot, or 1.5 s of our silence): start again.
            self.fail_all(CommandFailure::LinkLost);
            self.start_handshake(now_ms);
        } else {
            self.pump(now_ms);
        }
    }

    /// Sends queued commands while slots are free.
    fn pump(&mut self, now_ms: u64) {
        while self.connected() && !self.renew_if_due(now_ms) {
            let Some((id, command)) = self.commands.next_to_send(self.now_us) else {
                return;
            };
            let seq = self.send(now_ms, &Message::Command(command));
            // Every entry point set `now_us` (`at`): round trips are timed to the µs.
            self.commands.sent(id, seq, command, self.now_us);
        }
    }

    fn fail_all(&mut self, why: CommandFailure) {
        for (id, c) in self.commands.drain() {
            self.finish(id, c, CommandOutcome::Failed(why));
        }
    }

    fn finish(&mut self, id: CommandId, command: Command, outcome: CommandOutcome) {
        let c = &mut self.stats.commands;
        match outcome {
            CommandOutcome::Acked { .. } => c.acked += 1,
            CommandOutcome::Nacked { .. } => c.nacked += 1,
            CommandOutcome::Failed(CommandFailure::Superseded) => c.superseded += 1,
            CommandOutcome::Failed(_) => c.failed += 1,
        }
        self.events.push_back(LinkEvent::CommandDone {
            id,
            command,
            outcome,
        });
    }

    fn set_connection(&mut self, c: Connection) {
        if self.connection != c {
            self.connection = c.clone();
            self.events.push_back(LinkEvent::Connection(c));
        }
    }

    /// Encodes with the next sequence number; returns it.
    fn send(&mut self, now_ms: u64, msg: &Message<'_>) -> u16 {
        let seq = self.tx_seq;
        self.tx_seq = self.tx_seq.wrapping_add(1);
        self.session_frames = self.session_frames.saturating_add(1);
        self.send_with_seq(now_ms, seq, msg);
        seq
    }

    fn send_with_seq(&mut self, now_ms: u64, seq: u16, msg: &Message<'_>) {
        let mut buf = [0u8; MAX_FRAME];
        let clock = self.clock(now_ms);
        // Every message built here fits a frame; a failure would be a bug, counted not raised.
        if let Ok(n) = self.auth.encode(seq, msg, clock, &mut buf) {
            self.out.extend_from_slice(buf.get(..n).unwrap_or(&[]));
            self.stats.frames_out += 1;
            self.stats.bytes_out += n as u64;
            self.last_tx_ms = now_ms;
        }
    }

    /// The wall clock in signing ticks (10 µs since 2015; PROTOCOL.md §13).
    fn clock(&self, now_ms: u64) -> u64 {
        self.epoch_ticks.saturating_add(now_ms.saturating_mul(100))
    }
}

pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn truncate_utf8(s: &mut String, max: usize) {
    if s.len() > max {
        let mut end = max;
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        s.truncate(end);
    }
}

mod handshake;
mod owned;

use owned::{is_handshake_refusal, Owned, OwnedHelloReply};

#[cfg(test)]
#[path = "machine_tests.rs"]
mod tests;
