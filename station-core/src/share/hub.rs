//! The shared link's state machine: what the station that holds a robot's port says to the
//! other station programs attached to it, and what it sends the robot for them.
//!
//! Layer: pure state, no I/O (the server in `share::server` moves the bytes). A client speaks
//! the robot's own protocol (PROTOCOL.md): it sends `Hello` and is answered here with the
//! robot's `HelloReply` as the holder received it, so every station command works unchanged.
//! Its commands go to the robot through the holder's link under ids of their own, and each
//! outcome is answered to that client alone with its own sequence number; a retry of a command
//! still in flight is not sent twice. The robot's telemetry, progress, events, logs, ground
//! truth and situations go to every client. Transfers (map, plan and calibration objects) stay
//! with the holder: a client's `TransferBegin` is answered `Busy`, its `Download` refused
//! `Busy`. The client that drives by hand (teleop or manual mode) and disconnects stops the
//! robot; a task it started (a go-to, a plan, exploration) goes on, as it does when a command
//! line tool exits after sending it without a shared link.
//!
//! The local leg is not signed: the socket is the user's own (mode 0600 in a 0700 directory),
//! and the holder verifies the robot's signatures on the serial leg.
//!
//! What can fail: nothing; frames a client should not send are ignored.

use std::collections::{BTreeMap, HashMap, VecDeque};

use protocol::frame::{encode, Frame, MAX_FRAME};
use protocol::{
    Ack, AckInfo, Command, HelloReply, Log, Message, Mode, Nack, NackReason, TransferAck,
    TransferStatus, FINGERPRINT, PROTOCOL_VERSION,
};

use crate::link::{CommandId, CommandOutcome, Connection, LinkEvent, PeerInfo};

/// Names one attached client.
pub type ClientId = u64;

/// The first id of the commands sent for clients: far above the ids the holder's own users
/// draw from 1 upwards, so an outcome says whose command it was.
pub const FIRST_CLIENT_COMMAND: CommandId = 1 << 62;

/// Answers remembered per client, for a retry of a command already answered.
const ANSWERS_KEPT: usize = 16;
/// Commands one client may have in flight; more are refused `Busy` (a client cannot grow the
/// holder's queue without bound).
const IN_FLIGHT_MAX: usize = 32;

/// What the hub asks the server to do.
#[derive(Clone, Debug, PartialEq)]
pub enum HubOut {
    /// Write this frame to the client.
    Send(ClientId, Vec<u8>),
    /// Send this command to the robot through the holder's link, under this id.
    Submit(CommandId, Command),
    /// Close the client's connection (the holder's link is gone).
    Close(ClientId),
}

/// Who is driving the robot by hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Driver {
    /// Nobody, or the holder itself.
    NotAClient,
    Client(ClientId),
}

#[derive(Debug, Default)]
struct Client {
    /// The sequence number of the next frame to this client. Ground truth has its own
    /// numbering, as the emulator's truth frames do on the serial leg (the robot does not
    /// send them, so the station counts their loss apart).
    out_seq: u16,
    truth_seq: u16,
    /// Whether its `Hello` was answered: before that it gets nothing else.
    greeted: bool,
    /// Its commands' sequence numbers and their answers, newest last.
    answered: VecDeque<(u16, Vec<u8>)>,
}

/// The shared link's state.
#[derive(Debug)]
pub struct Hub {
    /// What the robot said in its `HelloReply` to the holder; `None` while not connected.
    peer: Option<PeerInfo>,
    clients: BTreeMap<ClientId, Client>,
    next_client: ClientId,
    /// Commands sent for clients and not yet answered: whose, with which sequence number.
    pending: HashMap<CommandId, (ClientId, u16, Command)>,
    next_command: CommandId,
    driver: Driver,
}

impl Default for Hub {
    fn default() -> Self {
        Self::new()
    }
}

impl Hub {
    pub fn new() -> Self {
        Hub {
            peer: None,
            clients: BTreeMap::new(),
            next_client: 1,
            pending: HashMap::new(),
            next_command: FIRST_CLIENT_COMMAND,
            driver: Driver::NotAClient,
        }
    }

    /// How many clients are attached.
    pub fn clients(&self) -> usize {
        self.clients.len()
    }

