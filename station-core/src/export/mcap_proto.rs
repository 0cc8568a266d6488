//! Protocol Buffers for the MCAP topics of every frame (`/telemetry`, `/pose`, `/truth`,
//! `/truth_pose`, `/tf`): the wire bytes of each message, and the schema Foxglove reads them by
//! (a `FileDescriptorSet`, MCAP's `protobuf` schema encoding).
//!
//! Layer: bytes only, no I/O. The poses and transforms are Foxglove's own well-known schemas
//! (`foxglove.PoseInFrame`, `foxglove.FrameTransform`, with `google.protobuf.Timestamp`), field
//! for field as Foxglove publishes them, so the 3D panel draws them; `/telemetry` and `/truth`
//! are `station.Telemetry` and `station.Truth`, whose field names are the JSON encoding's, so a
//! plot of `/telemetry.x_m` reads the same from either. Why protobuf: a frame's message is a
//! quarter of its JSON text's bytes and is written without formatting a number (issue 15: the
//! export of 10 minutes was a third kernel time writing 52 MB and a quarter JSON text).
//!
//! Encoding rules (protobuf's, proto3): a field is a key (field number << 3 | wire type) as a
//! varint, then a varint (integers, bools), 8 little-endian bytes (doubles), or a length and
//! bytes (strings, nested messages, packed repeated integers). A plain field at its default (0,
//! false, "") is left out; a sensor field a robot may lack is a proto3 `optional` field, written
//! whenever the robot has the sensor (even 0) and left out when it lacks it, which Foxglove
//! shows as no value (the JSON encoding's `null`).

use super::csv::TelemetryRow;
use super::mcap_msg::{FrameTransform, PoseInFrame, Quaternion, Time, Truth, Vector3};

const VARINT: u8 = 0;
const FIXED64: u8 = 1;
const LEN: u8 = 2;

fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push(v as u8 | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

fn key(out: &mut Vec<u8>, field: u32, wire: u8) {
    varint(out, u64::from(field) << 3 | u64::from(wire));
}

/// A double field, left out at +0.0 (proto3's default; -0.0 is written, as protobuf does).
fn double(out: &mut Vec<u8>, field: u32, v: f64) {
    if v.to_bits() != 0 {
        present_double(out, field, v);
    }
}

/// A double field written even at 0 (an `optional` field that is present).
fn present_double(out: &mut Vec<u8>, field: u32, v: f64) {
    key(out, field, FIXED64);
    out.extend_from_slice(&v.to_le_bytes());
}

/// An unsigned integer field, left out at 0.
fn uint(out: &mut Vec<u8>, field: u32, v: u64) {
    if v != 0 {
        present_uint(out, field, v);
    }
}

fn present_uint(out: &mut Vec<u8>, field: u32, v: u64) {
    key(out, field, VARINT);
    varint(out, v);
}

/// A string field, left out when empty.
fn string(out: &mut Vec<u8>, field: u32, s: &str) {
    if !s.is_empty() {
        bytes(out, field, s.as_bytes());
    }
}

fn bytes(out: &mut Vec<u8>, field: u32, b: &[u8]) {
    key(out, field, LEN);
    varint(out, b.len() as u64);
    out.extend_from_slice(b);
}

/// A nested message field: its length, then what `body` writes. The length is reserved as one
/// byte (every message here is shorter than 128 bytes) and widened if the body was longer.
fn message(out: &mut Vec<u8>, field: u32, body: impl FnOnce(&mut Vec<u8>)) {
    key(out, field, LEN);
    let at = out.len();
    out.push(0);
    body(out);
    let len = out.len() - at - 1;
    if len < 0x80 {
        out[at] = len as u8;
    } else {
        let mut prefix = Vec::with_capacity(10);
        varint(&mut prefix, len as u64);
        out.splice(at..=at, prefix);
    }
}

/// A packed repeated unsigned integer field (proto3's default for repeated scalars).
fn packed(out: &mut Vec<u8>, field: u32, values: &[u16]) {
    message(out, field, |out| {
        for v in values {
            varint(out, u64::from(*v));
        }
    });
}

/// `google.protobuf.Timestamp`: int64 seconds = 1, int32 nanos = 2.
fn timestamp(out: &mut Vec<u8>, field: u32, t: Time) {
    message(out, field, |out| {
        uint(out, 1, t.sec);
        uint(out, 2, t.nsec);
    });
}

/// `foxglove.Vector3`: double x = 1, y = 2, z = 3.
fn vector3(out: &mut Vec<u8>, field: u32, v: &Vector3) {
    message(out, field, |out| {
        double(out, 1, v.x);
        double(out, 2, v.y);
        double(out, 3, v.z);
    });
}

/// `foxglove.Quaternion`: double x = 1, y = 2, z = 3, w = 4.
fn quaternion(out: &mut Vec<u8>, field: u32, q: &Quaternion) {
    message(out, field, |out| {
        double(out, 1, q.x);
        double(out, 2, q.y);
        double(out, 3, q.z);
        double(out, 4, q.w);
    });
}

/// `foxglove.PoseInFrame`: timestamp = 1, frame_id = 2, pose = 3 (`foxglove.Pose`: position
/// = 1, orientation = 2).
pub fn pose_in_frame(out: &mut Vec<u8>, p: &PoseInFrame) {
    timestamp(out, 1, p.timestamp);
    string(out, 2, p.frame_id);
    message(out, 3, |out| {
        vector3(out, 1, &p.pose.position);
        quaternion(out, 2, &p.pose.orientation);
    });
}

/// `foxglove.FrameTransform`: timestamp = 1, parent_frame_id = 2, child_frame_id = 3,
/// translation = 4, rotation = 5.
pub fn frame_transform(out: &mut Vec<u8>, f: &FrameTransform) {
    timestamp(out, 1, f.timestamp);
    string(out, 2, f.parent_frame_id);
    string(out, 3, f.child_frame_id);
    vector3(out, 4, &f.translation);
    quaternion(out, 5, &f.rotation);
}

/// `station.Truth` (field numbers in [`FILES`]).
pub fn truth(out: &mut Vec<u8>, t: &Truth) {
    double(out, 1, t.robot_time_s);
    double(out, 2, t.x_m);
    double(out, 3, t.y_m);
    double(out, 4, t.heading_rad);
    uint(out, 5, u64::from(t.collisions));
}

/// `station.Telemetry` (field numbers in [`FILES`]); `has` says whether the robot has the
/// sensor behind an optional field (`scene::robot_has`).
pub fn telemetry(out: &mut Vec<u8>, r: &TelemetryRow, has: impl Fn(&str) -> bool) {
    double(out, 1, r.time_s);
    double(out, 2, r.robot_time_s);
    string(out, 3, r.mode);
    for (field, v) in [
        (4, r.x_m),
        (5, r.y_m),
        (6, r.heading_rad),
        (7, r.sigma_xy_m),
        (8, r.sigma_heading_rad),
        (9, r.v_left_m_s),
        (10, r.v_right_m_s),
    ] {
        double(out, field, v);
    }
    if has("enc_left") {
        present_uint(out, 11, u64::from(r.enc_left));
    }
    if has("enc_right") {
        present_uint(out, 12, u64::from(r.enc_right));
    }
    if has("ir") {
        packed(out, 13, &r.ir);
    }
    if has("light") {
        packed(out, 14, &r.light);
    }
    if has("compass_deg") {
        present_double(out, 15, r.compass_deg);
    }
    uint(out, 16, u64::from(r.flags));
    if has("on_goal") {
        present_uint(out, 17, u64::from(r.on_goal));
    }
    if has("on_line") {
        present_uint(out, 18, u64::from(r.on_line));
    }
    uint(out, 19, u64::from(r.contact));
    uint(out, 20, u64::from(r.failsafe));
    uint(out, 21, u64::from(r.goal_reached));
    if has("line_events") {
        present_uint(out, 22, u64::from(r.line_events));
    }
    if has("beacon_bearing_deg") {
        present_double(out, 23, r.beacon_bearing_deg);
    }
    if has("beacon_strength") {
        present_uint(out, 24, u64::from(r.beacon_strength));
    }
    if has("battery_v") {
        present_double(out, 25, r.battery_v);
    }
    uint(out, 26, u64::from(r.behaviours));
    for (field, v) in [
        (27, r.motor_left_m_s),
        (28, r.motor_right_m_s),
        (29, r.cycle_period_ms),
        (30, r.cycle_busy_ms),
    ] {
        double(out, field, v);
    }
    uint(out, 31, u64::from(r.cycle_overruns));
}

/// A field's type in a schema (descriptor.proto's `FieldDescriptorProto.Type` numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ty {
    Double,
    Int64,
    Int32,
    Uint32,
    Bool,
    String,
    /// A message, by its fully qualified name (`foxglove.Vector3`).
    Message(&'static str),
}

impl Ty {
    fn number(self) -> u64 {
        match self {
            Ty::Double => 1,
            Ty::Int64 => 3,
            Ty::Int32 => 5,
            Ty::Bool => 8,
            Ty::String => 9,
            Ty::Message(_) => 11,
            Ty::Uint32 => 13,
        }
    }
}

/// How a field repeats: once (proto3's implicit presence), `optional` (explicit presence), or
/// `repeated`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Label {
    Plain,
    Optional,
    Repeated,
}

