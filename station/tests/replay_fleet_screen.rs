//! The replay of a fleet recording (issue 17) as a whole-screen snapshot: three robots in one
//! version 2 file, every robot on the map with its track and number, the fleet panel, robot 2
//! picked (its panels shown). Built from messages (`record::synth`), fixed times.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{Message, Mode, Packed10x8, Pose, ProfileId, Telemetry};
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
use ratatui::Terminal;
use station::app::arena::ArenaOverlay;
use station::app::AppOptions;
use station::record::synth::{demo_peer, merge, Synth};
use station::record::{Meta, Recording};
use station::replay::session::ReplaySession;

fn arena() -> ArenaOverlay {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../emulator/arenas/wallsMicRato99.xml"
    );
    ArenaOverlay::load(std::path::Path::new(path)).unwrap()
}

/// Robot `k` (1-based, id `k`) on `/dev/ttyUSB{k-1}`: 6 s at 10 Hz from its own start, each
/// in its own mode.
fn robot(k: u32) -> Vec<u8> {
    let meta = Meta {
        created_unix_ms: 1_700_000_000_000,
        writer: "synth".into(),
        port: format!("/dev/ttyUSB{}", k - 1),
        baud: 115_200,
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    s.handshake(station::link::PeerInfo {
        robot_id: k as u8,
        profile: ProfileId::MicroRato,
        ..demo_peer()
    });
    let start = [(600, 600), (2400, 2200), (4300, 600)][k as usize - 1];
    let mode = [Mode::Explore, Mode::Wander, Mode::Manual][k as usize - 1];
    for i in 0..60u32 {
        let f = f64::from(i);
        let sign = if k == 2 { -1.0 } else { 1.0 };
        s.from_robot(
            10_000 + u64::from(i) * 100_000,
            &Message::Telemetry(Telemetry {
                time_ms: i * 100,
                mode,
                pose: Pose {
                    x_mm: start.0 + (sign * f * 15.0) as i32,
                    y_mm: start.1 + (sign * f * f * 0.3) as i32,
                    heading_mrad: (f * 20.0) as i16,
                },
                ir: Packed10x8::new([0, 40, 300, 900, 120, 10, 0, 0]),
                battery_mv: 7900 - 100 * k as u16 - i as u16,
                ..Telemetry::default()
            }),
        );
    }
    s.finish(6_000_000, "done")
}

fn screen(s: &ReplaySession, w: u16, h: u16) -> String {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| s.render(f, 0)).unwrap();
    let buf = t.backend().buffer().clone();
    let mut out = String::new();
    for y in 0..buf.area.height {
        for x in 0..buf.area.width {
            out.push_str(buf[(x, y)].symbol());
        }
        out.push('\n');
    }
    out
}

#[test]
fn replay_of_three_robots_shows_the_fleet_at_150x40() {
    let bytes = merge(&[robot(1), robot(2), robot(3)], "stopped by the operator");
    let rec = Recording::parse_strict(&bytes).unwrap();
    assert_eq!(rec.link_count(), 3);
    let mut s = ReplaySession::new(
        rec,
        "fleet.rec",
        AppOptions {
            port_label: "replay fleet.rec".into(),
            arena: Some(arena()),
            ..AppOptions::default()
        },
        1.0,
    );
    s.event(0, &Event::Resize(150, 40));
    s.player.seek(0, 5_000_000);
    s.player.toggle_pause(0);
    s.sync(0);
    s.event(
        0,
        &Event::Key(KeyEvent::new(KeyCode::Tab, KeyModifiers::NONE)),
    );
    let text = screen(&s, 150, 40);
    // Every robot on the fleet panel, robot 2 selected, each robot's number on the map.
    assert!(text.contains("Fleet: 2 of 3"), "{text}");
    for k in 1..=3 {
        assert!(text.contains(&format!("{k} micro-rato #{k}")), "{text}");
    }
    insta::assert_snapshot!(text);
}
