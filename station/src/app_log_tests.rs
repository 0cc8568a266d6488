//! Unit tests of what the operator reads through `App::update`: the log's coalescing of the
//! robot's repeated events and of parameter reads, stale values after link loss, and the
//! map's zoom and pan.

use super::*;
use crate::link::{CommandOutcome, LinkEvent};
use protocol::{AckInfo, Event, EventCode, MapCapacity, Mode, ParamId, ProfileId};

fn peer() -> PeerInfo {
    PeerInfo {
        session: 1,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile: ProfileId::Khepera,
        capabilities: 0,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id: 1,
    }
}

fn connected_app() -> App {
    let mut app = App::new(AppOptions::default());
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer(),
    ))));
    app
}

fn event(app: &mut App, code: EventCode, value: i32) {
    app.update(Action::Link(LinkEvent::Robot(Event { code, value })));
}

fn telemetry(app: &mut App, now_ms: u64, mode: Mode) {
    app.update(Action::Tick { now_ms });
    app.update(Action::Link(LinkEvent::Telemetry(Telemetry {
        mode,
        ..Telemetry::default()
    })));
}

fn texts(app: &App) -> Vec<String> {
    app.log.all().map(|l| l.display()).collect()
}

#[test]
fn a_beacon_calibration_every_second_is_one_line_with_a_count_and_its_last_time() {
    let mut app = connected_app();
    let before = app.log.len();
    for s in 1..=120u64 {
        app.update(Action::Tick { now_ms: s * 1000 });
        event(&mut app, EventCode::BeaconCalibration, 1000);
    }
    assert_eq!(app.log.len(), before + 1, "{:#?}", texts(&app));
    let l = app.log.window(1).next().unwrap();
    assert_eq!((l.count, l.t_ms), (120, 120_000));
    assert_eq!(
        l.display(),
        "beacon calibration, confidence 1.000 (×120 since 1.0 s)"
    );
}

#[test]
fn a_floor_survey_logs_one_line_not_two_per_line_crossed() {
    let mut app = connected_app();
    telemetry(&mut app, 100, Mode::Survey);
    let before = app.log.len();
    for n in 1..=40 {
        event(&mut app, EventCode::LineCrossed, n);
        event(&mut app, EventCode::PoseCorrected, 4);
    }
    assert_eq!(app.log.len(), before + 1, "{:#?}", texts(&app));
    let l = app.log.window(1).next().unwrap();
    assert_eq!(l.count, 40, "one count per line crossed");
    assert!(
        l.display()
            .starts_with("floor line 40 crossed, pose corrected by 4 mm (×40"),
        "{}",
        l.display()
    );
    // Outside a survey a correction (foraging's landmarks) is news of its own.
    telemetry(&mut app, 200, Mode::Forage);
    event(&mut app, EventCode::PoseCorrected, 30);
    assert_eq!(
        app.log.window(1).next().unwrap().display(),
        "pose corrected by 30 mm"
    );
}

#[test]
fn reading_every_parameter_adds_one_summary_line() {
    let mut app = connected_app();
    // The fetch on connect has its own reads in the outbox; this test is about `R`.
    app.take_outbox();
    app.update(Action::ShowView(View::Params));
    app.update(Action::ParamReadAll);
    let sent = app.take_outbox();
    // Every parameter this robot has the hardware for.
    let caps = peer().capabilities;
    let has = robot_firmware::params::PARAMS
        .iter()
        .filter(|p| p.requires & caps == p.requires)
        .count();
    assert_eq!(sent.len(), has);
    let before = app.log.len();
    for (id, c) in sent {
        let Command::GetParam { id: p } = c else {
            panic!("{c:?}")
        };
        app.update(Action::Link(LinkEvent::CommandDone {
            id,
            command: c,
            outcome: CommandOutcome::Acked {
                info: AckInfo::Param { id: p, value: 1.0 },
                sends: 1,
                rtt_ms: 3,
            },
        }));
    }
    assert_eq!(app.log.len(), before + 1, "{:#?}", texts(&app));
    let text = app.log.window(1).next().unwrap().display();
    assert_eq!(text, format!("parameters read: {has}"));
    // A refusal among them is not folded away.
    app.update(Action::Link(LinkEvent::CommandDone {
        id: 999,
        command: Command::GetParam { id: ParamId(400) },
        outcome: CommandOutcome::Nacked {
            reason: protocol::NackReason::UnknownParam,
            sends: 1,
        },
    }));
    assert_eq!(app.log.window(1).next().unwrap().level, Level::Error);
}

