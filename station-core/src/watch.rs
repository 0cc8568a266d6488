//! The robot as JSON lines, for scripts: `station watch` prints one line per telemetry frame,
//! progress report, event and log line, `station status` one snapshot of the same, and both
//! (with `station send --wait`) end when the link is lost.
//!
//! Layer: formatting over `LinkEvent`s, no I/O. Names and units are the export's: a telemetry
//! line is the MCAP `/telemetry` message's JSON (`export::mcap_msg::Body::Telemetry`, so a
//! sensor the robot lacks is null, not the 0 the wire carries), the CSV's columns by name.
//! Every line is one JSON object whose first keys are `kind`, `time_s` (the station's clock,
//! seconds since the command began) and `robot_time_s` (the robot's clock; progress reports,
//! events and log lines carry none of their own, so theirs is the last telemetry frame's, null
//! before one). `Fields` picks keys out of a line (`--fields`). What can fail: a field name no
//! chosen kind has, refused with the names there are, before any port is opened.

use protocol::{EventCode, Mode, Progress, Telemetry};
use serde::Serialize;
use serde_json::Value;

use crate::export::csv::TelemetryRow;
use crate::export::mcap_msg::Body;
use crate::format::{log_level_name, mode_name, progress_text};
use crate::link::{Connection, LinkEvent};

/// What a line is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Telemetry,
    Progress,
    Event,
    Log,
}

impl Kind {
    pub const ALL: [Kind; 4] = [Kind::Telemetry, Kind::Progress, Kind::Event, Kind::Log];

    /// The name a line's `kind` gives.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Telemetry => "telemetry",
            Kind::Progress => "progress",
            Kind::Event => "event",
            Kind::Log => "log",
        }
    }
}

/// One line: a whole JSON object, no newline.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub kind: Kind,
    pub json: Vec<u8>,
}

impl Line {
    /// The line as a JSON value (for a snapshot, or to pick fields from).
    pub fn value(&self) -> Value {
        serde_json::from_slice(&self.json).unwrap_or(Value::Null)
    }
}

/// Turns link events into lines, keeping the robot's clock from the last telemetry frame.
#[derive(Clone, Debug, Default)]
pub struct Lines {
    /// The robot's capabilities: the sensors it lacks are null.
    caps: Option<u32>,
    robot_time_s: Option<f64>,
}

/// A progress report's line (`Progress` in seconds and metres).
#[derive(Serialize)]
struct ProgressLine<'a> {
    kind: &'static str,
    time_s: f64,
    robot_time_s: Option<f64>,
    mode: &'static str,
    /// Plan execution: the waypoint driven to, 1-based, and the plan's count; else 0.
    waypoint: u16,
    waypoints: u16,
    distance_left_m: Option<f64>,
    elapsed_s: f64,
    stuck_s: f64,
    /// Null: the mode does not give up.
    give_up_s: Option<f64>,
    text: Option<&'a str>,
}

#[derive(Serialize)]
struct EventLine {
    kind: &'static str,
    time_s: f64,
    robot_time_s: Option<f64>,
    code: String,
    /// The event's name and sentence, as the export's `/events` and the station's log say it.
    name: &'static str,
    text: String,
    value: i32,
    /// `ModeChanged`: the new mode's name.
    #[serde(skip_serializing_if = "Option::is_none")]
    mode: Option<String>,
}

#[derive(Serialize)]
struct LogLine<'a> {
    kind: &'static str,
    time_s: f64,
    robot_time_s: Option<f64>,
    level: &'static str,
    text: &'a str,
}

impl Lines {
    /// Lines for a robot with capability bits `caps` (`None`: unknown, every sensor shown).
    pub fn new(caps: Option<u32>) -> Lines {
        Lines {
            caps,
            robot_time_s: None,
        }
    }

    /// The line for `ev`, received `t_us` into the command; `None` for what is not a line.
    pub fn line(&mut self, t_us: u64, ev: &LinkEvent) -> Option<Line> {
        let time_s = t_us as f64 / 1e6;
        let (kind, json) = match ev {
            LinkEvent::Telemetry(t) => (Kind::Telemetry, self.telemetry(t_us, t)),
            LinkEvent::Progress(p) => (Kind::Progress, self.progress(time_s, p)),
            LinkEvent::Robot(e) => {
                let line = EventLine {
                    kind: Kind::Event.name(),
                    time_s,
                    robot_time_s: self.robot_time_s,
                    code: format!("{:?}", e.code),
                    name: crate::format::event_name(e.code),
                    text: crate::format::event_text(e).1,
                    value: e.value,
                    mode: (e.code == EventCode::ModeChanged)
                        .then(|| crate::format::mode_name_i32(e.value)),
                };
                (Kind::Event, json_bytes(&line))
            }
            LinkEvent::Log { level, text } => {
                let line = LogLine {
                    kind: Kind::Log.name(),
                    time_s,
                    robot_time_s: self.robot_time_s,
                    level: log_level_name(*level),
                    text,
                };
                (Kind::Log, json_bytes(&line))
            }
            _ => return None,
        };
        Some(Line { kind, json })
    }

