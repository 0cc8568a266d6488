//! Replay: a recording drives the app exactly as the live link did, at any speed, with seek.
//!
//! Layer: pure state (time passed in, no I/O): `player` (position, speed, pause), `summary`
//! (`station replay --json`), `links` (its per-link form for a file of several links); the
//! station crate holds the replay's screen, terminal loop and command. `ReplayFeed` turns
//! records into the same
//! events the TUI gets live ([`ReplayEvent`], which the app takes as its `Action`s): the
//! robot's bytes go through the station's own `LinkMachine`
//! (decoder, sequence accounting, statistics, event translation), so the sensors, map, charts,
//! link panel and log show what they showed live; the connection state comes from the
//! recording's link records (what the live station decided); and the station's own recorded
//! bytes are decoded to pair each command with its Ack or Nack, so command outcomes and
//! round-trip times reach the log as they did live. Invariants: a replay never writes to any
//! port (the machine's own output, `Hello`s and heartbeats it would send, is discarded);
//! feeding is deterministic, so seeking back is "start again and feed up to there". Cannot
//! fail: damaged bytes inside a good record are decoding errors, counted as live.

pub mod links;
pub mod player;
pub mod summary;

use std::collections::HashMap;

use protocol::{Command, Feed, FrameDecoder, Kind, Message};

use crate::link::machine::{LinkMachine, MachineConfig};
use crate::link::stats::StatsCollector;
use crate::link::{CommandFailure, CommandOutcome, Connection, LinkEvent, LinkStats};
use crate::record::live::PeerRecord;
use crate::record::{LinkState, Record, RecordKind};

/// What a replay yields, in order: what the live link would have told the app.
#[derive(Clone, Debug, PartialEq)]
pub enum ReplayEvent {
    /// Time passes: `now_ms` since the recording started.
    Tick { now_ms: u64 },
    /// Something the link reported.
    Link(LinkEvent),
}

/// A command unanswered this long after its last send has timed out (PROTOCOL.md §7: 5 sends
/// 200 ms apart, then the station gives up).
const COMMAND_EXPIRY_MS: u64 = 1200;

/// Feeds records to an app, in order, up to a time.
pub struct ReplayFeed {
    port: String,
    next: usize,
    now_us: u64,
    machine: LinkMachine,
    station: StationSide,
    connection: Connection,
    connected_since_ms: Option<u64>,
    /// Times the link's timers ran: the feed's work besides the records themselves.
    timer_runs: u64,
}

impl ReplayFeed {
    /// A feed at time 0 of a recording of `port`.
    pub fn new(port: &str) -> ReplayFeed {
        let mut machine = LinkMachine::new(MachineConfig {
            station: "replay".into(),
            nonce_seed: 0,
        });
        // A signed recording replays without its key: the frames were verified when live.
        machine.trust_signatures();
        machine.port_opened(0, port);
        let _ = machine.take_output();
        let _ = machine.take_events();
        ReplayFeed {
            port: port.to_string(),
            next: 0,
            now_us: 0,
            machine,
            station: StationSide::default(),
            connection: Connection::Closed {
                reason: "replay starting".into(),
            },
            connected_since_ms: None,
            timer_runs: 0,
        }
    }

    /// The recording time fed so far, µs.
    pub fn position_us(&self) -> u64 {
        self.now_us
    }

    /// Index of the next record to feed.
    pub fn next_index(&self) -> usize {
        self.next
    }

    /// Frames of each kind seen so far: (from the robot, to the robot), by `Kind as usize`.
    pub fn frame_counts(&self) -> (&[u64; KINDS], &[u64; KINDS]) {
        (&self.station.frames_in, &self.station.frames_out)
    }

    /// Good frames from the robot so far, of every kind.
    pub fn frames_from_robot(&self) -> u64 {
        self.station.frames_in.iter().sum()
    }

    /// How many times the link's timers have run (each record runs them once, and so does
    /// every `advance_to` past the last record fed): the work a replay does besides decoding.
    pub fn timer_runs(&self) -> u64 {
        self.timer_runs
    }

