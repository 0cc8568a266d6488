//! What the link reports, into the state: connections, telemetry, the robot's events, and
//! the outcome of every command sent (`Pending`).

use protocol::{AckInfo, Command, Event, EventCode, Mode, Telemetry};

use super::log::{Level, Source};
use super::{groups, params, pose_m, App, Teleop, STATS_HISTORY};
use crate::link::api::{command_text, refusal_text};
use crate::link::{CommandFailure, CommandId, CommandOutcome, Connection, LinkEvent};

impl App {
    pub(super) fn on_link(&mut self, ev: LinkEvent) {
        if self.transfers_on_link(&ev) {
            return;
        }
        match ev {
            LinkEvent::Connection(c) => self.on_connection(c),
            LinkEvent::Telemetry(t) => self.on_telemetry(t),
            LinkEvent::Truth(t) => {
                let (x, y, _) = pose_m(&t.pose);
                self.true_track.push(x, y);
                self.localization.on_truth(&t);
                self.truth = Some(t);
            }
            LinkEvent::Localization(l) => self.localization.on_message(*l),
            LinkEvent::Progress(p) => self.on_progress(p),
            LinkEvent::Situation(s) => self.qt.on_situation(&s),
            LinkEvent::Robot(e) => self.on_robot_event(e),
            LinkEvent::Log { level, text } => self.note(level.into(), Source::Robot, text),
            LinkEvent::CommandDone {
                id,
                command,
                outcome,
            } => self.on_done(id, command, outcome),
            LinkEvent::Transfer(_) => {}
            LinkEvent::Stats(s) => {
                if self.rx_rate_history.len() == STATS_HISTORY {
                    self.rx_rate_history.remove(0);
                }
                self.rx_rate_history.push(s.bytes_in_per_s.round() as u64);
                self.stats = Some(*s);
            }
        }
    }

    pub(super) fn on_connection(&mut self, c: Connection) {
        let (level, text) = match &c {
            Connection::Closed { reason } => (Level::Warn, format!("link closed: {reason}")),
            Connection::Handshaking { port } => (Level::Info, format!("handshaking on {port}")),
            Connection::Connected(p) => (
                Level::Info,
                format!(
                    "connected: {} {} ({:?}), telemetry {} Hz",
                    p.firmware, p.firmware_version, p.profile, p.telemetry_hz
                ),
            ),
            Connection::Refused { message } => (Level::Error, format!("refused: {message}")),
        };
        self.note(level, Source::Link, text);
        let connected = matches!(c, Connection::Connected(_));
        // A report from another session (or a lost one) says nothing about now.
        self.progress = None;
        if let Connection::Connected(p) = &c {
            self.rate_hz = Some(p.telemetry_hz);
            self.peer = Some(p.clone());
        } else if self.teleop.driving {
            // Never resume motion by itself after a reconnect.
            self.teleop = Teleop::default();
            self.note(
                Level::Warn,
                Source::Command,
                "teleop stopped: link lost".into(),
            );
        }
        self.connection = c;
        // A new session starts from the robot's values, not from "?" until `R` (issue 16);
        // a replay has no robot to ask (its recorded replies fill the editor).
        if connected && !self.replaying {
            self.fetch_params();
            // A robot that restarted has its trace off again.
            if self.hal_trace_before.is_some() {
                self.hal_trace_on();
            }
        }
    }

    pub(super) fn on_telemetry(&mut self, t: Telemetry) {
        let (x, y, _) = pose_m(&t.pose);
        self.believed.push(x, y);
        self.encoders.push(t.wheels.encoders);
        self.forage.on_telemetry(&t);
        self.history.push(self.now_ms as f64 / 1000.0, t);
        self.telemetry = Some(t);
        self.telemetry_ms = Some(self.now_ms);
    }

    pub(super) fn on_robot_event(&mut self, e: Event) {
        let at = self
            .true_pose()
            .or_else(|| self.pose())
            .map(|(x, y, _)| (x, y));
        let site = self.map.arena.as_ref().and_then(|a| a.forage.as_ref());
        self.forage.on_event(&e, at, site);
        let v = e.value;
        // A correction in a survey completes the line crossing before it (floor-grid line
        // correction); elsewhere (foraging's landmarks) it stands alone.
        let surveying = self.telemetry.is_some_and(|t| t.mode == Mode::Survey);
        let group = match e.code {
            EventCode::BeaconCalibration => Some(groups::BEACON),
            EventCode::LightBearing => Some(groups::LIGHT_BEARING),
            EventCode::MapUpdated => Some(groups::MAP_UPDATED),
            EventCode::Collision => Some(groups::COLLISION),
            EventCode::LineCrossed => Some(groups::FLOOR_LINES),
            EventCode::PoseCorrected if surveying && self.lines_crossed.is_some() => {
                Some(groups::FLOOR_LINES.amends())
            }
            _ => None,
        };
        // The event in the station's words (`format::event_text`), saying more where the app
        // knows more.
        let (level, text) = match e.code {
            EventCode::GoalReached => (Level::Info, self.arrival_text()),
            EventCode::NoProgress => (Level::Warn, self.no_progress_text(v)),
            EventCode::PoseCorrected => match self.lines_crossed.filter(|_| surveying) {
                Some(n) => (
                    Level::Info,
                    format!("floor line {n} crossed, pose corrected by {v} mm"),
                ),
                None => event_words(&e),
            },
            EventCode::LineCrossed => {
                self.lines_crossed = Some(v);
                event_words(&e)
            }
            EventCode::ParamChanged => {
                let id = u16::try_from(v).unwrap_or(u16::MAX);
                // Changed by whoever (this editor, the rate keys, another station): read the
                // value in force so the editor and the header show it.
                if !self.replaying && robot_firmware::params::info(id).is_some() {
                    self.read_param_quietly(id);
                }
                event_words(&e)
            }
            _ => event_words(&e),
        };
        // A task that ended (or a mode that changed) takes its progress with it: the status
        // line shows what the robot reports now, not the last report of a task that is over.
        if matches!(
            e.code,
            EventCode::ModeChanged
                | EventCode::GoalReached
                | EventCode::PlanFinished
                | EventCode::PlanAborted
                | EventCode::NoProgress
        ) {
            self.progress = None;
        }
        self.note_grouped(level, Source::Event, text, group);
    }

