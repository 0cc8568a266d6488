//! The replay screen (ratatui `TestBackend` + insta) with its progress bar, and the replay's
//! keys: pause, seek both ways, speed, and that nothing a key does is ever sent.
#![allow(clippy::unwrap_used, clippy::panic)]

use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::Terminal;
use station::action::Action;
use station::app::{AppOptions, View};
use station::record::synth::demo;
use station::record::Recording;
use station::replay::session::ReplaySession;

fn session() -> ReplaySession {
    let rec = Recording::parse_strict(&demo(10, 10)).unwrap();
    let mut s = ReplaySession::new(
        rec,
        "demo.rec",
        AppOptions {
            port_label: "replay demo.rec".into(),
            arena: None,
            ..AppOptions::default()
        },
        1.0,
    );
    s.app_mut().update(Action::Resize {
        width: 100,
        height: 30,
    });
    s
}

fn screen(s: &ReplaySession, wall_us: u64) -> String {
    let mut t = Terminal::new(TestBackend::new(100, 30)).unwrap();
    t.draw(|f| s.render(f, wall_us)).unwrap();
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

fn key(s: &mut ReplaySession, wall_us: u64, code: KeyCode) {
    s.key(wall_us, &KeyEvent::new(code, KeyModifiers::NONE));
    s.sync(wall_us);
}

#[test]
fn replay_screen_paused_at_4_s_of_10_at_100x30() {
    let mut s = session();
    s.player.seek(0, 4_000_000);
    s.player.toggle_pause(0);
    s.sync(0);
    insta::assert_snapshot!(screen(&s, 0));
}

#[test]
fn replay_link_view_with_help_at_100x30() {
    let mut s = session();
    s.sync(10_500_000);
    key(&mut s, 10_500_000, KeyCode::F(5));
    assert_eq!(s.app().view, View::Link);
    key(&mut s, 10_500_000, KeyCode::Char('?'));
    assert!(s.help);
    insta::assert_snapshot!(screen(&s, 10_500_000));
}

#[test]
fn keys_pause_seek_both_ways_and_change_speed() {
    let mut s = session();
    s.sync(3_000_000);
    let at_3 = s.app().telemetry.unwrap();
    key(&mut s, 3_000_000, KeyCode::Char(' '));
    assert!(s.player.paused());
    s.sync(9_000_000);
    assert_eq!(s.app().telemetry.unwrap(), at_3, "paused: nothing moves");
    key(&mut s, 9_000_000, KeyCode::Right);
    assert_eq!(s.player.position(9_000_000), 8_000_000);
    let log_at_8 = s.app().log.len();
    key(&mut s, 9_000_000, KeyCode::Left);
    key(&mut s, 9_000_000, KeyCode::Left);
    assert_eq!(s.player.position(9_000_000), 0);
    key(&mut s, 9_000_000, KeyCode::Right);
    assert_eq!(
        s.app().telemetry.unwrap().time_ms,
        at_3.time_ms + 2000,
        "seeking back replays from the start to the same state"
    );
    key(&mut s, 9_000_000, KeyCode::End);
    assert_eq!(
        s.app().log.len(),
        log_at_8,
        "the log is rebuilt, not doubled"
    );
    key(&mut s, 9_000_000, KeyCode::Home);
    key(&mut s, 9_000_000, KeyCode::Char('+'));
    assert_eq!(s.player.speed(), 2.0);
    key(&mut s, 9_000_000, KeyCode::Char('7'));
    assert_eq!(s.player.speed(), 7.0);
    key(&mut s, 9_000_000, KeyCode::Char(' '));
    s.sync(10_000_000);
    assert_eq!(s.player.position(10_000_000), 7_000_000);
    // Driving, modes and go-to keys do nothing in a replay.
    for c in ['w', 'a', '1', 'g', 'P'] {
        key(&mut s, 10_000_000, KeyCode::Char(c));
    }
    key(&mut s, 10_000_000, KeyCode::Up);
    key(&mut s, 10_000_000, KeyCode::Enter);
    assert!(s.app_mut().take_outbox().is_empty());
    assert!(!s.app().teleop.driving);
    key(&mut s, 10_000_000, KeyCode::Char('q'));
    assert!(s.quit);
}

#[test]
fn a_replay_at_its_start_offers_no_live_hints() {
    let mut s = session();
    s.player.toggle_pause(0);
    s.sync(0);
    let start = screen(&s, 0);
    // Before the recording's first session: no "keeps trying" notice, no go-to hint, and the
    // sensors panel does not guess a robot.
    assert!(!start.contains("keeps trying"), "{start}");
    assert!(!start.contains("go-to"), "{start}");
    assert!(!start.contains("Sensors — "), "{start}");
}
