//! [`TransferEngine`]: the station's transfers as a state machine driven by link events.
//!
//! Layer: protocol state with no I/O and no clock, like `link::machine`. The owner feeds it
//! every `LinkEvent` ([`TransferEngine::on_link_event`]) and polls it with the time
//! ([`TransferEngine::poll`], every few tens of ms); it answers with [`EngineOut`]s (transfer
//! frames for `LinkHandle::transfer`, `Download` commands for `LinkHandle::submit_with_id`)
//! and [`TransferEvent`]s. Its commands carry ids from [`ENGINE_COMMAND_BASE`] up, so their
//! `CommandDone`s are told from everyone else's.
//!
//! Retries and resume (PROTOCOL.md §8), on top of the protocol's `Sender` and `Receiver`:
//! - an upload that times out (5 retry periods without progress) is begun again, which
//!   resumes at the robot's `next`, up to [`MAX_ATTEMPTS`] attempts in all; after the link
//!   drops and comes back it is begun again the same way;
//! - a download whose chunks stop for [`DOWNLOAD_STALL_MS`], that fails its CRC, or whose
//!   `Download` command goes unanswered is asked for again (the station keeps its partial
//!   bytes and answers the robot's new `TransferBegin` with its `next`), up to
//!   [`MAX_ATTEMPTS`]; after a reconnect it is asked for again the same way;
//! - a link down for longer than [`MAX_DISCONNECTED_MS`] ends the job (`LinkLost`).
//!
//! Invariants: one job at a time, in submission order; every submitted job ends in exactly
//! one `Finished` event; a downloaded object is handed out only when whole, its CRC-32C
//! matched and `protocol::object::parse` accepted it. Nothing here panics.

use std::collections::VecDeque;

use protocol::object::{kind_of, parse};
use protocol::transfer::{chunk_for_loss, next_tag, Outcome, Receiver, Sender, NO_TAG};

use super::UploadCounts;
use protocol::{
    AckInfo, Command, Message, ObjectKind, TransferAck, TransferBegin, TransferData, TransferStatus,
};

use super::{Direction, JobId, JobOutcome, JobReport, TransferError, TransferEvent};
use crate::link::{CommandFailure, CommandId, CommandOutcome, Connection, LinkEvent, LinkStats};
use crate::link::{TransferIn, TransferOut};

/// First command id the engine uses; ids below are everyone else's.
pub const ENGINE_COMMAND_BASE: CommandId = 1 << 62;
/// Attempts a job gets (the first and the restarts after timeouts or bad CRCs).
pub const MAX_ATTEMPTS: u8 = 3;
/// A download with no frame from the robot for this long is asked for again, ms (the robot's
/// sender gives up after 5 x 400 ms without progress).
pub const DOWNLOAD_STALL_MS: u64 = 2_500;
/// A job whose link stays down this long fails, ms.
pub const MAX_DISCONNECTED_MS: u64 = 10_000;
/// Largest object the station downloads: a 2048 x 2048 map and its header, rounded up.
pub const MAX_DOWNLOAD_BYTES: u32 = 1 << 21;
/// Pause before asking again after the link refused a `Download` for want of a session, ms.
const REQUEST_BACKOFF_MS: u64 = 200;

/// Whether a command id is one of the engine's.
pub fn is_engine_command(id: CommandId) -> bool {
    id >= ENGINE_COMMAND_BASE
}

/// What a job does.
#[derive(Clone, Debug, PartialEq)]
pub enum JobSpec {
    /// Send `bytes` as an object of kind `object` (id = CRC-32C of the bytes).
    Upload { object: ObjectKind, bytes: Vec<u8> },
    /// Fetch the robot's object. `have`: the (id, CRC) the station already holds, answered
    /// `AlreadyHave` when the robot's is the same (nothing is sent).
    Download {
        object: ObjectKind,
        have: Option<(u32, u32)>,
    },
}

/// Something for the link task.
#[derive(Clone, Debug, PartialEq)]
pub enum EngineOut {
    /// A transfer frame for `LinkHandle::transfer`.
    Frame(TransferOut),
    /// A command for `LinkHandle::submit_with_id`.
    Command { id: CommandId, command: Command },
}

