//! Protocol Buffers for the MCAP topics of every frame (`/telemetry`, `/pose`, `/truth`,
//! `/truth_pose`, `/tf`): each message's bytes, and the schema Foxglove reads them by (a
//! `FileDescriptorSet`, MCAP's `protobuf` schema encoding).
//!
//! Layer: bytes only, no I/O. The schemas are the `.proto` files in `station-core/proto/`:
//! Foxglove's own for poses and transforms (`foxglove.PoseInFrame`, `foxglove.FrameTransform`,
//! with `google.protobuf.Timestamp`), so the 3D panel draws them, and the station's
//! `station.Telemetry` and `station.Truth`, whose field names are the JSON encoding's, so a plot
//! of `/telemetry.x_m` reads the same from either. `build.rs` compiles them with protox (no
//! `protoc`) into a descriptor set and prost types ([`foxglove`], [`station`]); prost writes the
//! messages. Why protobuf: a frame's message is a quarter of its JSON text's bytes and is
//! written without formatting a number.
//!
//! proto3 leaves a plain field at its default (0, false, "") out; a sensor field a robot may
//! lack is an `optional` field, written whenever the robot has the sensor (even 0) and left out
//! when it lacks it, which Foxglove shows as no value (the JSON encoding's `null`).

use prost::Message as _;
use prost_types::{FileDescriptorProto, FileDescriptorSet};

use super::csv::TelemetryRow;
use super::mcap_msg::{FrameTransform, PoseInFrame, Quaternion, Time, Truth, Vector3};

/// Foxglove's messages, generated from `proto/foxglove`.
#[allow(clippy::all, clippy::pedantic, missing_docs)]
pub mod foxglove {
    include!(concat!(env!("OUT_DIR"), "/foxglove.rs"));
}

/// The station's messages, generated from `proto/station`.
#[allow(clippy::all, clippy::pedantic, missing_docs)]
pub mod station {
    include!(concat!(env!("OUT_DIR"), "/station.rs"));
}

/// Every schema file, each after those it imports (`build.rs` compiles `proto/` into it).
const SCHEMAS: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/mcap_schemas.bin"));

/// Appends `m`'s bytes to `out`.
fn encode(m: &impl prost::Message, out: &mut Vec<u8>) {
    // Only a buffer with too little room fails; a Vec grows.
    let _ = m.encode(out);
}

fn timestamp(t: Time) -> Option<prost_types::Timestamp> {
    Some(prost_types::Timestamp {
        seconds: i64::try_from(t.sec).unwrap_or(i64::MAX),
        // Below 10^9 by construction (`Time::from_ns`).
        nanos: i32::try_from(t.nsec).unwrap_or(0),
    })
}

fn vector3(v: &Vector3) -> Option<foxglove::Vector3> {
    Some(foxglove::Vector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    })
}

fn quaternion(q: &Quaternion) -> Option<foxglove::Quaternion> {
    Some(foxglove::Quaternion {
        x: q.x,
        y: q.y,
        z: q.z,
        w: q.w,
    })
}

/// Writes the messages, each into a message kept from the last one of its type: once its
/// strings and readings have room, filling one in allocates nothing.
#[derive(Default)]
pub struct Encoder {
    pose: foxglove::PoseInFrame,
    transform: foxglove::FrameTransform,
    telemetry: station::Telemetry,
}

/// `s` made `v`, in the room it has.
fn set(s: &mut String, v: &str) {
    if s != v {
        s.clear();
        s.push_str(v);
    }
}

impl Encoder {
    /// `foxglove.PoseInFrame`.
    pub fn pose_in_frame(&mut self, out: &mut Vec<u8>, p: &PoseInFrame) {
        let m = &mut self.pose;
        m.timestamp = timestamp(p.timestamp);
        set(&mut m.frame_id, p.frame_id);
        m.pose = Some(foxglove::Pose {
            position: vector3(&p.pose.position),
            orientation: quaternion(&p.pose.orientation),
        });
        encode(m, out);
    }

    /// `foxglove.FrameTransform`.
    pub fn frame_transform(&mut self, out: &mut Vec<u8>, f: &FrameTransform) {
        let m = &mut self.transform;
        m.timestamp = timestamp(f.timestamp);
        set(&mut m.parent_frame_id, f.parent_frame_id);
        set(&mut m.child_frame_id, f.child_frame_id);
        m.translation = vector3(&f.translation);
        m.rotation = quaternion(&f.rotation);
        encode(m, out);
    }

    /// `station.Truth`.
    pub fn truth(&mut self, out: &mut Vec<u8>, t: &Truth) {
        let m = station::Truth {
            robot_time_s: t.robot_time_s,
            x_m: t.x_m,
            y_m: t.y_m,
            heading_rad: t.heading_rad,
            collisions: t.collisions,
        };
        encode(&m, out);
    }

