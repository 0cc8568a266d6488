//! The planning layers on the map, as whole-screen snapshots (ratatui `TestBackend` + insta)
//! at 80 x 24 and 180 x 50, and the keys that drive them: `P` plans on the station from the
//! robot (or the map's start) to the cursor or goal, `o r n m e` toggle the layers.
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use ratatui::crossterm::event::{Event, KeyModifiers};
use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid};
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions, View};
use station::link::{Connection, LinkEvent, PeerInfo};
use station::plan::PlanState;

fn connect(app: &mut App) {
    let peer = PeerInfo {
        session: 0x1234_5678,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile: protocol::ProfileId::MicroRato,
        capabilities: protocol::caps::EMULATED,
        map_capacity: protocol::MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id: 1,
    };
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer,
    ))));
    // The parameter fetch every connection starts (issue 16); this test is about what follows.
    app.take_outbox();
}

/// Telemetry putting the believed pose at (`x`, `y`) metres.
fn pose(app: &mut App, x: f64, y: f64) {
    let t = protocol::Telemetry {
        pose: protocol::Pose {
            x_mm: (x * 1000.0) as i32,
            y_mm: (y * 1000.0) as i32,
            heading_mrad: 0,
        },
        ..protocol::Telemetry::default()
    };
    app.update(Action::Link(LinkEvent::Telemetry(t)));
}

fn arena() -> (emulator::arena::Arena, ArenaOverlay) {
    let a = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let overlay = ArenaOverlay::from_arena(&a);
    (a, overlay)
}

/// The Map view of Micro-Rato'99 with every planning layer, planned from the start to the
/// target (no robot connected: the map's own start).
fn planned() -> App {
    let (a, overlay) = arena();
    let mut app = App::new(AppOptions {
        port_label: "/dev/ttyUSB0".into(),
        arena: Some(overlay),
        ..AppOptions::default()
    });
    app.map.plan = PlanState::for_arena(&a, emulator::builtin::MICRO_RATO_99);
    connect(&mut app);
    app.update(Action::ShowView(View::Map));
    app.update(Action::PlanLocal);
    app
}

use support::tui::screen;

use support::tui::key;

#[test]
fn map_with_grid_regions_and_plan_at_80x24() {
    insta::assert_snapshot!(screen(&planned(), 80, 24));
}

#[test]
fn map_with_grid_regions_and_plan_at_180x50() {
    insta::assert_snapshot!(screen(&planned(), 180, 50));
}

#[test]
fn map_with_the_regions_hidden_at_80x24() {
    let mut app = planned();
    app.update(key(&app, 'r').unwrap());
    insta::assert_snapshot!(screen(&app, 80, 24));
}

#[test]
fn p_plans_from_the_map_start_to_the_cursor_and_logs_it() {
    let mut app = planned();
    assert_eq!(key(&app, 'P'), Some(Action::PlanLocal));
    app.update(Action::GoToCursorStart);
    app.update(Action::MoveCursor { dx: 4.35, dy: 0.45 });
    app.update(Action::PlanLocal);
    let r = app.map.plan.result.clone().unwrap();
    assert_eq!(r.start(), (0.5, 0.5));
    assert_eq!(r.goal(), (4.35, 0.45));
    assert!(r.smoothed.is_some());
    let last = app.log.window(1).last().unwrap().text.clone();
    assert!(last.starts_with("planned on the station"), "{last}");
    // Planning never sends anything to the robot.
    assert!(app.take_outbox().is_empty());
}

#[test]
fn p_plans_from_the_believed_pose_when_the_robot_reports_one() {
    let mut app = planned();
    pose(&mut app, 4.35, 4.35);
    app.update(Action::PlanLocal);
    let r = app.map.plan.result.clone().unwrap();
    assert_eq!(r.start(), (4.35, 4.35));
    // No cursor and no go-to goal: the map's goal, beside the beacon.
    assert_eq!(r.goal(), (2.925, 2.571));
}

