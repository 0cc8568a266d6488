//! Record -> file -> replay, against the real robot firmware in-process (`FirmwareSim` on an
//! in-memory port, tokio time paused): the file holds both directions and a gap marker for an
//! unplug, and the replay's summary and screen state agree with what the live link saw.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::time::Duration;

use protocol::{Command, Mode};
use station::app::{App, AppOptions};
use station::link::memory::{memory_port, Plug};
use station::link::sim::{FirmwareSim, SimCore, SimOptions};
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions, LinkStats, RunningLink};
use station::record::live::LiveRecorder;
use station::record::{LinkState, Meta, RecordKind, Recording};
use station::replay::summary::summarize;
use station::replay::ReplayFeed;
use tokio::sync::mpsc;
use tokio::time::Instant;

struct Rig {
    _sim: FirmwareSim,
    link: RunningLink,
    plug: Plug,
    tap: mpsc::UnboundedReceiver<station::link::TapRecord>,
    rec: LiveRecorder,
    live_stats: Option<LinkStats>,
    live_telemetry: u64,
    connected: u32,
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("record-rt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn rig(path: &std::path::Path) -> Rig {
    let (connector, peer) = memory_port();
    let plug = peer.plug();
    let sim = FirmwareSim::spawn(peer, SimCore::new(SimOptions::default()));
    let (tx, tap) = mpsc::unbounded_channel();
    let epoch = Instant::now();
    let link = spawn_link(
        connector,
        LinkOptions {
            nonce_seed: Some(7),
            tap: Some(tx),
            ..LinkOptions::default()
        },
    );
    let rec = LiveRecorder::start(
        path,
        &Meta::now("memory", 115_200),
        false,
        epoch,
        &Connection::Closed {
            reason: "starting".into(),
        },
    )
    .unwrap();
    Rig {
        _sim: sim,
        link,
        plug,
        tap,
        rec,
        live_stats: None,
        live_telemetry: 0,
        connected: 0,
    }
}

impl Rig {
    /// Records for `d` of tokio time.
    async fn run(&mut self, d: Duration) {
        let deadline = Instant::now() + d;
        loop {
            tokio::select! {
                Some(t) = self.tap.recv() => self.rec.on_tap(&t).unwrap(),
                Some(ev) = self.link.events.recv() => match ev {
                    LinkEvent::Connection(c) => {
                        self.connected += u32::from(matches!(c, Connection::Connected(_)));
                        self.rec.on_connection(&c).unwrap();
                    }
                    LinkEvent::Stats(s) => self.live_stats = Some(*s),
                    LinkEvent::Telemetry(_) => self.live_telemetry += 1,
                    _ => {}
                },
                () = tokio::time::sleep_until(deadline) => break,
            }
        }
    }
}

#[tokio::test(start_paused = true)]
async fn a_recording_with_an_unplug_replays_with_both_directions_and_a_gap() {
    let d = dir("gap");
    let path = d.join("run.rec");
    let mut r = rig(&path);
    r.run(Duration::from_secs(2)).await;
    assert_eq!(r.connected, 1);
    r.link.handle.submit(Command::SetMode(Mode::Wander));
    r.run(Duration::from_secs(1)).await;
    r.plug.unplug();
    r.run(Duration::from_secs(2)).await;
    r.plug.replug();
    r.run(Duration::from_secs(2)).await;
    assert_eq!(r.connected, 2, "the link came back");
    let live = r.live_stats.clone().unwrap();
    let written = r.rec.finish("test done").unwrap();
    assert_eq!(written.path, path);

    let rec = Recording::open(&path).unwrap();
    assert!(rec.damage.is_none(), "{:?}", rec.damage);
    assert_eq!(rec.end.as_deref(), Some("test done"));
    let to_robot: usize = rec
        .records
        .iter()
        .filter(|r| r.kind == RecordKind::ToRobot)
        .map(|r| r.data.len())
        .sum();
    assert!(to_robot > 100, "the station's own bytes are recorded");
    let gaps = rec
        .records
        .iter()
        .filter_map(|r| r.link())
        .filter(|(s, _)| *s == LinkState::Closed)
        .count();
    assert!(gaps >= 1, "the unplug is a link record");

    let s = summarize(&rec);
    assert_eq!(s.sessions, 2);
    assert_eq!(s.gaps.len(), 1, "{:?}", s.gaps);
    let g = &s.gaps[0];
    assert!(g.reason.contains("memory"), "{}", g.reason);
    assert!((1.8..=2.6).contains(&g.duration_s), "{g:?}");
    assert_eq!(s.frames_to_robot.get("Hello").copied(), Some(2));
    assert!(s.frames_to_robot.get("Heartbeat").copied().unwrap_or(0) > 5);
    assert_eq!(s.frames_to_robot.get("Command").copied(), Some(1));
    assert_eq!(s.frames_from_robot.get("HelloReply").copied(), Some(2));
    assert_eq!(s.commands.submitted, 1);
    assert_eq!(s.commands.acked, 1);
    // What the live link counted, the replay counts (over the same bytes).
    assert_eq!(s.telemetry.frames, r.live_telemetry);
    assert!(
        (9.0..=11.0).contains(&s.telemetry.mean_hz),
        "{}",
        s.telemetry.mean_hz
    );
    assert_eq!(s.errors.crc_errors, live.decoder.crc_errors);
    assert_eq!(s.bytes_to_robot as usize, to_robot);
    assert_eq!(s.robot.as_ref().unwrap().firmware, "robot-firmware");
    let _ = std::fs::remove_dir_all(&d);
}

#[tokio::test(start_paused = true)]
async fn the_replayed_app_ends_in_the_state_the_live_app_saw() {
    let d = dir("app");
    let path = d.join("run.rec");
    let mut r = rig(&path);
    r.run(Duration::from_secs(1)).await;
    r.link.handle.submit(Command::SetMode(Mode::Wander));
    r.run(Duration::from_secs(2)).await;
    r.rec.finish("done").unwrap();

    let rec = Recording::open(&path).unwrap();
    let mut app = App::new(AppOptions::default());
    // As `ReplaySession` does: a replayed connection asks the robot nothing.
    app.replaying = true;
    let mut feed = ReplayFeed::new(&rec.meta.port);
    let mut actions = Vec::new();
    feed.advance_to(&rec.records, rec.duration_us(), &mut actions);
    for a in actions {
        app.update(a.into());
    }
    assert!(app.connected());
    assert_eq!(app.telemetry.unwrap().mode, Mode::Wander);
    assert!(app.truth.is_some());
    let stats = app.stats.as_ref().unwrap();
    assert_eq!(stats.state, "connected");
    assert_eq!(stats.commands.acked, 1);
    assert!(stats.frames_out > 0);
    assert!(app.take_outbox().is_empty(), "a replay sends nothing");
    let log: Vec<String> = app.log.window(100).map(|l| l.text.clone()).collect();
    assert!(
        log.iter().any(|l| l.starts_with("ok: mode Wander")),
        "the command's outcome reaches the log: {log:?}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
