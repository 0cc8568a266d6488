//! The picker and "stop all": which robot the keys drive, who gets `Stop`, what the log says.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{Command, MapCapacity, NackReason, ProfileId};

use super::*;
use crate::app::{AppOptions, V_STEP};
use crate::link::{CommandFailure, PeerInfo};

fn peer(profile: ProfileId, robot_id: u8) -> PeerInfo {
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
        robot_id,
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
            Connection::Connected(peer(ProfileId::MicroRato, i as u8 + 1))
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
    assert!(log_has(f.app(), "selected micro-rato #2 on /tmp/robot2"));
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
        "stop all: micro-rato #1: stopped (acked in 9 ms)"
    ));
    assert!(log_has(shown, "stop all: micro-rato #2: REFUSED"));
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
    assert_eq!(f.label(0), "micro-rato #1");
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
        .filter(|l| l.text.contains("robot id 4 is stated by the robots on"))
        .count();
    assert_eq!(warnings, 1);
    assert!(log_has(f.app(), "/tmp/robot1 and /tmp/robot2"));
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

mod keys_and_clicks {
    use super::*;
    use crate::fleet::input::action_for;
    use ratatui::crossterm::event::{
        Event, KeyCode, KeyEvent, KeyModifiers, MouseButton, MouseEvent, MouseEventKind,
    };
    use ratatui::layout::Rect;

    fn key(code: KeyCode, modifiers: KeyModifiers) -> Event {
        Event::Key(KeyEvent::new(code, modifiers))
    }

    fn click(column: u16, row: u16) -> Event {
        Event::Mouse(MouseEvent {
            kind: MouseEventKind::Down(MouseButton::Left),
            column,
            row,
            modifiers: KeyModifiers::NONE,
        })
    }

    fn sized(mut f: Fleet) -> Fleet {
        f.update(Action::Resize {
            width: 150,
            height: 40,
        });
        f.sync_overlay();
        f
    }

    #[test]
    fn tab_alt_digits_and_bang_are_the_fleets_and_digits_stay_modes() {
        let f = sized(fleet([true; 3]));
        let app = f.app();
        let none = KeyModifiers::NONE;
        assert_eq!(
            action_for(app, &key(KeyCode::Tab, none)),
            Some(Action::StepRobot(1))
        );
        assert_eq!(
            action_for(app, &key(KeyCode::BackTab, KeyModifiers::SHIFT)),
            Some(Action::StepRobot(-1))
        );
        assert_eq!(
            action_for(app, &key(KeyCode::Char('3'), KeyModifiers::ALT)),
            Some(Action::SelectRobot(2))
        );
        // No robot 4: nothing, not a mode.
        assert_eq!(
            action_for(app, &key(KeyCode::Char('4'), KeyModifiers::ALT)),
            None
        );
        assert_eq!(
            action_for(app, &key(KeyCode::Char('3'), none)),
            Some(Action::SetMode(protocol::Mode::Wander))
        );
        assert_eq!(
            action_for(app, &key(KeyCode::Char('!'), none)),
            Some(Action::StopAll)
        );
    }

    #[test]
    fn while_typing_bang_is_text_and_one_robot_keeps_todays_keys() {
        let mut f = sized(fleet([true; 3]));
        f.update(Action::LogFilterStart);
        f.sync_overlay();
        assert_eq!(
            action_for(f.app(), &key(KeyCode::Char('!'), KeyModifiers::NONE)),
            Some(Action::LogFilterInput('!'))
        );
        let one = sized(Fleet::new(vec![Member {
            app: App::new(AppOptions::default()),
            port: "p".into(),
        }]));
        assert_eq!(
            action_for(one.app(), &key(KeyCode::Tab, KeyModifiers::NONE)),
            Some(Action::NextView)
        );
        assert_eq!(
            action_for(one.app(), &key(KeyCode::Char('!'), KeyModifiers::NONE)),
            None
        );
    }

    #[test]
    fn a_click_on_a_fleet_line_or_on_another_robot_picks_it_elsewhere_it_is_a_go_to() {
        let mut f = fleet([true; 3]);
        // Robot 2 stands at (2, 1.5) m; no arena: the map fits what it shows.
        let t = protocol::Telemetry {
            pose: protocol::Pose {
                x_mm: 2000,
                y_mm: 1500,
                heading_mrad: 0,
            },
            ..protocol::Telemetry::default()
        };
        f.on_link(1, LinkEvent::Telemetry(t));
        let f = sized(f);
        let app = f.app();
        let areas = crate::ui::areas(Rect::new(0, 0, 150, 40), app);
        let panel = areas.find(crate::ui::Panel::Fleet).unwrap();
        assert_eq!(
            action_for(app, &click(panel.x + 5, panel.y + 3)),
            Some(Action::SelectRobot(2))
        );
        // The map cell under robot 2: scan the map for the cell nearest its pose.
        let map = areas.find(crate::ui::Panel::Map).unwrap();
        let inner = ratatui::widgets::Block::bordered().inner(crate::ui::map::map_area(app, map));
        let mut best = (f64::MAX, 0, 0);
        for row in inner.y..inner.y + inner.height {
            for col in inner.x..inner.x + inner.width {
                let (x, y) = crate::ui::map::to_world(app, inner, col, row).unwrap();
                let d = (x - 2.0).hypot(y - 1.5);
                if d < best.0 {
                    best = (d, col, row);
                }
            }
        }
        assert_eq!(
            action_for(app, &click(best.1, best.2)),
            Some(Action::SelectRobot(1))
        );
        // Far from any robot: the selected robot's go-to cursor (Enter sends it).
        let far = action_for(app, &click(inner.x + 1, inner.y + 1));
        assert!(matches!(far, Some(Action::CursorAt { .. })), "{far:?}");
    }
}
