//! Whole-screen snapshots of the key screens (ratatui `TestBackend` + insta), at 80 x 24 and
//! at larger sizes. The app is fed a fixed story of link events with fixed times, so nothing
//! on screen is volatile except what `redact` filters (none today: kept for port paths).
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use protocol::{
    caps, AckInfo, Command, EmuTruth, Event, EventCode, LogLevel, Mode, NackReason, Packed10x8,
    ParamId, Pose, ProfileId, Telemetry,
};
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions, View};
use station::link::{CommandOutcome, Connection, LinkEvent, LinkStats, PeerInfo};

fn arena() -> ArenaOverlay {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../emulator/arenas/wallsMicRato99.xml"
    );
    ArenaOverlay::load(std::path::Path::new(path)).unwrap()
}

fn peer() -> PeerInfo {
    support::tui::peer(
        ProfileId::Khepera,
        caps::ENCODERS
            | caps::IR_PROXIMITY
            | caps::AMBIENT_LIGHT
            | caps::LINE_SENSOR
            | caps::BATTERY
            | caps::EMULATED,
    )
}

fn telemetry(i: u32) -> Telemetry {
    let f = f64::from(i);
    Telemetry {
        time_ms: i * 100,
        mode: Mode::Manual,
        pose: Pose {
            x_mm: 1000 + (f * 12.0) as i32,
            y_mm: 1000 + (f * f * 0.4) as i32,
            heading_mrad: (f * 20.0) as i16,
        },
        wheels: protocol::Wheels {
            speed_mm_s: [120, 136],
            encoders: [(i * 150) as u16, (i * 170) as u16],
        },
        ir: Packed10x8::new([0, 40, 300, 900, 120, 10, 0, 0]),
        light: Packed10x8::new([480, 470, 300, 120, 350, 500, 500, 500]),
        flags: protocol::flags::LINE,
        line_events: 3,
        battery_mv: 7650,
        behaviour: protocol::BehaviourOut {
            active: protocol::behaviours::AVOID,
            motor_mm_s: [120, 136],
        },
        cycle: protocol::CycleTiming {
            period_us: 80_000,
            busy_us: 350,
            overruns: 0,
        },
        sigma: protocol::PoseSigma {
            xy_mm: 14,
            heading_mrad: 30,
        },
        ..Telemetry::default()
    }
}

fn stats() -> LinkStats {
    let mut s = LinkStats {
        state: "connected".into(),
        uptime_ms: 42_000,
        session_ms: 40_000,
        frames_in: 812,
        frames_out: 190,
        bytes_in: 48_210,
        bytes_out: 3_020,
        bytes_in_per_s: 1210.0,
        bytes_out_per_s: 76.0,
        telemetry_frames: 400,
        telemetry_hz: 10.0,
        port_opens: 1,
        handshakes: 1,
        ..LinkStats::default()
    };
    s.robot_seq.received = 812;
    s.robot_seq.lost = 2;
    s.robot_seq.loss_percent = 0.25;
    s.truth_seq.received = 400;
    s.decoder.crc_errors = 1;
    s.decoder.bytes_dropped = 61;
    s.commands.acked = 9;
    s.commands.nacked = 1;
    s.commands.resends = 1;
    s.rtt_ms.samples = 9;
    s.rtt_ms.p50 = Some(7.0);
    s.rtt_ms.p99 = Some(19.0);
    s
}

