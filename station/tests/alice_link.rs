//! An ALICE's situations (message kind 16) reach the station's QT world model: the emulator's
//! simulated ALICE (`emulator::scenarios::alice::stream`) recorded frame by frame with the real encoder,
//! then replayed through the station's link machine (`ReplayFeed`, the path a live link's
//! bytes take) into the app; the map's `qt` layer on screen and hidden by `T`; and the model
//! in the MCAP export (`/qt_model`), its counts those of a model fed the same situations.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::process::Command;

use emulator::scenarios::alice::stream::AliceStream;
use protocol::{AliceSituation, Message, PROTOCOL_VERSION};
use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};
use ratatui::Terminal;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::qt_state::QtState;
use station::app::{App, AppOptions, View};
use station::record::synth::{demo_peer, Synth};
use station::record::{Meta, Recording};
use station::replay::ReplayFeed;

/// Situations at the thesis's 3 a second: 10 minutes.
const SITUATIONS: usize = 1800;
const PERIOD_US: u64 = 333_333;

fn situations(seed: u64, n: usize) -> Vec<AliceSituation> {
    let mut s = AliceStream::new(seed);
    (0..n).map(|_| s.next_situation()).collect()
}

fn recording(sits: &[AliceSituation]) -> Vec<u8> {
    let meta = Meta {
        created_unix_ms: 1_700_000_000_000,
        writer: "synth".into(),
        port: "memory".into(),
        baud: 115_200,
        protocol: PROTOCOL_VERSION,
        arena: "builtin:alice".into(),
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    s.handshake(demo_peer());
    for (i, sit) in sits.iter().enumerate() {
        s.from_robot(
            10_000 + i as u64 * PERIOD_US,
            &Message::AliceSituation(*sit),
        );
    }
    s.finish(20_000 + sits.len() as u64 * PERIOD_US, "end")
}

/// A model fed directly, without the link: what the station must end up with.
fn direct(sits: &[AliceSituation]) -> QtState {
    let mut qt = QtState::default();
    for s in sits {
        qt.on_situation(s);
    }
    qt
}

/// The app after the recording's frames went through the station's link machine.
fn replayed(sits: &[AliceSituation]) -> App {
    let rec = Recording::parse(&recording(sits)).unwrap();
    let mut app = App::new(AppOptions {
        port_label: "replay".into(),
        arena: Some(ArenaOverlay::from_arena(
            &emulator::builtin::load("builtin:alice", &Default::default()).unwrap(),
        )),
        ..AppOptions::default()
    });
    let mut feed = ReplayFeed::new("memory");
    let mut actions = Vec::new();
    feed.advance_to(&rec.records, u64::MAX / 2, &mut actions);
    for a in actions {
        app.update(a.into());
    }
    app
}

#[test]
fn the_stations_model_grows_from_the_emulators_stream() {
    let sits = situations(1, SITUATIONS);
    let early = replayed(&sits[..60]);
    let app = replayed(&sits);
    let want = direct(&sits);
    assert_eq!(
        app.qt.received, SITUATIONS as u64,
        "every situation arrived"
    );
    assert_eq!((app.qt.lost, app.qt.refused), (0, 0));
    let m = app
        .qt
        .model
        .as_ref()
        .expect("a model from the first situation");
    let w = want.model.as_ref().unwrap();
    assert_eq!(m.stats().samples, SITUATIONS as u64);
    // The link loses nothing: the same network as a model fed directly.
    assert_eq!(m.network().len(), w.network().len());
    assert_eq!(m.network().edges().count(), w.network().edges().count());
    assert_eq!(m.winner(), w.winner());
    // And it grows: a scene of 3 x 3 m takes many more cells than its first 20 s.
    let first = early.qt.model.as_ref().unwrap().network().len();
    assert!(
        m.network().len() >= 3 * first && m.network().len() >= 40,
        "{first} cells after 60 situations, {} after {SITUATIONS}",
        m.network().len()
    );
}

#[test]
fn lost_frames_are_counted_from_the_sequence() {
    let mut sits = situations(2, 100);
    sits.drain(40..43);
    let app = replayed(&sits);
    assert_eq!((app.qt.received, app.qt.lost), (97, 3));
}

fn screen(app: &App, w: u16, h: u16) -> String {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| station::ui::render(app, f)).unwrap();
    t.backend().to_string()
}

fn key(app: &mut App, c: char) {
    let ev = Event::Key(KeyEvent::new(KeyCode::Char(c), KeyModifiers::NONE));
    if let Some(a) = station::input::action_for(app, &ev) {
        app.update(a);
    }
}