/// The running job's progress, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    pub job: JobId,
    pub direction: Direction,
    pub object: ObjectKind,
    pub done: u32,
    /// 0 until the length is known (a download before the robot's answer).
    pub total: u32,
}

enum Phase {
    Upload {
        sender: Box<Sender>,
        bytes: Vec<u8>,
    },
    /// A `Download` is due at `not_before`.
    Request {
        have: Option<(u32, u32)>,
        not_before: u64,
    },
    /// The `Download` command `cmd` is out.
    Requested {
        cmd: CommandId,
        have: Option<(u32, u32)>,
    },
    /// The robot said what it sends; chunks are expected.
    Receiving {
        info: TransferBegin,
        have: Option<(u32, u32)>,
        last_frame_ms: u64,
    },
}

struct Active {
    job: JobId,
    direction: Direction,
    object: ObjectKind,
    started_ms: u64,
    attempts: u8,
    down_since: Option<u64>,
    /// The progress last reported.
    shown: (u32, u32),
    /// An upload the robot answered `Receiving`: it did not hold the object when this job
    /// began, so an `AlreadyHave` to a later attempt's Begin means this job installed it
    /// (its `Complete` answers were lost and the attempt timed out).
    robot_receiving: bool,
    /// An upload's first chunk size, bytes (0 for a download).
    first_chunk: u32,
    phase: Phase,
}

/// The station's transfer state machine. See the module documentation.
pub struct TransferEngine {
    connected: bool,
    queue: VecDeque<(JobId, JobSpec)>,
    active: Option<Active>,
    next_job: JobId,
    next_cmd: CommandId,
    rx: Receiver,
    /// Download bytes land here until verified (and stay, for resuming, if interrupted).
    staging: Vec<u8>,
    /// (id, CRC) of the last object a download ended with: a late `TransferBegin` of it is
    /// answered `AlreadyHave`.
    last_download: Option<(u32, u32)>,
    out: Vec<EngineOut>,
    events: VecDeque<TransferEvent>,
    /// Bytes in a million the line loses, estimated from the robot's frames (`Stats`): an
    /// upload starts with the chunk size that carries most on such a line.
    line_loss_ppm: Option<u32>,
    /// The tag of the last upload's `TransferBegin`: the next upload uses the one after.
    last_tag: u8,
}

impl Default for TransferEngine {
    fn default() -> Self {
        Self::new()
    }
}

impl std::fmt::Debug for TransferEngine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TransferEngine")
            .field("connected", &self.connected)
            .field("queued", &self.queue.len())
            .field("progress", &self.progress())
            .finish_non_exhaustive()
    }
}

/// A sender's frame as an owned `TransferOut`.
fn frame(m: &Message<'_>) -> Option<TransferOut> {
    match m {
        Message::TransferBegin(b) => Some(TransferOut::Begin(*b)),
        Message::TransferData(c) => Some(TransferOut::Chunk {
            tag: c.tag,
            offset: c.offset,
            data: c.data.to_vec(),
        }),
        Message::TransferAck(a) => Some(TransferOut::Ack(*a)),
        _ => None,
    }
}

impl TransferEngine {
    /// No job, not connected (the first `Connected` event, or `set_connected`, says so).
    pub fn new() -> Self {
        TransferEngine {
            connected: false,
            queue: VecDeque::new(),
            active: None,
            next_job: 1,
            next_cmd: ENGINE_COMMAND_BASE,
            rx: Receiver::new(),
            staging: Vec::new(),
            last_download: None,
            out: Vec::new(),
            events: VecDeque::new(),
            line_loss_ppm: None,
            last_tag: NO_TAG,
        }
    }

    /// A sender for `b`, starting with the chunk size the line's loss calls for.
    fn sender(&self, b: TransferBegin) -> Sender {
        let mut s = Sender::new(b.object, b.id, b.len, b.crc, b.tag);
        if let Some(ppm) = self.line_loss_ppm {
            s.set_chunk(chunk_for_loss(ppm));
        }
        s
    }

    /// Tells the engine the link is (or is not) in a session, for an owner that consumed the
    /// `Connected` event itself (the headless `connect`).
    pub fn set_connected(&mut self, connected: bool) {
        self.connected = connected;
    }

    /// Queues a job; it starts at the next `poll` once the jobs before it have ended.
    pub fn submit(&mut self, spec: JobSpec) -> JobId {
        let job = self.next_job;
        self.next_job += 1;
        self.queue.push_back((job, spec));
        job
    }