    /// Decoding errors in the station's own bytes (normally none).
    pub fn outgoing_errors(&self) -> u32 {
        self.station.out_decoder.stats().errors()
    }

    /// Feeds every record at or before `t_us` and lets the link's timers run to `t_us`;
    /// appends the app's actions to `out`.
    pub fn advance_to(&mut self, records: &[Record], t_us: u64, out: &mut Vec<ReplayEvent>) {
        while let Some(rec) = records.get(self.next) {
            if rec.t_us > t_us {
                break;
            }
            self.next += 1;
            self.now_us = self.now_us.max(rec.t_us);
            let now_ms = self.now_us / 1000;
            out.push(ReplayEvent::Tick { now_ms });
            self.feed(rec, now_ms, out);
            self.poll(now_ms, out);
        }
        if t_us > self.now_us {
            self.now_us = t_us;
            let now_ms = t_us / 1000;
            out.push(ReplayEvent::Tick { now_ms });
            self.poll(now_ms, out);
        }
    }

    fn feed(&mut self, rec: &Record, now_ms: u64, out: &mut Vec<ReplayEvent>) {
        match rec.kind {
            RecordKind::FromRobot => {
                // Frame by frame, so the machine's events and the station side's (command
                // outcomes) come out in the order the bytes arrived.
                let mut input = rec.data.as_slice();
                while !input.is_empty() {
                    let (used, reply) = self.station.split_incoming(input);
                    let (now, rest) = input.split_at(used.clamp(1, input.len()));
                    self.machine.receive(now_ms, now);
                    self.forward_machine(now_ms, out);
                    if let Some((cmd_seq, result)) = reply {
                        if let Some(ev) = self.station.answer(now_ms, cmd_seq, result) {
                            out.push(ReplayEvent::Link(ev));
                        }
                    }
                    input = rest;
                }
            }
            RecordKind::ToRobot => self.station.outgoing(now_ms, &rec.data),
            RecordKind::Link => {
                if let Some((state, text)) = rec.link() {
                    self.on_link(now_ms, state, &text, out);
                }
            }
            // The replayed app says its own lines again, from the frames it replays.
            RecordKind::StationLog | RecordKind::End | RecordKind::Unknown(_) => {}
        }
    }

    fn on_link(&mut self, now_ms: u64, state: LinkState, text: &str, out: &mut Vec<ReplayEvent>) {
        let c = match state {
            LinkState::Closed => Connection::Closed {
                reason: text.to_string(),
            },
            LinkState::Handshaking => Connection::Handshaking {
                port: text.to_string(),
            },
            LinkState::Connected => match serde_json::from_str::<PeerRecord>(text) {
                Ok(p) => Connection::Connected(p.to_peer()),
                // An unreadable robot description: still a session, with what is known.
                Err(_) => Connection::Connected(crate::link::PeerInfo {
                    session: 0,
                    firmware: text.chars().take(32).collect(),
                    firmware_version: String::new(),
                    profile: protocol::ProfileId::Khepera,
                    capabilities: 0,
                    map_capacity: protocol::MapCapacity {
                        width: 0,
                        height: 0,
                    },
                    telemetry_hz: 0,
                    failsafe_ms: 0,
                    robot_id: 1,
                }),
            },
            LinkState::Refused => Connection::Refused {
                message: text.to_string(),
            },
        };
        let was_connected = matches!(self.connection, Connection::Connected(_));
        let connected = matches!(c, Connection::Connected(_));
        if was_connected && !connected {
            // Everything in flight was lost with the session, as live.
            for ev in self.station.fail_all(CommandFailure::LinkLost) {
                out.push(ReplayEvent::Link(ev));
            }
            if state == LinkState::Handshaking {
                self.station.stats.link_timeouts =
                    self.station.stats.link_timeouts.saturating_add(1);
            }
        }
        if connected && !was_connected {
            self.station.stats.handshakes = self.station.stats.handshakes.saturating_add(1);
            self.connected_since_ms = Some(now_ms);
        } else if !connected {
            self.connected_since_ms = None;
        }
        if state == LinkState::Closed {
            // The port closed: a new one starts with a fresh decoder, as live.
            self.machine.port_closed(text.to_string());
            self.station.in_decoder.reset();
            self.machine.port_opened(now_ms, &self.port);
            let _ = self.machine.take_output();
            self.forward_machine(now_ms, out);
        }
        self.connection = c.clone();
        out.push(ReplayEvent::Link(LinkEvent::Connection(c)));
    }

