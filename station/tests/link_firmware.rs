//! The link task end to end against the real robot firmware, in-process: an in-memory port
//! whose far end is `robot_firmware::Robot` stepped with `ScriptedHal`. Tokio time is paused,
//! so seconds of link time run in milliseconds and every timing figure is exact.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use protocol::{caps, AckInfo, Command, Mode, NackReason, ParamId};
use robot_firmware::MotorCommand;
use station::link::memory::{memory_port, Plug};
use station::link::sim::{FirmwareSim, SimCore, SimOptions};
use station::link::{
    spawn_link, CommandFailure, CommandOutcome, Connection, LinkEvent, LinkOptions, LinkStats,
    RunningLink,
};
use tokio::time::Instant;

struct Bench {
    sim: FirmwareSim,
    link: RunningLink,
    plug: Plug,
}

fn bench(opts: SimOptions) -> Bench {
    let (connector, peer) = memory_port();
    let plug = peer.plug();
    let sim = FirmwareSim::spawn(peer, SimCore::new(opts));
    let link = spawn_link(
        connector,
        LinkOptions {
            nonce_seed: Some(42),
            ..LinkOptions::default()
        },
    );
    Bench { sim, link, plug }
}

impl Bench {
    /// Waits (in tokio time) for the first event `pick` accepts.
    async fn wait<T>(
        &mut self,
        within: Duration,
        mut pick: impl FnMut(&LinkEvent) -> Option<T>,
    ) -> T {
        let deadline = Instant::now() + within;
        loop {
            let ev = tokio::time::timeout_at(deadline, self.link.events.recv())
                .await
                .expect("timed out waiting for an event")
                .expect("event stream ended");
            if let Some(t) = pick(&ev) {
                return t;
            }
        }
    }

    async fn connected(&mut self, within: Duration) -> station::link::PeerInfo {
        self.wait(within, |e| match e {
            LinkEvent::Connection(Connection::Connected(p)) => Some(p.clone()),
            _ => None,
        })
        .await
    }

    /// The newest statistics: drains 300 ms of events (a snapshot is published every 250 ms).
    async fn stats(&mut self) -> LinkStats {
        let deadline = Instant::now() + Duration::from_millis(300);
        let mut last = None;
        while let Ok(Some(e)) = tokio::time::timeout_at(deadline, self.link.events.recv()).await {
            if let LinkEvent::Stats(s) = e {
                last = Some(*s);
            }
        }
        last.expect("a statistics snapshot")
    }

    /// Lets `d` of tokio time pass while draining events.
    async fn idle(&mut self, d: Duration) {
        let deadline = Instant::now() + d;
        while let Ok(Some(_)) = tokio::time::timeout_at(deadline, self.link.events.recv()).await {}
    }
}

#[tokio::test(start_paused = true)]
async fn the_station_handshakes_with_the_real_firmware_and_receives_telemetry() {
    let mut b = bench(SimOptions::default());
    let peer = b.connected(Duration::from_secs(1)).await;
    assert_eq!(peer.firmware, "robot-firmware");
    assert!(
        peer.has(caps::EMULATED),
        "the bench declares itself emulated"
    );
    assert_eq!(peer.telemetry_hz, 10);
    let t = b
        .wait(Duration::from_secs(1), |e| match e {
            LinkEvent::Telemetry(t) => Some(*t),
            _ => None,
        })
        .await;
    assert_eq!(t.pose.x_mm, 500, "the robot starts where the bench put it");
    b.idle(Duration::from_secs(2)).await;
    let s = b.stats().await;
    assert_eq!(s.state, "connected");
    assert!((9.0..=11.0).contains(&s.telemetry_hz), "{}", s.telemetry_hz);
    assert_eq!(s.robot_seq.lost, 0);
    assert!(s.truth_seq.received > 10, "EmuTruth counted on its own");
    assert_eq!(s.truth_seq.lost, 0);
    assert_eq!(s.decoder.errors(), 0);
    assert_eq!(s.handshakes, 1);
}

