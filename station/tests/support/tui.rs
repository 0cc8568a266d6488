//! What the screen tests build again and again: a robot's handshake reply, the screen as
//! text, a key press as the TUI reads it.

use protocol::{MapCapacity, ProfileId};
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
use ratatui::Terminal;
use station::action::Action;
use station::app::App;
use station::link::PeerInfo;

/// A robot's `HelloReply` as the station keeps it: `profile` with capability bits `caps`, the
/// firmware's 64 x 64 map, 10 Hz telemetry, robot id 1, session 0x12345678.
pub fn peer(profile: ProfileId, caps: u32) -> PeerInfo {
    PeerInfo {
        session: 0x1234_5678,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile,
        capabilities: caps,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id: 1,
    }
}

/// The TUI drawn at `w` x `h`, as text.
pub fn screen(app: &App, w: u16, h: u16) -> String {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| station::ui::render(app, f)).unwrap();
    t.backend().to_string()
}

/// What pressing `c` does, if anything.
pub fn key(app: &App, c: char) -> Option<Action> {
    let ev = Event::Key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE));
    station::input::action_for(app, &ev)
}
