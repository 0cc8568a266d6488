//! The TUI's side of transfers: upload a file, download the robot's map (live while it
//! explores), plan on the robot and draw its plan, execute it, start exploring.
//!
//! Layer: app state, part of `App::update` (no I/O, time from `Action::Tick`). The
//! [`TransferEngine`] runs here: it sees every link event first (`App::on_link` hands them
//! over), its `Download` commands join the app's outbox under their own ids, and its frames
//! wait in [`Transfers::take_frames`] for the TUI loop to hand to the link. Keys (see
//! `input.rs` and the help): `u` opens a path prompt (a map file in any arena format, or a
//! Map or Plan object file; prefilled with the last one, or the arena shown) and uploads it
//! with a progress bar; `M` downloads the robot's map and shows it (the station's planner and
//! the grid layer then use it); `E` sends `StartExploration`; `O` sends `Segment` and `Plan`
//! (to the plan's target, `app::plan_target`); `X` sends `ExecutePlan` with
//! the installed plan's id, but only for the plan the screen names: one the robot made for
//! the target the footer shows, or one uploaded. While `O` waits for the robot's answer `X`
//! waits too, and after a refused `O` there is no plan for its target (not even one the robot
//! made for it earlier): `X` says so and sends nothing.
//!
//! Live map: while telemetry says the robot is in Explore mode, the map is downloaded every
//! [`LIVE_MAP_PERIOD_MS`] (nothing travels when its id is unchanged: the engine answers the
//! robot's `TransferBegin` with `AlreadyHave`), once more when exploring ends, and shown, so
//! the map grows on screen as the robot marks it (seed 004 §5, Fig. 5). Every `PlanInstalled`
//! event downloads the plan the same way and draws it (the robot-plan layer).
//!
//! Invariant: every job's outcome reaches the log, except the live map's repeated successes
//! (its first success and every failure are logged). Cannot fail.

use std::collections::HashMap;

use protocol::units::point_mm;
use protocol::{Command, EventCode, Mode, ObjectKind, PointMm};

use super::log::{Level, Source};
use super::plan_target::PlanTarget;
pub use super::plan_target::{PlanFor, ROBOT_MAP_NAME};
use super::App;
use crate::link::{CommandOutcome, LinkEvent, SendWhen, TransferOut};
use crate::plan::{End, MapOptions};
use crate::transfer::objects::{check_capacity, load_for_upload, plan_waypoints};
use crate::transfer::{
    object_name, EngineOut, JobId, JobOutcome, JobReport, JobSpec, Progress, TransferEngine,
    TransferEvent,
};

/// Period of map downloads while the robot explores, ms.
pub const LIVE_MAP_PERIOD_MS: u64 = 1000;
/// Longest path the prompt takes.
const PROMPT_MAX: usize = 1024;

pub use crate::action::TransferAction;

/// Why a job was started.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Purpose {
    /// A file the operator chose: its path and the object sent.
    Upload(String, Vec<u8>),
    /// The operator asked for the map.
    Map,
    /// The live map while exploring.
    LiveMap,
    /// The plan a `PlanInstalled` announced.
    Plan,
}

impl Purpose {
    /// Jobs the operator started get a progress bar; background ones do not.
    fn shown(&self) -> bool {
        !matches!(self, Purpose::LiveMap)
    }
}

/// What the TUI keeps about transfers and the robot's objects.
#[derive(Debug, Default)]
pub struct Transfers {
    pub engine: TransferEngine,
    /// The upload prompt's text while it is open.
    pub prompt: Option<String>,
    /// The prompt still holds its suggestion untouched: typing replaces it, as a selected
    /// default does in a dialog; Backspace, End or an arrow keep it for editing.
    pub prompt_suggested: bool,
    /// The file uploaded last (the prompt's next default).
    pub last_path: Option<String>,
    /// The robot's map as last shown: (id, CRC).
    pub map_have: Option<(u32, u32)>,
    /// The robot's installed plan's id, from `PlanInstalled` or an upload.
    pub plan_id: Option<u32>,
    /// Where that plan goes; `X` executes it only when it is the plan the screen names.
    pub plan_for: Option<PlanFor>,
    /// The target of the last `O`, until the robot installs its plan or refuses.
    plan_asked: Option<PlanTarget>,
    /// The target of the last `O` the robot refused (or did not answer).
    plan_refused: Option<PlanTarget>,
    /// The robot's plan as downloaded or uploaded: its id and waypoints, metres.
    pub robot_plan: Option<(u32, Vec<(f64, f64)>)>,
    purposes: HashMap<JobId, Purpose>,
    frames: Vec<TransferOut>,
    next_map_ms: u64,
    was_exploring: bool,
    /// The live map has been shown once (later successes are not logged).
    live_shown: bool,
    /// The last live-map download failed (repeats are not logged).
    live_failed: bool,
}

