//! The recording's notes (`Action::Recording`) and the hardware trace it turns on while it
//! records (`record_hal_trace`).

use protocol::Command;

use super::log::{Level, Source};
use super::App;

impl App {
    pub(super) fn on_recording(&mut self, note: crate::record::live::RecordingNote) {
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
    pub(super) fn hal_trace_on(&mut self) {
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
    pub(super) fn hal_trace_back(&mut self) {
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
}