/// A field of a schema: name, number, type, label.
pub type Field = (&'static str, u32, Ty, Label);

/// A `.proto` file of the schemas: its name, package, imports and messages.
pub struct File {
    pub name: &'static str,
    pub package: &'static str,
    pub imports: &'static [&'static str],
    pub messages: &'static [(&'static str, &'static [Field])],
}

use Label::{Optional, Plain, Repeated};

/// Every schema the binary topics use, each file after those it imports. Foxglove's and
/// Google's are theirs, field for field (foxglove/schemas `schemas/proto`).
pub const FILES: &[File] = &[
    File {
        name: "google/protobuf/timestamp.proto",
        package: "google.protobuf",
        imports: &[],
        messages: &[(
            "Timestamp",
            &[
                ("seconds", 1, Ty::Int64, Plain),
                ("nanos", 2, Ty::Int32, Plain),
            ],
        )],
    },
    File {
        name: "foxglove/Vector3.proto",
        package: "foxglove",
        imports: &[],
        messages: &[(
            "Vector3",
            &[
                ("x", 1, Ty::Double, Plain),
                ("y", 2, Ty::Double, Plain),
                ("z", 3, Ty::Double, Plain),
            ],
        )],
    },
    File {
        name: "foxglove/Quaternion.proto",
        package: "foxglove",
        imports: &[],
        messages: &[(
            "Quaternion",
            &[
                ("x", 1, Ty::Double, Plain),
                ("y", 2, Ty::Double, Plain),
                ("z", 3, Ty::Double, Plain),
                ("w", 4, Ty::Double, Plain),
            ],
        )],
    },
    File {
        name: "foxglove/Pose.proto",
        package: "foxglove",
        imports: &["foxglove/Quaternion.proto", "foxglove/Vector3.proto"],
        messages: &[(
            "Pose",
            &[
                ("position", 1, Ty::Message("foxglove.Vector3"), Plain),
                ("orientation", 2, Ty::Message("foxglove.Quaternion"), Plain),
            ],
        )],
    },
    File {
        name: "foxglove/PoseInFrame.proto",
        package: "foxglove",
        imports: &["foxglove/Pose.proto", "google/protobuf/timestamp.proto"],
        messages: &[(
            "PoseInFrame",
            &[
                (
                    "timestamp",
                    1,
                    Ty::Message("google.protobuf.Timestamp"),
                    Plain,
                ),
                ("frame_id", 2, Ty::String, Plain),
                ("pose", 3, Ty::Message("foxglove.Pose"), Plain),
            ],
        )],
    },
    File {
        name: "foxglove/FrameTransform.proto",
        package: "foxglove",
        imports: &[
            "foxglove/Quaternion.proto",
            "foxglove/Vector3.proto",
            "google/protobuf/timestamp.proto",
        ],
        messages: &[(
            "FrameTransform",
            &[
                (
                    "timestamp",
                    1,
                    Ty::Message("google.protobuf.Timestamp"),
                    Plain,
                ),
                ("parent_frame_id", 2, Ty::String, Plain),
                ("child_frame_id", 3, Ty::String, Plain),
                ("translation", 4, Ty::Message("foxglove.Vector3"), Plain),
                ("rotation", 5, Ty::Message("foxglove.Quaternion"), Plain),
            ],
        )],
    },
    File {
        name: "station/Truth.proto",
        package: "station",
        imports: &[],
        messages: &[(
            "Truth",
            &[
                ("robot_time_s", 1, Ty::Double, Plain),
                ("x_m", 2, Ty::Double, Plain),
                ("y_m", 3, Ty::Double, Plain),
                ("heading_rad", 4, Ty::Double, Plain),
                ("collisions", 5, Ty::Uint32, Plain),
            ],
        )],
    },
    File {
        name: "station/Telemetry.proto",
        package: "station",
        imports: &[],
        messages: &[("Telemetry", TELEMETRY)],
    },
];