impl Transfers {
    /// Transfer frames for `LinkHandle::transfer`; empties the buffer.
    pub fn take_frames(&mut self) -> Vec<TransferOut> {
        std::mem::take(&mut self.frames)
    }

    /// The running job's progress, if the operator started it (for the progress bar), with
    /// what it is.
    pub fn shown_progress(&self) -> Option<(Progress, String)> {
        let p = self.engine.progress()?;
        let purpose = self.purposes.get(&p.job).filter(|p| p.shown())?;
        let what = match purpose {
            Purpose::Upload(path, _) => format!("upload {} {path}", object_name(p.object)),
            Purpose::Map | Purpose::LiveMap => "download robot map".into(),
            Purpose::Plan => "download robot plan".into(),
        };
        Some((p, what))
    }

    fn has(&self, purpose: &Purpose) -> bool {
        self.purposes.values().any(|p| p == purpose)
    }

    fn submit(&mut self, spec: JobSpec, purpose: Purpose) {
        let job = self.engine.submit(spec);
        self.purposes.insert(job, purpose);
    }
}

impl App {
    /// Applies a transfer key or prompt edit.
    pub(super) fn on_transfer_action(&mut self, a: TransferAction) {
        match a {
            TransferAction::OpenPrompt => {
                let default = self.transfers.last_path.clone().or_else(|| {
                    let m = self.map.plan.map()?;
                    (m.source != ROBOT_MAP_NAME).then(|| m.source.clone())
                });
                self.transfers.prompt_suggested = default.is_some();
                self.transfers.prompt = Some(default.unwrap_or_default());
            }
            TransferAction::PromptInput(c) => {
                let fresh = std::mem::take(&mut self.transfers.prompt_suggested);
                if let Some(p) = self.transfers.prompt.as_mut() {
                    if fresh {
                        p.clear();
                    }
                    if p.len() < PROMPT_MAX && !c.is_control() {
                        p.push(c);
                    }
                }
            }
            TransferAction::PromptBackspace => {
                self.transfers.prompt_suggested = false;
                if let Some(p) = self.transfers.prompt.as_mut() {
                    p.pop();
                }
            }
            TransferAction::PromptClear => {
                self.transfers.prompt_suggested = false;
                if let Some(p) = self.transfers.prompt.as_mut() {
                    p.clear();
                }
            }
            TransferAction::PromptKeep => self.transfers.prompt_suggested = false,
            TransferAction::PromptCancel => self.transfers.prompt = None,
            TransferAction::PromptCommit => {
                if let Some(path) = self.transfers.prompt.take() {
                    self.upload_file(path.trim());
                }
            }
            TransferAction::DownloadMap => {
                let have = self.transfers.map_have;
                let spec = JobSpec::Download {
                    object: ObjectKind::Map,
                    have,
                };
                self.transfers.submit(spec, Purpose::Map);
            }
            TransferAction::PlanOnRobot => self.plan_on_robot(),
            TransferAction::ExecutePlan => match self.executable_plan() {
                Ok(plan_id) => {
                    self.send(Command::ExecutePlan { plan_id });
                }
                Err(why) => self.note(Level::Warn, Source::Command, why),
            },
            TransferAction::StartExploration => {
                self.send(Command::StartExploration);
                self.transfers.next_map_ms = self.now_ms;
            }
        }
        self.pump_transfers();
    }