#[tokio::test(start_paused = true)]
async fn teleop_drives_the_firmware_motors_and_stop_halts_them() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    let teleop = Command::Teleop {
        v_mm_s: 160,
        w_mrad_s: 0,
    };
    let handle = b.link.handle.clone();
    let outcome = handle.call(teleop).await;
    assert!(
        matches!(outcome, CommandOutcome::Acked { sends: 1, .. }),
        "{outcome:?}"
    );
    // The motors move at the next control cycle (80 ms on a Khepera).
    b.idle(Duration::from_millis(100)).await;
    let m = b.sim.with(|s| s.hal.motors);
    assert_eq!(
        m,
        MotorCommand::new(20, 20),
        "160 mm/s is 20 units of 8 mm/s"
    );
    // Ten teleops a second for a second, as the TUI sends while driving.
    for _ in 0..10 {
        handle.submit(teleop);
        b.idle(Duration::from_millis(100)).await;
    }
    let x = b.sim.with(|s| s.robot.pose().x);
    assert!(x > 0.6, "the robot drove forward from 0.5 m, now at {x}");
    assert!(handle.call(Command::Stop).await.is_ack());
    b.idle(Duration::from_millis(100)).await;
    assert_eq!(b.sim.with(|s| s.hal.motors), MotorCommand::STOP);
}

#[tokio::test(start_paused = true)]
async fn refused_commands_come_back_with_the_robots_reason() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    let h = b.link.handle.clone();
    let cases = [
        (
            Command::SetParam {
                id: ParamId(0),
                value: 5.0,
            },
            NackReason::OutOfRange,
        ),
        (
            Command::GetParam { id: ParamId(999) },
            NackReason::UnknownParam,
        ),
        (Command::SetMode(Mode::Explore), NackReason::Unsupported),
        (Command::SetMode(Mode::GoTo), NackReason::BadState),
    ];
    for (command, reason) in cases {
        assert_eq!(
            h.call(command).await,
            CommandOutcome::Nacked { reason, sends: 1 },
            "{command:?}"
        );
    }
    // And an accepted parameter comes back with the value in force.
    let set = h
        .call(Command::SetParam {
            id: ParamId(0),
            value: 500.0,
        })
        .await;
    assert!(matches!(
        set,
        CommandOutcome::Acked {
            info: AckInfo::Param { value, .. },
            ..
        } if value == 500.0
    ));
}

#[tokio::test(start_paused = true)]
async fn a_dropped_command_is_retried_with_the_same_seq_and_executed_once() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    let h = b.link.handle.clone();
    // The command frame is lost on the way: the retry 200 ms later gets through.
    b.sim.with(|s| s.faults.drop_to_robot = 1);
    let o = h.call(Command::SetMode(Mode::Wander)).await;
    assert!(matches!(o, CommandOutcome::Acked { sends: 2, .. }), "{o:?}");
    // The ack is lost on the way back: the robot answers the retry from its reply cache.
    let before = b.sim.with(|s| s.robot.link().counters().retries_answered);
    b.sim.with(|s| s.faults.drop_from_robot = 1);
    let o = h.call(Command::SetMode(Mode::Idle)).await;
    assert!(matches!(o, CommandOutcome::Acked { sends: 2, .. }), "{o:?}");
    let after = b.sim.with(|s| s.robot.link().counters().retries_answered);
    assert_eq!(
        after,
        before + 1,
        "the retry was answered, not executed again"
    );
    let s = b.stats().await;
    assert_eq!(s.commands.resends, 2);
    assert_eq!(
        s.rtt_ms.samples, 0,
        "retried commands give no RTT sample (Karn)"
    );
}

