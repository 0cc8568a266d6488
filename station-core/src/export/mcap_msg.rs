//! The bodies of MCAP messages, typed, and their JSON: what `mcap::write` writes for every
//! topic, through one call (`Body::write`: protobuf by `mcap_proto` on a binary channel, else
//! `Body::write_json`) into the chunk's buffer.
//!
//! Layer: data and JSON text, no I/O. The topics of every frame (`/telemetry`, `/pose`,
//! `/truth`, `/truth_pose`, and `/tf` twice) are typed structs written as text directly: building
//! each as a `serde_json::Value` tree (a map per object, a string per key, all freed again) was
//! most of an export's time, and general float formatting most of the rest. Their numbers are
//! whole mm, mrad, us, ... scaled by a power of ten, written as integers with the point put
//! back (`scaled`), to the character what `serde_json` writes (tests check both, and the whole
//! JSON against the `Serialize` impls here). Topics of the occasional message (events, log
//! lines, commands, the scene's objects) keep `Value`, built where they are made.

use protocol::Pose;
use serde::ser::{SerializeStruct, Serializer};
use serde::Serialize;
use serde_json::Value;

use super::csv::TelemetryRow;
use super::mcap_proto;

/// A message body.
#[derive(Clone, Debug)]
pub enum Body {
    /// `/telemetry`; `caps` (the robot's, once its HelloReply was seen) nulls the sensors it
    /// lacks.
    Telemetry {
        row: Box<TelemetryRow>,
        caps: Option<u32>,
    },
    /// `foxglove.PoseInFrame` (`/pose`, `/truth_pose`).
    Pose(PoseInFrame),
    /// `foxglove.FrameTransform` (`/tf`).
    Transform(FrameTransform),
    /// `/truth`.
    Truth(Truth),
    /// Any other topic.
    Json(Value),
    /// JSON already written out (a `/qt_model` snapshot: its size counts against a budget).
    JsonText(Vec<u8>),
}

impl Body {
    /// Fills in `timestamp` fields (foxglove schemas) with the log time.
    pub fn stamp(&mut self, ns: u64) {
        let t = Time::from_ns(ns);
        match self {
            Body::Pose(p) => p.timestamp = t,
            Body::Transform(f) => f.timestamp = t,
            Body::Telemetry { .. } | Body::Truth(_) | Body::JsonText(_) => {}
            Body::Json(v) => stamp_value(v, t),
        }
    }
}

impl Body {
    /// Appends the body in its channel's encoding: `protobuf` (by `encoder`, given on a binary
    /// channel) for the typed bodies, else JSON. The one place a topic's message is written.
    pub fn write(&self, encoder: Option<&mut mcap_proto::Encoder>, out: &mut Vec<u8>) {
        let Some(enc) = encoder else {
            return self.write_json(out);
        };
        match self {
            Body::Telemetry { row, caps } => enc.telemetry(out, row, |field| {
                caps.is_none_or(|c| super::scene::robot_has(field, c))
            }),
            Body::Pose(p) => enc.pose_in_frame(out, p),
            Body::Transform(f) => enc.frame_transform(out, f),
            Body::Truth(t) => enc.truth(out, t),
            // No binary channel carries these (`mcap_proto::descriptor_set` has no schema for
            // their topics), so this is never reached; JSON keeps the bytes readable if it is.
            Body::Json(_) | Body::JsonText(_) => self.write_json(out),
        }
    }

    /// Appends the body's JSON (compact, as `json_text::write` writes it) to `out`.
    pub fn write_json(&self, out: &mut Vec<u8>) {
        match self {
            Body::Telemetry { row, caps } => write_telemetry(out, row, *caps),
            Body::Pose(p) => p.write_json(out),
            Body::Transform(f) => f.write_json(out),
            Body::Truth(t) => {
                out.extend_from_slice(b"{\"robot_time_s\":");
                scaled(out, t.robot_time_s, 3);
                out.extend_from_slice(b",\"x_m\":");
                scaled(out, t.x_m, 3);
                out.extend_from_slice(b",\"y_m\":");
                scaled(out, t.y_m, 3);
                out.extend_from_slice(b",\"heading_rad\":");
                scaled(out, t.heading_rad, 3);
                out.extend_from_slice(b",\"collisions\":");
                uint(out, u64::from(t.collisions));
                out.push(b'}');
            }
            // Writing a Value into a Vec cannot fail.
            Body::Json(v) => {
                let _ = crate::json_text::write(&mut *out, v);
            }
            Body::JsonText(text) => out.extend_from_slice(text),
        }
    }
}

