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
use super::ReplayFeed;
use crate::action::Action;
use crate::app::log::{Level, LogLine, Source};
use crate::app::{App, AppOptions, View};
use crate::record::Recording;

/// Longest wall time between two progress-bar updates while playing, µs.
pub const BAR_REFRESH_US: u64 = 100_000;

/// A replay in progress.
pub struct ReplaySession {
    rec: Recording,
    /// Links in the file: a file of several shows its first (the fleet view takes the rest).
    links: usize,
    file: String,
    opts: AppOptions,
    pub app: App,
    feed: ReplayFeed,
    pub player: Player,
    pub help: bool,
    pub quit: bool,
    actions: Vec<Action>,
    /// `--retrace`: drawn over the map and noted in the log after every restart.
    retrace: Option<std::sync::Arc<crate::retrace::overlay::RetraceOverlay>>,
}

impl ReplaySession {
    /// A session at the start of `rec`, playing at `speed`. `file` names it on screen.
    /// A file of several links replays its first link (link 0), and its log says how many
    /// robots the file holds.
    pub fn new(rec: Recording, file: &str, opts: AppOptions, speed: f64) -> ReplaySession {
        let links = rec.link_count();
        let rec = if links > 1 { rec.link(0) } else { rec };
        let player = Player::new(rec.duration_us(), speed);
        let feed = ReplayFeed::new(&rec.meta.port);
        let mut app = App::new(opts.clone());
        app.replaying = true;
        notes(&mut app, &rec, file, links);
        ReplaySession {
            rec,
            links,
            file: file.to_string(),
            opts,
            app,
            feed,
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

    pub fn recording(&self) -> &Recording {
        &self.rec
    }

    /// Brings the app to the player's position; true when the app changed.
    pub fn sync(&mut self, wall_us: u64) -> bool {
        self.player.settle(wall_us);
        let target = self.player.position(wall_us);
        let mut changed = false;
        if target < self.feed.position_us() {
            self.restart();
            changed = true;
        }
        self.actions.clear();
        self.feed
            .advance_to(&self.rec.records, target, &mut self.actions);
        for a in self.actions.drain(..) {
            changed |= !matches!(a, Action::Tick { .. });
            self.app.update(a);
        }
        // Nothing the app might want to send goes anywhere: neither commands nor the transfer
        // engine's answers to recorded chunks (kept, they would pile up while exploring).
        let _ = self.app.take_outbox();
        let _ = self.app.transfers.take_frames();
        changed
    }

    /// A fresh app and feed at time 0, keeping what the operator chose to look at.
    fn restart(&mut self) {
        let mut app = App::new(self.opts.clone());
        app.replaying = true;
        app.retrace = self.retrace.clone();
        app.size = self.app.size;
        app.view = self.app.view;
        app.chart = self.app.chart;
        app.map.hidden = std::mem::take(&mut self.app.map.hidden);
        notes(&mut app, &self.rec, &self.file, self.links);
        self.app = app;
        self.feed = ReplayFeed::new(&self.rec.meta.port);
    }

    /// When the loop should wake next to keep up (None: paused, nothing to do).
    pub fn next_wake(&self, wall_us: u64) -> Option<u64> {
        if self.player.paused() {
            return None;
        }
        let bar = wall_us + BAR_REFRESH_US;
        let next_record = self
            .rec
            .records
            .get(self.feed.next_index())
            .and_then(|r| self.player.wall_at(r.t_us));
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
            damage_offset: self.rec.damage.as_ref().map(|d| d.offset()),
            file: &self.file,
        }
    }

    /// Draws the screen.
    pub fn render(&self, frame: &mut Frame, wall_us: u64) {
        screen::render(&self.app, &self.status(wall_us), frame);
    }

    /// Handles a terminal event; true when the screen needs drawing.
    pub fn event(&mut self, wall_us: u64, ev: &Event) -> bool {
        match ev {
            Event::Resize(w, h) => {
                self.app.update(Action::Resize {
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
                    self.app.update(Action::LogScroll(3));
                    true
                }
                MouseEventKind::ScrollDown => {
                    self.app.update(Action::LogScroll(-3));
                    true
                }
                _ => false,
            },
            _ => false,
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
                if let Some(a) = view_action(&self.app, code) {
                    self.app.update(a);
                }
            }
        }
    }
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

/// The lines a replay's log starts with: what is replayed, how many robots the file holds,
/// and any damage.
fn notes(app: &mut App, rec: &Recording, file: &str, links: usize) {
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
            Level::Warn,
            format!(
                "{file} holds {links} robots (links); showing the first, {}; \
                 `station replay {file} --summary` reports each",
                rec.meta.port
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
    use crate::record::RecordKind;

    fn logged(s: &ReplaySession) -> Vec<String> {
        s.app.log.shown().iter().map(|l| l.text.clone()).collect()
    }

    #[test]
    fn a_file_of_two_robots_replays_the_first_and_says_it_holds_two() {
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
        };
        let mut s = ReplaySession::new(rec, "two.rec", opts, 1.0);
        assert_eq!(s.recording().meta.port, "/tmp/robot1");
        assert!(s
            .recording()
            .records
            .iter()
            .all(|r| r.link == 0 || r.kind == RecordKind::End));
        let note = "two.rec holds 2 robots (links); showing the first, /tmp/robot1";
        assert!(
            logged(&s).iter().any(|l| l.contains(note)),
            "{:?}",
            logged(&s)
        );
        // Seeking back rebuilds the app: the note stays.
        s.sync(3_000_000);
        s.player.seek(3_000_000, 0);
        s.sync(3_000_001);
        assert!(
            logged(&s).iter().any(|l| l.contains(note)),
            "{:?}",
            logged(&s)
        );
    }
}
