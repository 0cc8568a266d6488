//! The station's own client code against the emulator over a real pty: the link task with
//! its serial connector and the transfer client connect, drive the simulated robot with
//! teleop (its `EmuTruth` shows it moving), upload a map, plan on the robot and download the
//! plan, and reconnect within about a second when the emulator is restarted on the same path.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use emulator::link::{spawn, EmulatorOptions, RunningEmulator};
use protocol::object::PlanView;
use protocol::{Command, ObjectKind};
use station::link::serial::SerialConnector;
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions};
use station::plan::{MapOptions, NavMap};
use station::transfer::objects::map_object;
use station::transfer::{JobOutcome, TransferClient};
use tokio::time::Instant;

/// A fixed symlink path in a private directory: each emulator started on it keeps the name.
fn link_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("station-e2e-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("robot")
}

fn emulator(path: &Path) -> RunningEmulator {
    let mut opts = EmulatorOptions::builtin_default();
    opts.serve.link = Some(path.to_path_buf());
    opts.sim.seed = 4;
    spawn(opts).expect("emulator starts")
}

fn client(path: &Path) -> TransferClient {
    let link = spawn_link(SerialConnector::new(path, 115_200), LinkOptions::default());
    TransferClient::new(link, false)
}

async fn connected(c: &mut TransferClient, within: Duration) -> bool {
    c.wait_for(within, |e| match e {
        LinkEvent::Connection(Connection::Connected(_)) => Some(()),
        _ => None,
    })
    .await
    .is_some()
}

fn truth(c: &TransferClient) -> Option<protocol::Pose> {
    c.last_seen(|e| match e {
        LinkEvent::Truth(t) => Some(t.pose),
        _ => None,
    })
}

#[tokio::test]
async fn teleop_moves_the_robot_then_a_map_uploads_and_the_robot_plans_on_it() {
    let path = link_path("drive");
    let _emu = emulator(&path);
    let mut c = client(&path);
    assert!(connected(&mut c, Duration::from_secs(3)).await, "handshake");
    c.idle(Duration::from_millis(300)).await;
    let before = truth(&c).expect("EmuTruth frames");
    for _ in 0..10 {
        let teleop = Command::Teleop {
            v_mm_s: 200,
            w_mrad_s: 0,
        };
        assert!(c.command(teleop).await.is_ack());
        c.idle(Duration::from_millis(100)).await;
    }
    assert!(c.command(Command::Stop).await.is_ack());
    c.idle(Duration::from_millis(200)).await;
    let after = truth(&c).unwrap();
    let moved = f64::from(after.x_mm - before.x_mm).hypot(f64::from(after.y_mm - before.y_mm));
    println!("teleop: the true pose moved {moved:.0} mm");
    assert!(moved > 80.0, "the robot moved {moved} mm");

    let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).unwrap();
    let m = map_object(&map).unwrap();
    let up = c.upload(ObjectKind::Map, m.bytes.clone()).await;
    println!("{}", up.text());
    assert_eq!(up.outcome, JobOutcome::Complete);
    let again = c.upload(ObjectKind::Map, m.bytes.clone()).await;
    assert_eq!(again.outcome, JobOutcome::AlreadyHave);
    // From the map's start (the robot has driven off it) to the map's goal.
    let (id, plan) = c.plan_on_robot(m.start, None).await.unwrap();
    let view = PlanView::parse(&plan).unwrap();
    println!(
        "plan on the robot: id {id:#010x}, {} waypoints, {} bytes",
        view.waypoint_count(),
        plan.len()
    );
    assert_eq!(view.meta.map_id, m.id);
    // Waypoints go through the grid's 1/256-cell units: within a millimetre or two.
    let (first, start) = (view.waypoints().next().unwrap(), m.start.unwrap());
    assert!((first.x_mm - start.x_mm).abs() <= 2 && (first.y_mm - start.y_mm).abs() <= 2);
    let back = c.download(ObjectKind::Map).await;
    assert_eq!(back.bytes.as_deref(), Some(&m.bytes[..]));
    c.shutdown().await;
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}

#[tokio::test]
async fn the_station_reconnects_within_a_second_when_the_emulator_restarts() {
    let path = link_path("restart");
    let emu = emulator(&path);
    let mut c = client(&path);
    assert!(connected(&mut c, Duration::from_secs(3)).await, "handshake");
    c.idle(Duration::from_millis(200)).await;
    drop(emu);
    let lost = c
        .wait_for(Duration::from_secs(3), |e| match e {
            LinkEvent::Connection(Connection::Closed { reason }) => Some(reason.clone()),
            _ => None,
        })
        .await;
    println!("emulator stopped: {lost:?}");
    assert!(lost.is_some(), "the station noticed");
    c.idle(Duration::from_millis(500)).await;
    c.clear_seen();
    let _emu = emulator(&path);
    let back = Instant::now();
    assert!(
        connected(&mut c, Duration::from_secs(3)).await,
        "no reconnect"
    );
    let took = back.elapsed();
    println!(
        "reconnected {} ms after the port came back",
        took.as_millis()
    );
    assert!(took < Duration::from_millis(1000), "took {took:?}");
    // The new robot holds no map: an upload completes on the new session.
    let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).unwrap();
    let up = c
        .upload(ObjectKind::Map, map_object(&map).unwrap().bytes)
        .await;
    assert_eq!(up.outcome, JobOutcome::Complete);
    c.shutdown().await;
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}