/// Appends `v` as `serde_json` writes an f64, fast when `v` is a whole number scaled down by
/// `10^decimals` (the exact double nearest `k / 10^decimals`): then the shortest decimal that
/// reads back as `v`, which is what `serde_json` writes, is `k` with the point put back and
/// trailing zeros dropped (any other decimal of as few digits is at least `10^-decimals`
/// away, far more than the spacing of doubles below 10^9). Anything else takes the general
/// path.
pub fn scaled(out: &mut Vec<u8>, v: f64, decimals: u32) {
    const POW10: [f64; 7] = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6];
    if let Some(&p) = POW10.get(decimals as usize) {
        let k = (v * p).round();
        if k.abs() < 1e15 && v.abs() < 1e9 && k / p == v {
            if v.is_sign_negative() {
                out.push(b'-');
            }
            let k = k.abs() as u64;
            let ip = 10u64.pow(decimals);
            uint(out, k / ip);
            out.push(b'.');
            let mut frac = k % ip;
            if frac == 0 {
                out.push(b'0');
                return;
            }
            let mut digits = decimals;
            while frac.is_multiple_of(10) {
                frac /= 10;
                digits -= 1;
            }
            let mut buf = [b'0'; 6];
            for d in buf[..digits as usize].iter_mut().rev() {
                *d = b'0' + (frac % 10) as u8;
                frac /= 10;
            }
            out.extend_from_slice(&buf[..digits as usize]);
            return;
        }
    }
    float(out, v);
}

/// Appends any f64 as `serde_json` writes it (`null` for NaN and infinities).
fn float(out: &mut Vec<u8>, v: f64) {
    let _ = serde_json::to_writer(&mut *out, &v);
}

/// Appends an unsigned integer in decimal.
fn uint(out: &mut Vec<u8>, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut at = digits.len();
    loop {
        at -= 1;
        digits[at] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[at..]);
}

fn boolean(out: &mut Vec<u8>, b: bool) {
    out.extend_from_slice(if b { b"true" } else { b"false" });
}

impl Time {
    fn write_json(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"sec\":");
        uint(out, self.sec);
        out.extend_from_slice(b",\"nsec\":");
        uint(out, self.nsec);
        out.push(b'}');
    }
}

impl Vector3 {
    /// x and y are metres from whole mm; z is 0.
    fn write_json(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"x\":");
        scaled(out, self.x, 3);
        out.extend_from_slice(b",\"y\":");
        scaled(out, self.y, 3);
        out.extend_from_slice(b",\"z\":");
        scaled(out, self.z, 3);
        out.push(b'}');
    }
}

impl Quaternion {
    fn write_json(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"x\":");
        float(out, self.x);
        out.extend_from_slice(b",\"y\":");
        float(out, self.y);
        out.extend_from_slice(b",\"z\":");
        float(out, self.z);
        out.extend_from_slice(b",\"w\":");
        float(out, self.w);
        out.push(b'}');
    }
}

impl PoseInFrame {
    fn write_json(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"timestamp\":");
        self.timestamp.write_json(out);
        out.extend_from_slice(b",\"frame_id\":");
        string(out, self.frame_id);
        out.extend_from_slice(b",\"pose\":{\"position\":");
        self.pose.position.write_json(out);
        out.extend_from_slice(b",\"orientation\":");
        self.pose.orientation.write_json(out);
        out.extend_from_slice(b"}}");
    }
}

impl FrameTransform {
    fn write_json(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(b"{\"timestamp\":");
        self.timestamp.write_json(out);
        out.extend_from_slice(b",\"parent_frame_id\":");
        string(out, self.parent_frame_id);
        out.extend_from_slice(b",\"child_frame_id\":");
        string(out, self.child_frame_id);
        out.extend_from_slice(b",\"translation\":");
        self.translation.write_json(out);
        out.extend_from_slice(b",\"rotation\":");
        self.rotation.write_json(out);
        out.push(b'}');
    }
}

/// A string, escaped as every JSON output escapes it (`json_text`; these are the program's
/// own names).
fn string(out: &mut Vec<u8>, s: &str) {
    let _ = crate::json_text::write(&mut *out, s);
}

