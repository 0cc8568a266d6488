//! Unit tests of `App::update`: teleop repetition and safety, command outcomes, parameters.

use super::*;
use crate::link::api::CommandFailure;
use crate::link::{CommandOutcome, LinkEvent};
use protocol::{AckInfo, MapCapacity, Mode, NackReason, ParamId, ProfileId};

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
    // The parameter fetch every connection starts (issue 16); these tests are about what
    // follows, and the fetch is checked by its own test.
    let fetch = app.take_outbox();
    assert!(fetch
        .iter()
        .all(|(_, c)| matches!(c, Command::GetParam { .. })));
    app
}

/// Issue 16: the editor showed `?` until `R`. A connection reads every parameter the robot
/// has the hardware for, quietly (one log line for the whole fetch), and the rows the robot
/// cannot have say so without asking.
#[test]
fn connecting_fetches_every_parameter_and_logs_the_fetch_once() {
    let mut app = App::new(AppOptions::default());
    let mut peer = peer();
    peer.capabilities &= !protocol::caps::ENCODERS;
    let caps = peer.capabilities;
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer,
    ))));
    let fetch = app.take_outbox();
    let params = robot_firmware::params::PARAMS;
    // Every parameter the robot's capabilities support, none it cannot have.
    let wanted: Vec<u16> = params
        .iter()
        .filter(|p| p.requires & !caps == 0)
        .map(|p| p.id)
        .collect();
    let asked: Vec<u16> = fetch
        .iter()
        .filter_map(|(_, c)| match c {
            Command::GetParam { id } => Some(id.0),
            _ => None,
        })
        .collect();
    assert_eq!(asked, wanted);
    let lines = app.log.window(100).count();
    for (id, c) in fetch {
        let Command::GetParam { id: pid } = c else {
            continue;
        };
        app.update(Action::Link(LinkEvent::CommandDone {
            id,
            command: c,
            outcome: CommandOutcome::Acked {
                info: AckInfo::Param {
                    id: pid,
                    value: if pid.0 == 1 { 20.0 } else { 1.0 },
                },
                sends: 1,
                rtt_ms: 3,
            },
        }));
    }
    let log: Vec<String> = app.log.window(100).map(|l| l.text.clone()).collect();
    assert_eq!(log.len(), lines + 1, "{log:?}");
    assert_eq!(
        log.last().map(String::as_str),
        Some(format!("parameters read: {}", wanted.len()).as_str())
    );
    let i = app.params.index_of(6).unwrap_or(0);
    assert_eq!(app.params.status[i], params::ParamStatus::Absent);
    assert_eq!(
        app.rate_hz,
        Some(20),
        "the header's rate is the parameter's"
    );
}

fn teleops(out: &[(CommandId, Command)]) -> usize {
    out.iter()
        .filter(|(_, c)| matches!(c, Command::Teleop { .. }))
        .count()
}

#[test]
fn driving_repeats_teleop_at_10_hz_until_space_stops_it() {
    let mut app = connected_app();
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    let first = app.take_outbox();
    assert_eq!(
        first.first().map(|c| c.1),
        Some(Command::Teleop {
            v_mm_s: V_STEP,
            w_mrad_s: 0
        })
    );
    let mut sent = 0;
    for now_ms in (50..=1000).step_by(50) {
        app.update(Action::Tick { now_ms });
        sent += teleops(&app.take_outbox());
    }
    assert_eq!(sent, 10, "ten a second while driving");
    app.update(Action::StopDriving);
    assert_eq!(app.take_outbox().last().map(|c| c.1), Some(Command::Stop));
    for now_ms in (1050..=2000).step_by(50) {
        app.update(Action::Tick { now_ms });
    }
    assert_eq!(teleops(&app.take_outbox()), 0, "nothing after a stop");
}

