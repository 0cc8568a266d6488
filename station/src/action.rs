//! Everything that can change the app's state, as data.
//!
//! Layer: the one-way data flow's middle (ratatui templates, gitui): terminal input and link
//! events become `Action`s (`input.rs`, the TUI loop), `App::update` applies them, and
//! `ui::render` draws the result. An action never does I/O; commands the app wants sent are
//! queued in the app's outbox and handed to the link task by the loop.

use protocol::Mode;

use crate::app::view::View;
use crate::link::LinkEvent;

/// One change to the app.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Time passes: `now_ms` since the station started. Drives teleop repetition.
    Tick {
        now_ms: u64,
    },
    /// The terminal's size changed.
    Resize {
        width: u16,
        height: u16,
    },
    /// Something the link task reported.
    Link(LinkEvent),
    Quit,
    ToggleHelp,
    /// Scroll the help to this line (`input` clamps it to the help's length on screen).
    HelpScroll(u16),
    /// Close the topmost overlay or mode (help, go-to cursor, parameter edit).
    Back,
    NextView,
    PrevView,
    ShowView(View),
    /// Change the teleop velocity by a step: forward mm/s, turn mrad/s.
    Drive {
        dv: i16,
        dw: i16,
    },
    /// Zero the velocity, stop repeating teleop and send `Stop`.
    StopDriving,
    SetMode(Mode),
    /// Enter go-to mode with a cursor on the map at the robot.
    GoToCursorStart,
    /// Move the go-to cursor, metres.
    MoveCursor {
        dx: f64,
        dy: f64,
    },
    /// Send `GoTo` to the cursor.
    GoToCursor,
    /// Send `GoTo` to a point (a mouse click on the map with `--click-goes`), metres.
    GoToPoint {
        x_m: f64,
        y_m: f64,
    },
    /// Put the go-to cursor at a point (a mouse click on the map), metres: `Enter` then
    /// sends the robot there, so a stray click moves nothing.
    CursorAt {
        x_m: f64,
        y_m: f64,
    },
    /// Select another parameter.
    ParamSelect(i32),
    /// `GetParam` the selected parameter.
    ParamRead,
    /// `GetParam` every parameter.
    ParamReadAll,
    /// Start typing a new value for the selected parameter.
    ParamEdit,
    ParamInput(char),
    ParamBackspace,
    /// `SetParam` the typed value.
    ParamCommit,
    /// Start typing the parameter search (`/` in the parameter view).
    ParamSearchStart,
    ParamSearchInput(char),
    ParamSearchBackspace,
    /// Keep the search and go back to the list's keys (`Enter`).
    ParamSearchDone,
    /// Step the telemetry rate through 0, 1, 2, 5, 10, 20, 50 Hz.
    RateStep(i32),
    /// Show the next set of chart series.
    ChartNext,
    /// Scroll the log by entries (positive: older); it stops with the oldest at the top.
    LogScroll(i32),
    /// Follow the newest log entry again (End).
    LogFollow,
    /// Scroll the log to its oldest entry (Home).
    LogTop,
    /// Step the log's minimum severity: all, info, warn, error.
    LogLevelCycle,
    /// Start typing a text filter for the log (`/`).
    LogFilterStart,
    LogFilterInput(char),
    LogFilterBackspace,
    /// Apply the typed filter (empty: none).
    LogFilterCommit,
    /// Zoom the map by a factor about a point (fractions of the shown span from the centre).
    MapZoom {
        factor: f64,
        at: (f64, f64),
    },
    /// Pan the map by steps of a quarter of what is shown (x right, y up).
    MapPan {
        dx: i8,
        dy: i8,
    },
    /// Follow the robot with the map, or stop following (`F`); `keep` is the pan that shows
    /// the view as it is now, kept when following stops.
    MapFollow {
        keep: (f64, f64),
    },
    /// Show or hide a map layer by name.
    ToggleLayer(&'static str),
    /// Forget the drawn tracks.
    ClearTracks,
    /// Plan on the station from the believed pose to the plan's target and show it.
    PlanLocal,
    /// `G`: plans go to the map's goal again (forget the chosen target).
    PlanTargetReset,
    /// Start or stop recording the link to a file (the TUI loop does the I/O, then reports
    /// back with `Recording`).
    ToggleRecording,
    /// The recorder started, finished or failed.
    Recording(crate::record::live::RecordingNote),
    /// Upload, download, plan on the robot, execute, explore (`app::transfers`).
    Transfer(TransferAction),
    /// Fleet: select robot `i` (0-based) for the panels, the keys and the commands.
    SelectRobot(usize),
    /// Fleet: select the next (+1) or previous (-1) robot.
    StepRobot(i32),
    /// Fleet: send `Stop` to every connected robot.
    StopAll,
}

/// What a recording replays as is what the live link would have said.
impl From<station_core::replay::ReplayEvent> for Action {
    fn from(e: station_core::replay::ReplayEvent) -> Self {
        match e {
            station_core::replay::ReplayEvent::Tick { now_ms } => Action::Tick { now_ms },
            station_core::replay::ReplayEvent::Link(ev) => Action::Link(ev),
        }
    }
}

/// A transfer key or prompt edit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TransferAction {
    /// `u`: open the upload prompt.
    OpenPrompt,
    PromptInput(char),
    PromptBackspace,
    /// Ctrl-U: clear the prompt (as in a shell).
    PromptClear,
    /// End or an arrow: keep the suggestion and edit it.
    PromptKeep,
    /// Enter: upload the file named in the prompt.
    PromptCommit,
    /// Esc: close the prompt.
    PromptCancel,
    /// `M`: download the robot's map and show it.
    DownloadMap,
    /// `O`: segment and plan on the robot, then download and draw the plan.
    PlanOnRobot,
    /// `X`: execute the robot's installed plan.
    ExecutePlan,
    /// `E`: start exploring.
    StartExploration,
}