/// `/telemetry`, as `TelemetryJson` serialises it.
fn write_telemetry(out: &mut Vec<u8>, r: &TelemetryRow, caps: Option<u32>) {
    let has = |field: &str| caps.is_none_or(|c| super::scene::robot_has(field, c));
    // Each field's key with the separator before it.
    let key = |out: &mut Vec<u8>, k: &[u8]| out.extend_from_slice(k);
    key(out, b"{\"time_s\":");
    scaled(out, r.time_s, 6);
    key(out, b",\"robot_time_s\":");
    scaled(out, r.robot_time_s, 3);
    key(out, b",\"mode\":");
    string(out, r.mode);
    for (k, v) in [
        (&b",\"x_m\":"[..], r.x_m),
        (b",\"y_m\":", r.y_m),
        (b",\"heading_rad\":", r.heading_rad),
        (b",\"sigma_xy_m\":", r.sigma_xy_m),
        (b",\"sigma_heading_rad\":", r.sigma_heading_rad),
        (b",\"v_left_m_s\":", r.v_left_m_s),
        (b",\"v_right_m_s\":", r.v_right_m_s),
    ] {
        key(out, k);
        scaled(out, v, 3);
    }
    // A sensor's field: its value, or null when the robot lacks the sensor.
    let sensor = |out: &mut Vec<u8>, name: &str, k: &[u8], write: &dyn Fn(&mut Vec<u8>)| {
        key(out, k);
        if has(name) {
            write(out);
        } else {
            out.extend_from_slice(b"null");
        }
    };
    let readings = |out: &mut Vec<u8>, values: &[u16; 8]| {
        out.push(b'[');
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            uint(out, u64::from(*v));
        }
        out.push(b']');
    };
    sensor(out, "enc_left", b",\"enc_left\":", &|o| {
        uint(o, u64::from(r.enc_left))
    });
    sensor(out, "enc_right", b",\"enc_right\":", &|o| {
        uint(o, u64::from(r.enc_right))
    });
    sensor(out, "ir", b",\"ir\":", &|o| readings(o, &r.ir));
    sensor(out, "light", b",\"light\":", &|o| readings(o, &r.light));
    sensor(out, "compass_deg", b",\"compass_deg\":", &|o| {
        scaled(o, r.compass_deg, 1)
    });
    key(out, b",\"flags\":");
    uint(out, u64::from(r.flags));
    sensor(out, "on_goal", b",\"on_goal\":", &|o| boolean(o, r.on_goal));
    sensor(out, "on_line", b",\"on_line\":", &|o| boolean(o, r.on_line));
    key(out, b",\"contact\":");
    boolean(out, r.contact);
    key(out, b",\"failsafe\":");
    boolean(out, r.failsafe);
    key(out, b",\"goal_reached\":");
    boolean(out, r.goal_reached);
    sensor(out, "line_events", b",\"line_events\":", &|o| {
        uint(o, u64::from(r.line_events))
    });
    sensor(
        out,
        "beacon_bearing_deg",
        b",\"beacon_bearing_deg\":",
        &|o| scaled(o, r.beacon_bearing_deg, 1),
    );
    sensor(out, "beacon_strength", b",\"beacon_strength\":", &|o| {
        uint(o, u64::from(r.beacon_strength))
    });
    sensor(out, "battery_v", b",\"battery_v\":", &|o| {
        scaled(o, r.battery_v, 3)
    });
    key(out, b",\"behaviours\":");
    uint(out, u64::from(r.behaviours));
    for (k, v) in [
        (&b",\"motor_left_m_s\":"[..], r.motor_left_m_s),
        (b",\"motor_right_m_s\":", r.motor_right_m_s),
        (b",\"cycle_period_ms\":", r.cycle_period_ms),
        (b",\"cycle_busy_ms\":", r.cycle_busy_ms),
    ] {
        key(out, k);
        scaled(out, v, 3);
    }
    key(out, b",\"cycle_overruns\":");
    uint(out, u64::from(r.cycle_overruns));
    out.push(b'}');
}

impl Serialize for Body {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Body::Telemetry { row, caps } => TelemetryJson { row, caps: *caps }.serialize(s),
            Body::Pose(p) => p.serialize(s),
            Body::Transform(f) => f.serialize(s),
            Body::Truth(t) => t.serialize(s),
            Body::Json(v) => v.serialize(s),
            // Read back: the text is what `write_json` writes.
            Body::JsonText(t) => serde_json::from_slice::<Value>(t)
                .unwrap_or(Value::Null)
                .serialize(s),
        }
    }
}

