//! The station's state and the one function that changes it, `App::update`.
//!
//! Layer: pure state machine of the UI (ratatui templates' `update`, gitui's components without
//! their I/O). It never touches the terminal or the port: commands it wants sent go into an
//! outbox (`take_outbox`) that the TUI loop hands to the link task, and time arrives in
//! `Action::Tick`. Rendering borrows it immutably (`ui::render`). Invariants: teleop repeats
//! only while driving and only in a connected session (a reconnect never restarts motion by
//! itself); every command sent is remembered until its `CommandDone` arrives, so its outcome
//! (with the robot's Nack reason) reaches the log and the parameter editor. Cannot fail.

pub use station_core::arena;
pub use station_core::format::{mode_from_index, mode_name, mode_name_i32, MODES};
pub mod fleet;
pub mod forage;
pub mod history;
pub mod layout;
pub mod localization;
pub mod log;
pub mod params;
pub mod plan_target;
pub use station_core::qt_state;
pub mod transfers;
pub mod view;

pub use view::View;

use std::collections::HashMap;

use protocol::units::point_mm;
use protocol::{AckInfo, Command, EmuTruth, Event, EventCode, Mode, Telemetry};

use crate::action::Action;
use crate::link::api::{command_text, refusal_text};
use crate::link::{
    CommandFailure, CommandId, CommandOutcome, Connection, LinkEvent, LinkStats, PeerInfo, SendWhen,
};
use crate::record::StationLine;
use arena::ArenaOverlay;
use history::{EncoderUnwrap, History, Track};
use log::{Group, Level, LogBuffer, LogLine, Source};
use params::ParamEditor;

/// Teleop repeat period while driving (PROTOCOL.md §7: 10 Hz).
pub const TELEOP_PERIOD_MS: u64 = 100;
/// A tick this much before the period is up repeats teleop already: the TUI ticks every
/// 32 ms (`pace::SLOT`), so the repeat comes after 96 ms rather than 128.
pub const TELEOP_SLACK_MS: u64 = 20;
/// One arrow press changes the forward speed by this much, mm/s.
pub const V_STEP: i16 = 50;
/// One arrow press changes the turn rate by this much, mrad/s.
pub const W_STEP: i16 = 250;
/// Teleop limits the keys reach (the firmware clamps to its `teleop_max_mm_s` too).
pub const V_MAX: i16 = 500;
pub const W_MAX: i16 = 3000;
/// Telemetry rates `+`/`-` step through, Hz.
pub const RATES: [u8; 7] = [0, 1, 2, 5, 10, 20, 50];
/// Link statistics snapshots kept for the link panel's sparkline.
const STATS_HISTORY: usize = 120;
/// Telemetry older than this many periods is stale (the header and sensors say so).
const STALE_PERIODS: u64 = 3;
/// ... and at least this old, ms (a slow rate is not stale between two frames).
const STALE_MIN_MS: u64 = 1000;
/// Most station lines held for the recording between two drains of the loop (it drains
/// after every wake-up; this only bounds an app whose loop never does).
const STATION_LINES_HELD: usize = 1024;

/// Log groups: repeats of each are one line with a count (`app::log`).
mod groups {
    use super::Group;
    pub const BEACON: Group = Group::new("beacon calibration");
    pub const LIGHT_BEARING: Group = Group::new("light bearing");
    pub const MAP_UPDATED: Group = Group::new("map updated");
    pub const COLLISION: Group = Group::new("collision");
    /// A line crossed and the pose correction it brings: one line per survey.
    pub const FLOOR_LINES: Group = Group::new("floor lines");
    /// `R` (and any burst of reads): one summary line.
    pub const PARAM_READ: Group = Group::new("param read").summary("parameters read");
    pub const SUPERSEDED: Group = Group::new("superseded");
}

/// Keyboard teleop state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Teleop {
    pub v_mm_s: i16,
    pub w_mrad_s: i16,
    /// Teleop repeats at 10 Hz while true.
    pub driving: bool,
    last_sent_ms: Option<u64>,
}