    /// No job running or queued.
    pub fn is_idle(&self) -> bool {
        self.active.is_none() && self.queue.is_empty()
    }

    /// The job running now (`None` between jobs).
    pub fn active_job(&self) -> Option<JobId> {
        self.active.as_ref().map(|a| a.job)
    }

    /// Frames and commands for the link; empties the buffer.
    pub fn take_output(&mut self) -> Vec<EngineOut> {
        std::mem::take(&mut self.out)
    }

    /// Events so far, in order; empties the queue.
    pub fn take_events(&mut self) -> Vec<TransferEvent> {
        self.events.drain(..).collect()
    }

    /// The running job's progress.
    pub fn progress(&self) -> Option<Progress> {
        let a = self.active.as_ref()?;
        let (done, total) = match &a.phase {
            Phase::Upload { sender, .. } => sender.progress(),
            Phase::Receiving { info, .. } => match self.rx.progress() {
                Some((_, id, next, len)) if id == info.id => (next, len),
                _ => (0, info.len),
            },
            Phase::Request { .. } | Phase::Requested { .. } => (0, 0),
        };
        Some(Progress {
            job: a.job,
            direction: a.direction,
            object: a.object,
            done,
            total,
        })
    }

    /// The running upload's sender counts (chunks, resends, probes, timer expiries), for
    /// reports such as the goodput bench.
    pub fn upload_stats(&self) -> Option<protocol::transfer::SenderStats> {
        match &self.active.as_ref()?.phase {
            Phase::Upload { sender, .. } => Some(sender.stats()),
            _ => None,
        }
    }

    /// The running upload's chunk size in bytes (it adapts to losses), for reports.
    pub fn upload_chunk(&self) -> Option<u32> {
        match &self.active.as_ref()?.phase {
            Phase::Upload { sender, .. } => Some(sender.chunk()),
            _ => None,
        }
    }

    /// Ends the running job and every queued one with `Cancelled`.
    pub fn cancel_all(&mut self, now_ms: u64) {
        self.finish(now_ms, JobOutcome::Failed(TransferError::Cancelled), None);
        for (job, spec) in std::mem::take(&mut self.queue) {
            let (direction, object) = describe(&spec);
            self.report_unstarted(job, direction, object, TransferError::Cancelled);
        }
    }

    /// Takes a link event into account. Returns true for the events that are the engine's
    /// own (transfer frames, its commands' `CommandDone`), which other users can ignore.
    pub fn on_link_event(&mut self, now_ms: u64, ev: &LinkEvent) -> bool {
        match ev {
            LinkEvent::Connection(Connection::Connected(_)) => {
                self.connected = true;
                self.rx.new_session();
                self.reconnected(now_ms);
                false
            }
            LinkEvent::Connection(_) => {
                self.connected = false;
                if let Some(a) = self.active.as_mut() {
                    a.down_since.get_or_insert(now_ms);
                }
                false
            }
            LinkEvent::Stats(s) => {
                if let Some(ppm) = byte_loss_ppm(s) {
                    self.line_loss_ppm = Some(ppm);
                    // An upload begun before the line's loss was measured (the first on a
                    // fresh link) takes the measurement as soon as it comes.
                    if let Some(Active {
                        phase: Phase::Upload { sender, .. },
                        ..
                    }) = self.active.as_mut()
                    {
                        sender.limit_chunk(chunk_for_loss(ppm));
                    }
                }
                false
            }
            LinkEvent::CommandDone { id, outcome, .. } if is_engine_command(*id) => {
                self.command_done(now_ms, *id, outcome);
                self.poll(now_ms);
                true
            }
            LinkEvent::Transfer(t) => {
                match t {
                    TransferIn::Ack(ack) => {
                        if let Some(a) = self.active.as_mut() {
                            if let Phase::Upload { sender, .. } = &mut a.phase {
                                if ack.tag == sender.begin().tag
                                    && ack.status == TransferStatus::Receiving
                                {
                                    a.robot_receiving = true;
                                }
                                sender.on_ack(ack, now_ms as u32);
                            }
                        }
                    }
                    TransferIn::Begin(b) => self.on_begin(now_ms, b),
                    TransferIn::Chunk { tag, offset, data } => {
                        self.on_chunk(now_ms, *tag, *offset, data);
                    }
                }
                self.poll(now_ms);
                true
            }
            _ => false,
        }
    }