    fn poll(&mut self, now_ms: u64, out: &mut Vec<ReplayEvent>) {
        self.timer_runs += 1;
        self.machine.poll(now_ms);
        // Whatever the machine would send (Hellos, heartbeats) goes nowhere.
        let _ = self.machine.take_output();
        self.forward_machine(now_ms, out);
        for ev in self.station.expire(now_ms) {
            out.push(ReplayEvent::Link(ev));
        }
    }

    /// The machine's events, with its view of the connection (it never saw the handshake's
    /// session) replaced by the recorded one.
    fn forward_machine(&mut self, now_ms: u64, out: &mut Vec<ReplayEvent>) {
        for ev in self.machine.take_events() {
            match ev {
                LinkEvent::Connection(_) | LinkEvent::CommandDone { .. } => {}
                LinkEvent::Stats(s) => {
                    let s = self.merge_stats(now_ms, *s);
                    out.push(ReplayEvent::Link(LinkEvent::Stats(Box::new(s))));
                }
                ev => out.push(ReplayEvent::Link(ev)),
            }
        }
    }

    fn merge_stats(&mut self, now_ms: u64, mut s: LinkStats) -> LinkStats {
        let st = &mut self.station;
        let ours = st.stats.snapshot(now_ms, "", 0, st.out_decoder.stats());
        s.state = self.connection.name().to_string();
        s.session_ms = self
            .connected_since_ms
            .map_or(0, |t| now_ms.saturating_sub(t));
        s.frames_out = ours.frames_out;
        s.bytes_out = ours.bytes_out;
        s.bytes_out_per_s = ours.bytes_out_per_s;
        s.commands = ours.commands;
        s.rtt_ms = ours.rtt_ms;
        s.handshakes = ours.handshakes;
        s.link_timeouts = ours.link_timeouts;
        s
    }

    /// The statistics as of now (the last snapshot a live link would have published).
    pub fn stats(&mut self) -> LinkStats {
        let now_ms = self.now_us / 1000;
        let s = self.machine.stats(now_ms);
        self.merge_stats(now_ms, s)
    }
}

/// Message kinds on the wire.
pub const KINDS: usize = Kind::ALL.len();

/// The station's half, rebuilt from its recorded bytes: which commands were sent under which
/// sequence numbers, so the robot's answers can be paired with them.
#[derive(Default)]
struct StationSide {
    out_decoder: FrameDecoder,
    /// Decodes the robot's bytes a second time, only to find frame boundaries and replies.
    in_decoder: FrameDecoder,
    pending: HashMap<u16, Sent>,
    next_id: u64,
    stats: StatsCollector,
    frames_in: [u64; KINDS],
    frames_out: [u64; KINDS],
}

#[derive(Clone, Copy, Debug)]
struct Sent {
    id: u64,
    command: Command,
    last_ms: u64,
    sends: u32,
}

/// A robot's answer to a command.
#[derive(Clone, Copy, Debug)]
enum Reply {
    Ack(protocol::AckInfo),
    Nack(protocol::NackReason),
}

impl StationSide {
    /// How many bytes of `input` make up its next frame (or all of it), and the reply that
    /// frame carries, if any.
    fn split_incoming(&mut self, input: &[u8]) -> (usize, Option<(u16, Reply)>) {
        match self.in_decoder.feed(input) {
            Feed::NeedMore => (input.len(), None),
            Feed::Error { rest, .. } => (input.len() - rest.len(), None),
            Feed::Frame { frame, rest } => {
                if let Some(n) = self.frames_in.get_mut(frame.header.kind as usize) {
                    *n += 1;
                }
                let reply = match frame.message {
                    Message::Ack(a) => Some((a.cmd_seq, Reply::Ack(a.info))),
                    Message::Nack(n) => Some((n.cmd_seq, Reply::Nack(n.reason))),
                    _ => None,
                };
                (input.len() - rest.len(), reply)
            }
        }
    }

