//! The world's side alone; the board's loop driving it (and reproducing the emulator's own run
//! bit for bit) is tested in robot-firmware/board (`board::tests`).

use protocol::hil::{HilDecoder, Motors, Msg, PowerOn};
use protocol::{Mode, ProfileId};
use robot_firmware::MICRO_RATO;

use super::*;
use crate::sim::{Sim, SimConfig};

fn sim(seed: u64) -> Sim {
    let arena = crate::builtin::load(crate::builtin::MICRO_RATO_99, &Default::default())
        .expect("built-in arena");
    let mut cfg = SimConfig::new(&MICRO_RATO);
    cfg.seed = seed;
    Sim::new(arena, cfg).expect("sim")
}

fn frame(msg: &Msg) -> Vec<u8> {
    let mut out = Vec::new();
    send(msg, &mut out);
    out
}

fn decode(bytes: &[u8]) -> Vec<Msg> {
    let mut d = HilDecoder::new();
    bytes
        .iter()
        .filter_map(|&b| d.feed(b))
        .map(|r| r.expect("the world sends good frames"))
        .collect()
}

fn power_on() -> Vec<u8> {
    frame(&Msg::PowerOn(PowerOn {
        version: HIL_VERSION,
        profile: ProfileId::MicroRato,
    }))
}

#[test]
fn power_on_is_answered_with_the_setup_and_the_sensors_of_time_zero() {
    let mut w = HilWorld::new(sim(3), Some([7; KEY_LEN]), Mode::Idle).expect("world");
    let mut out = Vec::new();
    w.feed(&power_on(), &mut out).expect("accepted");
    let msgs = decode(&out);
    assert_eq!(msgs.len(), 2, "{msgs:?}");
    let Msg::Setup(s) = msgs[0] else {
        panic!("{msgs:?}")
    };
    assert_eq!(s.period_us, MICRO_RATO.cycle_us);
    assert_eq!(s.firmware_seed, firmware_seed(3));
    assert_eq!(s.key, Some([7; KEY_LEN]));
    assert!(s.beacon.is_some(), "Micro-Rato'99 has a beacon");
    let Msg::Sensors(z) = msgs[1] else {
        panic!("{msgs:?}")
    };
    assert_eq!((z.seq, z.time_us), (0, 0));
    assert!(z.compass.is_some() && z.encoders.is_none());
}

#[test]
fn motors_advance_one_period_and_a_stale_or_damaged_frame_changes_nothing() {
    let mut w = HilWorld::new(sim(1), None, Mode::Idle).expect("world");
    let mut out = Vec::new();
    w.feed(&power_on(), &mut out).expect("accepted");
    let go = |seq| {
        frame(&Msg::Motors(Motors {
            seq,
            left: 40,
            right: 40,
            arm: 0,
            closed: false,
        }))
    };
    out.clear();
    w.feed(&go(0), &mut out).expect("accepted");
    let msgs = decode(&out);
    let Msg::Sensors(s) = msgs[0] else {
        panic!("{msgs:?}")
    };
    assert_eq!((s.seq, s.time_us), (1, u64::from(MICRO_RATO.cycle_us)));
    let moved = w.summary();
    assert!(moved.distance_m > 0.0);
    // The same Motors again (a repeat): no second period.
    out.clear();
    w.feed(&go(0), &mut out).expect("accepted");
    assert!(out.is_empty());
    let mut bad = go(1);
    bad[3] ^= 0x10;
    w.feed(&bad, &mut out).expect("a bad frame is not fatal");
    assert!(out.is_empty());
    let s = w.summary();
    assert_eq!((s.exchanges, s.stale_motors, s.frame_errors), (1, 1, 1));
    assert_eq!(s.distance_m, moved.distance_m);
}

#[test]
fn a_board_built_for_another_profile_is_refused_by_name() {
    let mut w = HilWorld::new(sim(1), None, Mode::Idle).expect("world");
    let khepera = frame(&Msg::PowerOn(PowerOn {
        version: HIL_VERSION,
        profile: ProfileId::Khepera,
    }));
    let err = w.feed(&khepera, &mut Vec::new()).expect_err("refused");
    assert!(err.to_string().contains("Khepera"), "{err}");
}
