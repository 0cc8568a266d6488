//! Time of one `Robot::step()` on the host: a control cycle with telemetry, per profile and
//! mode, and a link-only pass (the main loop between control cycles).
#![allow(clippy::unwrap_used, clippy::panic)]

use criterion::{criterion_group, criterion_main, Criterion};
use protocol::{
    encode, Command, Hello, Message, PointMm, FINGERPRINT, MAX_FRAME, PROTOCOL_VERSION,
};
use robot_firmware::odometry::Pose;
use robot_firmware::robot::{DomDinis, Khepera};
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::{AnyRobot, Profile, Robot, RobotOptions, KHEPERA, MICRO_RATO};
use std::hint::black_box;

fn connected(profile: &'static Profile, cmd: Command) -> (AnyRobot, ScriptedHal) {
    let mut robot = AnyRobot::new(RobotOptions {
        profile,
        seed: 3,
        start: Pose::new(0.3, 0.3, 0.0),
        emulated: false,
        firmware_version: "bench",
    });
    let mut hal = ScriptedHal {
        encoders: profile.has(protocol::caps::ENCODERS).then_some([0, 0]),
        compass: Some(0.3),
        ir: [100, 300, 520, 480, 90, 20, 0, 0],
        ambient: [480, 470, 300, 310, 490, 500, 500, 500],
        ..ScriptedHal::default()
    };
    let mut buf = [0u8; MAX_FRAME];
    let hello = Hello {
        fingerprint: FINGERPRINT,
        protocol: PROTOCOL_VERSION,
        session: 1,
        station: "bench",
    };
    let n = encode(0, &Message::Hello(hello), &mut buf).unwrap();
    hal.push_rx(&buf[..n]);
    let n = encode(1, &Message::Command(cmd), &mut buf).unwrap();
    hal.push_rx(&buf[..n]);
    robot.step(&mut hal);
    (robot, hal)
}

fn bench_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    let cases: [(&str, &'static Profile, Command); 3] = [
        (
            "khepera_goto_control_cycle",
            &KHEPERA,
            Command::GoTo(PointMm {
                x_mm: 600,
                y_mm: 400,
            }),
        ),
        (
            "khepera_wander_control_cycle",
            &KHEPERA,
            Command::SetMode(protocol::Mode::Wander),
        ),
        (
            "micro_rato_goto_control_cycle",
            &MICRO_RATO,
            Command::GoTo(PointMm {
                x_mm: 3000,
                y_mm: 2500,
            }),
        ),
    ];
    for (name, profile, cmd) in cases {
        let (mut robot, mut hal) = connected(profile, cmd);
        let cycle = u64::from(profile.cycle_us);
        g.bench_function(name, |b| {
            b.iter(|| {
                // Every call is a full control cycle: the clock advances one period.
                hal.now_us += cycle;
                if let Some(e) = hal.encoders.as_mut() {
                    e[0] += 50;
                    e[1] += 53;
                }
                robot.step(black_box(&mut hal));
                hal.tx.clear();
            })
        });
    }
    // A full busy cycle: a heartbeat arrives, the control cycle runs, a telemetry frame
    // (50 Hz, so one every cycle) is built, encoded and written.
    let (mut robot, mut hal) = connected(&KHEPERA, Command::SetTelemetryRate { hz: 50 });
    if let AnyRobot::Khepera(r) = &mut robot {
        r.core
            .arbiter
            .set_mode(robot_firmware::behaviour::Mode::Wander);
    }
    let mut hb = [0u8; MAX_FRAME];
    let n = encode(
        9,
        &Message::Heartbeat(protocol::Heartbeat { time_ms: 0 }),
        &mut hb,
    )
    .unwrap();
    g.bench_function("khepera_cycle_with_heartbeat_in_and_telemetry_out", |b| {
        b.iter(|| {
            hal.now_us += u64::from(KHEPERA.cycle_us);
            hal.push_rx(&hb[..n]);
            robot.step(black_box(&mut hal));
            assert!(!hal.tx.is_empty());
            hal.tx.clear();
        })
    });
    let (mut robot, mut hal) = connected(&KHEPERA, Command::SetMode(protocol::Mode::Wander));
    g.bench_function("link_only_pass", |b| {
        b.iter(|| {
            // 100 us later: no control cycle is due, only the link is serviced.
            hal.now_us += 100;
            robot.step(black_box(&mut hal));
            hal.tx.clear();
        })
    });
    g.finish();
    eprintln!(
        "size_of::<Robot<DomDinis>>() = {} bytes, size_of::<Robot<Khepera>>() = {} bytes",
        std::mem::size_of::<Robot<DomDinis>>(),
        std::mem::size_of::<Robot<Khepera>>()
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2));
    targets = bench_step
}
criterion_main!(benches);