    /// Starts queued jobs and runs the timers and the upload window.
    pub fn poll(&mut self, now_ms: u64) {
        while self.active.is_none() {
            let Some((job, spec)) = self.queue.pop_front() else {
                return;
            };
            self.start(now_ms, job, spec);
        }
        self.drive(now_ms);
    }

    fn start(&mut self, now_ms: u64, job: JobId, spec: JobSpec) {
        let (direction, object) = describe(&spec);
        if !self.connected {
            self.report_unstarted(job, direction, object, TransferError::NotConnected);
            return;
        }
        let phase = match spec {
            JobSpec::Upload { object, bytes } => match Sender::for_object(object, &bytes, NO_TAG) {
                Some(sender) => {
                    self.last_tag = next_tag(self.last_tag);
                    let begin = TransferBegin {
                        tag: self.last_tag,
                        ..sender.begin()
                    };
                    Phase::Upload {
                        sender: Box::new(self.sender(begin)),
                        bytes,
                    }
                }
                None => {
                    let e = TransferError::TooLarge {
                        len: bytes.len() as u64,
                        max: u64::from(u32::MAX),
                    };
                    self.report_unstarted(job, direction, object, e);
                    return;
                }
            },
            JobSpec::Download { have, .. } => Phase::Request {
                have,
                not_before: now_ms,
            },
        };
        let first_chunk = match &phase {
            Phase::Upload { sender, .. } => sender.chunk(),
            _ => 0,
        };
        self.active = Some(Active {
            job,
            direction,
            object,
            started_ms: now_ms,
            attempts: 1,
            first_chunk,
            down_since: None,
            shown: (0, 0),
            robot_receiving: false,
            phase,
        });
        self.events.push_back(TransferEvent::Started {
            job,
            direction,
            object,
        });
    }

    fn report_unstarted(
        &mut self,
        job: JobId,
        direction: Direction,
        object: ObjectKind,
        e: TransferError,
    ) {
        self.events.push_back(TransferEvent::Finished(JobReport {
            job,
            direction,
            object,
            id: None,
            crc: None,
            len: 0,
            outcome: JobOutcome::Failed(e),
            elapsed_ms: 0,
            attempts: 0,
            bytes: None,
            sender: None,
        }));
    }

    fn drive(&mut self, now_ms: u64) {
        let connected = self.connected;
        let Some(a) = self.active.as_mut() else {
            return;
        };
        if !connected {
            let since = *a.down_since.get_or_insert(now_ms);
            if now_ms.saturating_sub(since) >= MAX_DISCONNECTED_MS {
                let e = TransferError::LinkLost(MAX_DISCONNECTED_MS / 1000);
                self.finish(now_ms, JobOutcome::Failed(e), None);
            }
            return;
        }
        a.down_since = None;
        match &mut a.phase {
            Phase::Upload { .. } => self.drive_upload(now_ms),
            Phase::Request { have, not_before } => {
                if now_ms < *not_before {
                    return;
                }
                let have = *have;
                let cmd = self.next_cmd;
                self.next_cmd += 1;
                // Bytes kept from an interrupted download are not claimed here: the
                // receiver's answer to the robot's Begin resumes them (PROTOCOL.md §8).
                let command = Command::Download { object: a.object };
                a.phase = Phase::Requested { cmd, have };
                self.out.push(EngineOut::Command { id: cmd, command });
            }
            Phase::Requested { .. } => {}
            Phase::Receiving { last_frame_ms, .. } => {
                if now_ms.saturating_sub(*last_frame_ms) >= DOWNLOAD_STALL_MS {
                    let attempts = a.attempts;
                    self.retry_download(now_ms, TransferError::TimedOut { attempts });
                }
            }
        }
    }

