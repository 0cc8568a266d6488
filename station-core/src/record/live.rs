//! Recording a live link: the link task's tap (every byte both ways), its connection changes
//! and the lines the station logs about it, turned into records on one clock.
//!
//! Layer: glue between the link's outputs and `RecordWriter`, used by `station record` and by
//! the TUI's record key. The tap stamps bytes with the link task's clock (µs since the task
//! started); connection changes are stamped when they arrive, on the same clock (`epoch` is
//! taken just before the link is spawned, so both clocks agree within microseconds). A
//! recording started while a port is open begins the robot's bytes at a frame boundary (the
//! bytes up to the first 0x00, the tail of a frame already half received, are skipped; the
//! station's own writes are whole frames) and with a link record
//! of the current state, so a replay knows the robot without having seen the handshake.
//! `TuiRecorder` is the TUI's record key around it. What can fail: the writer's file I/O
//! (`RecordError`), reported to the app as a `RecordingNote`, never a panic.

use std::path::Path;

use serde::Serialize;
use tokio::time::Instant;

use super::writer::{RecordWriter, Written};
use super::{LinkState, Meta, RecordError, RecordKind, StationLine};
use crate::link::{Connection, PeerInfo, TapDirection, TapRecord};

/// Byte and event counts of a recording in progress.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct LiveCounts {
    pub bytes_from_robot: u64,
    pub bytes_to_robot: u64,
    pub link_events: u64,
    /// Times the session was lost (left `connected`).
    pub gaps: u64,
    /// Whether a session was up at any time.
    pub connected: bool,
}

/// A recording of running links (one, or a fleet's several into one file).
pub struct LiveRecorder {
    writer: RecordWriter,
    /// The recording's time 0.
    start: Instant,
    links: Vec<LinkTrack>,
}

/// One link's side of a recording.
struct LinkTrack {
    /// The link task's clock origin: its tap stamps bytes in µs since then.
    epoch: Instant,
    /// Skip bytes up to the first delimiter, per direction (from robot, to robot).
    align: [bool; 2],
    was_connected: bool,
    counts: LiveCounts,
}

impl LiveRecorder {
    /// Starts recording one link to `path` (written as `path.partial`). `epoch` is the link's
    /// clock origin; `current` the connection state now.
    pub fn start(
        path: &Path,
        meta: &Meta,
        overwrite: bool,
        epoch: Instant,
        current: &Connection,
    ) -> Result<LiveRecorder, RecordError> {
        LiveRecorder::start_links(path, meta, overwrite, &[(epoch, current.clone())])
    }

    /// Starts recording several links into one file: link `i` is `links[i]` (its clock origin
    /// and its connection state now) and `meta.links[i]`.
    pub fn start_links(
        path: &Path,
        meta: &Meta,
        overwrite: bool,
        links: &[(Instant, Connection)],
    ) -> Result<LiveRecorder, RecordError> {
        let writer = RecordWriter::create(path, meta, overwrite)?;
        let mut r = LiveRecorder {
            writer,
            start: Instant::now(),
            links: links
                .iter()
                .map(|(epoch, current)| LinkTrack {
                    epoch: *epoch,
                    // The station writes whole frames; the robot's bytes arrive in arbitrary
                    // pieces.
                    align: [!matches!(current, Connection::Closed { .. }), false],
                    was_connected: false,
                    counts: LiveCounts::default(),
                })
                .collect(),
        };
        for (i, (_, current)) in links.iter().enumerate() {
            if !matches!(current, Connection::Closed { .. }) {
                r.on_link_connection(link_id(i), current)?;
            }
        }
        Ok(r)
    }

    /// The final name.
    pub fn path(&self) -> &Path {
        self.writer.path()
    }

    /// Recording time now, µs.
    pub fn elapsed_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    /// Counts over every link.
    pub fn counts(&self) -> LiveCounts {
        let mut all = LiveCounts::default();
        for c in self.link_counts() {
            all.bytes_from_robot += c.bytes_from_robot;
            all.bytes_to_robot += c.bytes_to_robot;
            all.link_events += c.link_events;
            all.gaps += c.gaps;
            all.connected |= c.connected;
        }
        all
    }

    /// Counts of each link, by link id.
    pub fn link_counts(&self) -> Vec<LiveCounts> {
        self.links.iter().map(|l| l.counts).collect()
    }

    /// Records bytes tapped from link 0.
    pub fn on_tap(&mut self, rec: &TapRecord) -> Result<(), RecordError> {
        self.on_link_tap(0, rec)
    }

