//! The engine against a scripted robot made of the protocol's own `Receiver` and `Sender`,
//! millisecond by millisecond, with frames lost on request.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::transfer::{Receiver, Sender};
use protocol::{crc32c, AckInfo, Command, MapCapacity, Message, NackReason, ObjectKind, ProfileId};

use super::*;
use crate::link::{CommandOutcome, Connection, LinkEvent, PeerInfo, TransferIn, TransferOut};
use crate::transfer::{JobOutcome, TransferError, TransferEvent};

fn connected() -> LinkEvent {
    LinkEvent::Connection(Connection::Connected(PeerInfo {
        session: 1,
        firmware: "robot-firmware".into(),
        firmware_version: "0".into(),
        profile: ProfileId::Khepera,
        capabilities: protocol::caps::TRANSFERS,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id: 1,
    }))
}

/// A robot that holds at most one object and answers like the firmware's `Objects`.
#[derive(Default)]
struct Robot {
    rx: Receiver,
    staging: Vec<u8>,
    held: Option<Vec<u8>>,
    tx: Option<(Sender, Vec<u8>)>,
    /// Frames (either way) still to lose.
    lose: Vec<bool>,
    silent: bool,
    /// The robot's answers to uploads that are lost on the way back.
    lose_answer: Option<fn(&protocol::TransferAck) -> bool>,
}

impl Robot {
    fn lost(&mut self) -> bool {
        if self.silent {
            return true;
        }
        if self.lose.is_empty() {
            false
        } else {
            self.lose.remove(0)
        }
    }
}

struct Bench {
    engine: TransferEngine,
    robot: Robot,
    t: u64,
    reports: Vec<JobReport>,
}

impl Bench {
    fn new() -> Bench {
        let mut engine = TransferEngine::new();
        engine.on_link_event(0, &connected());
        Bench {
            engine,
            robot: Robot {
                staging: vec![0; 4096],
                ..Robot::default()
            },
            t: 0,
            reports: Vec::new(),
        }
    }

    /// Runs until `job` ends (or `limit_ms` passes).
    fn run(&mut self, job: JobId, limit_ms: u64) -> JobReport {
        for _ in 0..limit_ms {
            self.t += 1;
            let t = self.t;
            self.engine.poll(t);
            let mut to_engine = Vec::new();
            for o in self.engine.take_output() {
                // Commands are never lost: the link retries them and always answers.
                if matches!(o, EngineOut::Frame(_)) && self.robot.lost() {
                    continue;
                }
                match o {
                    EngineOut::Frame(TransferOut::Begin(b)) => {
                        let have = self.robot.held.as_deref().map(crc32c) == Some(b.crc);
                        let a = self.robot.rx.on_begin(&b, 4096, have);
                        if !self.robot.lose_answer.is_some_and(|f| f(&a)) {
                            to_engine.push(LinkEvent::Transfer(TransferIn::Ack(a)));
                        }
                    }
                    EngineOut::Frame(TransferOut::Chunk { tag, offset, data }) => {
                        let c = protocol::TransferData {
                            tag,
                            offset,
                            data: &data,
                        };
                        let mut got = None;
                        let a = self.robot.rx.on_chunk(&c, &mut self.robot.staging, |v| {
                            got = Some(v.bytes.to_vec());
                            true
                        });
                        if got.is_some() {
                            self.robot.held = got;
                        }
                        if !self.robot.lose_answer.is_some_and(|f| f(&a)) {
                            to_engine.push(LinkEvent::Transfer(TransferIn::Ack(a)));
                        }
                    }
                    EngineOut::Frame(TransferOut::Ack(a)) => {
                        if let Some((s, _)) = self.robot.tx.as_mut() {
                            s.on_ack(&a, t as u32);
                        }
                    }
                    EngineOut::Command { id, command } => {
                        let Command::Download { object, .. } = command else {
                            panic!("{command:?}");
                        };
                        let outcome = match self.robot.held.clone() {
                            Some(bytes) => {
                                let s = Sender::for_object(object, &bytes, 1).unwrap();
                                let b = s.begin();
                                self.robot.tx = Some((s, bytes));
                                CommandOutcome::Acked {
                                    info: AckInfo::Object {
                                        object,
                                        id: b.id,
                                        len: b.len,
                                        crc: b.crc,
                                    },
                                    sends: 1,
                                    rtt_ms: 1,
                                }
                            }
                            None => CommandOutcome::Nacked {
                                reason: NackReason::NoMap,
                                sends: 1,
                            },
                        };
                        to_engine.push(LinkEvent::CommandDone {
                            id,
                            command,
                            outcome,
                        });
                    }
                }
            }
            if let Some((s, bytes)) = self.robot.tx.as_mut() {
                let mut frames = Vec::new();
                s.poll(t as u32, bytes, |m| {
                    frames.push(match m {
                        Message::TransferBegin(b) => TransferIn::Begin(*b),
                        Message::TransferData(c) => TransferIn::Chunk {
                            tag: c.tag,
                            offset: c.offset,
                            data: c.data.to_vec(),
                        },
                        _ => return true,
                    });
                    true
                });
                if s.is_done() {
                    self.robot.tx = None;
                }
                for f in frames {
                    if !self.robot.lost() {
                        to_engine.push(LinkEvent::Transfer(f));
                    }
                }
            }
            for ev in to_engine {
                if std::env::var_os("ENGINE_TRACE").is_some() {
                    eprintln!("{t} -> {ev:?}");
                }
                self.engine.on_link_event(t, &ev);
            }
            for ev in self.engine.take_events() {
                if let TransferEvent::Finished(r) = ev {
                    self.reports.push(r.clone());
                    if r.job == job {
                        return r;
                    }
                }
            }
        }
        panic!("job {job} did not end in {limit_ms} ms");
    }
}