/// The map's interactive state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapState {
    pub arena: Option<ArenaOverlay>,
    /// The go-to cursor, metres; shown while `cursor_mode`.
    pub cursor: (f64, f64),
    pub cursor_mode: bool,
    /// The last go-to goal sent (drawn `×`; `Esc` clears it).
    pub goal: Option<(f64, f64)>,
    /// The target the operator chose for plans (`O`/`P` with the cursor shown); `None`: the
    /// map's goal (`app::plan_target`).
    pub plan_target: Option<(f64, f64)>,
    /// Names of hidden layers.
    pub hidden: Vec<&'static str>,
    /// Planning on the station: the map's grid and regions, the last plan.
    pub plan: crate::plan::PlanState,
    /// The view follows the robot (`F`): its centre is the robot, `pan` an offset from it.
    pub follow: bool,
    /// See `zoom()`; 0 (the default) is 1.
    zoom: f64,
    /// See `pan()`.
    pan: (f64, f64),
}

impl MapState {
    pub fn visible(&self, layer: &str) -> bool {
        !self.hidden.contains(&layer)
    }

    /// Magnification over the whole arena (1: all of it).
    pub fn zoom(&self) -> f64 {
        self.zoom.clamp(1.0, MAX_ZOOM)
    }

    /// The view's centre, as fractions of the whole arena's span from its centre.
    pub fn pan(&self) -> (f64, f64) {
        self.pan
    }

    /// Zooms by `factor` keeping the point `at` where it is on screen (`at`: fractions of the
    /// shown span from the view's centre, x right, y up; (0, 0) zooms about the centre).
    /// Zooming out to the whole arena recentres it.
    pub fn zoom_by(&mut self, factor: f64, at: (f64, f64)) {
        let z = self.zoom();
        let z2 = (z * factor).clamp(1.0, MAX_ZOOM);
        if !z2.is_finite() || z2 <= 1.0 {
            self.zoom = 1.0;
            self.pan = (0.0, 0.0);
            return;
        }
        // The point under `at` is centre + at / z (arena spans); it stays put at zoom z2.
        let k = 1.0 / z - 1.0 / z2;
        self.zoom = z2;
        self.set_pan(self.pan.0 + at.0 * k, self.pan.1 + at.1 * k);
    }

    /// Moves the view by `dx`, `dy` steps of a quarter of what is shown (x right, y up).
    pub fn pan_by(&mut self, dx: i8, dy: i8) {
        let step = PAN_STEP / self.zoom();
        self.set_pan(
            self.pan.0 + f64::from(dx) * step,
            self.pan.1 + f64::from(dy) * step,
        );
    }

    /// Starts following the robot (zoomed in at least to `FOLLOW_ZOOM`: at the whole arena
    /// there is nothing to recentre), or stops, leaving the view at `keep` (the pan that shows
    /// what is shown now), so that it does not jump.
    pub fn toggle_follow(&mut self, keep: (f64, f64)) {
        if self.follow {
            self.follow = false;
            self.set_pan(keep.0, keep.1);
        } else {
            self.follow = true;
            self.pan = (0.0, 0.0);
            self.zoom = self.zoom().max(FOLLOW_ZOOM);
        }
    }

    fn set_pan(&mut self, x: f64, y: f64) {
        // The centre stays over the arena: the view never wanders off into nothing.
        self.pan = (x.clamp(-0.5, 0.5), y.clamp(-0.5, 0.5));
    }
}

/// Largest map magnification.
pub const MAX_ZOOM: f64 = 64.0;
/// One pan step, as a fraction of the shown span.
pub const PAN_STEP: f64 = 0.25;
/// One zoom step (a key press or a wheel notch).
pub const ZOOM_STEP: f64 = 1.5;
/// The least magnification while following the robot: two zoom steps.
pub const FOLLOW_ZOOM: f64 = ZOOM_STEP * ZOOM_STEP;

/// How the app starts.
#[derive(Clone, Debug, Default)]
pub struct AppOptions {
    /// What the header says the link is ("/dev/ttyUSB0", "built-in emulator on /dev/pts/3").
    pub port_label: String,
    pub arena: Option<ArenaOverlay>,
    /// A click on the map sends the robot at once (`--click-goes`) instead of placing the
    /// go-to cursor for `Enter` to confirm.
    pub click_goes: bool,
    /// While recording (`R`), the robot streams its hardware trace: hal_trace is set to 1 when
    /// the recording starts and put back when it ends (`--record-hal-trace`).
    pub record_hal_trace: bool,
}