    /// Records bytes tapped from link `link`, on the recording's clock.
    pub fn on_link_tap(&mut self, link: u8, rec: &TapRecord) -> Result<(), RecordError> {
        let start = self.start;
        let Some(track) = self.links.get_mut(usize::from(link)) else {
            return Ok(());
        };
        let (kind, i) = match rec.direction {
            TapDirection::FromRobot => (RecordKind::FromRobot, 0),
            TapDirection::ToRobot => (RecordKind::ToRobot, 1),
        };
        let mut bytes = rec.bytes.as_slice();
        if track.align.get(i).copied().unwrap_or(false) {
            match bytes.iter().position(|&b| b == 0) {
                Some(p) => {
                    bytes = bytes.get(p + 1..).unwrap_or(&[]);
                    if let Some(a) = track.align.get_mut(i) {
                        *a = false;
                    }
                }
                None => return Ok(()),
            }
        }
        if bytes.is_empty() {
            return Ok(());
        }
        match kind {
            RecordKind::FromRobot => track.counts.bytes_from_robot += bytes.len() as u64,
            _ => track.counts.bytes_to_robot += bytes.len() as u64,
        }
        // The link's clock to the recording's: the two origins differ by the moments the
        // link task and the recording started.
        let t = if track.epoch >= start {
            rec.t_us
                .saturating_add(track.epoch.duration_since(start).as_micros() as u64)
        } else {
            rec.t_us
                .saturating_sub(start.duration_since(track.epoch).as_micros() as u64)
        };
        self.writer.append_link(t, kind, link, bytes)
    }

    /// Records a connection change of link 0 (a gap marker when the session is lost).
    pub fn on_connection(&mut self, c: &Connection) -> Result<(), RecordError> {
        self.on_link_connection(0, c)
    }

    /// Records a connection change of link `link`.
    pub fn on_link_connection(&mut self, link: u8, c: &Connection) -> Result<(), RecordError> {
        let t = self.elapsed_us();
        let Some(track) = self.links.get_mut(usize::from(link)) else {
            return Ok(());
        };
        let (state, text) = link_record(c);
        let connected = state == LinkState::Connected;
        if track.was_connected && !connected {
            track.counts.gaps += 1;
        }
        track.was_connected = connected;
        track.counts.connected |= connected;
        track.counts.link_events += 1;
        let mut data = Vec::with_capacity(1 + text.len());
        data.push(state.code());
        data.extend_from_slice(text.as_bytes());
        self.writer.append_link(t, RecordKind::Link, link, &data)
    }

    /// Records a line the station logged about link `link` (a refusal, a give-up, an event
    /// in its words), now.
    pub fn on_station_log(&mut self, link: u8, line: &StationLine) -> Result<(), RecordError> {
        if usize::from(link) >= self.links.len() {
            return Ok(());
        }
        let t = self.elapsed_us();
        self.writer
            .append_link(t, RecordKind::StationLog, link, &line.encode())
    }

    /// Flushes and syncs when due.
    pub fn tick(&mut self, now: Instant) -> Result<(), RecordError> {
        self.writer.tick(now)
    }

    /// Ends the recording cleanly: end record, sync, rename.
    pub fn finish(self, reason: &str) -> Result<Written, RecordError> {
        let t = self.elapsed_us().max(self.writer.last_t_us());
        self.writer.finish(t, reason)
    }
}

/// Link index `i` as a record's link id (a recording holds at most `MAX_LINKS`).
fn link_id(i: usize) -> u8 {
    u8::try_from(i).unwrap_or(u8::MAX)
}

/// What a `Link` record says for a connection state. A connected state carries the robot as a
/// JSON object (`PeerRecord`), so a replay can show it even without the handshake's frames.
pub fn link_record(c: &Connection) -> (LinkState, String) {
    match c {
        Connection::Closed { reason } => (LinkState::Closed, reason.clone()),
        Connection::Handshaking { port } => (LinkState::Handshaking, port.clone()),
        Connection::Connected(p) => (
            LinkState::Connected,
            crate::json_text::compact(&PeerRecord::from(p)).unwrap_or_default(),
        ),
        Connection::Refused { message } => (LinkState::Refused, message.clone()),
    }
}

/// The robot of a `connected` link record, as JSON.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct PeerRecord {
    pub session: u32,
    pub firmware: String,
    pub firmware_version: String,
    /// "Khepera" or "MicroRato".
    pub profile: protocol::ProfileId,
    pub capabilities: u32,
    pub map_capacity: [u16; 2],
    pub telemetry_hz: u8,
    pub failsafe_ms: u16,
    /// The robot's id from its handshake; absent in recordings made before robots had ids
    /// (they were all robot 1, the firmware's default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot_id: Option<u8>,
}

impl From<&PeerInfo> for PeerRecord {
    fn from(p: &PeerInfo) -> Self {
        PeerRecord {
            session: p.session,
            firmware: p.firmware.clone(),
            firmware_version: p.firmware_version.clone(),
            profile: p.profile,
            capabilities: p.capabilities,
            map_capacity: [p.map_capacity.width, p.map_capacity.height],
            telemetry_hz: p.telemetry_hz,
            failsafe_ms: p.failsafe_ms,
            robot_id: Some(p.robot_id),
        }
    }
}