#[test]
fn after_link_loss_the_mode_and_readings_are_stale_with_their_age() {
    let mut app = connected_app();
    telemetry(&mut app, 1_000, Mode::Wander);
    app.update(Action::Tick { now_ms: 1_100 });
    assert_eq!(app.stale_s(), None, "fresh while frames arrive");
    app.update(Action::Link(LinkEvent::Connection(Connection::Closed {
        reason: "port closed".into(),
    })));
    app.update(Action::Tick { now_ms: 13_500 });
    assert_eq!(app.stale_s(), Some(12));
    // Connected but silent for more than three periods (and a second) is stale too.
    let mut app = connected_app();
    telemetry(&mut app, 1_000, Mode::Idle);
    app.update(Action::Tick { now_ms: 1_900 });
    assert_eq!(app.stale_s(), None);
    app.update(Action::Tick { now_ms: 2_100 });
    assert_eq!(app.stale_s(), Some(1));
}

#[test]
fn zooming_about_a_point_keeps_it_in_place_and_zooming_out_recentres() {
    let mut m = MapState::default();
    assert_eq!(m.zoom(), 1.0);
    m.zoom_by(2.0, (0.25, -0.25));
    // The point a quarter right of centre was at 0.25 of the whole span; at zoom 2 it is at
    // pan + 0.25 / 2, the same place.
    let (px, py) = m.pan();
    assert!((px + 0.25 / 2.0 - 0.25).abs() < 1e-12, "{px}");
    assert!((py - 0.25 / 2.0 + 0.25).abs() < 1e-12, "{py}");
    m.pan_by(40, 0);
    assert_eq!(m.pan().0, 0.5, "the view stays over the arena");
    m.zoom_by(1.0 / 64.0, (0.0, 0.0));
    assert_eq!((m.zoom(), m.pan()), (1.0, (0.0, 0.0)));
    m.zoom_by(1e9, (0.0, 0.0));
    assert_eq!(m.zoom(), MAX_ZOOM);
}

/// While recording, what the station logs waits for the loop to record it, each line as it
/// was said (before coalescing) with its subject; the robot's own log lines do not (its frames
/// hold them); before and after the recording nothing is kept.
#[test]
fn while_recording_the_stations_own_lines_wait_for_the_recording() {
    use crate::record::live::RecordingNote;
    use crate::record::LogSource;
    let mut app = connected_app();
    event(&mut app, EventCode::PlanFinished, 4);
    assert!(app.take_station_lines().is_empty(), "not recording");
    app.update(Action::Recording(RecordingNote::Started {
        file: "run.rec".into(),
        links: 1,
    }));
    event(&mut app, EventCode::PlanFinished, 4);
    event(&mut app, EventCode::NoProgress, 40_000);
    app.update(Action::Link(LinkEvent::Log {
        level: protocol::LogLevel::Info,
        text: "the robot's own words".into(),
    }));
    let lines = app.take_station_lines();
    let said: Vec<(LogSource, &str)> = lines.iter().map(|l| (l.source, l.text.as_str())).collect();
    assert_eq!(
        said,
        [
            (LogSource::Link, "recording to run.rec (R stops)"),
            (
                LogSource::Event,
                "plan finished: all 4 waypoints done, the robot stopped"
            ),
            (
                LogSource::Event,
                "the motion mode gave up: no progress for 40 s; the robot stopped (limit: \
                 parameter stuck_limit_s)"
            ),
        ]
    );
    assert_eq!(lines[2].level, protocol::LogLevel::Warn);
    assert!(app.take_station_lines().is_empty(), "taken once");
    app.update(Action::Recording(RecordingNote::Stopped {
        file: "run.rec".into(),
        seconds: 1.0,
        bytes: 100,
    }));
    event(&mut app, EventCode::Collision, 0);
    assert!(app.take_station_lines().is_empty(), "no longer recording");
}