fn object(n: usize) -> Vec<u8> {
    (0..n).map(|i| (i * 7 % 251) as u8).collect()
}

#[test]
fn an_upload_completes_then_is_already_held() {
    let mut b = Bench::new();
    let bytes = object(1000);
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: bytes.clone(),
    });
    let r = b.run(job, 5_000);
    assert_eq!(r.outcome, JobOutcome::Complete);
    assert_eq!((r.len, r.id), (1000, Some(crc32c(&bytes))));
    assert_eq!(b.robot.held.as_deref(), Some(&bytes[..]));
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes,
    });
    // The loss schedule may take the robot's Begin again: the request is repeated.
    assert_eq!(b.run(job, 20_000).outcome, JobOutcome::AlreadyHave);
}

/// Seeds 144 and 162 of the `transfer_goodput` bench at 1 % byte loss: the chunk that
/// completed the object was answered `Complete`, but that answer and every answer to its
/// resends were lost until the sender gave up; the next attempt's Begin was answered
/// `AlreadyHave` (the robot holds the object now), and the job ended `AlreadyHave` as if
/// nothing had been sent.
#[test]
fn an_upload_whose_complete_answers_are_all_lost_still_ends_complete() {
    let mut b = Bench::new();
    b.robot.lose_answer = Some(|a| a.status == protocol::TransferStatus::Complete);
    let bytes = object(1000);
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: bytes.clone(),
    });
    let r = b.run(job, 20_000);
    assert_eq!(r.outcome, JobOutcome::Complete, "{r:?}");
    assert_eq!(r.attempts, 2, "{r:?}");
    assert_eq!(b.robot.held.as_deref(), Some(&bytes[..]));
    // The same object again: the robot held it before this job began.
    b.robot.lose_answer = None;
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes,
    });
    // The loss schedule may take the robot's Begin again: the request is repeated.
    assert_eq!(b.run(job, 20_000).outcome, JobOutcome::AlreadyHave);
}

#[test]
fn a_download_arrives_whole_even_when_frames_are_lost_both_ways() {
    let mut b = Bench::new();
    // A valid Map object (the engine refuses to hand out a malformed one).
    let map = crate::transfer::objects::map_object(
        &crate::plan::NavMap::load(
            emulator::builtin::MICRO_RATO_99,
            &crate::plan::MapOptions::default(),
        )
        .unwrap(),
    )
    .unwrap();
    b.robot.held = Some(map.bytes.clone());
    b.robot.lose = (0..60).map(|i| i % 5 == 2).collect();
    let job = b.engine.submit(JobSpec::Download {
        object: ObjectKind::Map,
        have: None,
    });
    let r = b.run(job, 20_000);
    assert_eq!(r.outcome, JobOutcome::Complete, "{r:?}");
    assert_eq!(r.bytes.as_deref(), Some(&map.bytes[..]));
    // Asked again with what it holds, on a line that now loses nothing: nothing is sent.
    b.robot.lose.clear();
    let job = b.engine.submit(JobSpec::Download {
        object: ObjectKind::Map,
        have: Some((map.id, map.id)),
    });
    assert_eq!(b.run(job, 5_000).outcome, JobOutcome::AlreadyHave);
}

