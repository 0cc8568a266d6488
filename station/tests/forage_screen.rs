//! The foraging view (seed 000 §7): `station --arena builtin:forage` draws the lamps, the
//! objects under them, the home base and the three landmarks; the robot's events and
//! telemetry mark an object taken, the gripper carrying and the objects home.
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use protocol::{caps, Event, EventCode, Mode, Pose, ProfileId, Telemetry};
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions, View};
use station::link::{Connection, LinkEvent, PeerInfo};

fn forage_arena() -> ArenaOverlay {
    let a = emulator::builtin::load("builtin:forage", &emulator::arena::LoadOptions::default())
        .unwrap();
    ArenaOverlay::from_arena(&a)
}

fn peer() -> PeerInfo {
    support::tui::peer(
        ProfileId::Khepera,
        caps::ENCODERS
            | caps::IR_PROXIMITY
            | caps::AMBIENT_LIGHT
            | caps::GRIPPER
            | caps::CAMERA
            | caps::EMULATED,
    )
}

fn telemetry(i: u32, x_mm: i32, y_mm: i32, carrying: bool) -> Telemetry {
    Telemetry {
        time_ms: i * 100,
        mode: Mode::Forage,
        pose: Pose {
            x_mm,
            y_mm,
            heading_mrad: -2400,
        },
        flags: if carrying {
            protocol::flags::CARRYING
        } else {
            0
        },
        ..Telemetry::default()
    }
}

/// The robot has delivered one object and carries the second home from the lamp at
/// (0.80, 0.18).
fn story() -> App {
    let mut app = App::new(AppOptions {
        port_label: "built-in emulator".into(),
        arena: Some(forage_arena()),
        ..AppOptions::default()
    });
    let link = |app: &mut App, e| app.update(Action::Link(e));
    app.update(Action::Tick { now_ms: 100 });
    link(
        &mut app,
        LinkEvent::Connection(Connection::Connected(peer())),
    );
    let event = |code, value| LinkEvent::Robot(Event { code, value });
    link(&mut app, event(EventCode::ModeChanged, 9));
    link(
        &mut app,
        LinkEvent::Telemetry(telemetry(1, 780, 600, false)),
    );
    link(&mut app, event(EventCode::ObjectGrasped, 1));
    link(&mut app, event(EventCode::PoseCorrected, 14));
    link(&mut app, event(EventCode::ObjectDelivered, 1));
    link(
        &mut app,
        LinkEvent::Telemetry(telemetry(2, 760, 200, false)),
    );
    link(&mut app, event(EventCode::ObjectGrasped, 2));
    for i in 0..10 {
        app.update(Action::Tick {
            now_ms: 200 + u64::from(i) * 100,
        });
        let t = telemetry(3 + i, 740 - 40 * i as i32, 190 - 5 * i as i32, true);
        link(&mut app, LinkEvent::Telemetry(t));
    }
    app
}

use support::tui::screen;

#[test]
fn progress_follows_the_robots_events() {
    let app = story();
    assert_eq!((app.forage.grasped, app.forage.delivered), (2, 1));
    assert!(app.forage.carrying);
    // The objects under (0.82, 0.64) and (0.80, 0.18) were taken, not the one at (0.22, 0.62).
    assert!(app.forage.is_taken(0) && !app.forage.is_taken(1) && app.forage.is_taken(2));
}

#[test]
fn foraging_map_at_80x24() {
    let mut app = story();
    app.update(Action::ShowView(View::Map));
    let s = screen(&app, 80, 24);
    assert!(s.contains("home 1/3"), "{s}");
    assert!(s.contains("carrying"), "{s}");
    insta::assert_snapshot!(s);
}
