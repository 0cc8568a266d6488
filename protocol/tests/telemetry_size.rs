//! The telemetry frame's TRUE worst case on the wire, stated in PROTOCOL.md §2: at most 80
//! bytes for any `Telemetry` value. Each field travels within a range (`telemetry_range`) whose
//! widest value takes a known number of varint bytes; the widest frame is built here from those
//! ranges, and every value of every field's type (the widest by type, and random ones) is shown
//! to encode no wider. Before the ranges, the widest by type took 97 bytes.
#![allow(clippy::unwrap_used, clippy::panic)]

mod common;

use proptest::prelude::*;
use protocol::telemetry_range::{
    BEARING_DDEG, COMPASS_MAX_DDEG, CYCLE_MAX_US, HEADING_MRAD, MAX_TELEMETRY_FRAME, POSITION_MM,
    SIGMA_MAX, SPEED_MM_S, WIDEST_FRAME,
};
use protocol::{
    encode, Beacon, BehaviourOut, CycleTiming, Feed, FrameDecoder, Message, Mode, Packed10x8, Pose,
    PoseSigma, Telemetry, Wheels, MAX_FRAME,
};

/// PROTOCOL.md §2: "true worst case".
const WORST_CASE_ON_THE_WIRE: usize = 80;

/// The telemetry a frame's bytes decode to.
fn decode(wire: &[u8]) -> Telemetry {
    let mut dec = FrameDecoder::new();
    match dec.feed(wire) {
        Feed::Frame { frame, .. } => match frame.message {
            Message::Telemetry(t) => t,
            m => panic!("{m:?}"),
        },
        _ => panic!("no frame in {wire:02x?}"),
    }
}

fn frame_len(t: Telemetry) -> usize {
    let mut buf = [0u8; MAX_FRAME];
    encode(u16::MAX, &Message::Telemetry(t), &mut buf).unwrap()
}

/// Every field at the end of its range that takes the most bytes (for a signed field, both
/// ends take the same; the lower is used), the sequence number too.
fn widest_in_range() -> Telemetry {
    Telemetry {
        time_ms: u32::MAX,
        mode: Mode::CalibrateLight,
        pose: Pose {
            x_mm: POSITION_MM.0,
            y_mm: POSITION_MM.1,
            heading_mrad: HEADING_MRAD.0,
        },
        sigma: PoseSigma {
            xy_mm: SIGMA_MAX,
            heading_mrad: SIGMA_MAX,
        },
        wheels: Wheels {
            speed_mm_s: [SPEED_MM_S.0, SPEED_MM_S.1],
            encoders: [u16::MAX; 2],
        },
        ir: Packed10x8::new([1023; 8]),
        light: Packed10x8::new([1023; 8]),
        compass_ddeg: COMPASS_MAX_DDEG,
        flags: u8::MAX,
        line_events: u8::MAX,
        beacon: Beacon {
            bearing_ddeg: BEARING_DDEG.0,
            strength: u8::MAX,
        },
        battery_mv: u16::MAX,
        behaviour: BehaviourOut {
            active: u8::MAX,
            motor_mm_s: [SPEED_MM_S.0, SPEED_MM_S.1],
        },
        cycle: CycleTiming {
            period_us: CYCLE_MAX_US,
            busy_us: CYCLE_MAX_US,
            overruns: u8::MAX,
        },
    }
}

/// Every field at the widest value its type holds.
fn widest_by_type() -> Telemetry {
    Telemetry {
        time_ms: u32::MAX,
        mode: Mode::CalibrateLight,
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
        compass_ddeg: u16::MAX,
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
        ..widest_in_range()
    }
}

#[test]
fn the_widest_frame_the_ranges_allow_is_the_size_protocol_md_states() {
    let t = widest_in_range();
    assert_eq!(frame_len(t), WORST_CASE_ON_THE_WIRE);
    assert_eq!(WIDEST_FRAME, WORST_CASE_ON_THE_WIRE);
    assert_eq!(MAX_TELEMETRY_FRAME, 80);
    // Inside its ranges the frame is sent as it is.
    assert_eq!(t.bounded(), t);
    let doc = include_str!("../PROTOCOL.md");
    assert!(
        doc.contains(&format!("**{WORST_CASE_ON_THE_WIRE}** (true worst case")),
        "PROTOCOL.md does not state the true worst case of {WORST_CASE_ON_THE_WIRE} bytes"
    );
}

#[test]
fn the_widest_values_of_every_type_are_brought_into_the_ranges() {
    // 97 bytes before the ranges.
    assert_eq!(frame_len(widest_by_type()), WORST_CASE_ON_THE_WIRE);
    let mut buf = [0u8; MAX_FRAME];
    let n = encode(7, &Message::Telemetry(widest_by_type()), &mut buf).unwrap();
    let back = decode(&buf[..n]);
    assert_eq!(back, widest_by_type().bounded());
    assert_eq!(back.pose.x_mm, POSITION_MM.0);
    assert_eq!(back.cycle.period_us, CYCLE_MAX_US);
    assert_eq!(back.sigma.xy_mm, SIGMA_MAX);
}

#[test]
fn the_typical_frame_keeps_its_size() {
    // The widest values a robot plausibly sends, and the test vector: as before the ranges.
    assert_eq!(frame_len(common::full_telemetry()), 76);
    assert_eq!(common::full_telemetry().bounded(), common::full_telemetry());
}

proptest! {
    #[test]
    fn any_telemetry_fits_the_budget_and_decodes_to_its_bounded_self(t in common::telemetry()) {
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(1, &Message::Telemetry(t), &mut buf).unwrap();
        prop_assert!(n <= WORST_CASE_ON_THE_WIRE, "{n} bytes: {t:?}");
        prop_assert_eq!(decode(&buf[..n]), t.bounded());
        // Bounding twice changes nothing: a decoded frame re-encodes to the same bytes.
        prop_assert_eq!(t.bounded().bounded(), t.bounded());
    }
}