/// The station's whole UI state.
#[derive(Debug)]
pub struct App {
    pub now_ms: u64,
    /// Driven by `station replay`: what happened is shown, nothing is sent, and no hint
    /// offers to send anything.
    pub replaying: bool,
    pub size: (u16, u16),
    pub view: View,
    pub help: bool,
    /// The help's first line shown (`Action::HelpScroll`).
    pub help_scroll: u16,
    pub quit: bool,
    pub port_label: String,
    /// See `AppOptions::click_goes`.
    pub click_goes: bool,
    pub connection: Connection,
    pub peer: Option<PeerInfo>,
    pub telemetry: Option<Telemetry>,
    /// Station time the last telemetry arrived, ms.
    pub telemetry_ms: Option<u64>,
    pub truth: Option<EmuTruth>,
    pub stats: Option<LinkStats>,
    /// Bytes/s received, one sample per statistics snapshot.
    pub rx_rate_history: Vec<u64>,
    pub history: History,
    pub believed: Track,
    pub true_track: Track,
    pub encoders: EncoderUnwrap,
    pub log: LogBuffer,
    /// The retraced track (`station replay --retrace`), if any.
    pub retrace: Option<std::sync::Arc<crate::retrace::overlay::RetraceOverlay>>,
    pub teleop: Teleop,
    pub map: MapState,
    pub params: ParamEditor,
    /// The telemetry rate the robot confirmed last, Hz.
    pub rate_hz: Option<u8>,
    /// Index into `CHART_PRESETS`.
    pub chart: usize,
    /// The recording in progress (`R`): file name and station time it started.
    pub recording: Option<(String, u64)>,
    /// See `AppOptions::record_hal_trace`.
    pub record_hal_trace: bool,
    /// While recording with the hardware trace on: the hal_trace value to put back after.
    hal_trace_before: Option<f32>,
    /// While recording, the lines the station logged (not the robot's: its log lines are in
    /// its frames) waiting for the loop to record them (`take_station_lines`).
    station_lines: Vec<StationLine>,
    /// Map and plan transfers, the robot's objects, the upload prompt (`app::transfers`).
    pub transfers: transfers::Transfers,
    /// Floor-grid line correction (seed 003): tracks, line events, PPD, errors.
    pub localization: localization::LocalizationState,
    /// The QT world model (seed 001), fed by the robot's situations.
    pub qt: qt_state::QtState,
    /// Foraging (seed 000 §7): objects gripped and delivered, which were taken.
    pub forage: forage::ForageProgress,
    /// The robot's last `Progress` report: what its mode is doing.
    pub progress: Option<protocol::Progress>,
    /// The fleet this robot is the selected one of (`app::fleet`); `None`: one robot.
    pub fleet: Option<fleet::FleetOverlay>,
    next_id: CommandId,
    pending: HashMap<CommandId, Pending>,
    /// The last telemetry rate asked for and not yet answered: quick `+`/`-` presses step on
    /// from it, not from the rate the robot last acknowledged.
    rate_asked: Option<(CommandId, u8)>,
    /// The last floor line the robot reported crossing (its count), for the correction after.
    lines_crossed: Option<i32>,
    /// Commands to send, each with when it may go: a teleop repeat may wait for a quiet line.
    outbox: Vec<(CommandId, Command, SendWhen)>,
}

/// What the app remembers about a command until its outcome.
#[derive(Clone, Copy, Debug)]
struct Pending {
    /// The parameter's value before a `SetParam`, to show beside a refusal.
    before: Option<f32>,
    /// Part of a parameter fetch (on connect, `R`, a `ParamChanged`): the editor shows the
    /// outcome, and the log gets one line for the whole fetch, not one per parameter.
    quiet: bool,
}

