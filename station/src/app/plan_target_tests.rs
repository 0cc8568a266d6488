//! The plan's target (issue 16: `O` planned to the clicked go-to point, not the map's goal),
//! progress in the header, and refusals that name the limit and the way forward.

use super::super::{App, AppOptions};
use super::PlanTarget;
use crate::action::Action;
use crate::app::transfers::TransferAction;
use crate::link::{CommandOutcome, Connection, LinkEvent, PeerInfo};
use protocol::{Command, EventCode, MapCapacity, Mode, NackReason, PointMm, ProfileId, Progress};

fn app_on_micro_rato_99() -> App {
    let mut app = App::new(AppOptions::default());
    app.map.plan = crate::plan::PlanState::for_builtin();
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        PeerInfo {
            session: 1,
            firmware: "robot-firmware".into(),
            firmware_version: "0.1.0".into(),
            profile: ProfileId::MicroRato,
            capabilities: 0,
            map_capacity: MapCapacity {
                width: 64,
                height: 64,
            },
            telemetry_hz: 10,
            failsafe_ms: 300,
            robot_id: 1,
        },
    ))));
    app.take_outbox();
    app
}

fn last_log(app: &App) -> String {
    app.log
        .window(1)
        .next()
        .map(|l| l.text.clone())
        .unwrap_or_default()
}

fn plan_sent(app: &mut App) -> Option<Option<PointMm>> {
    app.take_outbox().into_iter().find_map(|(_, c)| match c {
        Command::Plan { to, .. } => Some(to),
        _ => None,
    })
}

#[test]
fn after_a_go_to_click_o_still_plans_to_the_maps_goal_and_says_so() {
    let mut app = app_on_micro_rato_99();
    let goal = app.plan_target().point().expect("Micro-Rato'99 has a goal");
    app.update(Action::GoToPoint { x_m: 1.0, y_m: 1.0 });
    app.take_outbox();
    assert_eq!(app.plan_target(), PlanTarget::MapGoal(Some(goal)));
    app.update(Action::Transfer(TransferAction::PlanOnRobot));
    let log: Vec<String> = app.log.window(3).map(|l| l.text.clone()).collect();
    // The robot plans to its own map's goal: no `to`.
    assert_eq!(plan_sent(&mut app), Some(None));
    assert!(
        log.iter()
            .any(|l| l.starts_with("planning on the robot to the map's goal (")),
        "{log:?}"
    );
}

#[test]
fn o_with_the_cursor_shown_chooses_the_target_and_esc_or_g_goes_back_to_the_goal() {
    let mut app = app_on_micro_rato_99();
    app.update(Action::GoToCursorStart);
    app.map.cursor = (1.0, 2.0);
    app.update(Action::Transfer(TransferAction::PlanOnRobot));
    assert_eq!(
        plan_sent(&mut app),
        Some(Some(PointMm {
            x_mm: 1000,
            y_mm: 2000
        }))
    );
    assert!(!app.map.cursor_mode);
    assert_eq!(app.plan_target(), PlanTarget::Chosen((1.0, 2.0)));
    // `O` again, without the cursor: the chosen target still.
    app.update(Action::Transfer(TransferAction::PlanOnRobot));
    assert!(matches!(plan_sent(&mut app), Some(Some(_))));
    // Esc clears it (and a go-to marker), the next Esc leaves the view.
    app.update(Action::GoToPoint { x_m: 2.0, y_m: 2.0 });
    app.view = crate::app::View::Map;
    app.update(Action::Back);
    assert!(matches!(app.plan_target(), PlanTarget::MapGoal(Some(_))));
    assert_eq!(app.map.goal, None);
    assert!(
        last_log(&app).starts_with("plans go to the map's goal ("),
        "{}",
        last_log(&app)
    );
    assert_eq!(app.view, crate::app::View::Map);
    app.update(Action::Back);
    assert_eq!(app.view, crate::app::View::Dashboard);
    // `G` does the same.
    app.update(Action::GoToCursorStart);
    app.update(Action::PlanLocal);
    assert!(matches!(app.plan_target(), PlanTarget::Chosen(_)));
    app.update(Action::PlanTargetReset);
    assert!(matches!(app.plan_target(), PlanTarget::MapGoal(_)));
}

#[test]
fn the_header_says_which_waypoint_how_far_and_how_long_stuck() {
    let mut app = app_on_micro_rato_99();
    app.update(Action::Link(LinkEvent::Telemetry(protocol::Telemetry {
        mode: Mode::ExecutePlan,
        ..protocol::Telemetry::default()
    })));
    let p = Progress {
        mode: Mode::ExecutePlan,
        waypoint: 3,
        waypoints: 9,
        distance_left_mm: Some(2140),
        elapsed_ms: 41_000,
        stuck_ms: 12_000,
        give_up_ms: 40_000,
    };
    app.update(Action::Link(LinkEvent::Progress(p)));
    assert_eq!(
        app.progress_text(false).as_deref(),
        Some("waypoint 3 of 9, 2.1 m left, 41 s, stuck 12 s (gives up at 40)")
    );
    // A report of another mode than telemetry's is stale.
    app.update(Action::Link(LinkEvent::Telemetry(protocol::Telemetry {
        mode: Mode::Idle,
        ..protocol::Telemetry::default()
    })));
    assert_eq!(app.progress_text(false), None);
    // Giving up is logged with the reason and the parameter that sets the limit.
    app.update(Action::Link(LinkEvent::Robot(protocol::Event {
        code: EventCode::NoProgress,
        value: 40_050,
    })));
    assert_eq!(
        last_log(&app),
        "plan execution gave up: no progress for 40 s, 2.1 m from its target; the robot \
         stopped (limit: parameter stuck_limit_s)"
    );
}

#[test]
fn a_segment_refused_for_capacity_names_the_limit_and_the_way_forward() {
    let mut app = app_on_micro_rato_99();
    app.update(Action::Link(LinkEvent::CommandDone {
        id: 3,
        command: Command::Segment,
        outcome: CommandOutcome::Nacked {
            reason: NackReason::CapacityExceeded,
            sends: 1,
        },
    }));
    let line = last_log(&app);
    let squares = format!(
        "at most {} squares",
        robot_firmware::nav::fixed::NAV64_REGIONS
    );
    for part in [
        squares.as_str(),
        "grid planner",
        "P in the TUI",
        "station segment",
    ] {
        assert!(line.contains(part), "{part}: {line}");
    }
}

#[test]
fn a_go_to_outside_the_arena_names_the_bounds_it_knows_and_reads_them() {
    let mut app = app_on_micro_rato_99();
    app.update(Action::Link(LinkEvent::CommandDone {
        id: 3,
        command: Command::GoTo(PointMm {
            x_mm: 100_000,
            y_mm: 100_000,
        }),
        outcome: CommandOutcome::Nacked {
            reason: NackReason::BadPoint,
            sends: 1,
        },
    }));
    let line = last_log(&app);
    assert!(line.contains("outside the robot's arena"), "{line}");
    let reads = app
        .take_outbox()
        .into_iter()
        .filter(|(_, c)| matches!(c, Command::GetParam { .. }))
        .count();
    assert_eq!(reads, 4);
}