/// A session: connect, 40 telemetry frames with truth, a refused and an accepted command,
/// events and log lines, and a statistics snapshot.
fn story() -> App {
    let mut app = App::new(AppOptions {
        port_label: "/dev/ttyUSB0".into(),
        arena: Some(arena()),
        ..AppOptions::default()
    });
    let link = |app: &mut App, e| app.update(Action::Link(e));
    app.update(Action::Tick { now_ms: 100 });
    link(
        &mut app,
        LinkEvent::Connection(Connection::Handshaking {
            port: "/dev/ttyUSB0".into(),
        }),
    );
    app.update(Action::Tick { now_ms: 300 });
    link(
        &mut app,
        LinkEvent::Connection(Connection::Connected(peer())),
    );
    // The parameter fetch the connection starts, answered as a Khepera starts.
    let mut robot = robot_firmware::AnyRobot::new(robot_firmware::RobotOptions {
        profile: &robot_firmware::KHEPERA,
        seed: 1,
        start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
        emulated: false,
        firmware_version: "0.1.0",
    });
    for (id, command) in app.take_outbox() {
        let Command::GetParam { id: param } = command else {
            continue;
        };
        let value = robot.param(param.0).unwrap_or(0.0);
        link(
            &mut app,
            LinkEvent::CommandDone {
                id,
                command,
                outcome: CommandOutcome::Acked {
                    info: AckInfo::Param { id: param, value },
                    sends: 1,
                    rtt_ms: 5,
                },
            },
        );
    }
    for i in 0..40 {
        app.update(Action::Tick {
            now_ms: 400 + u64::from(i) * 100,
        });
        let t = telemetry(i);
        link(&mut app, LinkEvent::Telemetry(t));
        let mut truth = t.pose;
        truth.x_mm += (i * 3) as i32;
        truth.y_mm -= (i * 2) as i32;
        link(
            &mut app,
            LinkEvent::Truth(EmuTruth {
                time_ms: t.time_ms,
                pose: truth,
                collisions: 0,
                robot_id: 1,
            }),
        );
    }
    link(
        &mut app,
        LinkEvent::Robot(Event {
            code: EventCode::ModeChanged,
            value: 1,
        }),
    );
    link(
        &mut app,
        LinkEvent::Log {
            level: LogLevel::Warn,
            text: "wall lost".into(),
        },
    );
    link(
        &mut app,
        LinkEvent::CommandDone {
            id: 101,
            command: Command::SetMode(Mode::Explore),
            outcome: CommandOutcome::Nacked {
                reason: NackReason::Unsupported,
                sends: 1,
            },
        },
    );
    link(
        &mut app,
        LinkEvent::CommandDone {
            id: 102,
            command: Command::GetParam { id: ParamId(0) },
            outcome: CommandOutcome::Acked {
                info: AckInfo::Param {
                    id: ParamId(0),
                    value: 300.0,
                },
                sends: 1,
                rtt_ms: 7,
            },
        },
    );
    link(&mut app, LinkEvent::Stats(Box::new(stats())));
    app
}

fn screen(app: &App, w: u16, h: u16) -> String {
    redact(&support::tui::screen(app, w, h))
}

/// Filters what may differ between runs (nothing in this fixed story; pty paths elsewhere).
fn redact(s: &str) -> String {
    s.replace(env!("CARGO_MANIFEST_DIR"), "[station]")
}

#[test]
fn dashboard_at_80x24() {
    insta::assert_snapshot!(screen(&story(), 80, 24));
}

#[test]
fn dashboard_at_120x40() {
    insta::assert_snapshot!(screen(&story(), 120, 40));
}

#[test]
fn dashboard_at_180x50() {
    insta::assert_snapshot!(screen(&story(), 180, 50));
}