impl App {
    pub fn new(opts: AppOptions) -> Self {
        let warnings = opts
            .arena
            .as_ref()
            .map(|a| a.warnings.clone())
            .unwrap_or_default();
        let mut app = App {
            now_ms: 0,
            replaying: false,
            size: (80, 24),
            view: View::Dashboard,
            help: false,
            help_scroll: 0,
            quit: false,
            port_label: opts.port_label,
            click_goes: opts.click_goes,
            connection: Connection::Closed {
                reason: "starting".into(),
            },
            peer: None,
            telemetry: None,
            telemetry_ms: None,
            truth: None,
            stats: None,
            rx_rate_history: Vec::new(),
            history: History::default(),
            believed: Track::default(),
            true_track: Track::default(),
            encoders: EncoderUnwrap::default(),
            log: LogBuffer::default(),
            retrace: None,
            teleop: Teleop::default(),
            map: MapState {
                arena: opts.arena,
                ..MapState::default()
            },
            params: ParamEditor::default(),
            rate_hz: None,
            chart: 0,
            recording: None,
            record_hal_trace: opts.record_hal_trace,
            hal_trace_before: None,
            station_lines: Vec::new(),
            transfers: transfers::Transfers::default(),
            localization: localization::LocalizationState::default(),
            qt: qt_state::QtState::default(),
            forage: forage::ForageProgress::default(),
            progress: None,
            fleet: None,
            next_id: 1,
            pending: HashMap::new(),
            rate_asked: None,
            lines_crossed: None,
            outbox: Vec::new(),
        };
        // An importer's warning is never silent: the file may not be what the user thinks.
        for w in warnings {
            app.note(Level::Warn, Source::Arena, w);
        }
        app
    }

    /// Commands to send, with the ids their outcomes will carry; empties the outbox.
    pub fn take_outbox(&mut self) -> Vec<(CommandId, Command)> {
        self.take_outbox_timed()
            .into_iter()
            .map(|(id, c, _)| (id, c))
            .collect()
    }

    /// `take_outbox`, with when each command should go: a teleop repeat's moment within its
    /// period does not matter, so it may wait for a quiet line; everything the operator asked
    /// for now (a key press included) goes at once.
    pub fn take_outbox_timed(&mut self) -> Vec<(CommandId, Command, SendWhen)> {
        std::mem::take(&mut self.outbox)
    }

    /// The lines the station logged since the last call, while recording: the recording keeps
    /// them (`record::RecordKind::StationLog`).
    pub fn take_station_lines(&mut self) -> Vec<StationLine> {
        std::mem::take(&mut self.station_lines)
    }

    pub fn connected(&self) -> bool {
        matches!(self.connection, Connection::Connected(_))
    }

    /// The robot's capability bits, once it said them.
    pub fn capabilities(&self) -> Option<u32> {
        self.peer.as_ref().map(|p| p.capabilities)
    }

    /// The chart shown: the chosen one, or the next the robot has sensors for.
    pub fn chart_shown(&self) -> usize {
        history::offered_preset(self.chart, self.capabilities())
    }

    /// The robot's believed pose, metres and radians.
    pub fn pose(&self) -> Option<(f64, f64, f64)> {
        self.telemetry.map(|t| pose_m(&t.pose))
    }

    /// The true pose from the emulator, metres and radians.
    pub fn true_pose(&self) -> Option<(f64, f64, f64)> {
        self.truth.map(|t| pose_m(&t.pose))
    }

