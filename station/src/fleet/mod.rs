//! Several robots at once (issue 17): one `App` per link, one of them selected.
//!
//! Layer: the UI's state machine one level up from `App`. Each robot keeps its own `App` (its
//! telemetry, log, parameters, plans, transfers), fed by its own link task exactly as a single
//! robot's is; the fleet routes: link events to the robot they came from, keys and commands to
//! the selected robot, ticks and resizes to all. It adds the picker (`SelectRobot`,
//! `StepRobot`), "stop all" (`StopAll`: `Stop` to every connected robot, each one's ack or
//! refusal reported in the log on screen), the robots' labels and the duplicate-id check.
//! With one robot it is a pass-through: the screens and keys are today's. Cannot fail.

pub mod input;
pub mod start;

use std::collections::HashSet;

use protocol::Command;

use crate::action::Action;
use crate::app::fleet::{FleetOverlay, FleetRobot};
use crate::app::log::Level;
use crate::app::{mode_name, App};
use crate::link::{CommandId, CommandOutcome, Connection, LinkEvent, PeerInfo};

/// The most robots one station drives: the picker's digit keys reach nine.
pub const MAX_ROBOTS: usize = 9;

/// One robot of the fleet.
#[derive(Debug)]
pub struct Member {
    pub app: App,
    /// Its port, as given (`/tmp/robot2`).
    pub port: String,
}

/// The robots and which one the panels, keys and commands are for.
#[derive(Debug)]
pub struct Fleet {
    pub members: Vec<Member>,
    selected: usize,
    /// "Stop all" commands not yet answered: robot index and command id.
    stop_all: HashSet<(usize, CommandId)>,
    /// Ids already reported as shared, so that a duplicate is warned about once.
    reported_duplicates: HashSet<u8>,
    pub quit: bool,
}

/// The id a robot states in its handshake (`HelloReply.robot_id`, parameter 33, like MAVLink's
/// system id). The one place the fleet reads it; a robot not yet connected has none.
pub fn robot_id(peer: &PeerInfo) -> Option<u8> {
    Some(peer.robot_id)
}

/// What a robot is called everywhere: its profile and its id when it reports one, else its
/// port's number in the fleet (1-based) — "micro-rato #7", "micro-rato 2", "robot 3" before
/// its handshake.
pub fn robot_label(index: usize, profile: Option<&str>, id: Option<u8>) -> String {
    let who = profile.unwrap_or("robot");
    match id {
        Some(id) => format!("{who} #{id}"),
        None => format!("{who} {}", index + 1),
    }
}

/// The robots (indices) whose id another robot reports too (`link::robot_ids` decides).
pub fn duplicate_ids(ids: &[Option<u8>]) -> Vec<usize> {
    let labels: Vec<String> = (0..ids.len()).map(|i| i.to_string()).collect();
    let shared: HashSet<u8> = crate::link::robot_ids::duplicates(
        labels.iter().map(String::as_str).zip(ids.iter().copied()),
    )
    .into_iter()
    .map(|d| d.robot_id)
    .collect();
    ids.iter()
        .enumerate()
        .filter(|(_, id)| id.is_some_and(|id| shared.contains(&id)))
        .map(|(i, _)| i)
        .collect()
}

/// The profile's name as people say it.
pub fn profile_name(p: protocol::ProfileId) -> &'static str {
    match p {
        protocol::ProfileId::Khepera => "khepera",
        protocol::ProfileId::MicroRato => "micro-rato",
        protocol::ProfileId::Alice => "alice",
    }
}

impl Fleet {
    /// A fleet of `members` (at least one), the first selected.
    pub fn new(members: Vec<Member>) -> Fleet {
        let mut f = Fleet {
            members,
            selected: 0,
            stop_all: HashSet::new(),
            reported_duplicates: HashSet::new(),
            quit: false,
        };
        f.sync_overlay();
        f
    }

    pub fn len(&self) -> usize {
        self.members.len()
    }

    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    pub fn selected(&self) -> usize {
        self.selected
    }

    /// The selected robot's app: what the screen shows and the keys drive.
    /// Selects robot `i` as it was before the fleet was rebuilt (a replay seeking back):
    /// no log line, no teleop to stop.
    pub fn restore_selection(&mut self, i: usize) {
        if i < self.len() {
            self.selected = i;
            self.sync_overlay();
        }
    }