    fn telemetry(&mut self, t_us: u64, t: &Telemetry) -> Vec<u8> {
        let row = TelemetryRow::new(t_us, t);
        self.robot_time_s = Some(row.robot_time_s);
        let mut body = Vec::with_capacity(640);
        Body::Telemetry {
            row: Box::new(row),
            caps: self.caps,
        }
        .write_json(&mut body);
        // `{"time_s":...}` becomes `{"kind":"telemetry","time_s":...}`.
        let mut out = Vec::with_capacity(body.len() + 20);
        out.extend_from_slice(b"{\"kind\":\"telemetry\",");
        out.extend_from_slice(body.get(1..).unwrap_or_default());
        out
    }

    fn progress(&self, time_s: f64, p: &Progress) -> Vec<u8> {
        let s = |ms: u32| f64::from(ms) / 1000.0;
        let text = progress_text(p, false);
        json_bytes(&ProgressLine {
            kind: Kind::Progress.name(),
            time_s,
            robot_time_s: self.robot_time_s,
            mode: mode_name(p.mode),
            waypoint: p.waypoint,
            waypoints: p.waypoints,
            distance_left_m: p.distance_left_mm.map(s),
            elapsed_s: s(p.elapsed_ms),
            stuck_s: s(p.stuck_ms),
            give_up_s: (p.give_up_ms > 0).then(|| s(p.give_up_ms)),
            text: text.as_deref(),
        })
    }
}

/// `v` as one line of JSON (a struct of numbers and strings: writing it cannot fail).
fn json_bytes<T: Serialize>(v: &T) -> Vec<u8> {
    let mut out = Vec::with_capacity(160);
    let _ = crate::json_text::write(&mut out, v);
    out
}

/// The keys a line of `kind` has, in order.
pub fn keys(kind: Kind) -> Vec<String> {
    let mut lines = Lines::new(None);
    let progress = Progress {
        mode: Mode::GoTo,
        waypoint: 0,
        waypoints: 0,
        distance_left_mm: None,
        elapsed_ms: 0,
        stuck_ms: 0,
        give_up_ms: 0,
    };
    let ev = match kind {
        Kind::Telemetry => LinkEvent::Telemetry(Telemetry::default()),
        Kind::Progress => LinkEvent::Progress(progress),
        Kind::Event => LinkEvent::Robot(protocol::Event {
            code: EventCode::ModeChanged,
            value: 0,
        }),
        Kind::Log => LinkEvent::Log {
            level: protocol::LogLevel::Info,
            text: String::new(),
        },
    };
    let Some(line) = lines.line(0, &ev) else {
        return Vec::new();
    };
    // serde_json's map is sorted; the line's own order is the order its keys appear in.
    let text = String::from_utf8_lossy(&line.json).into_owned();
    let mut found: Vec<(usize, String)> = match line.value() {
        Value::Object(m) => m
            .keys()
            .map(|k| {
                (
                    text.find(&format!("\"{k}\":")).unwrap_or(usize::MAX),
                    k.clone(),
                )
            })
            .collect(),
        _ => Vec::new(),
    };
    found.sort();
    found.into_iter().map(|(_, k)| k).collect()
}

/// Keys picked out of each line (`--fields x_m,y_m,ir.3`): a dotted name goes into an object
/// or an array. A line keeps its `kind` and the picked keys it has, in the order given; a line
/// with none of them is left out.
#[derive(Clone, Debug, PartialEq)]
pub struct Fields(Vec<String>);

