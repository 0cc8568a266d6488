//! A scripted station for the link-handler tests: it handshakes, numbers and sends frames,
//! steps the robot and collects what it says.
#![allow(dead_code, clippy::unwrap_used, clippy::panic)]

use protocol::*;
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{AnyRobot, RobotOptions, KHEPERA, MICRO_RATO};

/// What the station saw, owned.
#[derive(Clone, Debug, PartialEq)]
pub enum Seen {
    HelloReply {
        accepted: bool,
        session: u32,
        caps: u32,
    },
    Ack {
        cmd_seq: u16,
        info: AckInfo,
    },
    Nack {
        cmd_seq: u16,
        reason: NackReason,
    },
    Telemetry(Telemetry),
    Event(Event),
    Other(Kind),
}

pub struct Bench {
    pub robot: AnyRobot,
    pub hal: ScriptedHal,
    pub seq: u16,
    pub dec: FrameDecoder,
    /// The telemetry rate the last `HelloReply` stated.
    pub reply_hz: Option<u8>,
    /// Every `Progress` report, in order.
    pub progress: Vec<Progress>,
}

impl Bench {
    pub fn new(profile: &'static robot_firmware::Profile) -> Self {
        let robot = AnyRobot::new(RobotOptions {
            profile,
            seed: 1,
            start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        let hal = ScriptedHal {
            encoders: profile.has(caps::ENCODERS).then_some([0, 0]),
            ..ScriptedHal::default()
        };
        Bench {
            robot,
            hal,
            seq: 0,
            dec: FrameDecoder::new(),
            reply_hz: None,
            progress: Vec::new(),
        }
    }

    pub fn send_with_seq(&mut self, seq: u16, msg: &Message<'_>) {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, msg, &mut buf).unwrap();
        assert_eq!(self.hal.push_rx(&buf[..n]), n);
    }

    /// Sends a message with the next sequence number; returns that number.
    pub fn send(&mut self, msg: &Message<'_>) -> u16 {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        self.send_with_seq(seq, msg);
        seq
    }

    pub fn command(&mut self, c: Command) -> u16 {
        self.send(&Message::Command(c))
    }

    /// Advances the robot's clock by `ms` in 1 ms steps, collecting what it sent.
    pub fn run(&mut self, ms: u64) -> Vec<Seen> {
        let mut seen = Vec::new();
        for _ in 0..ms.max(1) {
            self.robot.step(&mut self.hal);
            self.drain(&mut seen);
            self.hal.now_us += 1000;
        }
        seen
    }

    /// Like `run`, with a heartbeat every 250 ms as a live station sends.
    pub fn run_alive(&mut self, ms: u64) -> Vec<Seen> {
        let mut seen = Vec::new();
        for _ in 0..ms / 250 {
            seen.extend(self.run(250));
            self.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
        }
        seen.extend(self.run(ms % 250));
        seen
    }

    pub fn drain(&mut self, seen: &mut Vec<Seen>) {
        let mut buf = [0u8; 4096];
        let n = self.hal.take_tx(&mut buf);
        let mut input = &buf[..n];
        loop {
            match self.dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { error, .. } => panic!("robot sent a bad frame: {error}"),
                Feed::Frame { frame, rest } => {
                    match frame.message {
                        Message::HelloReply(r) => self.reply_hz = Some(r.telemetry_hz),
                        Message::Progress(p) => self.progress.push(p),
                        _ => {}
                    }
                    seen.push(match frame.message {
                        Message::HelloReply(r) => Seen::HelloReply {
                            accepted: r.accepted,
                            session: r.session,
                            caps: r.capabilities,
                        },
                        Message::Ack(a) => Seen::Ack {
                            cmd_seq: a.cmd_seq,
                            info: a.info,
                        },
                        Message::Nack(n) => Seen::Nack {
                            cmd_seq: n.cmd_seq,
                            reason: n.reason,
                        },
                        Message::Telemetry(t) => Seen::Telemetry(t),
                        Message::Event(e) => Seen::Event(e),
                        m => Seen::Other(m.kind()),
                    });
                    input = rest;
                }
            }
        }
    }

    pub fn handshake(&mut self) {
        self.send(&Message::Hello(Hello {
            fingerprint: FINGERPRINT,
            protocol: PROTOCOL_VERSION,
            session: 77,
            station: "test",
        }));
        let seen = self.run(2);
        assert!(
            seen.contains(&Seen::HelloReply {
                accepted: true,
                session: 77,
                caps: self.caps()
            }),
            "{seen:?}"
        );
    }

    pub fn caps(&self) -> u32 {
        if self.robot.profile().id == ProfileId::Khepera {
            KHEPERA.capabilities
        } else {
            MICRO_RATO.capabilities
        }
    }
}

pub fn replies(seen: &[Seen]) -> Vec<Seen> {
    seen.iter()
        .filter(|s| matches!(s, Seen::Ack { .. } | Seen::Nack { .. }))
        .cloned()
        .collect()
}