    pub(super) fn on_done(&mut self, id: CommandId, command: Command, outcome: CommandOutcome) {
        let pending = self.pending.remove(&id);
        let before = pending.and_then(|p| p.before);
        let quiet = pending.is_some_and(|p| p.quiet) && matches!(command, Command::GetParam { .. });
        if self.rate_asked.is_some_and(|(asked, _)| asked == id) {
            self.rate_asked = None;
        }
        let what = command_text(&command);
        match outcome {
            CommandOutcome::Acked { info, rtt_ms, .. } => {
                match (command, info) {
                    (_, AckInfo::Param { id, value }) => {
                        self.params.set_value(id.0, value);
                        // One value, two places: the header's rate is this parameter.
                        if id.0 == robot_firmware::params::id::TELEMETRY_HZ {
                            self.rate_hz = Some(value as u8);
                        }
                    }
                    (Command::SetTelemetryRate { hz }, _) => {
                        self.rate_hz = Some(hz);
                        self.params
                            .set_value(robot_firmware::params::id::TELEMETRY_HZ, f32::from(hz));
                    }
                    _ => {}
                }
                if quiet {
                    self.fetch_done(true);
                    return;
                }
                // Teleop is acked ten times a second: only its failures are news.
                if !matches!(command, Command::Teleop { .. }) {
                    let detail = match info {
                        AckInfo::Param { id, value } => {
                            format!(" = {}", params::format_param_id(id.0, value))
                        }
                        _ => String::new(),
                    };
                    // A burst of reads (`R`) is one summary line.
                    let group =
                        matches!(command, Command::GetParam { .. }).then_some(groups::PARAM_READ);
                    self.note_grouped(
                        Level::Info,
                        Source::Command,
                        format!("ok: {what}{detail} ({rtt_ms} ms)"),
                        group,
                    );
                }
            }
            CommandOutcome::Nacked { reason, .. } => {
                if matches!(command, Command::Segment | Command::Plan { .. }) {
                    self.plan_not_made();
                }
                if let Command::SetParam { id, .. } | Command::GetParam { id } = command {
                    if reason == protocol::NackReason::Unsupported {
                        self.params.set_absent(id.0);
                    } else {
                        self.params.set_refused(id.0, reason, before);
                    }
                }
                if quiet {
                    self.fetch_done(false);
                    return;
                }
                if matches!(command, Command::Teleop { .. }) {
                    self.teleop = Teleop::default();
                }
                let detail = match command {
                    Command::Plan { from, to } if reason == protocol::NackReason::BadPoint => {
                        self.plan_refusal_detail(from, to)
                    }
                    Command::Segment | Command::Plan { .. }
                        if reason == protocol::NackReason::CapacityExceeded =>
                    {
                        self.squares_detail()
                    }
                    Command::GoTo(_) if reason == protocol::NackReason::BadPoint => {
                        self.arena_bounds_detail()
                    }
                    // These modes need a target the mode key cannot give: say which key can.
                    Command::SetMode(Mode::GoTo) => {
                        " (press g and pick a point, or click the map)".into()
                    }
                    Command::SetMode(Mode::ExecutePlan) => {
                        " (O plans on the robot, X executes its plan)".into()
                    }
                    _ => String::new(),
                };
                self.note(
                    Level::Error,
                    Source::Command,
                    format!(
                        "refused: {what}: {}{detail}",
                        refusal_text(&command, reason)
                    ),
                );
            }
            // Normal for teleop (ten a second): logged, as every failure is, but as detail.
            CommandOutcome::Failed(why @ CommandFailure::Superseded) => self.note_grouped(
                Level::Debug,
                Source::Command,
                format!("not sent: {what}: {why}"),
                Some(groups::SUPERSEDED),
            ),
            CommandOutcome::Failed(why) => {
                if matches!(command, Command::Segment | Command::Plan { .. }) {
                    self.plan_not_made();
                }
                if let Command::SetParam { id, .. } | Command::GetParam { id } = command {
                    self.params.set_failed(id.0, why.to_string());
                }
                if quiet {
                    self.fetch_done(false);
                    return;
                }
                self.note(
                    Level::Error,
                    Source::Command,
                    format!("failed: {what}: {why}"),
                );
            }
        }
    }

    /// One quiet parameter read ended; the last of a fetch logs the fetch's outcome.
    pub(super) fn fetch_done(&mut self, ok: bool) {
        if let Some((read, missed)) = self.params.fetch_step(ok) {
            let (level, text) = if missed == 0 {
                (Level::Info, format!("parameters read: {read}"))
            } else {
                (
                    Level::Warn,
                    format!("parameters read: {read}, {missed} not (see the editor, p)"),
                )
            };
            self.note(level, Source::Command, text);
        }
    }
}

/// An event as `format::event_text` says it, at the log's level.
fn event_words(e: &Event) -> (Level, String) {
    let (level, text) = station_core::format::event_text(e);
    (level.into(), text)
}
