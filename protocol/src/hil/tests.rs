extern crate std;
use std::format;
use std::string::String;
use std::vec;
use std::vec::Vec;

use proptest::prelude::*;

use super::*;

fn frame(msg: &Msg) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(msg, &mut out).expect("encodes");
    out[..n].to_vec()
}

fn decode_all(bytes: &[u8]) -> Vec<Result<Msg, HilError>> {
    let mut d = HilDecoder::new();
    bytes.iter().filter_map(|&b| d.feed(b)).collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn sample_sensors() -> Sensors {
    Sensors {
        seq: 7,
        time_us: 350_000,
        ir: [1, 2, 3, 4, 5, 6, 0, 0],
        ambient: [0; 8],
        compass: Some(1.5),
        ground: false,
        line: false,
        beacon: Some((-0.25, 200)),
        battery_mv: 9600,
        encoders: None,
        gripper: None,
        whiskers: None,
        photoresistors: None,
    }
}

fn sample_setup() -> Setup {
    Setup {
        version: HIL_VERSION,
        profile: ProfileId::MicroRato,
        period_us: 50_000,
        firmware_seed: 0xDEAD_BEEF,
        start: [0.5, 0.25, 0.0],
        beacon: Some(Xy { x: 3.0, y: 2.5 }),
        bounds: [Xy { x: 0.0, y: 0.0 }, Xy { x: 4.0, y: 3.0 }],
        power_on_mode: Mode::Explore,
        key: Some([0x11; KEY_LEN]),
    }
}

/// The vectors of docs/hil.md §5 (computed from the document's layouts alone by
/// tests/tools/hil_vectors.py): the bytes on the wire, delimiter included.
#[test]
fn test_vectors_match_the_document() {
    let power_on = Msg::PowerOn(PowerOn {
        version: 1,
        profile: ProfileId::MicroRato,
    });
    assert_eq!(hex(&frame(&power_on)), "08 01 01 01 70 2a ec 24 00");
    let motors = Msg::Motors(Motors {
        seq: 7,
        left: 60,
        right: -60,
        arm: 0,
        closed: false,
    });
    assert_eq!(
        hex(&frame(&motors)),
        "03 04 07 01 01 02 3c 03 c4 ff 01 05 df 8e 9f 03 00"
    );
    let sensors = Msg::Sensors(sample_sensors());
    assert_eq!(
        hex(&frame(&sensors)),
        "03 03 07 01 01 04 30 57 05 01 01 01 01 02 09 02 01 02 02 02 03 02 04 02 05 02 06 01 \
         01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 01 03 c0 3f 01 06 80 be \
         c8 80 25 01 01 01 01 01 01 01 05 30 af e4 b0 00"
    );
}

#[test]
fn every_message_round_trips() {
    let msgs = [
        Msg::PowerOn(PowerOn {
            version: 1,
            profile: ProfileId::Alice,
        }),
        Msg::Setup(sample_setup()),
        Msg::Setup(Setup {
            beacon: None,
            key: None,
            power_on_mode: Mode::Idle,
            ..sample_setup()
        }),
        Msg::Sensors(sample_sensors()),
        Msg::Sensors(Sensors {
            encoders: Some([-5, i32::MAX]),
            gripper: Some((255, true, false)),
            whiskers: Some(0x00FF_00FF),
            photoresistors: Some([9; 24]),
            ground: true,
            line: true,
            compass: None,
            beacon: None,
            ..sample_sensors()
        }),
        Msg::Motors(Motors {
            seq: u32::MAX,
            left: i16::MIN,
            right: i16::MAX,
            arm: 200,
            closed: true,
        }),
        Msg::Report(Report {
            static_ram: 1,
            stack_size: 2,
            stack_used: 3,
            rx_bytes: 4,
            rx_fifo_max: 5,
            rx_dropped: 6,
            cycles: 7,
            cycle_ticks_last: 8,
            cycle_ticks_max: 9,
            cycle_ticks_sum: 10,
            rx_passes: 11,
            rx_frames: 12,
            rx_pass_ticks_sum: 13,
            rx_pass_ticks_max: 14,
            sleeps: 15,
            hil_errors: 16,
        }),
        Msg::Fault(fault::PANIC),
    ];
    let mut stream = Vec::new();
    for m in &msgs {
        let f = frame(m);
        assert!(f.len() <= MAX_FRAME);
        assert_eq!(f.iter().filter(|&&b| b == 0).count(), 1, "{m:?}");
        stream.extend(f);
    }
    let got: Vec<Msg> = decode_all(&stream)
        .into_iter()
        .map(|r| r.expect("decodes"))
        .collect();
    assert_eq!(got, msgs);
}

#[test]
fn a_damaged_frame_is_refused_and_the_next_one_read() {
    let good = frame(&Msg::Fault(fault::HARD_FAULT));
    let mut bad = good.clone();
    bad[2] ^= 0x40;
    let mut stream = bad;
    stream.extend(&good);
    let got = decode_all(&stream);
    assert_eq!(got.len(), 2);
    assert!(got[0].is_err(), "{got:?}");
    assert_eq!(got[1], Ok(Msg::Fault(fault::HARD_FAULT)));
}

#[test]
fn an_oversize_frame_is_dropped_whole() {
    let mut stream = vec![0x55u8; MAX_ENCODED + 40];
    stream.push(0);
    stream.extend(frame(&Msg::Fault(1)));
    let got = decode_all(&stream);
    assert_eq!(got, vec![Err(HilError::Oversize), Ok(Msg::Fault(1))]);
}

#[test]
fn non_finite_numbers_and_unknown_values_are_refused() {
    // A compass reading of NaN, built by hand with a correct CRC.
    let mut raw = vec![kind::SENSORS];
    raw.extend(7u32.to_le_bytes());
    raw.extend(0u64.to_le_bytes());
    raw.extend(S_COMPASS.to_le_bytes());
    raw.extend([0u8; 32]);
    raw.extend(f32::NAN.to_le_bytes());
    raw.extend([0u8; 4 + 1 + 2 + 8]);
    raw.extend(crc32c(&raw).to_le_bytes());
    assert_eq!(parse(&raw), Err(HilError::NotFinite));
    let mut raw = vec![kind::POWER_ON, 1, 9];
    raw.extend(crc32c(&raw).to_le_bytes());
    assert_eq!(parse(&raw), Err(HilError::BadValue));
    let mut raw = vec![kind::FAULT, 1, 2];
    raw.extend(crc32c(&raw).to_le_bytes());
    assert_eq!(parse(&raw), Err(HilError::BadLength));
    let mut raw = vec![99, 1];
    raw.extend(crc32c(&raw).to_le_bytes());
    assert_eq!(parse(&raw), Err(HilError::UnknownKind(99)));
}

proptest! {
    /// Untrusted bytes: any input yields errors or messages, never a panic, and a good frame
    /// after a delimiter is always read.
    #[test]
    fn any_bytes_are_safe(noise in proptest::collection::vec(any::<u8>(), 0..600)) {
        let mut stream = noise;
        stream.push(0);
        let good = Msg::Motors(Motors { seq: 3, left: 1, right: 2, arm: 0, closed: false });
        stream.extend(frame(&good));
        let got = decode_all(&stream);
        prop_assert_eq!(got.last().cloned(), Some(Ok(good)));
    }
}
