//! One replay session: the recording, the feed, the app it drives, the player and the keys.
//!
//! Layer: pure state with the wall clock passed in (µs since the replay started); the terminal
//! loop (`replay::tui`) does the I/O around it and tests drive it directly. `sync(wall)` brings
//! the app to the player's position: forward by feeding the records in between, backward by
//! rebuilding the app and the feed and feeding from the start (deterministic, so the screen is
//! what it would have been). View state (which view, chart, hidden layers, log scroll) survives
//! a seek back. Keys that would send anything (driving, modes, go-to, parameters) are not
//! mapped: a replay never talks to a robot. Cannot fail.

use ratatui::crossterm::event::MouseEventKind;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use ratatui::Frame;

use super::player::{Player, SEEK_STEP_US};
use super::screen::{self, ReplayStatus};
use super::{ReplayEvent, ReplayFeed};
use crate::action::Action;
use crate::app::log::{Level, LogLine, Source};
use crate::app::{App, AppOptions, View};
use crate::fleet::{Fleet, Member};
use crate::record::Recording;

/// Longest wall time between two progress-bar updates while playing, µs.
pub const BAR_REFRESH_US: u64 = 100_000;

/// A replay in progress.
pub struct ReplaySession {
    /// The file's links, each as a recording of its own (`Recording::link`), by link id; a
    /// version 1 file is its one link, unchanged.
    links: Vec<Recording>,
    /// One feed per link: each robot's bytes go through its own link machine, as live.
    feeds: Vec<ReplayFeed>,
    /// One app per link, as the live fleet has: the picker chooses whose panels are shown, the
    /// map and the fleet panel show every robot. One link: a pass-through, today's screens.
    fleet: Fleet,
    file: String,
    opts: AppOptions,
    pub player: Player,
    pub help: bool,
    pub quit: bool,
    actions: Vec<ReplayEvent>,
    /// `--retrace`: drawn over the map and noted in the log after every restart.
    retrace: Option<std::sync::Arc<crate::retrace::overlay::RetraceOverlay>>,
}

impl ReplaySession {
    /// A session at the start of `rec`, playing at `speed`. `file` names it on screen.
    /// A file of several links replays them all, as the live fleet view shows them.
    pub fn new(rec: Recording, file: &str, opts: AppOptions, speed: f64) -> ReplaySession {
        let links = if rec.link_count() > 1 {
            rec.links()
        } else {
            vec![rec]
        };
        let duration_us = links.iter().map(Recording::duration_us).max().unwrap_or(0);
        let player = Player::new(duration_us, speed);
        ReplaySession {
            feeds: fresh_feeds(&links),
            fleet: fresh_fleet(&links, &opts, file, None, &mut []),
            links,
            file: file.to_string(),
            opts,
            player,
            help: false,
            quit: false,
            actions: Vec::new(),
            retrace: None,
        }
    }

    /// Draws `retrace` (`station replay --retrace`) over the replay.
    pub fn with_retrace(
        mut self,
        retrace: Option<std::sync::Arc<crate::retrace::overlay::RetraceOverlay>>,
    ) -> Self {
        self.retrace = retrace;
        self.restart();
        self
    }

    /// The recording replayed: the file itself, or with several links, link 0's.
    pub fn recording(&self) -> &Recording {
        &self.links[0]
    }

    /// How many robots (links) the file holds.
    pub fn robots(&self) -> usize {
        self.links.len()
    }

    /// The robots, the selected one's app first among equals.
    pub fn fleet(&self) -> &Fleet {
        &self.fleet
    }

    /// The app on screen: the selected robot's.
    pub fn app(&self) -> &App {
        self.fleet.app()
    }

    pub fn app_mut(&mut self) -> &mut App {
        self.fleet.app_mut()
    }

    /// Brings every robot's app to the player's position; true when an app changed.
    pub fn sync(&mut self, wall_us: u64) -> bool {
        self.player.settle(wall_us);
        let target = self.player.position(wall_us);
        let mut changed = false;
        if self.feeds.iter().any(|f| target < f.position_us()) {
            self.restart();
            changed = true;
        }
        for i in 0..self.links.len() {
            self.actions.clear();
            self.feeds[i].advance_to(&self.links[i].records, target, &mut self.actions);
            for a in self.actions.drain(..) {
                changed |= !matches!(a, ReplayEvent::Tick { .. });
                match a {
                    // Through the fleet: it checks the robots' ids against each other.
                    ReplayEvent::Link(ev) => self.fleet.on_link(i, ev),
                    ReplayEvent::Tick { now_ms } => {
                        self.fleet.members[i].app.update(Action::Tick { now_ms })
                    }
                }
            }
            // Nothing the app might want to send goes anywhere: neither commands nor the
            // transfer engine's answers to recorded chunks (kept, they would pile up while
            // exploring).
            let app = &mut self.fleet.members[i].app;
            let _ = app.take_outbox();
            let _ = app.transfers.take_frames();
        }
        if changed {
            self.fleet.sync_overlay();
        }
        changed
    }