    /// Applies one action.
    pub fn update(&mut self, action: Action) {
        match action {
            Action::Tick { now_ms } => self.tick(now_ms),
            Action::Resize { width, height } => self.size = (width, height),
            Action::Link(ev) => self.on_link(ev),
            Action::Quit => {
                if self.teleop.driving {
                    self.stop_driving();
                }
                self.quit = true;
            }
            Action::ToggleHelp => {
                self.help = !self.help;
                self.help_scroll = 0;
            }
            Action::HelpScroll(line) => self.help_scroll = line,
            Action::Back => self.back(),
            Action::NextView => self.step_view(1),
            Action::PrevView => self.step_view(-1),
            Action::ShowView(v) => self.view = v,
            Action::Drive { dv, dw } => self.drive(dv, dw),
            Action::StopDriving => self.stop_driving(),
            Action::SetMode(m) => {
                self.teleop.driving = false;
                self.send(Command::SetMode(m));
            }
            Action::GoToCursorStart => {
                if !matches!(self.view, View::Dashboard | View::Map) {
                    self.view = View::Map;
                }
                if let Some((x, y, _)) = self.pose() {
                    self.map.cursor = (x, y);
                }
                self.map.cursor_mode = true;
            }
            Action::MoveCursor { dx, dy } => {
                self.map.cursor.0 += dx;
                self.map.cursor.1 += dy;
            }
            Action::GoToCursor => {
                let (x, y) = self.map.cursor;
                self.map.cursor_mode = false;
                self.go_to(x, y);
            }
            Action::GoToPoint { x_m, y_m } => {
                self.map.cursor = (x_m, y_m);
                self.map.cursor_mode = false;
                self.go_to(x_m, y_m);
            }
            Action::CursorAt { x_m, y_m } => {
                self.map.cursor = (x_m, y_m);
                self.map.cursor_mode = true;
            }
            Action::ParamSelect(d) => self.params.select(d),
            Action::ParamRead => {
                if let Some(p) = self.params.selected_info() {
                    self.read_param(p.id);
                }
            }
            Action::ParamReadAll => self.fetch_params(),
            Action::ParamEdit => {
                if self.params.selected_info().is_some() {
                    self.params.searching = false;
                    self.params.input = Some(String::new());
                    self.params.input_error = None;
                }
            }
            Action::ParamSearchStart => self.params.searching = true,
            Action::ParamSearchInput(c) => {
                let mut text = self.params.search.clone();
                if text.chars().count() < log::FILTER_MAX && !c.is_control() {
                    text.push(c);
                }
                self.params.set_search(text);
            }
            Action::ParamSearchBackspace => {
                let mut text = self.params.search.clone();
                text.pop();
                self.params.set_search(text);
            }
            Action::ParamSearchDone => self.params.searching = false,
            Action::ParamInput(c) => {
                self.params.input_error = None;
                if let Some(s) = &mut self.params.input {
                    if s.len() < 24 {
                        s.push(c);
                    }
                }
            }
            Action::ParamBackspace => {
                self.params.input_error = None;
                if let Some(s) = &mut self.params.input {
                    s.pop();
                }
            }
            Action::ParamCommit => self.commit_param(),
            Action::RateStep(d) => self.step_rate(d),
            Action::ChartNext => {
                self.chart = history::offered_preset(self.chart_shown() + 1, self.capabilities());
            }
            Action::LogScroll(d) => {
                let rows = self.log_rows();
                self.log.scroll_by(d, rows);
            }
            Action::LogFollow => self.log.follow(),
            Action::LogTop => {
                let rows = self.log_rows();
                self.log.to_top(rows);
            }
            Action::LogLevelCycle => self.log.cycle_level(),
            Action::LogFilterStart => {
                self.log.filter_input = Some(self.log.filter.text.clone());
            }
            Action::LogFilterInput(c) => {
                if let Some(s) = &mut self.log.filter_input {
                    if s.chars().count() < log::FILTER_MAX && !c.is_control() {
                        s.push(c);
                    }
                }
            }
            Action::LogFilterBackspace => {
                if let Some(s) = &mut self.log.filter_input {
                    s.pop();
                }
            }
            Action::LogFilterCommit => {
                if let Some(s) = self.log.filter_input.take() {
                    self.log.set_text_filter(s);
                }
            }
            Action::MapZoom { factor, at } => self.map.zoom_by(factor, at),
            Action::MapPan { dx, dy } => self.map.pan_by(dx, dy),
            Action::MapFollow { keep } => {
                self.map.toggle_follow(keep);
                let text = if self.map.follow {
                    "map follows the robot (F stops; hjkl look around it)"
                } else {
                    "map stays put (F follows the robot)"
                };
                self.note(Level::Info, Source::Command, text.into());
            }
            Action::ToggleLayer(name) => {
                if let Some(i) = self.map.hidden.iter().position(|h| *h == name) {
                    self.map.hidden.remove(i);
                } else {
                    self.map.hidden.push(name);
                }
            }
            Action::ClearTracks => {
                self.believed.clear();
                self.true_track.clear();
                self.localization.clear();
            }
            Action::PlanLocal => self.plan_locally(),
            Action::PlanTargetReset => {
                if !self.reset_plan_target() {
                    let to = self.plan_target().describe();
                    self.note(Level::Info, Source::Command, format!("plans go to {to}"));
                }
            }
            // Done by the TUI loop, which owns the file; it reports with `Recording`.
            Action::ToggleRecording => {}
            Action::Recording(note) => self.on_recording(note),
            Action::Transfer(a) => self.on_transfer_action(a),
            // The fleet's own (`crate::fleet::Fleet::update`); one robot has nothing to pick.
            Action::SelectRobot(_) | Action::StepRobot(_) | Action::StopAll => {}
        }
    }