/// `station.Telemetry`: the JSON encoding's fields (README "Export"), in its order.
const TELEMETRY: &[Field] = &[
    ("time_s", 1, Ty::Double, Plain),
    ("robot_time_s", 2, Ty::Double, Plain),
    ("mode", 3, Ty::String, Plain),
    ("x_m", 4, Ty::Double, Plain),
    ("y_m", 5, Ty::Double, Plain),
    ("heading_rad", 6, Ty::Double, Plain),
    ("sigma_xy_m", 7, Ty::Double, Plain),
    ("sigma_heading_rad", 8, Ty::Double, Plain),
    ("v_left_m_s", 9, Ty::Double, Plain),
    ("v_right_m_s", 10, Ty::Double, Plain),
    ("enc_left", 11, Ty::Uint32, Optional),
    ("enc_right", 12, Ty::Uint32, Optional),
    ("ir", 13, Ty::Uint32, Repeated),
    ("light", 14, Ty::Uint32, Repeated),
    ("compass_deg", 15, Ty::Double, Optional),
    ("flags", 16, Ty::Uint32, Plain),
    ("on_goal", 17, Ty::Bool, Optional),
    ("on_line", 18, Ty::Bool, Optional),
    ("contact", 19, Ty::Bool, Plain),
    ("failsafe", 20, Ty::Bool, Plain),
    ("goal_reached", 21, Ty::Bool, Plain),
    ("line_events", 22, Ty::Uint32, Optional),
    ("beacon_bearing_deg", 23, Ty::Double, Optional),
    ("beacon_strength", 24, Ty::Uint32, Optional),
    ("battery_v", 25, Ty::Double, Optional),
    ("behaviours", 26, Ty::Uint32, Plain),
    ("motor_left_m_s", 27, Ty::Double, Plain),
    ("motor_right_m_s", 28, Ty::Double, Plain),
    ("cycle_period_ms", 29, Ty::Double, Plain),
    ("cycle_busy_ms", 30, Ty::Double, Plain),
    ("cycle_overruns", 31, Ty::Uint32, Plain),
];

/// The file that defines message `full_name` (`foxglove.PoseInFrame`).
fn file_of(full_name: &str) -> Option<&'static File> {
    FILES.iter().find(|f| {
        f.messages.iter().any(|(m, _)| {
            full_name
                .strip_prefix(f.package)
                .and_then(|r| r.strip_prefix('.'))
                == Some(m)
        })
    })
}