    pub fn app(&self) -> &App {
        &self.members[self.selected].app
    }

    pub fn app_mut(&mut self) -> &mut App {
        &mut self.members[self.selected].app
    }

    /// This robot's label (`robot_label`).
    pub fn label(&self, i: usize) -> String {
        let peer = self.members.get(i).and_then(|m| m.app.peer.as_ref());
        robot_label(
            i,
            peer.map(|p| profile_name(p.profile)),
            peer.and_then(robot_id),
        )
    }

    /// Applies one action: the fleet's own, or the selected robot's (ticks and resizes go to
    /// every robot).
    pub fn update(&mut self, action: Action) {
        // Ticks change nothing the overlay shows but staleness, which the next frame's sync
        // picks up: no copy of every track 30 times a second.
        let sync = !matches!(action, Action::Tick { .. });
        match action {
            Action::SelectRobot(i) => self.select(i),
            Action::StepRobot(d) => {
                let n = self.len() as i32;
                let i = (self.selected as i32 + d).rem_euclid(n.max(1));
                self.select(i as usize);
            }
            Action::StopAll => self.stop_all(),
            // The recording holds every robot's link: each robot's header shows it.
            Action::Tick { .. } | Action::Resize { .. } | Action::Recording(_) => {
                for m in &mut self.members {
                    m.app.update(action.clone());
                }
            }
            Action::Quit => {
                // Every robot being driven from the keyboard is stopped, not only the one shown.
                for m in &mut self.members {
                    m.app.update(Action::Quit);
                }
                self.quit = true;
            }
            a => {
                self.app_mut().update(a);
                self.quit |= self.app().quit;
            }
        }
        if sync {
            self.sync_overlay();
        }
    }

    /// A link event from robot `i`'s link.
    pub fn on_link(&mut self, i: usize, ev: LinkEvent) {
        if let LinkEvent::CommandDone {
            id,
            command: Command::Stop,
            outcome,
        } = &ev
        {
            if self.stop_all.remove(&(i, *id)) {
                let (level, text) = match outcome {
                    CommandOutcome::Acked { rtt_ms, .. } => {
                        (Level::Info, format!("stopped (acked in {rtt_ms} ms)"))
                    }
                    CommandOutcome::Nacked { reason, .. } => (
                        Level::Error,
                        format!(
                            "REFUSED: {}",
                            crate::link::api::refusal_text(&Command::Stop, *reason)
                        ),
                    ),
                    CommandOutcome::Failed(why) => (Level::Error, format!("FAILED: {why}")),
                };
                self.note_for(i, level, text);
            }
        }
        let connection = matches!(ev, LinkEvent::Connection(_));
        let Some(m) = self.members.get_mut(i) else {
            return;
        };
        m.app.update(Action::Link(ev));
        if connection {
            self.check_duplicate_ids();
        }
    }

    /// Keeps the selected robot's overlay current: call before drawing and before mapping a
    /// mouse event (it copies every robot's track, so not on every link event).
    pub fn sync_overlay(&mut self) {
        if self.len() < 2 {
            return;
        }
        let ids: Vec<Option<u8>> = self
            .members
            .iter()
            .map(|m| m.app.peer.as_ref().and_then(robot_id))
            .collect();
        let dups = duplicate_ids(&ids);
        let robots = (0..self.len())
            .map(|i| {
                let mut r = summary(&self.members[i].app);
                r.label = self.label(i);
                r.duplicate_id = dups.contains(&i);
                r
            })
            .collect();
        let overlay = FleetOverlay {
            selected: self.selected,
            robots,
        };
        for (i, m) in self.members.iter_mut().enumerate() {
            // Only the selected robot's screen is drawn; the others drop a stale copy.
            m.app.fleet = (i == self.selected).then(|| overlay.clone());
        }
    }

    fn select(&mut self, i: usize) {
        if i >= self.len() || i == self.selected {
            return;
        }
        let old = self.selected;
        // The keys drive the selected robot: one left behind keeps no keyboard drive going.
        if self.members[old].app.teleop.driving {
            self.members[old].app.update(Action::StopDriving);
            let label = self.label(old);
            self.members[old]
                .app
                .fleet_note(Level::Warn, format!("teleop stopped: {label} deselected"));
        }
        self.selected = i;
        let label = self.label(i);
        // A path from the command line: no control character reaches the terminal.
        let port = crate::terminal_text::printable(&self.members[i].port).into_owned();
        self.app_mut()
            .fleet_note(Level::Info, format!("selected {label} on {port}"));
    }