    fn drive_upload(&mut self, now_ms: u64) {
        let fresh = self.active.as_ref().and_then(|a| match &a.phase {
            Phase::Upload { sender, .. } => Some(self.sender(sender.begin())),
            _ => None,
        });
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let Phase::Upload { sender, bytes } = &mut a.phase else {
            return;
        };
        let out = &mut self.out;
        let mut poll = |s: &mut Sender| {
            s.poll(now_ms as u32, bytes, |m| {
                out.extend(frame(m).map(EngineOut::Frame));
                true
            })
        };
        poll(sender);
        if sender.outcome() == Some(Outcome::TimedOut) && a.attempts < MAX_ATTEMPTS {
            // Begin again: the robot answers with the bytes it holds, so this resumes.
            if let Some(fresh) = fresh {
                **sender = fresh;
            }
            a.attempts += 1;
            poll(sender);
        }
        let outcome = sender.outcome();
        let mut progress = sender.progress();
        let attempts = a.attempts;
        let robot_receiving = a.robot_receiving;
        match outcome {
            None => self.report_progress(progress),
            Some(o) => {
                let outcome = match o {
                    Outcome::Complete => JobOutcome::Complete,
                    // The robot took this job's bytes: the last chunk completed the object,
                    // but every answer saying so was lost (the id is the bytes' CRC-32C).
                    Outcome::AlreadyHave if robot_receiving => {
                        progress = (progress.1, progress.1);
                        JobOutcome::Complete
                    }
                    Outcome::AlreadyHave => JobOutcome::AlreadyHave,
                    Outcome::Rejected => JobOutcome::Failed(TransferError::Rejected),
                    Outcome::CrcMismatch => JobOutcome::Failed(TransferError::CrcMismatch),
                    Outcome::UnknownId => JobOutcome::Failed(TransferError::UnknownId),
                    Outcome::TimedOut => JobOutcome::Failed(TransferError::TimedOut { attempts }),
                    Outcome::ObjectChanged => JobOutcome::Failed(TransferError::ObjectChanged),
                    Outcome::Busy => JobOutcome::Failed(TransferError::Busy),
                };
                if outcome == JobOutcome::Complete {
                    self.report_progress(progress);
                }
                self.finish(now_ms, outcome, None);
            }
        }
    }

    fn report_progress(&mut self, (done, total): (u32, u32)) {
        let Some(a) = self.active.as_mut() else {
            return;
        };
        if a.shown != (done, total) {
            a.shown = (done, total);
            self.events.push_back(TransferEvent::Progress {
                job: a.job,
                done,
                total,
            });
        }
    }

    /// The link is back: an upload begins again (resuming), a download is asked for again.
    fn reconnected(&mut self, now_ms: u64) {
        let fresh = self.active.as_ref().and_then(|a| match &a.phase {
            Phase::Upload { sender, .. } => Some(self.sender(sender.begin())),
            _ => None,
        });
        let Some(a) = self.active.as_mut() else {
            return;
        };
        a.down_since = None;
        match &mut a.phase {
            Phase::Upload { sender, .. } => {
                if let Some(fresh) = fresh {
                    **sender = fresh;
                }
            }
            Phase::Receiving { have, .. } => {
                a.phase = Phase::Request {
                    have: *have,
                    not_before: now_ms,
                };
            }
            Phase::Request { .. } | Phase::Requested { .. } => {}
        }
    }

    /// Asks for the download again (keeping the partial bytes), or fails with `e` when the
    /// attempts are used up.
    fn retry_download(&mut self, now_ms: u64, e: TransferError) {
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let have = match &a.phase {
            Phase::Request { have, .. }
            | Phase::Requested { have, .. }
            | Phase::Receiving { have, .. } => *have,
            Phase::Upload { .. } => return,
        };
        if a.attempts >= MAX_ATTEMPTS {
            self.finish(now_ms, JobOutcome::Failed(e), None);
            return;
        }
        a.attempts += 1;
        a.phase = Phase::Request {
            have,
            not_before: now_ms,
        };
    }