impl PeerRecord {
    /// Back to the link's type.
    pub fn to_peer(&self) -> PeerInfo {
        PeerInfo {
            session: self.session,
            firmware: self.firmware.clone(),
            firmware_version: self.firmware_version.clone(),
            profile: self.profile,
            capabilities: self.capabilities,
            map_capacity: protocol::MapCapacity {
                width: self.map_capacity[0],
                height: self.map_capacity[1],
            },
            telemetry_hz: self.telemetry_hz,
            failsafe_ms: self.failsafe_ms,
            robot_id: self
                .robot_id
                .unwrap_or(robot_firmware::params::DEFAULT_ROBOT_ID),
        }
    }
}

/// What the TUI's recorder tells the app.
#[derive(Clone, Debug, PartialEq)]
pub enum RecordingNote {
    /// Recording to `file` started, of `links` links (a fleet's robots all in one file).
    Started { file: String, links: usize },
    /// The recording was finished and renamed to `file`.
    Stopped {
        file: String,
        seconds: f64,
        bytes: u64,
    },
    /// Recording could not start, or stopped on an error (what was written is kept).
    Failed { why: String },
}

/// The TUI's record key: the links' taps, always drained, written to one file while recording
/// (a fleet's links all into one, link `i` as link id `i`).
///
/// Layer: I/O, owned by the TUI loop (the I/O edge); the app only hears `RecordingNote`s. The
/// loop drains the taps whenever it wakes (link events come with every read, ticks 20 times a
/// second), so the channels stay short; taps arriving while not recording are dropped.
pub struct TuiRecorder {
    links: Vec<TapLink>,
    meta: Meta,
    /// Where recordings go, or why there is nowhere.
    dir: Result<std::path::PathBuf, String>,
    active: Option<LiveRecorder>,
}

/// One recorded link: its tap, its clock origin, its connection state now (so a recording
/// started mid-session knows the robot).
struct TapLink {
    tap: tokio::sync::mpsc::UnboundedReceiver<TapRecord>,
    epoch: Instant,
    connection: Connection,
}

impl TuiRecorder {
    /// A recorder over a link started at `epoch` with this tap; `meta` describes the port.
    pub fn new(
        tap: tokio::sync::mpsc::UnboundedReceiver<TapRecord>,
        epoch: Instant,
        meta: Meta,
    ) -> TuiRecorder {
        TuiRecorder::new_links(vec![(tap, epoch)], meta)
    }

    /// A recorder over several links, by link id: each one's tap and clock origin. `meta`
    /// names them (`Meta::now_links`).
    pub fn new_links(
        taps: Vec<(tokio::sync::mpsc::UnboundedReceiver<TapRecord>, Instant)>,
        meta: Meta,
    ) -> TuiRecorder {
        TuiRecorder {
            links: taps
                .into_iter()
                .map(|(tap, epoch)| TapLink {
                    tap,
                    epoch,
                    connection: Connection::Closed {
                        reason: "starting".into(),
                    },
                })
                .collect(),
            meta,
            dir: Ok(std::path::PathBuf::from(".")),
            active: None,
        }
    }

    /// A recorder that cannot record (no tap).
    pub fn disabled() -> TuiRecorder {
        TuiRecorder::new_links(Vec::new(), Meta::default())
    }

    /// Records into `dir` instead of the current directory; `dir` is created (owner only)
    /// when a recording starts.
    pub fn in_dir(mut self, dir: &Path) -> TuiRecorder {
        self.dir = Ok(dir.to_path_buf());
        self
    }

    /// Records into `dir`, or, with no directory to record into, refuses each `R` saying
    /// `why` (`record::default_recordings_dir`).
    pub fn in_dir_or(self, dir: Result<std::path::PathBuf, String>) -> TuiRecorder {
        TuiRecorder { dir, ..self }
    }

    pub fn recording(&self) -> bool {
        self.active.is_some()
    }

    /// Takes every tapped record waiting on every link (recording them if recording,
    /// dropping them if not); call whenever the loop wakes. The records carry their own times.
    pub fn drain_taps(&mut self) -> Option<RecordingNote> {
        let mut note = None;
        for i in 0..self.links.len() {
            while let Some(t) = self.links.get_mut(i).and_then(|l| l.tap.try_recv().ok()) {
                if let Some(n) = self.on_link_tap(i, &t) {
                    note = Some(n);
                }
            }
        }
        note
    }

    /// Records bytes tapped from link 0 if recording.
    pub fn on_tap(&mut self, t: &TapRecord) -> Option<RecordingNote> {
        self.on_link_tap(0, t)
    }