    /// A client attached.
    pub fn add_client(&mut self) -> ClientId {
        let id = self.next_client;
        self.next_client += 1;
        self.clients.insert(id, Client::default());
        id
    }

    /// A client went away: its commands' answers go nowhere; if it was driving by hand, the
    /// robot stops.
    pub fn client_gone(&mut self, c: ClientId) -> Vec<HubOut> {
        self.clients.remove(&c);
        self.pending.retain(|_, (owner, _, _)| *owner != c);
        if self.driver == Driver::Client(c) {
            self.driver = Driver::NotAClient;
            let id = self.command_id();
            return vec![HubOut::Submit(id, Command::Stop)];
        }
        Vec::new()
    }

    fn command_id(&mut self) -> CommandId {
        let id = self.next_command;
        self.next_command += 1;
        id
    }

    /// A frame from client `c`.
    pub fn client_frame(&mut self, c: ClientId, frame: &Frame<'_>) -> Vec<HubOut> {
        if !self.clients.contains_key(&c) {
            return Vec::new();
        }
        let seq = frame.header.seq;
        match &frame.message {
            Message::Hello(h) => {
                // Not connected to the robot: no answer, so the client keeps asking until
                // the holder's link is up (or its own timeout says so).
                let Some(peer) = self.peer.clone() else {
                    return Vec::new();
                };
                let accepted = h.fingerprint == FINGERPRINT && h.protocol == PROTOCOL_VERSION;
                let reply = HelloReply {
                    fingerprint: FINGERPRINT,
                    protocol: PROTOCOL_VERSION,
                    session: h.session,
                    accepted,
                    firmware: &peer.firmware,
                    firmware_version: &peer.firmware_version,
                    profile: peer.profile,
                    capabilities: peer.capabilities,
                    map_capacity: peer.map_capacity,
                    telemetry_hz: peer.telemetry_hz,
                    failsafe_ms: peer.failsafe_ms,
                    robot_id: peer.robot_id,
                };
                let out = self.frame_to(c, &Message::HelloReply(reply));
                if let Some(client) = self.clients.get_mut(&c) {
                    client.greeted = accepted;
                }
                out.into_iter().collect()
            }
            Message::Command(cmd) => self.command(c, seq, *cmd),
            Message::TransferBegin(b) => {
                let ack = TransferAck {
                    tag: b.tag,
                    next: 0,
                    status: TransferStatus::Busy,
                    sack: 0,
                };
                self.frame_to(c, &Message::TransferAck(ack))
                    .into_iter()
                    .collect()
            }
            // Heartbeats: the holder's own link keeps the robot's session alive. Chunks and
            // acks of transfers the hub refused: nothing to do.
            _ => Vec::new(),
        }
    }

    fn command(&mut self, c: ClientId, seq: u16, cmd: Command) -> Vec<HubOut> {
        let Some(client) = self.clients.get(&c) else {
            return Vec::new();
        };
        if !client.greeted {
            return self
                .frame_to(
                    c,
                    &Message::Nack(Nack {
                        cmd_seq: seq,
                        reason: NackReason::NoHandshake,
                    }),
                )
                .into_iter()
                .collect();
        }
        // A retry: answered already (the answer was lost), or still in flight.
        if let Some((_, bytes)) = client.answered.iter().find(|(s, _)| *s == seq) {
            return vec![HubOut::Send(c, bytes.clone())];
        }
        if self.pending.values().any(|(o, s, _)| *o == c && *s == seq) {
            return Vec::new();
        }
        let in_flight = self.pending.values().filter(|(o, _, _)| *o == c).count();
        if in_flight >= IN_FLIGHT_MAX {
            return self.answer(c, seq, Err(NackReason::Busy));
        }
        if matches!(cmd, Command::Download { .. }) {
            // The object would come to the holder's transfers, not to this client.
            return self.answer(c, seq, Err(NackReason::Busy));
        }
        let id = self.command_id();
        self.pending.insert(id, (c, seq, cmd));
        vec![HubOut::Submit(id, cmd)]
    }

