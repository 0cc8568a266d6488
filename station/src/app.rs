//! The station's state and the one function that changes it, `App::update`.
//!
//! Layer: pure state machine of the UI (ratatui templates' `update`, gitui's components without
//! their I/O). It never touches the terminal or the port: commands it wants sent go into an
//! outbox (`take_outbox`) that the TUI loop hands to the link task, and time arrives in
//! `Action::Tick`. Rendering borrows it immutably (`ui::render`). Invariants: teleop repeats
//! only while driving and only in a connected session (a reconnect never restarts motion by
//! itself); every command sent is remembered until its `CommandDone` arrives, so its outcome
//! (with the robot's Nack reason) reaches the log and the parameter editor. Cannot fail.
//!
//! `App`'s methods are spread over its submodules by what they answer: `update` and the
//! views' state here, what the link reports in `link_events`, what the keys send in `outbox`,
//! the recording's notes in `recording` (and transfers, parameters, ... in theirs).

pub use station_core::arena;
pub use station_core::format::{mode_from_index, mode_name, mode_name_i32, MODES};
pub mod fleet;
pub mod forage;
pub mod history;
pub mod layout;
mod link_events;
pub mod localization;
pub mod log;
mod map;
mod outbox;
pub mod params;
pub mod plan_target;
mod recording;
pub use station_core::qt_state;
pub mod transfers;
pub mod view;

pub use map::{MapState, FOLLOW_ZOOM, MAX_ZOOM, PAN_STEP, ZOOM_STEP};
pub use view::View;

use std::collections::HashMap;

use protocol::{Command, EmuTruth, Telemetry};

use crate::action::Action;
use crate::link::{CommandId, Connection, LinkStats, PeerInfo, SendWhen};
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
