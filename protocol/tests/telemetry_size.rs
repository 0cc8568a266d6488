//! The telemetry frame's TRUE worst case on the wire, stated in PROTOCOL.md §2: every field at
//! the widest value its type can hold (postcard varints: a u32 or i32 takes up to 5 bytes, a
//! u16 or i16 up to 3), not only the widest the robot plausibly sends (`full_telemetry`, 76
//! bytes). A station sizing buffers or a link budget for telemetry must use this figure.
#![allow(clippy::unwrap_used)]

use protocol::{
    encode, Beacon, BehaviourOut, CycleTiming, Message, Mode, Packed10x8, Pose, PoseSigma,
    Telemetry, Wheels, MAX_FRAME,
};

/// PROTOCOL.md §2: "true worst case".
const WORST_CASE_ON_THE_WIRE: usize = 97;

fn widest_telemetry() -> Telemetry {
    Telemetry {
        time_ms: u32::MAX,
        mode: Mode::ExecutePlan,
        pose: Pose {
            x_mm: i32::MIN,
            y_mm: i32::MIN,
            heading_mrad: i16::MIN,
        },
        sigma: PoseSigma {
            xy_mm: u16::MAX,
            heading_mrad: u16::MAX,
        },
        wheels: Wheels {
            speed_mm_s: [i16::MIN; 2],
            encoders: [u16::MAX; 2],
        },
        ir: Packed10x8::new([1023; 8]),
        light: Packed10x8::new([1023; 8]),
        compass_ddeg: u16::MAX,
        flags: u8::MAX,
        line_events: u8::MAX,
        beacon: Beacon {
            bearing_ddeg: i16::MIN,
            strength: u8::MAX,
        },
        battery_mv: u16::MAX,
        behaviour: BehaviourOut {
            active: u8::MAX,
            motor_mm_s: [i16::MIN; 2],
        },
        cycle: CycleTiming {
            period_us: u32::MAX,
            busy_us: u32::MAX,
            overruns: u8::MAX,
        },
    }
}

#[test]
fn the_widest_telemetry_frame_is_the_size_protocol_md_states() {
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(u16::MAX, &Message::Telemetry(widest_telemetry()), &mut buf).unwrap();
    assert_eq!(
        n, WORST_CASE_ON_THE_WIRE,
        "update PROTOCOL.md §2 and this constant"
    );
    let doc = include_str!("../PROTOCOL.md");
    assert!(
        doc.contains(&format!("**{WORST_CASE_ON_THE_WIRE}** (true worst case")),
        "PROTOCOL.md does not state the true worst case of {WORST_CASE_ON_THE_WIRE} bytes"
    );
}