    fn tick(&mut self, now_ms: u64) {
        self.now_ms = now_ms;
        let due = self
            .teleop
            .last_sent_ms
            .is_none_or(|t| now_ms.saturating_sub(t) + TELEOP_SLACK_MS >= TELEOP_PERIOD_MS);
        if self.teleop.driving && due {
            self.send_teleop(SendWhen::QuietLine);
        }
        self.transfers_tick();
    }

    fn back(&mut self) {
        if self.help {
            self.help = false;
        } else if self.params.input.is_some() {
            self.params.input = None;
        } else if self.params.searching
            || (self.view == View::Params && !self.params.search.is_empty())
        {
            // Esc drops the search: every parameter again.
            self.params.searching = false;
            self.params.set_search(String::new());
        } else if self.log.filter_input.is_some() {
            // Esc while typing a filter drops the filter too: the way back to everything.
            self.log.filter_input = None;
            self.log.set_text_filter(String::new());
        } else if self.map.cursor_mode {
            self.map.cursor_mode = false;
        } else if self.reset_plan_target() {
            // A clicked target and a chosen plan target go first, then the view.
        } else if self.view != View::Dashboard {
            self.view = View::Dashboard;
        }
    }

    fn step_view(&mut self, d: i32) {
        let n = View::ALL.len() as i32;
        let i = View::ALL.iter().position(|v| *v == self.view).unwrap_or(0) as i32;
        let j = (i + d).rem_euclid(n) as usize;
        self.view = View::ALL.get(j).copied().unwrap_or(View::Dashboard);
    }

    fn drive(&mut self, dv: i16, dw: i16) {
        if !self.connected() {
            self.note(Level::Warn, Source::Command, "teleop: not connected".into());
            return;
        }
        let t = &mut self.teleop;
        t.v_mm_s = t.v_mm_s.saturating_add(dv).clamp(-V_MAX, V_MAX);
        t.w_mrad_s = t.w_mrad_s.saturating_add(dw).clamp(-W_MAX, W_MAX);
        t.driving = true;
        self.send_teleop(SendWhen::Now);
    }

    /// Sends the teleop in force: a key press `Now`, a repeat `QuietLine`.
    fn send_teleop(&mut self, when: SendWhen) {
        self.teleop.last_sent_ms = Some(self.now_ms);
        let command = Command::Teleop {
            v_mm_s: self.teleop.v_mm_s,
            w_mrad_s: self.teleop.w_mrad_s,
        };
        self.send_when(command, when);
    }

    fn stop_driving(&mut self) {
        self.teleop = Teleop::default();
        self.send(Command::Stop);
    }

    /// Plans on the station from the believed pose (else the map's start) to the plan's
    /// target (`app::plan_target`: the cursor while shown, else the chosen target, else the
    /// map's goal).
    fn plan_locally(&mut self) {
        let from = self.pose().map(|(x, y, _)| (x, y));
        let to = match self.take_plan_target() {
            plan_target::PlanTarget::Chosen(p) => Some(p),
            plan_target::PlanTarget::MapGoal(_) => None,
        };
        let (level, text) = match self.map.plan.plan(from, to) {
            Ok(line) => (Level::Info, line),
            Err(e) => (Level::Warn, e),
        };
        self.note(level, Source::Command, text);
    }

    fn go_to(&mut self, x: f64, y: f64) {
        let goal = match point_mm(["go-to x", "go-to y"], (x, y)) {
            Ok(p) => p,
            Err(e) => {
                self.note(Level::Warn, Source::Command, format!("not sent: {e}"));
                return;
            }
        };
        self.teleop.driving = false;
        self.map.goal = Some((x, y));
        self.send(Command::GoTo(goal));
    }

    pub(super) fn read_param(&mut self, id: u16) {
        self.params.set_pending(id);
        self.send(Command::GetParam {
            id: protocol::ParamId(id),
        });
    }