    /// Fresh apps and feeds at time 0, keeping what the operator chose to look at (each
    /// robot's view, chart, hidden layers) and which robot is selected.
    fn restart(&mut self) {
        let mut kept: Vec<App> = self.fleet.members.drain(..).map(|m| m.app).collect();
        let selected = self.fleet.selected();
        let mut fleet = fresh_fleet(
            &self.links,
            &self.opts,
            &self.file,
            self.retrace.as_ref(),
            &mut kept,
        );
        fleet.restore_selection(selected);
        self.fleet = fleet;
        self.feeds = fresh_feeds(&self.links);
    }

    /// When the loop should wake next to keep up (None: paused, nothing to do).
    pub fn next_wake(&self, wall_us: u64) -> Option<u64> {
        if self.player.paused() {
            return None;
        }
        let bar = wall_us + BAR_REFRESH_US;
        let next_record = self
            .links
            .iter()
            .zip(&self.feeds)
            .filter_map(|(rec, feed)| rec.records.get(feed.next_index()))
            .filter_map(|r| self.player.wall_at(r.t_us))
            .min();
        Some(next_record.map_or(bar, |w| w.min(bar)).max(wall_us + 1))
    }

    /// What the progress bar shows at `wall_us`.
    pub fn status(&self, wall_us: u64) -> ReplayStatus<'_> {
        ReplayStatus {
            position_us: self.player.position(wall_us),
            duration_us: self.player.duration_us(),
            speed: self.player.speed(),
            paused: self.player.paused(),
            help: self.help,
            damage_offset: self.links[0].damage.as_ref().map(|d| d.offset()),
            file: &self.file,
            robots: self.links.len(),
        }
    }

    /// Draws the screen.
    pub fn render(&self, frame: &mut Frame, wall_us: u64) {
        screen::render(self.app(), &self.status(wall_us), frame);
    }

    /// Handles a terminal event; true when the screen needs drawing.
    pub fn event(&mut self, wall_us: u64, ev: &Event) -> bool {
        if let Some(a) = self.fleet_action(ev) {
            if let Some(a) = a {
                self.fleet.update(a);
            }
            return true;
        }
        match ev {
            Event::Resize(w, h) => {
                self.fleet.update(Action::Resize {
                    width: *w,
                    height: *h,
                });
                true
            }
            Event::Key(k) if k.kind != KeyEventKind::Release => {
                self.key(wall_us, k);
                true
            }
            Event::Mouse(m) => match m.kind {
                MouseEventKind::ScrollUp => {
                    self.app_mut().update(Action::LogScroll(3));
                    true
                }
                MouseEventKind::ScrollDown => {
                    self.app_mut().update(Action::LogScroll(-3));
                    true
                }
                _ => false,
            },
            _ => false,
        }
    }

    /// The fleet's picker keys and clicks, as live (`fleet::input`): Tab / Shift-Tab step,
    /// Alt-1 .. Alt-9 pick, a click on a fleet line or a robot on the map picks. `Some(None)`:
    /// the fleet's key, doing nothing. "Stop all" sends, so a replay has no such key; nor does
    /// anything while the replay's help is open (any key closes it).
    fn fleet_action(&self, ev: &Event) -> Option<Option<Action>> {
        if self.help {
            return None;
        }
        match crate::fleet::input::fleet_action_for(self.app(), ev)? {
            Some(Action::StopAll) => None,
            a => Some(a),
        }
    }

    /// Handles a key.
    pub fn key(&mut self, wall_us: u64, k: &KeyEvent) {
        let ctrl = k.modifiers.contains(KeyModifiers::CONTROL);
        if (ctrl && k.code == KeyCode::Char('c')) || k.code == KeyCode::Char('q') {
            self.quit = true;
            return;
        }
        if self.help {
            self.help = false;
            return;
        }
        let p = &mut self.player;
        match k.code {
            KeyCode::Char(' ') => p.toggle_pause(wall_us),
            KeyCode::Left => p.seek_by(wall_us, -SEEK_STEP_US),
            KeyCode::Right => p.seek_by(wall_us, SEEK_STEP_US),
            KeyCode::Home => p.seek(wall_us, 0),
            KeyCode::End => p.seek(wall_us, p.duration_us()),
            KeyCode::Char('+' | '=') => p.step_speed(wall_us, 1),
            KeyCode::Char('-') => p.step_speed(wall_us, -1),
            KeyCode::Char(c @ '1'..='9') => {
                p.set_speed(wall_us, f64::from(c.to_digit(10).unwrap_or(1)));
            }
            KeyCode::Char('?') => self.help = true,
            code => {
                if let Some(a) = view_action(self.app(), code) {
                    self.app_mut().update(a);
                }
            }
        }
    }
}