    /// `station.Telemetry`; `has` says whether the robot has the sensor behind an optional
    /// field (`scene::robot_has`).
    pub fn telemetry(&mut self, out: &mut Vec<u8>, r: &TelemetryRow, has: impl Fn(&str) -> bool) {
        let readings = |to: &mut Vec<u32>, field: &str, v: &[u16; 8]| {
            to.clear();
            if has(field) {
                to.extend(v.iter().map(|&x| u32::from(x)));
            }
        };
        let m = &mut self.telemetry;
        readings(&mut m.ir, "ir", &r.ir);
        readings(&mut m.light, "light", &r.light);
        set(&mut m.mode, r.mode);
        m.time_s = r.time_s;
        m.robot_time_s = r.robot_time_s;
        m.x_m = r.x_m;
        m.y_m = r.y_m;
        m.heading_rad = r.heading_rad;
        m.sigma_xy_m = r.sigma_xy_m;
        m.sigma_heading_rad = r.sigma_heading_rad;
        m.v_left_m_s = r.v_left_m_s;
        m.v_right_m_s = r.v_right_m_s;
        m.enc_left = has("enc_left").then_some(u32::from(r.enc_left));
        m.enc_right = has("enc_right").then_some(u32::from(r.enc_right));
        m.compass_deg = has("compass_deg").then_some(r.compass_deg);
        m.flags = u32::from(r.flags);
        m.on_goal = has("on_goal").then_some(r.on_goal);
        m.on_line = has("on_line").then_some(r.on_line);
        m.contact = r.contact;
        m.failsafe = r.failsafe;
        m.goal_reached = r.goal_reached;
        m.line_events = has("line_events").then_some(u32::from(r.line_events));
        m.beacon_bearing_deg = has("beacon_bearing_deg").then_some(r.beacon_bearing_deg);
        m.beacon_strength = has("beacon_strength").then_some(u32::from(r.beacon_strength));
        m.battery_v = has("battery_v").then_some(r.battery_v);
        m.behaviours = u32::from(r.behaviours);
        m.motor_left_m_s = r.motor_left_m_s;
        m.motor_right_m_s = r.motor_right_m_s;
        m.cycle_period_ms = r.cycle_period_ms;
        m.cycle_busy_ms = r.cycle_busy_ms;
        m.cycle_overruns = u32::from(r.cycle_overruns);
        encode(m, out);
    }
}

/// Whether file `f` defines message `full_name` (`foxglove.PoseInFrame`).
fn defines(f: &FileDescriptorProto, full_name: &str) -> bool {
    let Some((package, name)) = full_name.rsplit_once('.') else {
        return false;
    };
    f.package() == package && f.message_type.iter().any(|m| m.name() == name)
}

/// The schema of message `full_name` as MCAP's `protobuf` schema encoding wants it: a
/// `FileDescriptorSet` of its file and every file that file imports, each after its imports
/// (what `protoc --include_imports --descriptor_set_out` writes). `None` for a message no
/// schema file defines.
pub fn descriptor_set(full_name: &str) -> Option<Vec<u8>> {
    let all = FileDescriptorSet::decode(SCHEMAS).ok()?;
    let root = all.file.iter().find(|f| defines(f, full_name))?;
    let mut order = Vec::new();
    add_with_imports(&all, root, &mut order);
    let set = FileDescriptorSet {
        file: order.into_iter().cloned().collect(),
    };
    Some(set.encode_to_vec())
}

fn add_with_imports<'a>(
    all: &'a FileDescriptorSet,
    f: &'a FileDescriptorProto,
    order: &mut Vec<&'a FileDescriptorProto>,
) {
    if order.iter().any(|o| o.name == f.name) {
        return;
    }
    for import in &f.dependency {
        if let Some(dep) = all.file.iter().find(|d| d.name() == import) {
            add_with_imports(all, dep, order);
        }
    }
    order.push(f);
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
        let mut enc = Encoder::default();
        let mut out = Vec::new();
        enc.pose_in_frame(&mut out, &p);
        assert_eq!(
            hex(&out),
            "0a0b0880e2cfaa061080ade20412036d61701a1f0a1209000000000000f83f11000000000000d0bf\
             120921000000000000f03f"
        );

        let mut f = FrameTransform::from_map("base_link", &pose());
        f.timestamp = STAMP;
        out.clear();
        enc.frame_transform(&mut out, &f);
        assert_eq!(
            hex(&out),
            "0a0b0880e2cfaa061080ade20412036d61701a09626173655f6c696e6b221209000000000000f83f\
             11000000000000d0bf2a0921000000000000f03f"
        );

        out.clear();
        enc.truth(
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
        enc.telemetry(&mut out, &row, |f| f != "light" && f != "battery_v");
        assert_eq!(
            hex(&out),
            "09295c8fc2f528bc3f119a9999999999b93f1a0657616e64657221000000000000f83f29000000000000\
             d0bf399a9999999999a93f499a9999999999c93f519a9999999999c9bf580060ffff036a0900010\
             2ff07040506077966666666667e76408001a501880100900101980101b00100b90100000000008066\
             c0c00107d00103d901000000000000d03fe9010000000000004940f101000000000000f83ff80102"
        );
    }

    #[test]
    fn a_schema_holds_its_file_and_every_file_it_imports() {
        let set = descriptor_set("foxglove.FrameTransform").unwrap_or_default();
        let set = FileDescriptorSet::decode(set.as_slice()).unwrap_or_default();
        let names: Vec<&str> = set.file.iter().map(|f| f.name()).collect();
        assert_eq!(
            names,
            [
                "foxglove/Quaternion.proto",
                "foxglove/Vector3.proto",
                "google/protobuf/timestamp.proto",
                "foxglove/FrameTransform.proto"
            ]
        );
        assert!(set.file.iter().all(|f| f.source_code_info.is_none()));
        assert!(descriptor_set("foxglove.Grid").is_none());
        let telemetry = descriptor_set("station.Telemetry").unwrap_or_default();
        let telemetry = FileDescriptorSet::decode(telemetry.as_slice()).unwrap_or_default();
        let fields = &telemetry.file[0].message_type[0].field;
        assert_eq!(fields.len(), 31);
        // A sensor the robot may lack is proto3 `optional` (its own synthetic oneof).
        let enc_left = fields.iter().find(|f| f.name() == "enc_left");
        assert_eq!(enc_left.and_then(|f| f.proto3_optional), Some(true));
    }
}