    /// Reads a parameter without a log line of its own (see `Pending::quiet`).
    fn read_param_quietly(&mut self, id: u16) {
        self.params.set_pending(id);
        let cid = self.send(Command::GetParam {
            id: protocol::ParamId(id),
        });
        if let Some(p) = self.pending.get_mut(&cid) {
            p.quiet = true;
        }
    }

    /// Reads every parameter this robot has (on connect and on `R`); the ones its hardware
    /// lacks (`ParamInfo::requires`) are marked as such without asking.
    fn fetch_params(&mut self) {
        let caps = self.peer.as_ref().map_or(u32::MAX, |p| p.capabilities);
        let mut asked = 0;
        for p in self.params.params() {
            if caps & p.requires == p.requires {
                self.read_param_quietly(p.id);
                asked += 1;
            } else {
                self.params.set_absent(p.id);
            }
        }
        self.params.start_fetch(asked);
    }

    fn commit_param(&mut self) {
        match self.params.parse_input() {
            Ok((id, value)) => {
                self.params.input = None;
                let before = self.params.value_of(id);
                self.params.set_pending(id);
                let command = Command::SetParam {
                    id: protocol::ParamId(id),
                    value,
                };
                let cid = self.send(command);
                if let Some(p) = self.pending.get_mut(&cid) {
                    p.before = before;
                }
            }
            Err(e) => {
                self.params.input_error = Some(e.clone());
                self.note(Level::Warn, Source::Command, format!("param: {e}"));
            }
        }
    }

    #[cfg(test)]
    pub(crate) fn rate_asked_for_test(&self) -> Option<(CommandId, u8)> {
        self.rate_asked
    }

    fn step_rate(&mut self, d: i32) {
        let current = self
            .rate_asked
            .map(|(_, hz)| hz)
            .or(self.rate_hz)
            .or(self.peer.as_ref().map(|p| p.telemetry_hz))
            .unwrap_or(protocol::timing::TELEMETRY_DEFAULT_HZ);
        // The nearest step at or above the current rate, then one step along.
        let i = RATES
            .iter()
            .position(|&r| r >= current)
            .unwrap_or(RATES.len() - 1) as i32;
        let j = (i + d).clamp(0, RATES.len() as i32 - 1) as usize;
        let hz = RATES.get(j).copied().unwrap_or(current);
        let id = self.send(Command::SetTelemetryRate { hz });
        self.rate_asked = Some((id, hz));
    }

    /// Queues a command to go at once; returns its id.
    fn send(&mut self, command: Command) -> CommandId {
        self.send_when(command, SendWhen::Now)
    }

    /// Queues a command to go `when` says; returns its id.
    fn send_when(&mut self, command: Command, when: SendWhen) -> CommandId {
        let id = self.next_id;
        self.next_id += 1;
        self.pending.insert(
            id,
            Pending {
                before: None,
                quiet: false,
            },
        );
        self.outbox.push((id, command, when));
        id
    }