/// One app per link at time 0; `old[i]`, when there, gives robot `i`'s view state.
/// `retrace` is drawn on robot 1's (link 0's) screen: the retrace reads the file as one
/// robot's.
fn fresh_fleet(
    links: &[Recording],
    opts: &AppOptions,
    file: &str,
    retrace: Option<&std::sync::Arc<crate::retrace::overlay::RetraceOverlay>>,
    old: &mut [App],
) -> Fleet {
    let n = links.len();
    let members = links
        .iter()
        .enumerate()
        .map(|(i, rec)| {
            let mut app = App::new(opts.clone());
            app.replaying = true;
            app.retrace = retrace.filter(|_| i == 0).cloned();
            if let Some(o) = old.get_mut(i) {
                app.size = o.size;
                app.view = o.view;
                app.chart = o.chart;
                app.map.hidden = std::mem::take(&mut o.map.hidden);
            }
            notes(&mut app, rec, file, i, n);
            Member {
                app,
                port: rec.meta.port.clone(),
            }
        })
        .collect();
    Fleet::new(members)
}

fn fresh_feeds(links: &[Recording]) -> Vec<ReplayFeed> {
    links
        .iter()
        .map(|r| ReplayFeed::new(&r.meta.port))
        .collect()
}

/// Keys that only change what is shown.
fn view_action(app: &App, code: KeyCode) -> Option<Action> {
    Some(match code {
        KeyCode::Esc => Action::Back,
        KeyCode::Tab => Action::NextView,
        KeyCode::BackTab => Action::PrevView,
        KeyCode::F(n) => Action::ShowView(*View::ALL.get(usize::from(n).checked_sub(1)?)?),
        KeyCode::Char('p') => Action::ShowView(View::Params),
        KeyCode::Char('c') => Action::ChartNext,
        KeyCode::Char('t') => Action::ToggleLayer("truth"),
        KeyCode::Char('x') => Action::ClearTracks,
        KeyCode::PageUp => Action::LogScroll(5),
        KeyCode::PageDown => Action::LogScroll(-5),
        KeyCode::Up if app.view == View::Params => Action::ParamSelect(-1),
        KeyCode::Down if app.view == View::Params => Action::ParamSelect(1),
        _ => return None,
    })
}