    /// An event of the holder's link. Returns whether it was the hub's own (the outcome of a
    /// client's command: the holder's users never submitted it) and what to do.
    pub fn link_event(&mut self, ev: &LinkEvent) -> (bool, Vec<HubOut>) {
        let message = match ev {
            LinkEvent::Connection(Connection::Connected(peer)) => {
                self.peer = Some(peer.clone());
                return (false, Vec::new());
            }
            LinkEvent::Connection(_) => {
                // The robot is gone from the holder: every client's session with it ends.
                let had_peer = self.peer.take().is_some();
                let outs = if had_peer {
                    let ids: Vec<ClientId> = self.clients.keys().copied().collect();
                    self.clients.clear();
                    self.pending.clear();
                    self.driver = Driver::NotAClient;
                    ids.into_iter().map(HubOut::Close).collect()
                } else {
                    Vec::new()
                };
                return (false, outs);
            }
            LinkEvent::CommandDone {
                id,
                command,
                outcome,
            } => return self.command_done(*id, command, outcome),
            LinkEvent::Telemetry(t) => Message::Telemetry(*t),
            LinkEvent::Truth(t) => Message::EmuTruth(*t),
            LinkEvent::Localization(l) => Message::Localization(**l),
            LinkEvent::Progress(p) => Message::Progress(*p),
            LinkEvent::Situation(s) => Message::AliceSituation(*s),
            LinkEvent::Robot(e) => Message::Event(*e),
            LinkEvent::Log { level, text } => {
                let msg = Message::Log(Log {
                    level: *level,
                    text,
                });
                return (false, self.broadcast(&msg));
            }
            LinkEvent::Transfer(_) | LinkEvent::Stats(_) => return (false, Vec::new()),
        };
        (false, self.broadcast(&message))
    }

    fn command_done(
        &mut self,
        id: CommandId,
        command: &Command,
        outcome: &CommandOutcome,
    ) -> (bool, Vec<HubOut>) {
        if id < FIRST_CLIENT_COMMAND {
            // The holder's own command: a hand-driving one makes the holder the driver.
            if matches!(outcome, CommandOutcome::Acked { .. }) && drives(command) {
                self.driver = Driver::NotAClient;
            }
            return (false, Vec::new());
        }
        let Some((c, seq, cmd)) = self.pending.remove(&id) else {
            // A client's command whose client went away (or the hub's own Stop).
            return (true, Vec::new());
        };
        let answer = match outcome {
            CommandOutcome::Acked { info, .. } => {
                if drives(&cmd) {
                    self.driver = Driver::Client(c);
                } else if matches!(cmd, Command::Stop) && self.driver == Driver::Client(c) {
                    self.driver = Driver::NotAClient;
                }
                Ok(*info)
            }
            CommandOutcome::Nacked { reason, .. } => Err(*reason),
            // No answer from the robot: none to the client either, which retries (and is
            // sent again) or gives up by its own timers, as on a direct link.
            _ => return (true, Vec::new()),
        };
        (true, self.answer(c, seq, answer))
    }

    fn answer(
        &mut self,
        c: ClientId,
        seq: u16,
        answer: Result<AckInfo, NackReason>,
    ) -> Vec<HubOut> {
        let msg = match answer {
            Ok(info) => Message::Ack(Ack { cmd_seq: seq, info }),
            Err(reason) => Message::Nack(Nack {
                cmd_seq: seq,
                reason,
            }),
        };
        let Some(HubOut::Send(_, bytes)) = self.frame_to(c, &msg) else {
            return Vec::new();
        };
        if let Some(client) = self.clients.get_mut(&c) {
            if client.answered.len() == ANSWERS_KEPT {
                client.answered.pop_front();
            }
            client.answered.push_back((seq, bytes.clone()));
        }
        vec![HubOut::Send(c, bytes)]
    }

    /// `msg` to every client that has been greeted.
    fn broadcast(&mut self, msg: &Message<'_>) -> Vec<HubOut> {
        let ids: Vec<ClientId> = self
            .clients
            .iter()
            .filter(|(_, cl)| cl.greeted)
            .map(|(id, _)| *id)
            .collect();
        ids.into_iter()
            .filter_map(|c| self.frame_to(c, msg))
            .collect()
    }