#[test]
fn qt_layer_on_the_map_at_100x30_and_t_hides_it() {
    let sits = situations(1, 900);
    let mut app = replayed(&sits);
    app.update(Action::ShowView(View::Map));
    let shown = screen(&app, 100, 30);
    insta::assert_snapshot!(shown);
    key(&mut app, 'T');
    let hidden = screen(&app, 100, 30);
    assert_ne!(shown, hidden, "T hides the qt layer");
    key(&mut app, 'T');
    assert_eq!(screen(&app, 100, 30), shown, "T again shows it");
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("alice-link-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn mcap_export_has_the_model_with_its_counts() {
    let sits = situations(3, 600);
    let d = dir("mcap");
    std::fs::write(d.join("alice.rec"), recording(&sits)).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_station"))
        .args(["export", "alice.rec", "--mcap", "alice.mcap"])
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(d.join("alice.mcap")).unwrap();
    let mut snaps = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/qt_model" {
            assert_eq!(m.channel.schema.as_ref().unwrap().name, "station.QtModel");
            snaps.push(serde_json::from_slice::<serde_json::Value>(&m.data).unwrap());
        }
    }
    // One a second of robot time (situations 333-334 ms apart), the first included.
    let seconds = sits.last().unwrap().time_ms / 1000;
    assert!(
        (snaps.len() as i64 - i64::from(seconds)).abs() <= 1,
        "{} snapshots over {seconds} s",
        snaps.len()
    );
    for v in [&snaps[0], &snaps[snaps.len() / 2], snaps.last().unwrap()] {
        let n = v["samples"].as_u64().unwrap() as usize;
        let want = direct(&sits[..n]);
        let w = want.model.as_ref().unwrap();
        let cells = v["cells"].as_array().unwrap();
        let edges = v["edges"].as_array().unwrap();
        assert_eq!(cells.len(), w.network().len());
        assert_eq!(v["cell_count"].as_u64().unwrap() as usize, cells.len());
        assert_eq!(edges.len(), w.network().edges().count());
        assert_eq!(v["edge_count"].as_u64().unwrap() as usize, edges.len());
        assert_eq!(v["winner"].as_u64().map(|x| x as u32), w.winner());
        assert!(edges
            .iter()
            .all(|e| e["confidence"].as_f64().unwrap() > 0.0));
    }
    assert!(snaps.last().unwrap()["cell_count"].as_u64().unwrap() > 20);
}

/// Issue 31 item 3: random situations each a robot second after the last grow the network to
/// its 2,000-cell cap and each was due a snapshot of all of it: 2,000 of them (116 KB) made a
/// 261 MB MCAP. The snapshots now stay within their budget, in proportion to the recording,
/// and the export says how many it left out.
#[test]
fn random_situations_a_second_apart_export_in_proportion_to_the_recording() {
    let mut state = 31u64;
    let mut rand = |bits: u32| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> (64 - bits)) as u32
    };
    let n = 2000;
    let sits: Vec<AliceSituation> = (0..n)
        .map(|i| AliceSituation {
            time_ms: 1000 * (i + 1),
            seq: i as u16,
            whiskers: rand(24),
            light: std::array::from_fn(|_| rand(8) as u8),
            odometry: protocol::Pose {
                x_mm: rand(14) as i32 - 8192,
                y_mm: rand(14) as i32 - 8192,
                heading_mrad: rand(12) as i16 - 2048,
            },
        })
        .collect();
    let bytes = recording(&sits);
    let rec = Recording::parse_strict(&bytes).unwrap();
    let data: u64 = rec.records.iter().map(|r| r.data.len() as u64).sum();
    let mut out = Vec::new();
    let written = station::export::mcap::write(
        &rec,
        station::export::mcap::Encoding::Protobuf,
        std::io::Cursor::new(&mut out),
        std::path::Path::new("random.mcap"),
    )
    .unwrap();
    // The budget, and one snapshot over it at most: 2,000 cells of about 160 bytes.
    let budget = station::export::qt::BUDGET_FLOOR + station::export::qt::BUDGET_PER_BYTE * data;
    println!(
        "{} recorded bytes ({data} of record data): {} MCAP bytes, budget {budget}; {:?}",
        bytes.len(),
        out.len(),
        written.notes
    );
    assert!(
        (out.len() as u64) < budget + 400_000,
        "{} bytes from {} ({} messages)",
        out.len(),
        bytes.len(),
        written.messages
    );
    let note = written.notes.join("\n");
    assert!(
        note.contains("/qt_model: ")
            && note.contains("snapshots due (one a second of robot time) left out"),
        "{note}"
    );
}

/// The message's size on the wire and its share of a 115200 baud link at the thesis's
/// 3 situations a second (and at a 20 Hz control cycle, were it sent every cycle).
#[test]
fn situation_fits_the_link() {
    let sits = situations(1, SITUATIONS);
    let mut buf = [0u8; protocol::MAX_FRAME];
    let sizes: Vec<usize> = sits
        .iter()
        .map(|s| protocol::encode(s.seq, &Message::AliceSituation(*s), &mut buf).unwrap())
        .collect();
    let widest = AliceSituation {
        time_ms: u32::MAX,
        seq: u16::MAX,
        whiskers: (1 << 24) - 1,
        light: [255; 24],
        odometry: protocol::Pose {
            x_mm: i32::MIN,
            y_mm: i32::MIN,
            heading_mrad: i16::MIN,
        },
    };
    let max = protocol::encode(u16::MAX, &Message::AliceSituation(widest), &mut buf).unwrap();
    let mean = sizes.iter().sum::<usize>() as f64 / sizes.len() as f64;
    let byte_s = 115_200.0 / 10.0;
    let share = |hz: f64| max as f64 * hz / byte_s * 100.0;
    eprintln!(
        "kind 16: mean {mean:.1} B, max {max} B; at 3 Hz {:.2} % of 115200 baud, at 20 Hz {:.1} %",
        share(3.0),
        share(20.0)
    );
    assert!(sizes.iter().all(|&n| n <= max));
    assert!(share(20.0) < 15.0, "{max} B");
}