    /// The id `X` may execute: the installed plan if it is the one the screen names, else
    /// why not.
    fn executable_plan(&self) -> Result<u32, String> {
        let t = &self.transfers;
        let now = self.plan_target();
        let Some(id) = t.plan_id else {
            return Err("X: no plan on the robot yet: O plans on it, u uploads one".into());
        };
        if let Some(asked) = t.plan_asked {
            return Err(format!(
                "X: the robot is still planning to {}; X when its plan is shown",
                asked.describe()
            ));
        }
        if t.plan_refused.is_some_and(|r| r.same(&now)) {
            return Err(format!(
                "X: no plan to {}: the robot refused to plan there (see the log); O plans \
                 again, G goes back to the map's goal",
                now.describe()
            ));
        }
        match &t.plan_for {
            Some(PlanFor::Target(to)) if to.same(&now) => Ok(id),
            Some(PlanFor::Uploaded(_)) => Ok(id),
            Some(PlanFor::Target(to)) => Err(format!(
                "X: the robot's plan goes to {}, not {}; O plans to {}",
                to.describe(),
                now.describe(),
                now.describe()
            )),
            Some(PlanFor::Elsewhere) => Err(format!(
                "X: the robot's plan {id:#010x} was installed elsewhere, not shown here; O plans \
                 to {}",
                now.describe()
            )),
            None => Err(format!(
                "X: no plan to {} on the robot; O plans there",
                now.describe()
            )),
        }
    }

    /// The `O` the robot refused or left unanswered: there is no plan for its target, not
    /// even one the robot made for it before.
    pub(super) fn plan_not_made(&mut self) {
        let t = &mut self.transfers;
        if let Some(asked) = t.plan_asked.take() {
            if matches!(&t.plan_for, Some(PlanFor::Target(to)) if to.same(&asked)) {
                t.plan_for = None;
            }
            t.plan_refused = Some(asked);
        }
    }

    fn upload_file(&mut self, path: &str) {
        if path.is_empty() {
            return;
        }
        self.transfers.last_path = Some(path.to_string());
        let loaded = match load_for_upload(path, &MapOptions::default()) {
            Ok(l) => l,
            Err(e) => {
                self.note(Level::Error, Source::Command, format!("upload: {e}"));
                return;
            }
        };
        if let (Some(m), Some(peer)) = (&loaded.map, &self.peer) {
            if let Err(e) = check_capacity(m.width, m.height, m.cell_mm, peer.map_capacity) {
                self.note(
                    Level::Error,
                    Source::Command,
                    format!("upload refused: {e}"),
                );
                return;
            }
        }
        self.note(
            Level::Info,
            Source::Command,
            format!("uploading {}", loaded.summary),
        );
        let bytes = loaded.bytes;
        let spec = JobSpec::Upload {
            object: loaded.object,
            bytes: bytes.clone(),
        };
        self.transfers
            .submit(spec, Purpose::Upload(path.to_string(), bytes));
    }

    /// `Segment`, then `Plan` to the plan's target (`app::plan_target`: the cursor while
    /// shown, else the chosen target, else the robot's map's goal), saying which; the plan is
    /// downloaded when the robot announces it.
    fn plan_on_robot(&mut self) {
        let target = self.take_plan_target();
        let to = match target {
            PlanTarget::Chosen(p) => Some(p),
            // The robot plans to its own map's goal when given none.
            PlanTarget::MapGoal(_) => None,
        };
        self.note(
            Level::Info,
            Source::Command,
            format!("planning on the robot to {}", target.describe()),
        );
        // Until the robot answers, X waits for this plan rather than run an earlier one.
        self.transfers.plan_asked = Some(target);
        self.transfers.plan_refused = None;
        let to = match to.map(|p| point_mm(["goal x", "goal y"], p)).transpose() {
            Ok(to) => to,
            Err(e) => {
                self.note(Level::Warn, Source::Command, format!("not sent: {e}"));
                return;
            }
        };
        self.send(Command::Segment);
        self.send(Command::Plan { from: None, to });
    }