    fn on_link_tap(&mut self, link: usize, t: &TapRecord) -> Option<RecordingNote> {
        let r = self.active.as_mut()?.on_link_tap(link_id(link), t);
        self.check(r)
    }

    /// Notes a link event of link 0: connection changes are recorded.
    pub fn on_link_event(&mut self, ev: &crate::link::LinkEvent) -> Option<RecordingNote> {
        self.on_event_of(0, ev)
    }

    /// Notes a link event of link `link`: connection changes are recorded.
    pub fn on_event_of(
        &mut self,
        link: usize,
        ev: &crate::link::LinkEvent,
    ) -> Option<RecordingNote> {
        let crate::link::LinkEvent::Connection(c) = ev else {
            return None;
        };
        self.links.get_mut(link)?.connection = c.clone();
        let r = self.active.as_mut()?.on_link_connection(link_id(link), c);
        self.check(r)
    }

    /// Records a line the station logged about robot `link`, if recording.
    pub fn on_station_log(&mut self, link: usize, line: &StationLine) -> Option<RecordingNote> {
        let r = self.active.as_mut()?.on_station_log(link_id(link), line);
        self.check(r)
    }

    /// Flushes when due.
    pub fn tick(&mut self) -> Option<RecordingNote> {
        let r = self.active.as_mut()?.tick(Instant::now());
        self.check(r)
    }

    fn check(&mut self, r: Result<(), RecordError>) -> Option<RecordingNote> {
        let e = r.err()?;
        let path = self.active.take().map(|a| a.path().to_path_buf());
        Some(RecordingNote::Failed {
            why: format!(
                "{e}; what was written is in {}",
                path.map(|p| super::partial_path(&p).display().to_string())
                    .unwrap_or_default()
            ),
        })
    }

    /// Starts a recording to a new timestamped file, or finishes the one running.
    pub fn toggle(&mut self) -> RecordingNote {
        match self.stop() {
            Some(note) => note,
            None => self.start(),
        }
    }

    fn start(&mut self) -> RecordingNote {
        if self.links.is_empty() {
            return RecordingNote::Failed {
                why: "this link has no tap to record".into(),
            };
        }
        let dir = match &self.dir {
            Ok(d) => d.clone(),
            Err(why) => {
                return RecordingNote::Failed {
                    why: format!("cannot record: {why}"),
                }
            }
        };
        if let Err(e) = super::create_private_dir(&dir) {
            return RecordingNote::Failed {
                why: format!("cannot record: cannot create {}: {e}", dir.display()),
            };
        }
        let mut meta = self.meta.clone();
        let now = Meta::now(&meta.port, meta.baud);
        meta.created_unix_ms = now.created_unix_ms;
        let path = free_name(&dir, meta.created_unix_ms);
        let links: Vec<(Instant, Connection)> = self
            .links
            .iter()
            .map(|l| (l.epoch, l.connection.clone()))
            .collect();
        match LiveRecorder::start_links(&path, &meta, false, &links) {
            Ok(r) => {
                self.active = Some(r);
                RecordingNote::Started {
                    file: path.display().to_string(),
                    links: links.len(),
                }
            }
            Err(e) => RecordingNote::Failed {
                why: format!("cannot record: {e}"),
            },
        }
    }

    /// Finishes a running recording (on the key, or when the TUI quits).
    pub fn stop(&mut self) -> Option<RecordingNote> {
        let rec = self.active.take()?;
        let path = rec.path().to_path_buf();
        Some(match rec.finish("stopped by the operator") {
            Ok(w) => RecordingNote::Stopped {
                file: w.path.display().to_string(),
                seconds: w.duration_us as f64 / 1e6,
                bytes: w.bytes,
            },
            Err(e) => RecordingNote::Failed {
                why: format!(
                    "{e}; what was written is in {}",
                    super::partial_path(&path).display()
                ),
            },
        })
    }
}

/// `dir/station-YYYYMMDD-HHMMSS.rec`, with `-2`, `-3`, ... if taken.
fn free_name(dir: &Path, unix_ms: u64) -> std::path::PathBuf {
    let stamp: String = crate::replay::summary::utc(unix_ms)
        .chars()
        .filter(char::is_ascii_digit)
        .collect();
    let (date, time) = stamp.split_at(stamp.len().min(8));
    let base = format!("station-{date}-{time}");
    let join = |name: String| {
        if dir == Path::new(".") {
            std::path::PathBuf::from(name)
        } else {
            dir.join(name)
        }
    };
    let mut path = join(format!("{base}.rec"));
    let mut n = 2;
    while path.exists() || super::partial_path(&path).exists() {
        path = join(format!("{base}-{n}.rec"));
        n += 1;
    }
    path
}