/// foxglove's `time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Time {
    pub sec: u64,
    pub nsec: u64,
}

impl Time {
    pub fn from_ns(ns: u64) -> Time {
        Time {
            sec: ns / 1_000_000_000,
            nsec: ns % 1_000_000_000,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    /// A rotation by `heading` radians about +z.
    pub fn yaw(heading: f64) -> Quaternion {
        let (s, c) = (heading / 2.0).sin_cos();
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pose3 {
    pub position: Vector3,
    pub orientation: Quaternion,
}

/// The wire's pose in metres and radians: position and heading.
fn metres(p: &Pose) -> (Vector3, f64) {
    (
        Vector3 {
            x: f64::from(p.x_mm) / 1000.0,
            y: f64::from(p.y_mm) / 1000.0,
            z: 0.0,
        },
        f64::from(p.heading_mrad) / 1000.0,
    )
}

/// foxglove.PoseInFrame in frame `map`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PoseInFrame {
    pub timestamp: Time,
    pub frame_id: &'static str,
    pub pose: Pose3,
}

impl PoseInFrame {
    pub fn map(p: &Pose) -> PoseInFrame {
        let (position, heading) = metres(p);
        PoseInFrame {
            timestamp: Time::default(),
            frame_id: "map",
            pose: Pose3 {
                position,
                orientation: Quaternion::yaw(heading),
            },
        }
    }
}

/// foxglove.FrameTransform from `map`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameTransform {
    pub timestamp: Time,
    pub parent_frame_id: &'static str,
    pub child_frame_id: &'static str,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

impl FrameTransform {
    /// `map` -> `child` at pose `p`.
    pub fn from_map(child: &'static str, p: &Pose) -> FrameTransform {
        let (translation, heading) = metres(p);
        FrameTransform {
            timestamp: Time::default(),
            parent_frame_id: "map",
            child_frame_id: child,
            translation,
            rotation: Quaternion::yaw(heading),
        }
    }
}

/// `/truth`: the emulator's `EmuTruth`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Truth {
    pub robot_time_s: f64,
    pub x_m: f64,
    pub y_m: f64,
    pub heading_rad: f64,
    pub collisions: u32,
}

/// Fills in a `Value`'s `timestamp` and its SceneUpdate entities' (as the typed bodies do).
fn stamp_value(v: &mut Value, t: Time) {
    let time = serde_json::json!({"sec": t.sec, "nsec": t.nsec});
    if let Some(ts) = v.get_mut("timestamp") {
        *ts = time.clone();
    }
    if let Some(Value::Array(entities)) = v.get_mut("entities") {
        for e in entities {
            if let Some(ts) = e.get_mut("timestamp") {
                *ts = time.clone();
            }
        }
    }
}

/// `/telemetry` through serde: the reference `write_telemetry` is checked against. The row's
/// fields, a sensor the robot lacks as null (`scene::SENSOR_FIELDS`
/// names them), and without the truth columns (those are `/truth`).
struct TelemetryJson<'a> {
    row: &'a TelemetryRow,
    caps: Option<u32>,
}

impl Serialize for TelemetryJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let r = self.row;
        let has = |field: &str| match self.caps {
            Some(c) => super::scene::robot_has(field, c),
            None => true,
        };
        let mut m = s.serialize_struct("Telemetry", 45)?;
        // A sensor's field: its value, or null when the robot lacks the sensor.
        macro_rules! sensor {
            ($name:literal, $v:expr) => {
                m.serialize_field($name, &has($name).then_some($v))?
            };
        }
        m.serialize_field("time_s", &r.time_s)?;
        m.serialize_field("robot_time_s", &r.robot_time_s)?;
        m.serialize_field("mode", r.mode)?;
        m.serialize_field("x_m", &r.x_m)?;
        m.serialize_field("y_m", &r.y_m)?;
        m.serialize_field("heading_rad", &r.heading_rad)?;
        m.serialize_field("sigma_xy_m", &r.sigma_xy_m)?;
        m.serialize_field("sigma_heading_rad", &r.sigma_heading_rad)?;
        m.serialize_field("v_left_m_s", &r.v_left_m_s)?;
        m.serialize_field("v_right_m_s", &r.v_right_m_s)?;
        sensor!("enc_left", r.enc_left);
        sensor!("enc_right", r.enc_right);
        sensor!("ir", r.ir);
        sensor!("light", r.light);
        sensor!("compass_deg", r.compass_deg);
        m.serialize_field("flags", &r.flags)?;
        sensor!("on_goal", r.on_goal);
        sensor!("on_line", r.on_line);
        m.serialize_field("contact", &r.contact)?;
        m.serialize_field("failsafe", &r.failsafe)?;
        m.serialize_field("goal_reached", &r.goal_reached)?;
        sensor!("line_events", r.line_events);
        sensor!("beacon_bearing_deg", r.beacon_bearing_deg);
        sensor!("beacon_strength", r.beacon_strength);
        sensor!("battery_v", r.battery_v);
        m.serialize_field("behaviours", &r.behaviours)?;
        m.serialize_field("motor_left_m_s", &r.motor_left_m_s)?;
        m.serialize_field("motor_right_m_s", &r.motor_right_m_s)?;
        m.serialize_field("cycle_period_ms", &r.cycle_period_ms)?;
        m.serialize_field("cycle_busy_ms", &r.cycle_busy_ms)?;
        m.serialize_field("cycle_overruns", &r.cycle_overruns)?;
        m.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Beacon, Mode, Packed10x8, Telemetry};

    #[test]
    fn scaled_numbers_are_what_serde_json_writes() {
        let mut values = vec![
            0.0,
            -0.0,
            1e20,
            -1e20,
            f64::NAN,
            f64::INFINITY,
            0.1 + 0.2,
            1e-7,
        ];
        for n in (-3_000_000i64..3_000_000).step_by(997) {
            for p in [1.0, 10.0, 1e3, 1e6] {
                values.push(n as f64 / p);
            }
        }
        for n in [
            i64::from(i32::MIN),
            i64::from(i32::MAX),
            i64::from(u32::MAX),
        ] {
            values.extend([n as f64 / 1e3, n as f64 / 1e6, n as f64 / 10.0]);
        }
        let mut out = Vec::new();
        for v in values {
            for d in [0, 1, 3, 6] {
                out.clear();
                scaled(&mut out, v, d);
                let want = serde_json::to_string(&v).unwrap_or_default();
                assert_eq!(String::from_utf8_lossy(&out), want, "{v} at {d}");
            }
        }
    }

    fn telemetry() -> Telemetry {
        Telemetry {
            time_ms: 4_294_967,
            mode: Mode::ExecutePlan,
            pose: protocol::Pose {
                x_mm: -1_048_576,
                y_mm: 1234,
                heading_mrad: -3142,
            },
            ir: Packed10x8::new([0, 1, 2, 1023, 4, 5, 6, 7]),
            compass_ddeg: 3599,
            flags: 0b1010_0101,
            beacon: Beacon {
                bearing_ddeg: -1800,
                strength: 7,
            },
            battery_mv: 65535,
            ..Telemetry::default()
        }
    }

    #[test]
    fn written_json_is_what_the_serialize_impls_make() {
        let t = telemetry();
        let row = TelemetryRow::new(123_456_789, &t);
        let bodies = [
            Body::Telemetry {
                row: Box::new(row.clone()),
                caps: None,
            },
            Body::Telemetry {
                row: Box::new(row),
                caps: Some(protocol::caps::IR_PROXIMITY | protocol::caps::BEACON),
            },
            Body::Pose(PoseInFrame::map(&t.pose)),
            Body::Transform(FrameTransform::from_map("truth", &t.pose)),
            Body::Truth(Truth {
                robot_time_s: 4294967.295,
                x_m: -0.001,
                y_m: 2147483.647,
                heading_rad: 2.5,
                collisions: 9,
            }),
            Body::Json(serde_json::json!({"state": "x\u{1b}y", "n": [1, 2.5]})),
        ];
        for mut b in bodies {
            b.stamp(1_700_000_000_123_456_789);
            let mut out = Vec::new();
            b.write_json(&mut out);
            let want = serde_json::to_vec(&b).unwrap_or_default();
            assert_eq!(
                String::from_utf8_lossy(&out),
                String::from_utf8_lossy(&want),
                "{b:?}"
            );
        }
    }
}