#[test]
fn a_teleop_repeat_may_wait_for_a_quiet_line_and_a_key_press_goes_at_once() {
    let mut app = connected_app();
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    let press = app.take_outbox_timed();
    assert_eq!(press.len(), 1);
    assert_eq!(press[0].2, SendWhen::Now, "a key press");
    app.update(Action::Tick { now_ms: 100 });
    let repeat = app.take_outbox_timed();
    assert_eq!(repeat.len(), 1);
    assert!(matches!(repeat[0].1, Command::Teleop { .. }));
    assert_eq!(repeat[0].2, SendWhen::QuietLine, "a repeat");
    // A press and a stop in the same wake-up as a repeat go at once; the repeat may wait.
    app.update(Action::Tick { now_ms: 200 });
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    app.update(Action::StopDriving);
    let whens: Vec<SendWhen> = app.take_outbox_timed().iter().map(|c| c.2).collect();
    assert_eq!(
        whens,
        vec![SendWhen::QuietLine, SendWhen::Now, SendWhen::Now]
    );
    // Taken without timing, nothing is left marked.
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    app.update(Action::Tick { now_ms: 400 });
    let _ = app.take_outbox();
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    assert_eq!(app.take_outbox_timed()[0].2, SendWhen::Now);
}

#[test]
fn a_lost_link_stops_teleop_and_a_reconnect_does_not_resume_it() {
    let mut app = connected_app();
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    app.update(Action::Link(LinkEvent::Connection(Connection::Closed {
        reason: "unplugged".into(),
    })));
    assert!(!app.teleop.driving);
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer(),
    ))));
    app.take_outbox();
    for now_ms in (100..=1000).step_by(100) {
        app.update(Action::Tick { now_ms });
    }
    assert_eq!(teleops(&app.take_outbox()), 0);
}

#[test]
fn driving_while_disconnected_sends_nothing_and_says_why() {
    let mut app = App::new(AppOptions::default());
    app.update(Action::Drive { dv: V_STEP, dw: 0 });
    assert!(app.take_outbox().is_empty());
    assert!(app.log.window(1).any(|l| l.text.contains("not connected")));
}

#[test]
fn a_refused_parameter_write_shows_the_robots_reason_in_the_editor_and_the_log() {
    let mut app = connected_app();
    app.update(Action::ShowView(View::Params));
    // Read failsafe_ms (id 0) first: 300.
    app.update(Action::ParamRead);
    let (id, cmd) = app.take_outbox()[0];
    app.update(Action::Link(LinkEvent::CommandDone {
        id,
        command: cmd,
        outcome: CommandOutcome::Acked {
            info: AckInfo::Param {
                id: ParamId(0),
                value: 300.0,
            },
            sends: 1,
            rtt_ms: 5,
        },
    }));
    app.update(Action::ParamEdit);
    for c in "5".chars() {
        app.update(Action::ParamInput(c));
    }
    app.update(Action::ParamCommit);
    let (id, cmd) = app.take_outbox()[0];
    assert_eq!(
        cmd,
        Command::SetParam {
            id: ParamId(0),
            value: 5.0
        }
    );
    app.update(Action::Link(LinkEvent::CommandDone {
        id,
        command: cmd,
        outcome: CommandOutcome::Nacked {
            reason: NackReason::OutOfRange,
            sends: 1,
        },
    }));
    assert_eq!(
        params::status_text(&app.params.params()[0], &app.params.status[0]),
        "300 (refused: value out of range)"
    );
    assert!(app
        .log
        .window(1)
        .any(|l| l.text == "refused: param set failsafe_ms 5: value out of range: 50 to 10000 ms"));
}

#[test]
fn an_unanswered_command_is_logged_as_failed_and_superseded_teleops_as_one_detail_line() {
    let mut app = connected_app();
    let before = app.log.len();
    for id in 90..100 {
        app.update(Action::Link(LinkEvent::CommandDone {
            id,
            command: Command::Teleop {
                v_mm_s: 1,
                w_mrad_s: 0,
            },
            outcome: CommandOutcome::Failed(CommandFailure::Superseded),
        }));
    }
    assert_eq!(app.log.len(), before + 1, "ten supersessions, one line");
    let l = app.log.window(1).next().unwrap();
    assert_eq!((l.level, l.count), (Level::Debug, 10));
    assert!(
        l.text.contains("superseded by a newer teleop"),
        "{}",
        l.text
    );
    app.update(Action::Link(LinkEvent::CommandDone {
        id: 100,
        command: Command::Stop,
        outcome: CommandOutcome::Failed(CommandFailure::Timeout { sends: 5 }),
    }));
    assert!(app
        .log
        .window(1)
        .any(|l| l.text == "failed: stop: no answer after 5 sends"));
}

