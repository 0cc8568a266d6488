//! The picker and "stop all": which robot the keys drive, who gets `Stop`, what the log says.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{Command, MapCapacity, NackReason, ProfileId};

use super::*;
use crate::app::{AppOptions, V_STEP};
use crate::link::{CommandFailure, PeerInfo};

fn peer(profile: ProfileId) -> PeerInfo {
    PeerInfo {
        session: 1,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile,
        capabilities: 0,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
    }
}

/// Three robots on /tmp/robot1..3; `connected[i]`: robot i has shaken hands.
fn fleet(connected: [bool; 3]) -> Fleet {
    let members = (1..=3)
        .map(|k| Member {
            app: App::new(AppOptions::default()),
            port: format!("/tmp/robot{k}"),
        })
        .collect();
    let mut f = Fleet::new(members);
    for (i, up) in connected.iter().enumerate() {
        let c = if *up {
            Connection::Connected(peer(ProfileId::MicroRato))
        } else {
            Connection::Closed {
                reason: "cannot open /tmp/robot: no such file".into(),
            }
        };
        f.on_link(i, LinkEvent::Connection(c));
    }
    outboxes(&mut f);
    f
}

/// Every robot's queued commands, emptied.
fn outboxes(f: &mut Fleet) -> Vec<Vec<(CommandId, Command)>> {
    f.members.iter_mut().map(|m| m.app.take_outbox()).collect()
}

fn log_has(app: &App, text: &str) -> bool {
    app.log.window(100).any(|l| l.text.contains(text))
}

#[test]
fn keys_and_commands_go_to_the_selected_robot_only() {
    let mut f = fleet([true; 3]);
    assert_eq!(f.selected(), 0);
    f.update(Action::SelectRobot(1));
    assert_eq!(f.selected(), 1);
    f.update(Action::SetMode(protocol::Mode::Wander));
    f.update(Action::Drive { dv: V_STEP, dw: 0 });
    let out = outboxes(&mut f);
    assert!(out[0].is_empty() && out[2].is_empty(), "{out:?}");
    assert_eq!(out[1][0].1, Command::SetMode(protocol::Mode::Wander));
    assert!(matches!(out[1][1].1, Command::Teleop { v_mm_s: 50, .. }));
    assert!(log_has(f.app(), "selected micro-rato 2 on /tmp/robot2"));
}

#[test]
fn the_picker_steps_round_and_ignores_robots_that_are_not_there() {
    let mut f = fleet([true; 3]);
    f.update(Action::StepRobot(-1));
    assert_eq!(f.selected(), 2);
    f.update(Action::StepRobot(1));
    assert_eq!(f.selected(), 0);
    f.update(Action::SelectRobot(7));
    assert_eq!(f.selected(), 0);
    // Only the selected robot's screen carries the fleet.
    assert!(f.members[0].app.in_fleet());
    assert!(f.members[1].app.fleet.is_none());
}

#[test]
fn a_robot_left_behind_while_driven_is_stopped_not_left_driving() {
    let mut f = fleet([true; 3]);
    f.update(Action::Drive { dv: V_STEP, dw: 0 });
    outboxes(&mut f);
    f.update(Action::SelectRobot(2));
    let out = outboxes(&mut f);
    assert_eq!(out[0].last().map(|c| c.1), Some(Command::Stop));
    for now_ms in (100..=1000).step_by(100) {
        f.update(Action::Tick { now_ms });
    }
    let out = outboxes(&mut f);
    assert!(
        out.iter().all(|o| o.is_empty()),
        "no teleop repeats: {out:?}"
    );
}

#[test]
fn stop_all_sends_stop_to_every_connected_robot_and_reports_each_answer() {
    let mut f = fleet([true, true, false]);
    f.update(Action::SelectRobot(1));
    // Robot 1 is being driven: stop all ends that too.
    f.members[0].app.update(Action::Drive { dv: V_STEP, dw: 0 });
    outboxes(&mut f);
    f.update(Action::StopAll);
    let out = outboxes(&mut f);
    assert_eq!(out[0].len(), 1);
    assert_eq!(out[0][0].1, Command::Stop);
    assert_eq!(out[1][0].1, Command::Stop);
    assert!(out[2].is_empty(), "robot 3 is not connected");
    assert!(!f.members[0].app.teleop.driving);
    let shown = f.app();
    assert!(log_has(shown, "stop all: Stop sent to 2 of 3 robots"));
    assert!(log_has(
        shown,
        "stop all: robot 3: NOT STOPPED: not connected"
    ));
    // Robot 1 acks, robot 2 refuses.
    f.on_link(
        0,
        LinkEvent::CommandDone {
            id: out[0][0].0,
            command: Command::Stop,
            outcome: CommandOutcome::Acked {
                info: protocol::AckInfo::Done,
                sends: 1,
                rtt_ms: 9,
            },
        },
    );
    f.on_link(
        1,
        LinkEvent::CommandDone {
            id: out[1][0].0,
            command: Command::Stop,
            outcome: CommandOutcome::Nacked {
                reason: NackReason::Busy,
                sends: 1,
            },
        },
    );
    let shown = f.app();
    assert!(log_has(
        shown,
        "stop all: micro-rato 1: stopped (acked in 9 ms)"
    ));
    assert!(log_has(shown, "stop all: micro-rato 2: REFUSED"));
    // The robot not shown has it in its own log too.
    assert!(log_has(&f.members[0].app, "stop all: stopped"));
    // An ordinary Stop later is not reported as part of stop all.
    f.update(Action::StopDriving);
    let id = outboxes(&mut f)[1][0].0;
    let before = f.app().log.window(100).count();
    f.on_link(
        1,
        LinkEvent::CommandDone {
            id,
            command: Command::Stop,
            outcome: CommandOutcome::Failed(CommandFailure::LinkLost),
        },
    );
    assert!(!f
        .app()
        .log
        .window(100)
        .skip(before)
        .any(|l| l.text.contains("stop all")));
}

#[test]
fn labels_use_the_robot_id_when_there_is_one_and_the_port_index_otherwise() {
    assert_eq!(robot_label(1, Some("micro-rato"), None), "micro-rato 2");
    assert_eq!(robot_label(1, Some("micro-rato"), Some(7)), "micro-rato #7");
    assert_eq!(robot_label(2, None, None), "robot 3");
    let f = fleet([true, false, false]);
    assert_eq!(f.label(0), "micro-rato 1");
    assert_eq!(f.label(1), "robot 2");
}

#[test]
fn two_robots_with_the_same_id_are_reported_once_and_marked() {
    assert_eq!(duplicate_ids(&[Some(1), Some(2), Some(1)]), vec![0, 2]);
    assert!(duplicate_ids(&[Some(1), None, None, Some(2)]).is_empty());
    let mut f = fleet([true; 3]);
    f.warn_duplicate_ids(&[Some(4), Some(4), None]);
    f.warn_duplicate_ids(&[Some(4), Some(4), None]);
    let warnings = f
        .app()
        .log
        .window(100)
        .filter(|l| l.text.contains("robot id 4 is reported by 2 robots"))
        .count();
    assert_eq!(warnings, 1);
    assert!(log_has(f.app(), "/tmp/robot1, /tmp/robot2"));
}

#[test]
fn one_robot_is_a_pass_through() {
    let mut f = Fleet::new(vec![Member {
        app: App::new(AppOptions::default()),
        port: "/dev/ttyUSB0".into(),
    }]);
    f.update(Action::StepRobot(1));
    assert_eq!(f.selected(), 0);
    assert!(f.app().fleet.is_none(), "no overlay: today's screens");
}
