//! The line-correction view (seed 003) from a real run: the emulator's Khepera surveys the
//! built-in floor grid for 90 s with the unchanged firmware, and the station is fed exactly
//! what the link would carry (telemetry and truth at 10 Hz, `Localization` at 5 Hz, built by
//! the firmware's own code). The map shows the true, corrected and uncorrected tracks, the
//! nearest-line track, line events and PPD samples; the panel beside it the errors over time.
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use emulator::sim::{Sim, SimConfig};
use protocol::{caps, Command, EmuTruth, Mode, Pose, ProfileId};
use robot_firmware::KHEPERA;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions, View};
use station::link::{Connection, LinkEvent, PeerInfo};

fn peer() -> PeerInfo {
    support::tui::peer(ProfileId::Khepera, KHEPERA.capabilities | caps::EMULATED)
}

/// 90 s of survey, fed to a station app.
fn surveyed() -> App {
    let arena = emulator::builtin::floor_grid();
    let mut app = App::new(AppOptions {
        port_label: "built-in emulator".into(),
        arena: Some(ArenaOverlay::from_arena(&arena)),
        ..AppOptions::default()
    });
    let cfg = SimConfig {
        seed: 3,
        floor_grid_m: Some(0.1),
        ..SimConfig::new(&KHEPERA)
    };
    let mut sim = Sim::new(arena, cfg).unwrap();
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer(),
    ))));
    sim.robot_mut().apply(Command::SetMode(Mode::Survey), 0);
    for ms in 1..=90_000u32 {
        sim.step();
        if ms % 200 == 0 {
            let m = sim.robot().linecorr().expect("line correction").report(ms);
            app.update(Action::Link(LinkEvent::Localization(Box::new(m))));
        }
        if ms % 100 == 0 {
            app.update(Action::Tick {
                now_ms: u64::from(ms),
            });
            let t = sim.robot().telemetry(ms);
            app.update(Action::Link(LinkEvent::Telemetry(t)));
            let p = sim.truth();
            app.update(Action::Link(LinkEvent::Truth(EmuTruth {
                time_ms: ms,
                pose: Pose {
                    x_mm: (p.x * 1000.0).round() as i32,
                    y_mm: (p.y * 1000.0).round() as i32,
                    heading_mrad: (p.heading * 1000.0).round() as i16,
                },
                collisions: sim.collisions(),
                robot_id: 1,
            })));
        }
    }
    app
}

use support::tui::screen;

#[test]
fn the_map_shows_the_tracks_line_events_ppd_and_the_error_chart() {
    let mut app = surveyed();
    app.update(Action::ShowView(View::Map));
    let l = &app.localization;
    // 90 s at 0.1 m/s crosses many lines; the errors were judged against the truth.
    assert!(l.events.len() > 50, "{}", l.events.len());
    assert!(l.errors.len() > 400, "{}", l.errors.len());
    assert!(
        l.max_mm[0] < 50.0,
        "corrected stays within half a square: {:?}",
        l.max_mm
    );
    assert!(l.max_mm[1] > l.max_mm[0], "{:?}", l.max_mm);
    let s = screen(&app, 100, 30);
    assert!(
        s.contains("Line correction") && s.contains("Position error"),
        "{s}"
    );
    insta::assert_snapshot!("line_correction_map_at_100x30", s);
    // At 80 x 24 the panel still fits beside the square arena.
    let small = screen(&app, 80, 24);
    assert!(small.contains("Line correction"), "{small}");
}

#[test]
fn layer_keys_hide_the_line_correction_layers() {
    let mut app = surveyed();
    app.update(Action::ShowView(View::Map));
    let before = screen(&app, 100, 30);
    for layer in [
        station::ui::localization::ODOMETRY,
        station::ui::localization::LINES,
        station::ui::localization::PPD,
        station::ui::localization::FLOOR,
    ] {
        app.update(Action::ToggleLayer(layer));
        assert!(!app.map.visible(layer));
    }
    let after = screen(&app, 100, 30);
    assert_ne!(before, after);
    // The line-event marks are gone from the map.
    let marks = |s: &str| s.matches('+').count();
    assert!(marks(&after) < marks(&before), "{after}");
}