/// The schema of message `full_name` as MCAP's `protobuf` schema encoding wants it: a
/// `FileDescriptorSet` of its file and every file that file imports, each after its imports
/// (what `protoc --include_imports --descriptor_set_out` writes, less comments and `json_name`).
/// `None` for a message not in [`FILES`].
pub fn descriptor_set(full_name: &str) -> Option<Vec<u8>> {
    let root = file_of(full_name)?;
    let mut order: Vec<&'static File> = Vec::new();
    add_with_imports(root, &mut order);
    let mut out = Vec::new();
    for f in order {
        // FileDescriptorSet.file = 1
        message(&mut out, 1, |out| file_descriptor(out, f));
    }
    Some(out)
}

fn add_with_imports(f: &'static File, order: &mut Vec<&'static File>) {
    if order.iter().any(|o| o.name == f.name) {
        return;
    }
    for name in f.imports {
        if let Some(dep) = FILES.iter().find(|d| d.name == *name) {
            add_with_imports(dep, order);
        }
    }
    order.push(f);
}

/// `FileDescriptorProto`: name = 1, package = 2, dependency = 3, message_type = 4,
/// syntax = 12.
fn file_descriptor(out: &mut Vec<u8>, f: &File) {
    string(out, 1, f.name);
    string(out, 2, f.package);
    for dep in f.imports {
        string(out, 3, dep);
    }
    for (name, fields) in f.messages {
        message(out, 4, |out| message_descriptor(out, name, fields));
    }
    string(out, 12, "proto3");
}

