//! [`TransferClient`]: a connected link plus a [`TransferEngine`], driven by async code.
//!
//! Layer: the async edge for the headless commands (`station upload-map` and friends) and the
//! tests. It owns a `RunningLink` whose handshake is done, feeds the engine every link event,
//! polls it every [`TICK`], and hands its frames and commands to the link. The other link
//! events seen meanwhile (telemetry, truth, robot events, connection changes) are kept, the
//! last [`KEPT_EVENTS`], for [`TransferClient::wait_for`] and [`TransferClient::last_seen`]. What can fail: each job ends in a [`JobReport`] (never an
//! error); [`TransferClient::plan_on_robot`] says which step failed ([`RobotPlanError`]).

use std::collections::VecDeque;
use std::time::Duration;

use protocol::{crc32c, AckInfo, Command, EventCode, ObjectKind, PointMm};
use tokio::time::Instant;

use super::engine::{EngineOut, JobSpec, TransferEngine};
use super::{JobOutcome, JobReport, TransferError, TransferEvent};
use crate::link::api::{command_text, refusal_text};
use crate::link::{CommandOutcome, LinkEvent, RunningLink};

/// How often the engine is polled while a job runs.
pub const TICK: Duration = Duration::from_millis(10);
/// Link events kept for `wait_for`.
pub const KEPT_EVENTS: usize = 256;

/// A handshaken link with a transfer engine.
pub struct TransferClient {
    pub link: RunningLink,
    engine: TransferEngine,
    t0: Instant,
    seen: VecDeque<LinkEvent>,
}

/// Why an on-robot plan did not arrive.
#[derive(Debug, thiserror::Error)]
pub enum RobotPlanError {
    #[error("{what} refused: {text}")]
    Refused {
        what: String,
        reason: protocol::NackReason,
        /// The refusal in words, with the limit and the way forward (`refusal_text`).
        text: String,
    },
    #[error("{what} failed: {why}")]
    Failed { what: String, why: String },
    #[error("the robot acknowledged the plan but announced no PlanInstalled within 2 s")]
    NoPlanEvent,
    #[error("downloading the plan: {0}")]
    Download(TransferError),
    #[error("the downloaded plan's CRC {crc:#010x} is not the installed plan's id {id:#010x}")]
    IdMismatch { id: u32, crc: u32 },
}

impl TransferClient {
    /// Wraps a link whose handshake is done (`connected`), or not yet.
    pub fn new(link: RunningLink, connected: bool) -> Self {
        let mut engine = TransferEngine::new();
        engine.set_connected(connected);
        TransferClient {
            link,
            engine,
            t0: Instant::now(),
            seen: VecDeque::new(),
        }
    }

    fn now_ms(&self) -> u64 {
        u64::try_from(self.t0.elapsed().as_millis()).unwrap_or(u64::MAX)
    }

    fn flush(&mut self) {
        for o in self.engine.take_output() {
            match o {
                EngineOut::Frame(f) => self.link.handle.transfer(f),
                EngineOut::Command { id, command } => self.link.handle.submit_with_id(id, command),
            }
        }
    }

    fn keep(&mut self, ev: LinkEvent) {
        if matches!(ev, LinkEvent::Stats(_)) {
            return;
        }
        if self.seen.len() == KEPT_EVENTS {
            self.seen.pop_front();
        }
        self.seen.push_back(ev);
    }

    /// Reads one link event (or waits a tick), feeding the engine. False: the link task ended.
    async fn step(&mut self) -> bool {
        let now = self.now_ms();
        self.engine.poll(now);
        self.flush();
        tokio::select! {
            ev = self.link.events.recv() => match ev {
                Some(ev) => {
                    let now = self.now_ms();
                    if !self.engine.on_link_event(now, &ev) {
                        self.keep(ev);
                    }
                    self.flush();
                    true
                }
                None => false,
            },
            () = tokio::time::sleep(TICK) => true,
        }
    }

    /// Runs one job to its end; `progress(done, total)` is called as bytes are acknowledged.
    pub async fn run(&mut self, spec: JobSpec, mut progress: impl FnMut(u32, u32)) -> JobReport {
        let job = self.engine.submit(spec);
        loop {
            for ev in self.engine.take_events() {
                match ev {
                    TransferEvent::Finished(r) if r.job == job => return r,
                    TransferEvent::Progress {
                        job: j,
                        done,
                        total,
                    } if j == job => progress(done, total),
                    _ => {}
                }
            }
            if !self.step().await {
                // The link task ended: nothing more can happen.
                let now = self.now_ms();
                self.engine.cancel_all(now);
                let ended = self.engine.take_events().into_iter().find_map(|e| match e {
                    TransferEvent::Finished(r) if r.job == job => Some(r),
                    _ => None,
                });
                if let Some(mut r) = ended {
                    r.outcome = JobOutcome::Failed(TransferError::Request(
                        crate::link::CommandFailure::Shutdown,
                    ));
                    return r;
                }
            }
        }
    }