    /// What the station can say about a `Plan` the robot refused with `BadPoint`: the points
    /// it sent (the robot's position and the map's goal as last seen when not given) and,
    /// with the robot's map shown, which of them lies outside it or in a cell that is not
    /// free. Starts with " (" so it follows the Nack's own words.
    pub(super) fn plan_refusal_detail(&self, from: Option<PointMm>, to: Option<PointMm>) -> String {
        let m = |p: PointMm| (f64::from(p.x_mm) / 1000.0, f64::from(p.y_mm) / 1000.0);
        let robot_map = self
            .map
            .plan
            .map()
            .filter(|map| map.source == ROBOT_MAP_NAME);
        let from_m = from.map(m).or_else(|| self.pose().map(|(x, y, _)| (x, y)));
        let to_m = to
            .map(m)
            .or_else(|| robot_map.and_then(|map| map.goal).map(|g| g.centre));
        // "(x, y)" when given, else what the robot takes, with where the station believes it is.
        let say = |given: bool, what: &str, p: Option<(f64, f64)>| {
            let at = p.map(|(x, y)| format!("({x:.3}, {y:.3})"));
            match (given, at) {
                (true, Some(at)) => at,
                (false, Some(at)) => format!("{what} {at}"),
                (_, None) => what.to_string(),
            }
        };
        let mut text = format!(
            " (from {} to {}",
            say(from.is_some(), "the robot's position", from_m),
            say(to.is_some(), "the map's goal", to_m),
        );
        if let Some(map) = robot_map {
            let ends = [(End::Start, from_m), (End::Goal, to_m)];
            for (end, p) in ends.into_iter().filter_map(|(e, p)| Some((e, p?))) {
                if let Err(e) = map.check_point(end, p) {
                    text.push_str(&format!("; {e}"));
                }
            }
        }
        text.push(')');
        text
    }

    /// Called with every link event before the app looks at it; true when the event was the
    /// engine's own (a transfer frame, its commands' outcomes) and needs nothing else.
    pub(super) fn transfers_on_link(&mut self, ev: &LinkEvent) -> bool {
        let now = self.now_ms;
        let consumed = self.transfers.engine.on_link_event(now, ev);
        match ev {
            LinkEvent::Robot(e) if e.code == EventCode::PlanInstalled => {
                let id = e.value as u32;
                let t = &mut self.transfers;
                if let Some(asked) = t.plan_asked.take() {
                    t.plan_for = Some(PlanFor::Target(asked));
                } else if t.plan_id != Some(id) {
                    // Not ours (an upload names its plan when it completes, below).
                    t.plan_for = Some(PlanFor::Elsewhere);
                }
                self.transfers.plan_id = Some(id);
                let have = self
                    .transfers
                    .robot_plan
                    .as_ref()
                    .filter(|(held, _)| *held == id)
                    .map(|(held, _)| (*held, *held));
                if have.is_none() {
                    let spec = JobSpec::Download {
                        object: ObjectKind::Plan,
                        have,
                    };
                    self.transfers.submit(spec, Purpose::Plan);
                }
            }
            LinkEvent::CommandDone {
                command: Command::Plan { .. },
                outcome: CommandOutcome::Acked { .. },
                ..
            } => {
                // The robot planned: its PlanInstalled follows and brings the plan here.
                self.transfers.robot_plan = None;
            }
            _ => {}
        }
        self.pump_transfers();
        consumed
    }

    /// Runs the engine's timers and the live map (called at every tick).
    pub(super) fn transfers_tick(&mut self) {
        let now = self.now_ms;
        let exploring = self.connected()
            && self
                .telemetry
                .as_ref()
                .is_some_and(|t| t.mode == Mode::Explore);
        let connected = self.connected();
        let t = &mut self.transfers;
        let ended = t.was_exploring && !exploring && connected;
        if (exploring && now >= t.next_map_ms || ended) && !t.has(&Purpose::LiveMap) {
            t.next_map_ms = now + LIVE_MAP_PERIOD_MS;
            let spec = JobSpec::Download {
                object: ObjectKind::Map,
                have: t.map_have,
            };
            t.submit(spec, Purpose::LiveMap);
        }
        t.was_exploring = exploring;
        t.engine.poll(now);
        self.pump_transfers();
    }

    /// Moves the engine's output to the outboxes and acts on its reports.
    fn pump_transfers(&mut self) {
        for o in self.transfers.engine.take_output() {
            match o {
                EngineOut::Frame(f) => self.transfers.frames.push(f),
                EngineOut::Command { id, command } => {
                    self.outbox.push((id, command, SendWhen::Now))
                }
            }
        }
        for ev in self.transfers.engine.take_events() {
            if let TransferEvent::Finished(r) = ev {
                let purpose = self.transfers.purposes.remove(&r.job);
                self.on_job_finished(r, purpose);
            }
        }
    }