    /// `Stop` to every connected robot; one log line for each that cannot be reached now, and
    /// one more for each as its ack or refusal comes (`on_link`).
    fn stop_all(&mut self) {
        let mut sent = 0;
        for i in 0..self.len() {
            match self.members[i].app.stop_for_fleet() {
                Ok(id) => {
                    self.stop_all.insert((i, id));
                    sent += 1;
                }
                Err(why) => self.note_for(i, Level::Error, format!("NOT STOPPED: {why}")),
            }
        }
        let n = self.len();
        self.app_mut().fleet_note(
            Level::Warn,
            format!("stop all: Stop sent to {sent} of {n} robots"),
        );
    }

    /// A fleet line about robot `i`: in the log on screen (the selected robot's) and, when
    /// another robot's, in that robot's own log too.
    fn note_for(&mut self, i: usize, level: Level, text: String) {
        let label = self.label(i);
        self.app_mut()
            .fleet_note(level, format!("stop all: {label}: {text}"));
        if i != self.selected {
            if let Some(m) = self.members.get_mut(i) {
                m.app.fleet_note(level, format!("stop all: {text}"));
            }
        }
    }

    /// Warns once for each id that two robots report.
    fn check_duplicate_ids(&mut self) {
        let ids: Vec<Option<u8>> = self
            .members
            .iter()
            .map(|m| m.app.peer.as_ref().and_then(robot_id))
            .collect();
        warn_duplicates(self, &ids);
    }

    /// The duplicate-id check against given ids (`robot_id` reads none yet): warns in the log
    /// on screen, once per id.
    pub fn warn_duplicate_ids(&mut self, ids: &[Option<u8>]) {
        warn_duplicates(self, ids);
    }
}

fn warn_duplicates(fleet: &mut Fleet, ids: &[Option<u8>]) {
    let ports: Vec<String> = fleet
        .members
        .iter()
        .map(|m| crate::terminal_text::printable(&m.port).into_owned())
        .collect();
    let dups = crate::link::robot_ids::duplicates(
        ports.iter().map(String::as_str).zip(ids.iter().copied()),
    );
    for d in dups {
        if fleet.reported_duplicates.insert(d.robot_id) {
            fleet.app_mut().fleet_note(Level::Warn, d.warning());
        }
    }
}

/// One robot's line and marker, from its app.
fn summary(app: &App) -> FleetRobot {
    let activity = match (app.telemetry, &app.progress) {
        (Some(t), Some(p)) if p.mode == t.mode => {
            let mut s = mode_name(t.mode).to_string();
            if p.waypoints > 0 {
                s.push_str(&format!(" {}/{}", p.waypoint, p.waypoints));
            }
            if let Some(d) = p.distance_left_mm {
                s.push_str(&format!(" {:.1} m", f64::from(d) / 1000.0));
            }
            s
        }
        (Some(t), _) => mode_name(t.mode).to_string(),
        (None, _) => "—".into(),
    };
    let (link, connected) = match &app.connection {
        Connection::Connected(_) => {
            let text = match &app.stats {
                Some(s) if s.robot_seq.loss_percent >= 0.05 => format!(
                    "ok {:.0} Hz, {:.1} % lost",
                    s.telemetry_hz, s.robot_seq.loss_percent
                ),
                Some(s) => format!("ok {:.0} Hz", s.telemetry_hz),
                None => "ok".into(),
            };
            (text, true)
        }
        Connection::Handshaking { .. } => ("handshaking".into(), false),
        Connection::Closed { reason } => (format!("down: {reason}"), false),
        Connection::Refused { message } => (format!("refused: {message}"), false),
    };
    let battery_v = app
        .telemetry
        .filter(|t| t.battery_mv > 0)
        .map(|t| f64::from(t.battery_mv) / 1000.0);
    FleetRobot {
        label: String::new(),
        profile: app
            .peer
            .as_ref()
            .map_or("?", |p| profile_name(p.profile))
            .to_string(),
        activity,
        link,
        connected,
        battery_v,
        stale_s: app.stale_s(),
        duplicate_id: false,
        pose: app.pose(),
        track: app.believed.points().copied().collect(),
    }
}

#[cfg(test)]
mod tests;