    /// The station's recorded bytes: counts them and notes the commands.
    fn outgoing(&mut self, now_ms: u64, bytes: &[u8]) {
        self.stats.bytes_out += bytes.len() as u64;
        let mut input = bytes;
        loop {
            let (seq, command, rest) = match self.out_decoder.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { rest, .. } => {
                    input = rest;
                    continue;
                }
                Feed::Frame { frame, rest } => {
                    self.stats.frames_out += 1;
                    if let Some(n) = self.frames_out.get_mut(frame.header.kind as usize) {
                        *n += 1;
                    }
                    match frame.message {
                        Message::Command(c) => (frame.header.seq, c, rest),
                        _ => {
                            input = rest;
                            continue;
                        }
                    }
                }
            };
            input = rest;
            self.sent(now_ms, seq, command);
        }
    }

    fn sent(&mut self, now_ms: u64, seq: u16, command: Command) {
        if let Some(s) = self.pending.get_mut(&seq) {
            // A retry keeps its sequence number (PROTOCOL.md §7).
            s.sends += 1;
            s.last_ms = now_ms;
            self.stats.commands.resends += 1;
            return;
        }
        if matches!(command, Command::Teleop { .. }) {
            // A newer teleop supersedes the older ones, silently, as live.
            self.pending
                .retain(|_, s| !matches!(s.command, Command::Teleop { .. }));
        }
        self.stats.commands.submitted += 1;
        self.next_id += 1;
        self.pending.insert(
            seq,
            Sent {
                id: self.next_id,
                command,
                last_ms: now_ms,
                sends: 1,
            },
        );
    }

    fn answer(&mut self, now_ms: u64, cmd_seq: u16, reply: Reply) -> Option<LinkEvent> {
        let Some(s) = self.pending.remove(&cmd_seq) else {
            self.stats.commands.unmatched_replies += 1;
            return None;
        };
        let outcome = match reply {
            Reply::Ack(info) => {
                let rtt_ms = now_ms.saturating_sub(s.last_ms);
                if s.sends == 1 {
                    self.stats.rtt_sample(rtt_ms);
                }
                self.stats.commands.acked += 1;
                CommandOutcome::Acked {
                    info,
                    sends: s.sends,
                    rtt_ms,
                }
            }
            Reply::Nack(reason) => {
                self.stats.commands.nacked += 1;
                CommandOutcome::Nacked {
                    reason,
                    sends: s.sends,
                }
            }
        };
        Some(LinkEvent::CommandDone {
            id: s.id,
            command: s.command,
            outcome,
        })
    }

    fn expire(&mut self, now_ms: u64) -> Vec<LinkEvent> {
        let mut gone: Vec<(u16, Sent)> = self
            .pending
            .iter()
            .filter(|(_, s)| now_ms.saturating_sub(s.last_ms) >= COMMAND_EXPIRY_MS)
            .map(|(k, s)| (*k, *s))
            .collect();
        gone.sort_by_key(|(_, s)| s.id);
        gone.into_iter()
            .map(|(k, s)| {
                self.pending.remove(&k);
                self.fail(s, CommandFailure::Timeout { sends: s.sends })
            })
            .collect()
    }

    fn fail_all(&mut self, why: CommandFailure) -> Vec<LinkEvent> {
        let mut all: Vec<Sent> = self.pending.drain().map(|(_, s)| s).collect();
        all.sort_by_key(|s| s.id);
        all.into_iter().map(|s| self.fail(s, why)).collect()
    }

    fn fail(&mut self, s: Sent, why: CommandFailure) -> LinkEvent {
        self.stats.commands.failed += 1;
        LinkEvent::CommandDone {
            id: s.id,
            command: s.command,
            outcome: CommandOutcome::Failed(why),
        }
    }
}