    fn frame_to(&mut self, c: ClientId, msg: &Message<'_>) -> Option<HubOut> {
        let client = self.clients.get_mut(&c)?;
        let seq = if matches!(msg, Message::EmuTruth(_)) {
            &mut client.truth_seq
        } else {
            &mut client.out_seq
        };
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(*seq, msg, &mut buf).ok()?;
        *seq = seq.wrapping_add(1);
        Some(HubOut::Send(c, buf.get(..n)?.to_vec()))
    }
}

/// Whether a command drives the robot by hand: its sender is then the one whose going away
/// must stop the robot (as the robot's failsafe stops it when the station goes silent).
fn drives(cmd: &Command) -> bool {
    matches!(cmd, Command::Teleop { .. } | Command::SetMode(Mode::Manual))
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::frame::{Feed, FrameDecoder};
    use protocol::{Hello, MapCapacity, ProfileId, Telemetry};

    fn peer() -> PeerInfo {
        PeerInfo {
            session: 7,
            firmware: "robot-firmware".into(),
            firmware_version: "0.1.0".into(),
            profile: ProfileId::MicroRato,
            capabilities: 0x48,
            map_capacity: MapCapacity {
                width: 64,
                height: 64,
            },
            telemetry_hz: 10,
            failsafe_ms: 300,
            robot_id: 2,
        }
    }

    fn frame_of(seq: u16, msg: &Message<'_>) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, msg, &mut buf).expect("encodes");
        buf[..n].to_vec()
    }

    /// Feeds `bytes` (one frame) to the hub as client `c`'s.
    fn from_client(hub: &mut Hub, c: ClientId, bytes: &[u8]) -> Vec<HubOut> {
        let mut d = FrameDecoder::new();
        match d.feed(bytes) {
            Feed::Frame { frame, .. } => hub.client_frame(c, &frame),
            _ => panic!("not a frame"),
        }
    }

    fn decode(bytes: &[u8]) -> (u16, String) {
        let mut d = FrameDecoder::new();
        match d.feed(bytes) {
            Feed::Frame { frame, .. } => (frame.header.seq, format!("{:?}", frame.message)),
            _ => panic!("not a frame"),
        }
    }

    fn hello(session: u32) -> Vec<u8> {
        frame_of(
            0,
            &Message::Hello(Hello {
                fingerprint: FINGERPRINT,
                protocol: PROTOCOL_VERSION,
                session,
                station: "station-cli",
            }),
        )
    }

    fn connected_hub() -> Hub {
        let mut hub = Hub::new();
        hub.link_event(&LinkEvent::Connection(Connection::Connected(peer())));
        hub
    }

    #[test]
    fn a_client_is_answered_with_the_robots_hello_reply_for_its_own_session() {
        let mut hub = Hub::new();
        let c = hub.add_client();
        assert!(
            from_client(&mut hub, c, &hello(99)).is_empty(),
            "not connected yet"
        );
        hub.link_event(&LinkEvent::Connection(Connection::Connected(peer())));
        let out = from_client(&mut hub, c, &hello(99));
        let [HubOut::Send(to, bytes)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert_eq!(*to, c);
        let (_, text) = decode(bytes);
        assert!(text.contains("session: 99"), "{text}");
        assert!(text.contains("accepted: true"), "{text}");
        assert!(text.contains("robot_id: 2"), "{text}");
    }

    #[test]
    fn commands_are_acked_to_their_client_with_its_sequence_number_and_sent_once() {
        let mut hub = connected_hub();
        let a = hub.add_client();
        let b = hub.add_client();
        from_client(&mut hub, a, &hello(1));
        from_client(&mut hub, b, &hello(2));
        let stop = frame_of(41, &Message::Command(Command::Stop));
        let out = from_client(&mut hub, a, &stop);
        let [HubOut::Submit(id, Command::Stop)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert!(*id >= FIRST_CLIENT_COMMAND);
        // The client's retry while it is in flight is not sent again.
        assert!(from_client(&mut hub, a, &stop).is_empty());
        let (owned, out) = hub.link_event(&LinkEvent::CommandDone {
            id: *id,
            command: Command::Stop,
            outcome: CommandOutcome::Acked {
                info: AckInfo::Done,
                sends: 1,
                rtt_ms: 3,
            },
        });
        assert!(owned, "the holder's users never see a client's outcome");
        let [HubOut::Send(to, bytes)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert_eq!(*to, a, "acked to the client that sent it, not to b");
        assert!(decode(bytes).1.contains("cmd_seq: 41"));
        // A retry after the answer (the answer was lost) gets the same answer again.
        let again = from_client(&mut hub, a, &stop);
        assert_eq!(again, vec![HubOut::Send(a, bytes.clone())]);
    }

    #[test]
    fn telemetry_goes_to_every_greeted_client_and_commands_before_hello_are_refused() {
        let mut hub = connected_hub();
        let a = hub.add_client();
        let b = hub.add_client();
        from_client(&mut hub, a, &hello(1));
        let (owned, out) = hub.link_event(&LinkEvent::Telemetry(Telemetry::default()));
        assert!(!owned);
        assert_eq!(out.len(), 1, "b has not said hello: {out:?}");
        let out = from_client(&mut hub, b, &frame_of(5, &Message::Command(Command::Stop)));
        let [HubOut::Send(_, bytes)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert!(decode(bytes).1.contains("NoHandshake"));
    }

    #[test]
    fn a_client_driving_by_hand_that_goes_away_stops_the_robot_and_a_task_starter_does_not() {
        let mut hub = connected_hub();
        let a = hub.add_client();
        from_client(&mut hub, a, &hello(1));
        let teleop = Command::Teleop {
            v_mm_s: 100,
            w_mrad_s: 0,
        };
        let out = from_client(&mut hub, a, &frame_of(3, &Message::Command(teleop)));
        let [HubOut::Submit(id, _)] = out.as_slice() else {
            panic!("{out:?}")
        };
        hub.link_event(&LinkEvent::CommandDone {
            id: *id,
            command: teleop,
            outcome: CommandOutcome::Acked {
                info: AckInfo::Done,
                sends: 1,
                rtt_ms: 3,
            },
        });
        let out = hub.client_gone(a);
        assert!(
            matches!(out.as_slice(), [HubOut::Submit(_, Command::Stop)]),
            "{out:?}"
        );

        let b = hub.add_client();
        from_client(&mut hub, b, &hello(2));
        let goto = Command::GoTo(protocol::PointMm {
            x_mm: 500,
            y_mm: 500,
        });
        let out = from_client(&mut hub, b, &frame_of(4, &Message::Command(goto)));
        let [HubOut::Submit(id, _)] = out.as_slice() else {
            panic!("{out:?}")
        };
        hub.link_event(&LinkEvent::CommandDone {
            id: *id,
            command: goto,
            outcome: CommandOutcome::Acked {
                info: AckInfo::Done,
                sends: 1,
                rtt_ms: 3,
            },
        });
        assert!(hub.client_gone(b).is_empty(), "a go-to goes on");
    }

    #[test]
    fn a_client_cannot_queue_commands_without_bound() {
        let mut hub = connected_hub();
        let a = hub.add_client();
        from_client(&mut hub, a, &hello(1));
        for seq in 0..IN_FLIGHT_MAX as u16 {
            let out = from_client(
                &mut hub,
                a,
                &frame_of(seq, &Message::Command(Command::Stop)),
            );
            assert!(matches!(out.as_slice(), [HubOut::Submit(..)]), "{out:?}");
        }
        let out = from_client(
            &mut hub,
            a,
            &frame_of(999, &Message::Command(Command::Stop)),
        );
        let [HubOut::Send(_, bytes)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert!(decode(bytes).1.contains("Busy"));
    }

    #[test]
    fn transfers_stay_with_the_holder_and_link_loss_closes_every_client() {
        let mut hub = connected_hub();
        let a = hub.add_client();
        from_client(&mut hub, a, &hello(1));
        let dl = Command::Download {
            object: protocol::ObjectKind::Map,
        };
        let out = from_client(&mut hub, a, &frame_of(9, &Message::Command(dl)));
        let [HubOut::Send(_, bytes)] = out.as_slice() else {
            panic!("{out:?}")
        };
        assert!(decode(bytes).1.contains("Busy"));
        let (_, out) = hub.link_event(&LinkEvent::Connection(Connection::Closed {
            reason: "unplugged".into(),
        }));
        assert_eq!(out, vec![HubOut::Close(a)]);
        assert_eq!(hub.clients(), 0);
    }
}