    fn on_link(&mut self, ev: LinkEvent) {
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

    fn on_connection(&mut self, c: Connection) {
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

    fn on_telemetry(&mut self, t: Telemetry) {
        let (x, y, _) = pose_m(&t.pose);
        self.believed.push(x, y);
        self.encoders.push(t.wheels.encoders);
        self.forage.on_telemetry(&t);
        self.history.push(self.now_ms as f64 / 1000.0, t);
        self.telemetry = Some(t);
        self.telemetry_ms = Some(self.now_ms);
    }

    fn on_robot_event(&mut self, e: Event) {
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

    fn on_done(&mut self, id: CommandId, command: Command, outcome: CommandOutcome) {
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
    fn fetch_done(&mut self, ok: bool) {
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

    fn on_recording(&mut self, note: crate::record::live::RecordingNote) {
        use crate::record::live::RecordingNote;
        let (level, text) = match note {
            RecordingNote::Started { file, links } => {
                self.recording = Some((file.clone(), self.now_ms));
                let what = if links > 1 {
                    format!("recording all {links} robots' links to {file}")
                } else {
                    format!("recording to {file}")
                };
                (Level::Info, format!("{what} (R stops)"))
            }
            RecordingNote::Stopped {
                file,
                seconds,
                bytes,
            } => {
                self.recording = None;
                self.hal_trace_back();
                (
                    Level::Info,
                    format!("recording saved: {file} ({seconds:.1} s, {bytes} bytes)"),
                )
            }
            RecordingNote::Failed { why } => {
                self.recording = None;
                self.hal_trace_back();
                (Level::Error, format!("recording: {why}"))
            }
        };
        self.note(level, Source::Link, text);
        // After the line that says where the recording goes: the trace is in it.
        self.hal_trace_on();
    }

    /// A recording started (or its robot came back): with `record_hal_trace`, the robot
    /// streams its hardware trace into it, so `station retrace` can re-run it.
    fn hal_trace_on(&mut self) {
        use robot_firmware::params::id::HAL_TRACE;
        if !self.record_hal_trace || self.replaying || self.recording.is_none() {
            return;
        }
        let now = self.params.value_of(HAL_TRACE);
        if self.hal_trace_before.is_none() {
            // Unknown (not read yet): off, the firmware's default.
            self.hal_trace_before = Some(now.unwrap_or(0.0));
        }
        if now == Some(1.0) {
            return;
        }
        self.note(
            Level::Info,
            Source::Command,
            "hardware trace on while recording (hal_trace = 1, put back after)".into(),
        );
        self.send(Command::SetParam {
            id: protocol::ParamId(HAL_TRACE),
            value: 1.0,
        });
    }

    /// The recording ended: hal_trace as it was before it.
    fn hal_trace_back(&mut self) {
        let Some(before) = self.hal_trace_before.take() else {
            return;
        };
        if before != 1.0 {
            self.send(Command::SetParam {
                id: protocol::ParamId(robot_firmware::params::id::HAL_TRACE),
                value: before,
            });
        }
    }

    /// Logs a line of the station's own about the link (what the TUI's start-up set up).
    pub fn note_link(&mut self, level: Level, text: String) {
        self.note(level, Source::Link, text);
    }

    fn note(&mut self, level: Level, source: Source, text: String) {
        self.note_grouped(level, source, text, None);
    }

    /// Logs a line that joins the recent entry of its group, if any (`app::log`).
    fn note_grouped(&mut self, level: Level, source: Source, text: String, group: Option<Group>) {
        if self.recording.is_some() && self.station_lines.len() < STATION_LINES_HELD {
            if let Some(source) = source.recorded() {
                self.station_lines.push(StationLine {
                    level: level.into(),
                    source,
                    text: text.clone(),
                });
            }
        }
        let line = LogLine::new(self.now_ms, level, source, text);
        self.log.push(match group {
            Some(g) => line.grouped(g),
            None => line,
        });
    }

    /// How old the values on screen are, seconds, when they are stale: the link is down, or
    /// no telemetry came for `STALE_PERIODS` periods (and `STALE_MIN_MS`). None while fresh
    /// or before any telemetry.
    pub fn stale_s(&self) -> Option<u64> {
        let at = self.telemetry_ms?;
        let age = self.now_ms.saturating_sub(at);
        let period = match self.rate_hz {
            Some(hz) if hz > 0 => 1000 / u64::from(hz),
            _ => 0,
        };
        let limit = (STALE_PERIODS * period).max(STALE_MIN_MS);
        (!self.connected() || age > limit).then_some(age / 1000)
    }

    /// Rows the log panel shows now (the Log view's when the panel is hidden): a page for
    /// scrolling, so that scrolling stops with the oldest line at the top.
    fn log_rows(&self) -> usize {
        let screen = ratatui::layout::Rect::new(0, 0, self.size.0, self.size.1);
        let rows = |app: &App| {
            layout::areas(screen, app)
                .find(layout::Panel::Log)
                .map(|r| usize::from(r.height.saturating_sub(2)))
        };
        rows(self).unwrap_or_else(|| usize::from(self.size.1.saturating_sub(4)))
    }
}

/// An event as `format::event_text` says it, at the log's level.
fn event_words(e: &Event) -> (Level, String) {
    let (level, text) = station_core::format::event_text(e);
    (level.into(), text)
}

fn pose_m(p: &protocol::Pose) -> (f64, f64, f64) {
    (
        f64::from(p.x_mm) / 1000.0,
        f64::from(p.y_mm) / 1000.0,
        f64::from(p.heading_mrad) / 1000.0,
    )
}

#[cfg(test)]
#[path = "app_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "app_log_tests.rs"]
mod log_tests;