#[test]
fn parameter_editor_shows_values_and_refusals_at_80x24() {
    let mut app = story();
    app.update(Action::ShowView(View::Params));
    app.update(Action::ParamRead);
    let (id, command) = app.take_outbox()[0];
    app.update(Action::Link(LinkEvent::CommandDone {
        id,
        command,
        outcome: CommandOutcome::Acked {
            info: AckInfo::Param {
                id: ParamId(0),
                value: 300.0,
            },
            sends: 1,
            rtt_ms: 6,
        },
    }));
    app.update(Action::ParamSelect(1));
    app.update(Action::ParamEdit);
    for c in "99".chars() {
        app.update(Action::ParamInput(c));
    }
    app.update(Action::ParamCommit);
    let (id, command) = app.take_outbox()[0];
    app.update(Action::Link(LinkEvent::CommandDone {
        id,
        command,
        outcome: CommandOutcome::Nacked {
            reason: NackReason::OutOfRange,
            sends: 1,
        },
    }));
    app.update(Action::ParamSelect(1));
    app.update(Action::ParamEdit);
    app.update(Action::ParamInput('2'));
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn help_overlay_at_80x24() {
    let mut app = story();
    app.update(Action::ToggleHelp);
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn link_view_at_80x24() {
    let mut app = story();
    app.update(Action::ShowView(View::Link));
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn charts_view_at_100x30() {
    let mut app = story();
    app.update(Action::ShowView(View::Charts));
    insta::assert_snapshot!(screen(&app, 100, 30));
}

#[test]
fn map_view_with_the_go_to_cursor_at_80x24() {
    let mut app = story();
    app.update(Action::ShowView(View::Map));
    app.update(Action::GoToCursorStart);
    app.update(Action::MoveCursor { dx: 1.0, dy: 0.5 });
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn a_busy_port_is_explained_in_the_header_and_link_panel() {
    let mut app = App::new(AppOptions {
        port_label: "/dev/ttyUSB0".into(),
        arena: None,
        ..AppOptions::default()
    });
    app.update(Action::Link(LinkEvent::Connection(Connection::Closed {
        reason: "/dev/ttyUSB0 is in use by pid 4242 (minicom)".into(),
    })));
    app.update(Action::ShowView(View::Link));
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn a_schema_mismatch_names_both_builds() {
    let mut app = App::new(AppOptions::default());
    app.update(Action::Link(LinkEvent::Connection(Connection::Refused {
        message: "robot firmware robot-firmware 0.0.9 has schema 0102030405060708 (protocol 1); \
                  this station has schema 78944ffb8613ea27 (protocol 1): rebuild one of them"
            .into(),
    })));
    insta::assert_snapshot!(screen(&app, 100, 24));
}

#[test]
fn a_click_on_the_map_places_the_go_to_cursor_at_that_point() {
    use ratatui::crossterm::event::{
        Event as TEvent, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
    };
    let mut app = story();
    app.update(Action::Resize {
        width: 80,
        height: 24,
    });
    app.update(Action::ShowView(View::Map));
    let areas = station::ui::areas(ratatui::layout::Rect::new(0, 0, 80, 24), &app);
    let map = areas.find(station::ui::Panel::Map).unwrap();
    // The middle of the map panel is the middle of the 5 m arena.
    let click = TEvent::Mouse(MouseEvent {
        kind: MouseEventKind::Down(MouseButton::Left),
        column: map.x + map.width / 2,
        row: map.y + map.height / 2,
        modifiers: KeyModifiers::NONE,
    });
    let Some(Action::CursorAt { x_m, y_m }) = station::input::action_for(&app, &click) else {
        panic!("a click on the map places the go-to cursor");
    };
    let [x0, y0, x1, y1] = arena().bounds;
    assert!((x_m - (x0 + x1) / 2.0).abs() < 0.2, "{x_m}");
    assert!((y_m - (y0 + y1) / 2.0).abs() < 0.3, "{y_m}");
}

#[test]
fn a_signed_session_says_so_beside_the_capabilities_and_counts_refused_frames() {
    let mut app = story();
    let unsigned = screen(&app, 120, 40);
    assert!(!unsigned.contains("auth "), "{unsigned}");
    let mut s = stats();
    s.auth.keyed = true;
    app.update(Action::Link(LinkEvent::Stats(Box::new(s.clone()))));
    let signed = screen(&app, 120, 40);
    assert!(signed.contains("│auth signed  refused 0 "), "{signed}");
    s.auth.stale_timestamp = 3;
    app.update(Action::Link(LinkEvent::Stats(Box::new(s))));
    let refused = screen(&app, 120, 40);
    assert!(refused.contains("│auth signed  refused 3 "), "{refused}");
    // Still readable at the smallest size: the line is there, unwrapped.
    assert!(
        screen(&app, 80, 24).contains("auth signed  refused 3") || {
            // At 80x24 the link panel is a view of its own (Tab), not on the dashboard.
            app.update(Action::ShowView(View::Link));
            screen(&app, 80, 24).contains("auth signed  refused 3")
        }
    );
}

#[test]
fn the_header_keeps_the_recording_clock_readable_at_80_columns() {
    let mut app = story();
    app.recording = Some(("/home/me/station-20261122-161849.rec".into(), app.now_ms));
    let wide = screen(&app, 180, 50);
    let top = wide.lines().next().unwrap();
    assert!(
        top.contains("● REC station-20261122-161849.rec 0:00"),
        "{top}"
    );
    assert!(top.contains("robot-firmware"), "{top}");
    let narrow = screen(&app, 80, 24);
    let top = narrow.lines().next().unwrap();
    // The file name and firmware version give way; the clock, mode and rate stay.
    assert!(top.contains("● REC 0:00"), "{top}");
    assert!(
        top.contains("mode Manual") && top.contains("10 Hz"),
        "{top}"
    );
}