#[test]
fn a_click_lands_where_the_map_is_drawn_beside_the_plan_panel() {
    use ratatui::crossterm::event::{MouseButton, MouseEvent, MouseEventKind};
    let mut app = planned();
    app.update(Action::Resize {
        width: 180,
        height: 50,
    });
    let areas = station::ui::areas(ratatui::layout::Rect::new(0, 0, 180, 50), &app);
    let panel = areas.find(station::ui::Panel::Map).unwrap();
    let (map, side) = station::ui::plan_panel::split(&app, panel);
    assert!(side.is_some() && map.width < panel.width);
    let click = Event::Mouse(MouseEvent {
        kind: MouseEventKind::Down(MouseButton::Left),
        column: map.x + map.width / 2,
        row: map.y + map.height / 2,
        modifiers: KeyModifiers::NONE,
    });
    let Some(Action::CursorAt { x_m, y_m }) = station::input::action_for(&app, &click) else {
        panic!("a click on the map places the go-to cursor");
    };
    // The middle of the drawn map is the middle of the 5 m arena.
    assert!(
        (x_m - 2.5).abs() < 0.2 && (y_m - 2.5).abs() < 0.3,
        "({x_m}, {y_m})"
    );
}

#[test]
fn a_plan_into_a_wall_is_refused_in_the_log_and_the_title() {
    let mut app = planned();
    app.update(Action::GoToCursorStart);
    app.update(Action::MoveCursor { dx: 1.1, dy: 1.0 });
    app.update(Action::PlanLocal);
    let last = app.log.window(1).last().unwrap().text.clone();
    assert!(
        last.contains("goal (1.100, 1.000) is in an obstacle cell"),
        "{last}"
    );
    let s = screen(&app, 120, 30);
    assert!(s.contains("is in an obstacle"), "{s}");
}

#[test]
fn layer_keys_toggle_each_planning_layer() {
    let mut app = planned();
    for (c, name) in [
        ('o', "grid"),
        ('r', "regions"),
        ('n', "plan"),
        ('m', "smoothed"),
        ('e', "ends"),
    ] {
        assert_eq!(key(&app, c), Some(Action::ToggleLayer(name)));
        app.update(Action::ToggleLayer(name));
        assert!(!app.map.visible(name));
    }
    // Everything of the plan hidden: the arena alone remains.
    let bare = screen(&app, 80, 24);
    assert!(!bare.contains('•') && !bare.contains('█'));
}

#[test]
fn a_map_object_from_the_robot_is_shown_through_the_seam() {
    // A 6 x 4 grid of 0.25 m cells with a wall across x = 3 except the top row, as a Map
    // object carries it: size, cell mm, origin mm, start and goal mm, packed cells.
    let mut g = Grid::new(
        6,
        4,
        Geometry::new(250, -500, 0).unwrap(),
        vec![0u8; grid_bytes(6, 4)],
    )
    .unwrap();
    g.fill(Cell::Free);
    for y in 0..3 {
        g.set(3, y, Cell::Obstacle).unwrap();
    }
    use protocol::object::{encode_map, MapHeader};
    use protocol::PointMm;
    let pt = |x_mm, y_mm| PointMm { x_mm, y_mm };
    let header = MapHeader {
        width: 6,
        height: 4,
        cell_mm: 250,
        origin: pt(-500, 0),
        start: Some(pt(-375, 125)),
        goal: Some(pt(875, 125)),
    };
    let mut bytes = vec![0u8; header.object_len()];
    encode_map(&header, g.as_bytes(), &mut bytes).unwrap();
    let mut app = App::new(AppOptions::default());
    assert!(app
        .map
        .plan
        .show_map_object("from robot", &bytes[..10])
        .is_err());
    app.map.plan.show_map_object("from robot", &bytes).unwrap();
    app.update(Action::ShowView(View::Map));
    app.update(Action::PlanLocal);
    let r = app.map.plan.result.clone().unwrap();
    assert_eq!((r.start(), r.goal()), ((-0.375, 0.125), (0.875, 0.125)));
    // Around the wall's open end at the top row.
    assert!(
        r.waypoints.iter().any(|&(_, y)| y > 0.75),
        "{:?}",
        r.waypoints
    );
    let s = screen(&app, 80, 24);
    assert!(s.contains("from robot"), "{s}");
}