    /// Uploads `bytes` as an object of kind `object`.
    pub async fn upload(&mut self, object: ObjectKind, bytes: Vec<u8>) -> JobReport {
        self.run(JobSpec::Upload { object, bytes }, |_, _| {}).await
    }

    /// Downloads the robot's object of kind `object`.
    pub async fn download(&mut self, object: ObjectKind) -> JobReport {
        self.run(JobSpec::Download { object, have: None }, |_, _| {})
            .await
    }

    /// Sends a command and waits for its outcome, feeding the engine meanwhile.
    pub async fn command(&mut self, command: Command) -> CommandOutcome {
        let handle = self.link.handle.clone();
        let call = handle.call(command);
        tokio::pin!(call);
        loop {
            tokio::select! {
                outcome = &mut call => return outcome,
                alive = self.step() => if !alive {
                    return (&mut call).await;
                },
            }
        }
    }

    /// Waits up to `within` for a link event `pick` accepts, looking first at the events
    /// already seen (and forgetting it once found).
    pub async fn wait_for<T>(
        &mut self,
        within: Duration,
        mut pick: impl FnMut(&LinkEvent) -> Option<T>,
    ) -> Option<T> {
        let deadline = Instant::now() + within;
        loop {
            if let Some(i) = self.seen.iter().position(|e| pick(e).is_some()) {
                return self.seen.remove(i).and_then(|e| pick(&e));
            }
            if Instant::now() >= deadline || !self.step().await {
                return None;
            }
        }
    }

    /// The newest event seen that `pick` accepts (kept for the next caller).
    pub fn last_seen<T>(&self, pick: impl FnMut(&LinkEvent) -> Option<T>) -> Option<T> {
        self.seen.iter().rev().find_map(pick)
    }

    /// Forgets the events seen so far.
    pub fn clear_seen(&mut self) {
        self.seen.clear();
    }

    /// Lets `d` pass, feeding the engine and keeping the events.
    pub async fn idle(&mut self, d: Duration) {
        let deadline = Instant::now() + d;
        while Instant::now() < deadline {
            if !self.step().await {
                return;
            }
        }
    }

    /// Plans on the robot: `Segment`, then `Plan {from, to}`; waits for `PlanInstalled` and
    /// downloads the plan. Returns its id and object bytes.
    pub async fn plan_on_robot(
        &mut self,
        from: Option<PointMm>,
        to: Option<PointMm>,
    ) -> Result<(u32, Vec<u8>), RobotPlanError> {
        self.clear_seen();
        for command in [Command::Segment, Command::Plan { from, to }] {
            let what = command_text(&command);
            match self.command(command).await {
                CommandOutcome::Acked {
                    info: AckInfo::Done,
                    ..
                } => {}
                CommandOutcome::Acked { info, .. } => {
                    let why = format!("unexpected answer {info:?}");
                    return Err(RobotPlanError::Failed { what, why });
                }
                CommandOutcome::Nacked { reason, .. } => {
                    let text = refusal_text(&command, reason);
                    return Err(RobotPlanError::Refused { what, reason, text });
                }
                CommandOutcome::Failed(f) => {
                    let why = f.to_string();
                    return Err(RobotPlanError::Failed { what, why });
                }
            }
        }
        let id = self
            .wait_for(Duration::from_secs(2), |e| match e {
                LinkEvent::Robot(ev) if ev.code == EventCode::PlanInstalled => {
                    Some(ev.value as u32)
                }
                _ => None,
            })
            .await
            .ok_or(RobotPlanError::NoPlanEvent)?;
        let report = self.download(ObjectKind::Plan).await;
        let bytes = match (report.outcome, report.bytes) {
            (JobOutcome::Complete, Some(b)) => b,
            (JobOutcome::Failed(e), _) => return Err(RobotPlanError::Download(e)),
            (_, _) => return Err(RobotPlanError::Download(TransferError::Malformed)),
        };
        let crc = crc32c(&bytes);
        if crc != id {
            return Err(RobotPlanError::IdMismatch { id, crc });
        }
        Ok((id, bytes))
    }

    /// Closes the port and waits (up to a second) for the link task to end.
    pub async fn shutdown(self) {
        self.link.handle.shutdown();
        let _ = tokio::time::timeout(Duration::from_secs(1), self.link.task).await;
    }
}
