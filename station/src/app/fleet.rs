//! What one robot's app knows of the fleet it belongs to, and the few things the fleet asks
//! of it.
//!
//! Layer: part of the pure UI state. The fleet (`crate::fleet`) owns one `App` per robot and,
//! before each frame and each mouse event, gives the selected robot's app a
//! `FleetOverlay`: a snapshot of every robot's line and map marker. Drawing and input read it
//! from the app they already have, so the single-robot screens and key map stay as they are
//! (no overlay: not a fleet). Cannot fail.

use protocol::Command;

/// The "stop all" key: unused by the single-robot key map, shown in the footer and help (the
/// fleet's input handles it).
pub const STOP_ALL_KEY: char = '!';

use super::log::{Level, Source};
use super::App;
use crate::link::CommandId;

/// The fleet as the selected robot's screen shows it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FleetOverlay {
    /// Index of the selected robot in `robots`.
    pub selected: usize,
    pub robots: Vec<FleetRobot>,
}

/// One robot's fleet-panel line and map marker.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FleetRobot {
    /// `crate::fleet::robot_label`.
    pub label: String,
    /// The profile it said in its handshake ("?" before).
    pub profile: String,
    /// Its mode and what the mode is doing ("Explore", "ExecutePlan 3/9 2.1 m").
    pub activity: String,
    /// The link in a few words: "ok 50 Hz", "lost 0.4 %", or why it is down.
    pub link: String,
    /// Whether the link is up (the line is drawn in red otherwise).
    pub connected: bool,
    /// Battery, volts.
    pub battery_v: Option<f64>,
    /// Seconds since its values were fresh, when stale (`App::stale_s`).
    pub stale_s: Option<u64>,
    /// Another robot reports the same id.
    pub duplicate_id: bool,
    /// Believed pose, metres and radians.
    pub pose: Option<(f64, f64, f64)>,
    /// Believed track, metres.
    pub track: Vec<(f64, f64)>,
}

impl App {
    /// Whether this app is the selected robot of a fleet of several.
    pub fn in_fleet(&self) -> bool {
        self.fleet.as_ref().is_some_and(|f| f.robots.len() > 1)
    }

    /// `Stop` for "stop all": sent when connected (its outcome reaches this robot's log as
    /// every command's does; the fleet reports it too); else why not.
    pub fn stop_for_fleet(&mut self) -> Result<CommandId, String> {
        use crate::link::Connection;
        match &self.connection {
            Connection::Connected(_) => {}
            Connection::Closed { reason } => return Err(format!("not connected ({reason})")),
            Connection::Refused { message } => return Err(format!("refused us ({message})")),
            Connection::Handshaking { .. } => return Err("not connected yet".into()),
        }
        // A keyboard drive in progress would send its next teleop and move again.
        self.teleop = super::Teleop::default();
        Ok(self.send(Command::Stop))
    }

    /// A line from the fleet (stop all, duplicate ids) in this robot's log.
    pub fn fleet_note(&mut self, level: Level, text: String) {
        self.note(level, Source::Command, text);
    }
}