    fn on_job_finished(&mut self, r: JobReport, purpose: Option<Purpose>) {
        let live = purpose == Some(Purpose::LiveMap);
        if let JobOutcome::Failed(_) = r.outcome {
            if !(live && self.transfers.live_failed) {
                self.note(Level::Error, Source::Command, r.text());
            }
            self.transfers.live_failed |= live;
            return;
        }
        if live {
            self.transfers.live_failed = false;
        }
        let held = r.id.zip(r.crc);
        let bytes = match (&r.outcome, &r.bytes, &purpose) {
            (JobOutcome::Complete, Some(b), _) => Some(b.clone()),
            _ => None,
        };
        match (r.direction, r.object) {
            (crate::transfer::Direction::Download, ObjectKind::Map) => {
                if let Some(b) = bytes {
                    self.show_robot_map(&b, held, live);
                } else if !live {
                    self.note(Level::Info, Source::Command, r.text());
                }
            }
            (crate::transfer::Direction::Download, ObjectKind::Plan) => {
                if let Some(b) = bytes {
                    self.set_robot_plan(r.id, &b);
                }
            }
            (crate::transfer::Direction::Upload, object) => {
                self.note(Level::Info, Source::Command, r.text());
                if let Some(Purpose::Upload(path, bytes)) = &purpose {
                    self.after_upload(path, object, r.id, bytes);
                }
            }
            (crate::transfer::Direction::Download, ObjectKind::LightCalibration) => {
                self.note(Level::Info, Source::Command, r.text());
            }
            (_, ObjectKind::Regions) => {}
        }
    }

    /// The robot holds what was uploaded: show it as the robot's.
    fn after_upload(&mut self, path: &str, object: ObjectKind, id: Option<u32>, bytes: &[u8]) {
        let held = id.map(|i| (i, i));
        match object {
            ObjectKind::Map => self.show_robot_map(bytes, held, true),
            ObjectKind::Plan => {
                self.transfers.plan_id = id;
                self.transfers.plan_for = Some(PlanFor::Uploaded(path.to_string()));
                self.transfers.plan_asked = None;
                self.set_robot_plan(id, bytes);
            }
            ObjectKind::Regions | ObjectKind::LightCalibration => {}
        }
    }

    fn show_robot_map(&mut self, bytes: &[u8], held: Option<(u32, u32)>, quiet: bool) {
        match self.map.plan.show_map_object(ROBOT_MAP_NAME, bytes) {
            Ok(()) => {
                self.transfers.map_have = held;
                let first = !self.transfers.live_shown;
                self.transfers.live_shown = true;
                if !quiet || first {
                    let counts = self.map.plan.map().map(|m| m.counts());
                    let (f, o, u) = counts.unwrap_or_default();
                    self.note(
                        Level::Info,
                        Source::Command,
                        format!(
                            "showing the robot's map: {f} free, {o} obstacle, {u} unknown cells"
                        ),
                    );
                }
            }
            Err(e) => self.note(Level::Error, Source::Command, format!("robot map: {e}")),
        }
    }

    fn set_robot_plan(&mut self, id: Option<u32>, bytes: &[u8]) {
        match plan_waypoints(bytes) {
            Ok(points) => {
                let id = id.unwrap_or_else(|| protocol::crc32c(bytes));
                let length: f64 = crate::plan::solve::length(&points);
                // A plan with no regions comes from the robot's grid planner, which it uses
                // when the map has more squares than it holds (robot-firmware nav::fixed).
                let grid =
                    protocol::object::PlanView::parse(bytes).is_ok_and(|v| v.nav.regions == 0);
                let how = if grid {
                    " by the grid planner (more squares than the robot holds)"
                } else {
                    ""
                };
                self.note(
                    Level::Info,
                    Source::Command,
                    format!(
                        "robot plan {id:#010x}{how}: {} waypoints, {length:.2} m; X executes it",
                        points.len()
                    ),
                );
                self.transfers.robot_plan = Some((id, points));
            }
            Err(e) => self.note(Level::Error, Source::Command, format!("robot plan: {e}")),
        }
    }
}