    fn command_done(&mut self, now_ms: u64, id: CommandId, outcome: &CommandOutcome) {
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let Phase::Requested { cmd, have } = a.phase else {
            return;
        };
        if cmd != id {
            return;
        }
        match *outcome {
            CommandOutcome::Acked {
                info:
                    AckInfo::Object {
                        object,
                        id,
                        len,
                        crc,
                    },
                ..
            } if object == a.object => {
                a.phase = Phase::Receiving {
                    // The robot's Begin gives the tag.
                    info: TransferBegin {
                        object,
                        id,
                        len,
                        crc,
                        tag: NO_TAG,
                    },
                    have,
                    last_frame_ms: now_ms,
                };
            }
            CommandOutcome::Acked { info, .. } => {
                let e = TransferError::Unexpected(format!("{info:?}"));
                self.finish(now_ms, JobOutcome::Failed(e), None);
            }
            CommandOutcome::Nacked { reason, .. } => {
                let e = TransferError::Refused(reason);
                self.finish(now_ms, JobOutcome::Failed(e), None);
            }
            CommandOutcome::Failed(CommandFailure::NotConnected | CommandFailure::LinkLost) => {
                // The link is down or re-handshaking: ask again once it is back.
                a.phase = Phase::Request {
                    have,
                    not_before: now_ms + REQUEST_BACKOFF_MS,
                };
            }
            CommandOutcome::Failed(f @ CommandFailure::Timeout { .. }) => {
                self.retry_download(now_ms, TransferError::Request(f));
            }
            CommandOutcome::Failed(f) => {
                self.finish(now_ms, JobOutcome::Failed(TransferError::Request(f)), None);
            }
        }
    }

    fn on_begin(&mut self, now_ms: u64, b: &TransferBegin) {
        let wanted = self.active.as_ref().and_then(|a| match &a.phase {
            Phase::Receiving { info, have, .. } if (info.object, info.id) == (b.object, b.id) => {
                Some(*have)
            }
            Phase::Requested { have, .. } if a.object == b.object => Some(*have),
            _ => None,
        });
        let Some(have) = wanted else {
            // Not asked for (a late Begin of a finished or abandoned download): stop it.
            let status = if self.last_download == Some((b.id, b.crc)) {
                TransferStatus::AlreadyHave
            } else {
                TransferStatus::Rejected
            };
            let next = if status == TransferStatus::AlreadyHave {
                b.len
            } else {
                0
            };
            let ack = TransferAck {
                tag: b.tag,
                next,
                status,
                sack: 0,
            };
            self.out.push(EngineOut::Frame(TransferOut::Ack(ack)));
            return;
        };
        let limit = if b.len > MAX_DOWNLOAD_BYTES {
            0
        } else {
            b.len as usize
        };
        let held = have == Some((b.id, b.crc));
        let mut ack = self.rx.on_begin(b, limit, held);
        if ack.status == TransferStatus::Receiving {
            if ack.next > 0 && self.staging.len() != b.len as usize {
                // Bytes held without their buffer (cannot happen): start over.
                self.rx.reset();
                ack = self.rx.on_begin(b, limit, held);
            }
            if ack.next == 0 {
                self.staging = vec![0; b.len as usize];
            }
        }
        self.out.push(EngineOut::Frame(TransferOut::Ack(ack)));
        match ack.status {
            TransferStatus::AlreadyHave => {
                self.set_receiving(now_ms, *b, have);
                self.last_download = Some((b.id, b.crc));
                self.finish(now_ms, JobOutcome::AlreadyHave, None);
            }
            TransferStatus::Rejected => {
                self.set_receiving(now_ms, *b, have);
                let e = TransferError::TooLarge {
                    len: u64::from(b.len),
                    max: u64::from(MAX_DOWNLOAD_BYTES),
                };
                self.finish(now_ms, JobOutcome::Failed(e), None);
            }
            _ => {
                self.set_receiving(now_ms, *b, have);
                self.report_progress((ack.next, b.len));
            }
        }
    }

    fn set_receiving(&mut self, now_ms: u64, info: TransferBegin, have: Option<(u32, u32)>) {
        if let Some(a) = self.active.as_mut() {
            a.phase = Phase::Receiving {
                info,
                have,
                last_frame_ms: now_ms,
            };
        }
    }