impl Fields {
    /// The comma-separated names in `list`, each checked against the keys of the `kinds` lines.
    pub fn parse(list: &str, kinds: &[Kind]) -> Result<Fields, String> {
        // Every line keeps its `kind` anyway: naming it again would write the key twice.
        let names: Vec<String> = list
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty() && s != "kind")
            .collect();
        if names.is_empty() {
            return Err("--fields names no field (e.g. --fields x_m,y_m,heading_rad)".into());
        }
        let known: Vec<(Kind, Vec<String>)> = kinds.iter().map(|&k| (k, keys(k))).collect();
        for name in &names {
            let top = name.split('.').next().unwrap_or(name);
            if known.iter().any(|(_, ks)| ks.iter().any(|k| k == top)) {
                continue;
            }
            let listed: Vec<String> = known
                .iter()
                .map(|(k, ks)| format!("{}: {}", k.name(), ks.join(", ")))
                .collect();
            return Err(format!(
                "--fields: no line has {:?}; the keys are ({})",
                crate::terminal_text::printable(name),
                listed.join("; ")
            ));
        }
        Ok(Fields(names))
    }

    /// `line` with only its kind and the picked keys; `None` when it has none of them.
    pub fn pick(&self, line: &Line) -> Option<Vec<u8>> {
        let v = line.value();
        let mut out = Vec::with_capacity(64);
        out.extend_from_slice(b"{\"kind\":");
        let _ = crate::json_text::write(&mut out, line.kind.name());
        let mut any = false;
        for name in &self.0 {
            let Some(found) = pick(&v, name) else {
                continue;
            };
            out.push(b',');
            let _ = crate::json_text::write(&mut out, name.as_str());
            out.push(b':');
            let _ = crate::json_text::write(&mut out, found);
            any = true;
        }
        out.push(b'}');
        any.then_some(out)
    }
}

/// The value at dotted `path` in `v` (an object key or an array index at each step).
fn pick<'a>(v: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('.').try_fold(v, |at, step| match at {
        Value::Object(m) => m.get(step),
        Value::Array(a) => a.get(step.parse::<usize>().ok()?),
        _ => None,
    })
}

/// How long a session may be gone before the link counts as lost: a renewal (PROTOCOL.md §7)
/// handshakes again within a round trip, so a link that is not back by then is not renewing.
pub const RECONNECT_GRACE_US: u64 = 2_000_000;

/// Tells a lost link from a renewed session: a closed or refused port is lost at once; a
/// session that ends (a renewal, or 1.5 s of the robot's silence) is lost unless the link is
/// connected again within `RECONNECT_GRACE_US`.
#[derive(Clone, Debug, Default)]
pub struct LinkLoss {
    /// Since when the session is gone, and why.
    gone: Option<(u64, String)>,
}

impl LinkLoss {
    /// A connection change at `t_us`; `Some(reason)` when the link is lost.
    pub fn on_connection(&mut self, t_us: u64, c: &Connection) -> Option<String> {
        match c {
            Connection::Connected(_) => {
                self.gone = None;
                None
            }
            Connection::Closed { reason } => Some(format!("the port closed: {reason}")),
            Connection::Refused { message } => Some(format!("the robot refused us: {message}")),
            Connection::Handshaking { .. } => {
                if self.gone.is_none() {
                    self.gone = Some((t_us, "the session ended".into()));
                }
                None
            }
        }
    }

    /// When `poll` must next be called, if a session is gone.
    pub fn deadline_us(&self) -> Option<u64> {
        self.gone
            .as_ref()
            .map(|(since, _)| since + RECONNECT_GRACE_US)
    }