#[tokio::test(start_paused = true)]
async fn a_command_nobody_answers_fails_after_five_sends() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    let h = b.link.handle.clone();
    b.sim.with(|s| s.faults.drop_to_robot = 5);
    let t0 = Instant::now();
    let o = h.call(Command::Stop).await;
    assert_eq!(
        o,
        CommandOutcome::Failed(CommandFailure::Timeout { sends: 5 })
    );
    let took = t0.elapsed();
    assert!(
        took >= Duration::from_millis(1000) && took < Duration::from_millis(1100),
        "{took:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn the_link_reconnects_within_a_second_of_the_port_coming_back() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    let h = b.link.handle.clone();
    assert!(h
        .call(Command::Teleop {
            v_mm_s: 100,
            w_mrad_s: 0
        })
        .await
        .is_ack());
    b.plug.unplug();
    let reason = b
        .wait(Duration::from_secs(1), |e| match e {
            LinkEvent::Connection(Connection::Closed { reason }) => Some(reason.clone()),
            _ => None,
        })
        .await;
    assert!(reason.contains("memory"), "{reason}");
    // The robot's failsafe stops the motors once the station falls silent.
    b.idle(Duration::from_millis(500)).await;
    assert_eq!(b.sim.with(|s| s.hal.motors), MotorCommand::STOP);
    // While unplugged, commands fail at once rather than queue up.
    assert_eq!(
        h.call(Command::Stop).await,
        CommandOutcome::Failed(CommandFailure::NotConnected)
    );
    b.idle(Duration::from_secs(2)).await;
    b.plug.replug();
    let t0 = Instant::now();
    b.connected(Duration::from_secs(1)).await;
    assert!(t0.elapsed() < Duration::from_secs(1));
    assert!(h.call(Command::SetMode(Mode::Manual)).await.is_ack());
    let s = b.stats().await;
    assert_eq!(s.handshakes, 2);
    assert!(s.port_opens >= 2);
}

#[tokio::test(start_paused = true)]
async fn a_silent_robot_ends_the_session_after_1_5_s_and_the_link_handshakes_again() {
    let mut b = bench(SimOptions::default());
    b.connected(Duration::from_secs(1)).await;
    b.sim.with(|s| s.faults.drop_from_robot = u32::MAX);
    let t0 = Instant::now();
    b.wait(Duration::from_secs(3), |e| {
        matches!(e, LinkEvent::Connection(Connection::Handshaking { .. })).then_some(())
    })
    .await;
    let took = t0.elapsed();
    assert!(
        took >= Duration::from_millis(1400) && took <= Duration::from_millis(1600),
        "{took:?}"
    );
    b.sim.with(|s| s.faults.drop_from_robot = 0);
    b.connected(Duration::from_secs(1)).await;
    assert_eq!(b.stats().await.link_timeouts, 1);
}

#[tokio::test(start_paused = true)]
async fn the_tap_sees_every_byte_both_ways_for_recording() {
    let (connector, peer) = memory_port();
    let _sim = FirmwareSim::spawn(peer, SimCore::new(SimOptions::default()));
    let (tap_tx, mut tap_rx) = tokio::sync::mpsc::unbounded_channel();
    let mut link = spawn_link(
        connector,
        LinkOptions {
            nonce_seed: Some(1),
            tap: Some(tap_tx),
            ..LinkOptions::default()
        },
    );
    let deadline = Instant::now() + Duration::from_secs(1);
    let mut stats = None;
    while let Ok(Some(e)) = tokio::time::timeout_at(deadline, link.events.recv()).await {
        if let LinkEvent::Stats(s) = e {
            stats = Some(*s);
        }
    }
    let stats = stats.expect("stats");
    let (mut to_robot, mut from_robot) = (Vec::new(), Vec::new());
    let mut last_t = 0;
    while let Ok(r) = tap_rx.try_recv() {
        assert!(r.t_us >= last_t, "records are in time order");
        last_t = r.t_us;
        match r.direction {
            station::link::TapDirection::ToRobot => to_robot.extend(r.bytes),
            station::link::TapDirection::FromRobot => from_robot.extend(r.bytes),
        }
    }
    assert_eq!(
        to_robot.first(),
        Some(&0),
        "the flush delimiter is recorded too"
    );
    assert!(to_robot.len() as u64 >= stats.bytes_out.saturating_sub(64));
    assert!(from_robot.len() as u64 >= stats.bytes_in.saturating_sub(256));
    assert!(!from_robot.is_empty());
}