/// The lines a replay's log starts with: what is replayed, which of the file's robots this
/// is when it holds several, and any damage.
fn notes(app: &mut App, rec: &Recording, file: &str, link: usize, links: usize) {
    // `--retrace`: what differed, first (robot text is not in it: names and numbers only).
    let retrace_lines = app
        .retrace
        .as_ref()
        .map(|r| r.lines.clone())
        .unwrap_or_default();
    let mut note = |level, text: String| {
        app.log.push(LogLine::new(0, level, Source::Link, text));
    };
    for line in retrace_lines {
        note(Level::Info, line);
    }
    note(
        Level::Info,
        format!(
            "replaying {file}: {:.1} s of {} ({}); nothing is sent to any port",
            rec.duration_us() as f64 / 1e6,
            if rec.meta.port.is_empty() {
                "an unnamed port"
            } else {
                &rec.meta.port
            },
            match &rec.end {
                Some(why) => format!("ended: {why}"),
                None => "unfinished: no end record".into(),
            }
        ),
    );
    if links > 1 {
        note(
            Level::Info,
            format!(
                "{file} holds {links} robots (links); these panels are robot {} (link {link}); \
                 Tab, Alt-1..{links} or a click picks another",
                link + 1
            ),
        );
    }
    if let Some(d) = &rec.damage {
        note(
            Level::Error,
            format!("{d}; replaying the {} records before it", rec.records.len()),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::synth::{demo_robot, merge};

    fn logged(s: &ReplaySession) -> Vec<String> {
        s.app().log.shown().iter().map(|l| l.text.clone()).collect()
    }

    fn two_robots() -> ReplaySession {
        let both = merge(
            &[
                demo_robot(2, 10, 1, "/tmp/robot1"),
                demo_robot(4, 10, 2, "/tmp/robot2"),
            ],
            "done",
        );
        let rec = Recording::parse_strict(&both).unwrap();
        let opts = AppOptions {
            port_label: "replay".into(),
            arena: None,
            ..AppOptions::default()
        };
        ReplaySession::new(rec, "two.rec", opts, 1.0)
    }

    fn press(s: &mut ReplaySession, code: KeyCode, modifiers: KeyModifiers) {
        s.event(0, &Event::Key(KeyEvent::new(code, modifiers)));
    }

    #[test]
    fn a_file_of_two_robots_replays_both_and_the_picker_chooses_whose_panels() {
        let mut s = two_robots();
        assert_eq!(s.robots(), 2);
        // The longer robot's length: robot 2 was recorded for 4 s.
        assert!(
            s.player.duration_us() > 3_900_000,
            "{}",
            s.player.duration_us()
        );
        s.sync(3_000_000);
        // Both robots are fed, each from its own link: robot 1's recording ends at 2 s.
        let t = |s: &ReplaySession, i: usize| s.fleet().members[i].app.telemetry.map(|t| t.time_ms);
        assert_eq!(t(&s, 0), Some(1900));
        assert!(t(&s, 1).unwrap() > 2500, "{:?}", t(&s, 1));
        assert!(s
            .fleet()
            .members
            .iter()
            .all(|m| m.app.peer.is_some() && !m.app.believed.is_empty()));
        // The fleet overlay: both robots on the selected robot's screen.
        let f = s.app().fleet.clone().unwrap();
        assert_eq!(f.robots.len(), 2);
        assert!(f
            .robots
            .iter()
            .all(|r| r.pose.is_some() && !r.track.is_empty()));
        let note = "two.rec holds 2 robots (links); these panels are robot 1 (link 0)";
        assert!(
            logged(&s).iter().any(|l| l.contains(note)),
            "{:?}",
            logged(&s)
        );
        // Ids 1 and 2: no duplicate warning.
        assert!(!logged(&s).iter().any(|l| l.contains("is stated by")));
        // Tab picks robot 2 (views stay on F1-F7); Alt-1 back; `!` stops nothing.
        press(&mut s, KeyCode::Tab, KeyModifiers::NONE);
        assert_eq!(s.fleet().selected(), 1);
        assert_eq!(s.app().view, View::Dashboard);
        assert!(logged(&s)
            .iter()
            .any(|l| l.contains("these panels are robot 2")));
        press(&mut s, KeyCode::Char('!'), KeyModifiers::NONE);
        for m in &mut s.fleet.members {
            assert!(m.app.take_outbox().is_empty());
        }
        // Seeking back rebuilds every app: the selection and the notes stay.
        s.player.seek(3_000_000, 0);
        s.sync(3_000_001);
        assert_eq!(s.fleet().selected(), 1);
        assert!(logged(&s)
            .iter()
            .any(|l| l.contains("these panels are robot 2")));
        press(&mut s, KeyCode::Char('1'), KeyModifiers::ALT);
        assert_eq!(s.fleet().selected(), 0);
        // Alt-1 is the picker's, not the speed key's.
        assert_eq!(s.player.speed(), 1.0);
    }

    #[test]
    fn a_version_1_file_is_one_robot_with_no_fleet() {
        let rec = Recording::parse_strict(&crate::record::synth::demo(2, 10)).unwrap();
        let opts = AppOptions {
            port_label: "replay".into(),
            arena: None,
            ..AppOptions::default()
        };
        let mut s = ReplaySession::new(rec, "one.rec", opts, 1.0);
        s.sync(1_000_000);
        assert_eq!(s.robots(), 1);
        assert!(s.app().fleet.is_none());
        press(&mut s, KeyCode::Tab, KeyModifiers::NONE);
        assert_ne!(s.app().view, View::Dashboard, "Tab is still the next view");
        assert!(!logged(&s).iter().any(|l| l.contains("holds")));
    }
}