    /// `Some(reason)` when the session has been gone longer than the grace at `t_us`.
    pub fn poll(&self, t_us: u64) -> Option<String> {
        let (since, why) = self.gone.as_ref()?;
        (t_us >= since + RECONNECT_GRACE_US).then(|| {
            format!(
                "{why} and no handshake followed within {} s (the robot is silent or gone)",
                RECONNECT_GRACE_US / 1_000_000
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Event, LogLevel, Pose};

    fn text(l: &Line) -> String {
        String::from_utf8(l.json.clone()).unwrap()
    }

    #[test]
    fn every_line_starts_with_its_kind_and_times_and_reads_back_as_json() {
        let mut lines = Lines::new(Some(0));
        let ev = LinkEvent::Robot(Event {
            code: EventCode::GoalReached,
            value: 0,
        });
        let before = lines.line(500_000, &ev).unwrap();
        assert_eq!(
            text(&before),
            r#"{"kind":"event","time_s":0.5,"robot_time_s":null,"code":"GoalReached","name":"goal reached","text":"goal reached: the robot arrived","value":0}"#
        );
        let t = Telemetry {
            time_ms: 12_345,
            pose: Pose {
                x_mm: 1500,
                y_mm: -250,
                heading_mrad: 1571,
            },
            ..Telemetry::default()
        };
        let tel = lines.line(1_250_000, &LinkEvent::Telemetry(t)).unwrap();
        let s = text(&tel);
        assert!(
            s.starts_with(r#"{"kind":"telemetry","time_s":1.25,"robot_time_s":12.345,"mode":"Idle","x_m":1.5,"y_m":-0.25,"heading_rad":1.571,"#),
            "{s}"
        );
        // The robot has none of the sensors (caps 0): their readings are null.
        let v = tel.value();
        assert!(v["ir"].is_null() && v["compass_deg"].is_null(), "{s}");
        // Lines after a telemetry frame carry its robot time.
        let log = lines
            .line(
                2_000_000,
                &LinkEvent::Log {
                    level: LogLevel::Warn,
                    text: "wheel \u{9b}slip".into(),
                },
            )
            .unwrap();
        assert_eq!(
            text(&log),
            r#"{"kind":"log","time_s":2.0,"robot_time_s":12.345,"level":"warn","text":"wheel \u009bslip"}"#
        );
        let mode = lines
            .line(
                2_100_000,
                &LinkEvent::Robot(Event {
                    code: EventCode::ModeChanged,
                    value: 2,
                }),
            )
            .unwrap();
        assert_eq!(mode.value()["mode"], "GoTo");
        let p = Progress {
            mode: Mode::ExecutePlan,
            waypoint: 2,
            waypoints: 5,
            distance_left_mm: Some(1234),
            elapsed_ms: 14_000,
            stuck_ms: 0,
            give_up_ms: 120_000,
        };
        let prog = lines.line(3_000_000, &LinkEvent::Progress(p)).unwrap();
        assert_eq!(
            text(&prog),
            r#"{"kind":"progress","time_s":3.0,"robot_time_s":12.345,"mode":"ExecutePlan","waypoint":2,"waypoints":5,"distance_left_m":1.234,"elapsed_s":14.0,"stuck_s":0.0,"give_up_s":120.0,"text":"waypoint 2 of 5, 1.2 m left, 14 s"}"#
        );
        assert!(lines
            .line(0, &LinkEvent::Truth(Default::default()))
            .is_none());
    }

    #[test]
    fn fields_pick_keys_in_the_order_given_and_refuse_names_no_line_has() {
        let mut lines = Lines::new(None);
        let t = Telemetry {
            pose: Pose {
                x_mm: 100,
                y_mm: 200,
                heading_mrad: 0,
            },
            ..Telemetry::default()
        };
        let tel = lines.line(0, &LinkEvent::Telemetry(t)).unwrap();
        let f = Fields::parse("y_m, x_m,ir.2", &Kind::ALL).unwrap();
        assert_eq!(
            String::from_utf8(f.pick(&tel).unwrap()).unwrap(),
            r#"{"kind":"telemetry","y_m":0.2,"x_m":0.1,"ir.2":0}"#
        );
        // An event has none of them: left out.
        let ev = LinkEvent::Robot(Event {
            code: EventCode::Collision,
            value: 0,
        });
        assert_eq!(f.pick(&lines.line(0, &ev).unwrap()), None);
        let e = Fields::parse("pose.x", &[Kind::Telemetry]).unwrap_err();
        assert!(
            e.contains("no line has \"pose.x\"") && e.contains("x_m, y_m"),
            "{e}"
        );
        assert!(Fields::parse(" , ", &Kind::ALL).is_err());
        let f = Fields::parse("kind,x_m", &Kind::ALL).unwrap();
        assert_eq!(
            String::from_utf8(f.pick(&tel).unwrap()).unwrap(),
            r#"{"kind":"telemetry","x_m":0.1}"#
        );
        // A key of a kind not chosen is refused too.
        assert!(Fields::parse("level", &[Kind::Telemetry]).is_err());
        assert!(Fields::parse("level", &[Kind::Log]).is_ok());
    }

    #[test]
    fn keys_are_in_line_order() {
        let k = keys(Kind::Telemetry);
        assert_eq!(&k[..4], ["kind", "time_s", "robot_time_s", "mode"]);
        assert_eq!(
            keys(Kind::Log),
            ["kind", "time_s", "robot_time_s", "level", "text"]
        );
    }

    #[test]
    fn a_session_that_comes_back_within_the_grace_is_not_a_lost_link() {
        let mut l = LinkLoss::default();
        let hs = Connection::Handshaking { port: "p".into() };
        assert_eq!(l.on_connection(1_000, &hs), None);
        assert_eq!(l.deadline_us(), Some(1_000 + RECONNECT_GRACE_US));
        assert_eq!(l.poll(1_000 + RECONNECT_GRACE_US - 1), None);
        assert!(l.poll(1_000 + RECONNECT_GRACE_US).is_some());
        let closed = Connection::Closed {
            reason: "gone".into(),
        };
        assert!(l.on_connection(5, &closed).unwrap().contains("gone"));
    }
}