/// `DescriptorProto`: name = 1, field = 2, oneof_decl = 8. A proto3 `optional` field is in a
/// synthetic oneof of its own, named `_` and the field's name, after any real oneof (there are
/// none here).
fn message_descriptor(out: &mut Vec<u8>, name: &str, fields: &[Field]) {
    string(out, 1, name);
    let mut oneofs = 0u64;
    for &(fname, number, ty, label) in fields {
        // FieldDescriptorProto: name = 1, number = 3, label = 4, type = 5, type_name = 6,
        // oneof_index = 9, proto3_optional = 17. Labels: 1 optional, 3 repeated.
        message(out, 2, |out| {
            string(out, 1, fname);
            present_uint(out, 3, u64::from(number));
            present_uint(out, 4, if label == Repeated { 3 } else { 1 });
            present_uint(out, 5, ty.number());
            if let Ty::Message(m) = ty {
                key(out, 6, LEN);
                varint(out, m.len() as u64 + 1);
                out.push(b'.');
                out.extend_from_slice(m.as_bytes());
            }
            if label == Optional {
                present_uint(out, 9, oneofs);
                present_uint(out, 17, 1);
                oneofs += 1;
            }
        });
    }
    for &(fname, _, _, label) in fields {
        if label == Optional {
            // OneofDescriptorProto: name = 1.
            message(out, 8, |out| {
                key(out, 1, LEN);
                varint(out, fname.len() as u64 + 1);
                out.push(b'_');
                out.extend_from_slice(fname.as_bytes());
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::Pose;

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    const STAMP: Time = Time {
        sec: 1_700_000_000,
        nsec: 10_000_000,
    };

    fn pose() -> Pose {
        Pose {
            x_mm: 1500,
            y_mm: -250,
            heading_mrad: 0,
        }
    }

    /// The bytes of one message of each schema, pinned (worked out field by field apart from
    /// this code: key = number << 3 | wire type, varints, little-endian doubles; zeros left
    /// out). Timestamp 1_700_000_000 s + 10 ms is `0a 0b 08 80e2cfaa06 10 80ade204`.
    #[test]
    fn each_schema_writes_the_bytes_protobuf_defines() {
        let mut p = PoseInFrame::map(&pose());
        p.timestamp = STAMP;
        let mut out = Vec::new();
        pose_in_frame(&mut out, &p);
        assert_eq!(
            hex(&out),
            "0a0b0880e2cfaa061080ade20412036d61701a1f0a1209000000000000f83f11000000000000d0bf\
             120921000000000000f03f"
        );

        let mut f = FrameTransform::from_map("base_link", &pose());
        f.timestamp = STAMP;
        out.clear();
        frame_transform(&mut out, &f);
        assert_eq!(
            hex(&out),
            "0a0b0880e2cfaa061080ade20412036d61701a09626173655f6c696e6b221209000000000000f83f\
             11000000000000d0bf2a0921000000000000f03f"
        );

        out.clear();
        truth(
            &mut out,
            &Truth {
                robot_time_s: 0.1,
                x_m: 1.507,
                y_m: -0.25,
                heading_rad: -2.5,
                collisions: 3,
            },
        );
        assert_eq!(
            hex(&out),
            "099a9999999999b93f11e9263108ac1cf83f19000000000000d0bf2100000000000004c02803"
        );

        let row = TelemetryRow {
            time_s: 0.11,
            robot_time_s: 0.1,
            mode: "Wander",
            x_m: 1.5,
            y_m: -0.25,
            heading_rad: 0.0,
            sigma_xy_m: 0.05,
            sigma_heading_rad: 0.0,
            v_left_m_s: 0.2,
            v_right_m_s: -0.2,
            enc_left: 0,
            enc_right: 65535,
            ir: [0, 1, 2, 1023, 4, 5, 6, 7],
            light: [500; 8],
            compass_deg: 359.9,
            flags: 0xa5,
            on_goal: false,
            on_line: true,
            contact: true,
            failsafe: false,
            goal_reached: false,
            line_events: 0,
            beacon_bearing_deg: -180.0,
            beacon_strength: 7,
            battery_v: 7.4,
            behaviours: 3,
            motor_left_m_s: 0.25,
            motor_right_m_s: 0.0,
            cycle_period_ms: 50.0,
            cycle_busy_ms: 1.5,
            cycle_overruns: 2,
            true_x_m: None,
            true_y_m: None,
            true_heading_rad: None,
            collisions: None,
        };
        out.clear();
        // A robot without ambient light and battery sensors: those fields are left out; the
        // sensors it has are written even at 0 (enc_left, on_goal, line_events).
        telemetry(&mut out, &row, |f| f != "light" && f != "battery_v");
        assert_eq!(
            hex(&out),
            "09295c8fc2f528bc3f119a9999999999b93f1a0657616e64657221000000000000f83f29000000000000\
             d0bf399a9999999999a93f499a9999999999c93f519a9999999999c9bf580060ffff036a0900010\
             2ff07040506077966666666667e76408001a501880100900101980101b00100b90100000000008066\
             c0c00107d00103d901000000000000d03fe9010000000000004940f101000000000000f83ff80102"
        );
    }

    #[test]
    fn a_message_longer_than_127_bytes_gets_a_wider_length() {
        let mut out = Vec::new();
        message(&mut out, 1, |out| out.extend_from_slice(&[7; 300]));
        assert_eq!(&out[..3], &[0x0a, 0xac, 0x02]);
        assert_eq!(out.len(), 3 + 300);
        assert!(out[3..].iter().all(|&b| b == 7));
    }

    #[test]
    fn a_schema_holds_its_file_and_every_file_it_imports() {
        let set = descriptor_set("foxglove.FrameTransform").unwrap_or_default();
        let names: Vec<&str> = FILES
            .iter()
            .map(|f| f.name)
            .filter(|n| set.windows(n.len()).any(|w| w == n.as_bytes()))
            .collect();
        assert_eq!(
            names,
            [
                "google/protobuf/timestamp.proto",
                "foxglove/Vector3.proto",
                "foxglove/Quaternion.proto",
                "foxglove/FrameTransform.proto"
            ]
        );
        assert!(descriptor_set("foxglove.Grid").is_none());
        assert!(descriptor_set("station.Telemetry").is_some());
    }
}
