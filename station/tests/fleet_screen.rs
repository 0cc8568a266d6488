//! The fleet view (issue 17) as a whole-screen snapshot: three robots, one refusing our key,
//! robot 3 selected after "stop all". Fixed events and times, as `screens.rs`.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{caps, Command, MapCapacity, Mode, Packed10x8, Pose, ProfileId, Telemetry};
use ratatui::backend::TestBackend;
use ratatui::Terminal;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions};
use station::fleet::{Fleet, Member};
use station::link::{CommandOutcome, Connection, LinkEvent, PeerInfo};

fn arena() -> ArenaOverlay {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../emulator/arenas/wallsMicRato99.xml"
    );
    ArenaOverlay::load(std::path::Path::new(path)).unwrap()
}

fn peer(robot_id: u8) -> PeerInfo {
    PeerInfo {
        session: 0x1234_5678,
        firmware: "robot-firmware".into(),
        firmware_version: "0.1.0".into(),
        profile: ProfileId::MicroRato,
        capabilities: caps::IR_PROXIMITY | caps::BATTERY | caps::EMULATED,
        map_capacity: MapCapacity {
            width: 64,
            height: 64,
        },
        telemetry_hz: 10,
        failsafe_ms: 300,
        robot_id,
    }
}

fn telemetry(i: u32, start: (i32, i32), mode: Mode) -> Telemetry {
    let f = f64::from(i);
    Telemetry {
        time_ms: i * 100,
        mode,
        pose: Pose {
            x_mm: start.0 + (f * 25.0) as i32,
            y_mm: start.1 + (f * f * 0.8) as i32,
            heading_mrad: (f * 20.0) as i16,
        },
        ir: Packed10x8::new([0, 40, 300, 900, 120, 10, 0, 0]),
        battery_mv: 7900 - i as u16,
        ..Telemetry::default()
    }
}

fn fleet() -> Fleet {
    let members = (1..=3)
        .map(|k| Member {
            app: App::new(AppOptions {
                port_label: format!("/dev/ttyUSB{}", k - 1),
                arena: Some(arena()),
                ..AppOptions::default()
            }),
            port: format!("/dev/ttyUSB{}", k - 1),
        })
        .collect();
    let mut f = Fleet::new(members);
    f.update(Action::Tick { now_ms: 100 });
    for i in [0, 2] {
        f.on_link(
            i,
            LinkEvent::Connection(Connection::Connected(peer(i as u8 + 1))),
        );
    }
    f.on_link(
        1,
        LinkEvent::Connection(Connection::Refused {
            message: "link authentication failed: the robot has another key".into(),
        }),
    );
    for m in &mut f.members {
        m.app.take_outbox();
    }
    let starts = [(600, 600), (0, 0), (4300, 600)];
    let modes = [Mode::Explore, Mode::Idle, Mode::Manual];
    for step in 0..30 {
        f.update(Action::Tick {
            now_ms: 200 + u64::from(step) * 100,
        });
        for i in [0, 2] {
            f.on_link(
                i,
                LinkEvent::Telemetry(telemetry(step, starts[i], modes[i])),
            );
        }
    }
    f.update(Action::SelectRobot(2));
    f.update(Action::StopAll);
    let sent: Vec<_> = f.members.iter_mut().map(|m| m.app.take_outbox()).collect();
    for i in [0, 2] {
        // An exploring robot's live map download may be queued too.
        let (id, command) = *sent[i].iter().find(|(_, c)| *c == Command::Stop).unwrap();
        f.on_link(
            i,
            LinkEvent::CommandDone {
                id,
                command,
                outcome: CommandOutcome::Acked {
                    info: protocol::AckInfo::Done,
                    sends: 1,
                    rtt_ms: 6 + i as u64,
                },
            },
        );
    }
    f
}

fn screen(f: &mut Fleet, w: u16, h: u16) -> String {
    f.update(Action::Resize {
        width: w,
        height: h,
    });
    f.sync_overlay();
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|frame| station::ui::render(f.app(), frame)).unwrap();
    t.backend().to_string()
}

#[test]
fn fleet_view_at_150x40() {
    insta::assert_snapshot!(screen(&mut fleet(), 150, 40));
}

#[test]
fn fleet_view_at_80x24() {
    insta::assert_snapshot!(screen(&mut fleet(), 80, 24));
}

#[test]
fn fleet_help_lists_stop_all_first() {
    let mut f = fleet();
    f.update(Action::ToggleHelp);
    let s = screen(&mut f, 100, 40);
    let first = s.lines().position(|l| l.contains("STOP ALL")).unwrap();
    let quit = s.lines().position(|l| l.contains("quit (stops")).unwrap();
    assert!(first < quit, "{s}");
}