#[test]
fn a_download_of_nothing_and_a_job_without_a_link_fail_with_the_reason() {
    let mut b = Bench::new();
    let job = b.engine.submit(JobSpec::Download {
        object: ObjectKind::Map,
        have: None,
    });
    let r = b.run(job, 1_000);
    assert_eq!(
        r.outcome,
        JobOutcome::Failed(TransferError::Refused(NackReason::NoMap))
    );
    assert!(r.text().contains("holds no map"), "{}", r.text());
    let mut e = TransferEngine::new();
    let job = e.submit(JobSpec::Upload {
        object: ObjectKind::Plan,
        bytes: vec![1],
    });
    e.poll(0);
    let ended = e.take_events();
    assert!(ended
        .iter()
        .any(|ev| matches!(ev, TransferEvent::Finished(r)
        if r.job == job && r.outcome == JobOutcome::Failed(TransferError::NotConnected))));
}

#[test]
fn a_silent_robot_times_out_after_every_attempt_and_a_dead_link_ends_the_job() {
    let mut b = Bench::new();
    b.robot.silent = true;
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: object(300),
    });
    let r = b.run(job, 20_000);
    assert_eq!(
        r.outcome,
        JobOutcome::Failed(TransferError::TimedOut {
            attempts: MAX_ATTEMPTS
        })
    );
    // Three attempts of five 400 ms retry periods each.
    assert!((5_900..=6_100).contains(&r.elapsed_ms), "{}", r.elapsed_ms);
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: object(300),
    });
    b.engine.poll(b.t);
    let closed = LinkEvent::Connection(Connection::Closed {
        reason: "unplugged".into(),
    });
    b.engine.on_link_event(b.t, &closed);
    let r = b.run(job, 20_000);
    assert_eq!(r.outcome, JobOutcome::Failed(TransferError::LinkLost(10)));
}

#[test]
fn an_upload_interrupted_by_a_reconnect_resumes() {
    let mut b = Bench::new();
    let bytes = object(2000);
    let job = b.engine.submit(JobSpec::Upload {
        object: ObjectKind::Plan,
        bytes: bytes.clone(),
    });
    // Run a little, then the link drops and comes back: the Begin again resumes.
    for _ in 0..3 {
        b.t += 1;
        b.engine.poll(b.t);
        let _ = b.engine.take_output();
    }
    let closed = LinkEvent::Connection(Connection::Closed { reason: "x".into() });
    b.engine.on_link_event(b.t, &closed);
    b.engine.on_link_event(b.t + 500, &connected());
    b.t += 500;
    let r = b.run(job, 10_000);
    assert_eq!(r.outcome, JobOutcome::Complete);
    assert_eq!(b.robot.held.as_deref(), Some(&bytes[..]));
}

/// The first upload on a fresh link begins before the station has measured the line's loss
/// (the command line uploads right after the handshake): it probes with small chunks, and
/// the first measurement replaces the guess at once; a later one only ever caps it.
#[test]
fn an_upload_begun_before_the_loss_was_measured_takes_the_first_measurement() {
    let mut e = TransferEngine::new();
    e.set_connected(true);
    e.submit(JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: vec![7; 1060],
    });
    e.poll(0);
    assert_eq!(
        e.upload_chunk(),
        Some(64),
        "nothing measured: the sender probes with two units"
    );
    // A few clean frames are no measurement (a 1 % line gives four one time in 20).
    let mut few = crate::link::LinkStats {
        bytes_in: 400,
        ..Default::default()
    };
    few.decoder.frames_ok = 5;
    e.on_link_event(1, &LinkEvent::Stats(Box::new(few)));
    assert_eq!(e.upload_chunk(), Some(64));
    let mut s = crate::link::LinkStats {
        bytes_in: 800,
        ..Default::default()
    };
    // 10 frames of 80 bytes, 5 of them damaged: about 0.9 % of bytes lost.
    s.decoder.frames_ok = 5;
    s.decoder.crc_errors = 5;
    e.on_link_event(1, &LinkEvent::Stats(Box::new(s.clone())));
    assert_eq!(e.upload_chunk(), Some(32));
    // A clean measurement later does not grow it: growth is earned by loss-free progress.
    s.decoder.frames_ok = 100;
    s.decoder.crc_errors = 0;
    e.on_link_event(2, &LinkEvent::Stats(Box::new(s)));
    assert_eq!(e.upload_chunk(), Some(32));
}