#[test]
fn the_rate_keys_step_through_the_standard_rates() {
    let mut app = connected_app();
    app.update(Action::RateStep(1));
    assert_eq!(app.take_outbox()[0].1, Command::SetTelemetryRate { hz: 20 });
    // Quick presses step on from what was asked, not from the last acknowledged rate.
    app.update(Action::RateStep(1));
    app.update(Action::RateStep(-1));
    app.update(Action::RateStep(-1));
    let asked: Vec<_> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    let hz = |hz| Command::SetTelemetryRate { hz };
    assert_eq!(asked, [hz(50), hz(20), hz(10)]);
    // Once the last one is refused, the next press steps from the rate the robot has.
    let (last, _) = app.rate_asked_for_test().unwrap();
    app.update(Action::Link(LinkEvent::CommandDone {
        id: last,
        command: hz(10),
        outcome: CommandOutcome::Nacked {
            reason: protocol::NackReason::OutOfRange,
            sends: 1,
        },
    }));
    app.update(Action::RateStep(-1));
    assert_eq!(app.take_outbox()[0].1, hz(5));
}

#[test]
fn a_click_on_the_map_sends_go_to_in_millimetres() {
    let mut app = connected_app();
    app.update(Action::GoToPoint {
        x_m: 1.25,
        y_m: -0.5,
    });
    assert_eq!(
        app.take_outbox()[0].1,
        Command::GoTo(protocol::PointMm {
            x_mm: 1250,
            y_mm: -500
        })
    );
    assert_eq!(app.map.goal, Some((1.25, -0.5)));
}

#[test]
fn a_stalled_light_calibration_is_logged_as_a_stall_not_an_unknown_code() {
    let mut app = connected_app();
    app.update(Action::Link(LinkEvent::Robot(protocol::Event {
        code: protocol::EventCode::LightCalibrated,
        value: protocol::calibration::STALLED,
    })));
    let line = app.log.window(1).next().map(|l| l.text.clone());
    assert!(
        line.as_deref().is_some_and(|t| t.contains("stalled")),
        "{line:?}"
    );
}

#[test]
fn a_refused_go_to_mode_says_which_key_gives_it_a_point() {
    let mut app = connected_app();
    app.update(Action::Link(LinkEvent::CommandDone {
        id: 7,
        command: Command::SetMode(Mode::GoTo),
        outcome: CommandOutcome::Nacked {
            reason: NackReason::BadState,
            sends: 1,
        },
    }));
    let line = app.log.window(1).next().map(|l| l.text.clone());
    assert!(
        line.as_deref()
            .is_some_and(|t| t.contains("not allowed in the current mode (press g")),
        "{line:?}"
    );
}

#[test]
fn a_value_that_is_not_a_number_is_shown_on_the_edit_line_and_nothing_is_sent() {
    let mut app = connected_app();
    app.update(Action::ShowView(View::Params));
    app.update(Action::ParamEdit);
    for c in "1.5.".chars() {
        app.update(Action::ParamInput(c));
    }
    app.update(Action::ParamCommit);
    assert!(app.take_outbox().is_empty());
    assert_eq!(
        app.params.input_error.as_deref(),
        Some("\"1.5.\" is not a number")
    );
    // Still editing: the next key clears the complaint and fixes the text.
    assert_eq!(app.params.input.as_deref(), Some("1.5."));
    app.update(Action::ParamBackspace);
    assert_eq!(app.params.input_error, None);
}

#[test]
fn the_arena_importers_warnings_are_in_the_log_from_the_start() {
    // A <Row> lab with an unknown element: the importer's warning must reach the operator.
    let dir = std::env::temp_dir().join(format!("station-arena-warn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lab = dir.join("rows.xml");
    std::fs::write(
        &lab,
        r#"<Lab Width="14" Height="4"><Row Pos="0" Pattern="  |"/><Decor/></Lab>"#,
    )
    .unwrap();
    let overlay = ArenaOverlay::load(&lab).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(overlay.walls.len(), 1);
    let app = App::new(AppOptions {
        arena: Some(overlay),
        ..AppOptions::default()
    });
    let warned: Vec<_> = app
        .log
        .window(10)
        .filter(|l| l.level == Level::Warn && l.source == Source::Arena)
        .collect();
    assert_eq!(
        warned.len(),
        1,
        "{:?}",
        app.log.window(10).collect::<Vec<_>>()
    );
    assert!(warned[0].text.contains("unknown element 'Decor'"));
}