    fn on_chunk(&mut self, now_ms: u64, tag: u8, offset: u32, data: &[u8]) {
        let chunk = TransferData { tag, offset, data };
        let mut got = None;
        // Every chunk is answered, ours or not: the receiver repeats a finished transfer's
        // answer and says `UnknownId` to anything else, which stops a stray sender.
        let ack = self.rx.on_chunk(&chunk, &mut self.staging, |v| {
            let ok = matches!(kind_of(v.bytes), Ok(k) if k == v.object) && parse(v.bytes).is_ok();
            if ok {
                got = Some(v.bytes.to_vec());
            }
            ok
        });
        self.out.push(EngineOut::Frame(TransferOut::Ack(ack)));
        let Some(a) = self.active.as_mut() else {
            return;
        };
        let Phase::Receiving {
            info,
            last_frame_ms,
            ..
        } = &mut a.phase
        else {
            return;
        };
        if info.tag != tag || tag == NO_TAG {
            return;
        }
        *last_frame_ms = now_ms;
        let info = *info;
        match ack.status {
            TransferStatus::Receiving => self.report_progress((ack.next, info.len)),
            TransferStatus::Complete => {
                self.report_progress((info.len, info.len));
                self.last_download = Some((info.id, info.crc));
                self.finish(now_ms, JobOutcome::Complete, got);
            }
            TransferStatus::CrcMismatch => self.retry_download(now_ms, TransferError::CrcMismatch),
            TransferStatus::Rejected => {
                self.finish(now_ms, JobOutcome::Failed(TransferError::Malformed), None);
            }
            // Answers a receiver gives, never a sender: ignored, as a robot's would be.
            TransferStatus::AlreadyHave | TransferStatus::UnknownId | TransferStatus::Busy => {}
        }
    }

    /// Ends the running job with `outcome` and reports it.
    fn finish(&mut self, now_ms: u64, outcome: JobOutcome, bytes: Option<Vec<u8>>) {
        let Some(a) = self.active.take() else {
            return;
        };
        let (id, crc, len) = match &a.phase {
            Phase::Upload { sender, .. } => {
                let b = sender.begin();
                (Some(b.id), Some(b.crc), b.len)
            }
            Phase::Receiving { info, .. } => (Some(info.id), Some(info.crc), info.len),
            Phase::Request { .. } | Phase::Requested { .. } => (None, None, 0),
        };
        let sender = match &a.phase {
            Phase::Upload { sender, .. } => Some(UploadCounts {
                stats: sender.stats(),
                first_chunk: a.first_chunk,
                last_chunk: sender.chunk(),
            }),
            _ => None,
        };
        self.events.push_back(TransferEvent::Finished(JobReport {
            job: a.job,
            direction: a.direction,
            object: a.object,
            id,
            crc,
            len,
            outcome,
            elapsed_ms: now_ms.saturating_sub(a.started_ms),
            attempts: a.attempts,
            bytes,
            sender,
        }));
    }
}

/// Bytes in a million the line loses, from the share of the robot's frames that arrived
/// damaged and their mean length: a frame of `m` bytes survives with `(1 - p)^m`. `None`
/// until a few frames have been seen.
fn byte_loss_ppm(s: &LinkStats) -> Option<u32> {
    /// Frames received undamaged before a line counts as clean: at 1 % of bytes lost, an
    /// 80-byte telemetry frame arrives whole less than half the time, so a dozen in a row
    /// (about half a second of telemetry and truth) happen about once in 10,000.
    const CLEAN_EVIDENCE_FRAMES: f64 = 12.0;
    let d = &s.decoder;
    let bad = [
        d.crc_errors,
        d.bad_cobs,
        d.too_short,
        d.oversize,
        d.bad_version,
        d.unknown_kind,
        d.undecodable,
    ]
    .iter()
    .map(|&n| f64::from(n))
    .sum::<f64>();
    let frames = f64::from(d.frames_ok) + bad;
    if frames < 4.0 || s.bytes_in == 0 {
        return None;
    }
    // No damaged frame among a few says little: a line losing 1 % of its bytes gives four
    // clean frames one time in twenty, and 224-byte chunks on it arrive one time in eleven.
    // Until enough frames came clean the sender keeps probing the line.
    if bad == 0.0 && frames < CLEAN_EVIDENCE_FRAMES {
        return None;
    }
    let mean_len = s.bytes_in as f64 / frames;
    let p = 1.0 - (1.0 - bad / frames).powf(1.0 / mean_len.max(1.0));
    Some((p * 1e6).round().clamp(0.0, 1e6) as u32)
}

fn describe(spec: &JobSpec) -> (Direction, ObjectKind) {
    match spec {
        JobSpec::Upload { object, .. } => (Direction::Upload, *object),
        JobSpec::Download { object, .. } => (Direction::Download, *object),
    }
}

#[cfg(test)]
#[path = "engine_tests.rs"]
mod tests;
