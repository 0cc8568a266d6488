//! The TUI's transfers: the live map while the robot explores (a whole-screen snapshot of the
//! map partially known, seed 004 Fig. 5), the keys that upload, plan on the robot and execute,
//! and the progress bar. The robot's side is played by the test with the protocol's own
//! `Sender`; the map comes from the emulator's simulation exploring Micro-Rato'99 for 40 s.
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use protocol::transfer::Sender;
use protocol::{
    caps, crc32c, AckInfo, Command, Event, EventCode, Message, Mode, ObjectKind, Pose, ProfileId,
    Telemetry,
};
use ratatui::crossterm::event::{Event as TermEvent, KeyCode, KeyEvent, KeyModifiers};
use robot_firmware::transfer::MAP_OBJECT_MAX;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::transfers::TransferAction;
use station::app::{App, AppOptions, View};
use station::link::{CommandOutcome, Connection, LinkEvent, PeerInfo, TransferIn, TransferOut};
use station::plan::{MapOptions, NavMap, PlanState, Planner};
use station::transfer::objects::{map_object, plan_object};

fn peer() -> PeerInfo {
    support::tui::peer(
        ProfileId::MicroRato,
        caps::COMPASS | caps::BEACON | caps::TRANSFERS | caps::EMULATED,
    )
}

fn app() -> App {
    let a = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let mut app = App::new(AppOptions {
        port_label: "/dev/ttyUSB0".into(),
        arena: Some(ArenaOverlay::from_arena(&a)),
        ..AppOptions::default()
    });
    app.map.plan = PlanState::for_arena(&a, emulator::builtin::MICRO_RATO_99);
    app.map.hidden.push(station::ui::map_layers::REGIONS);
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer(),
    ))));
    // The parameter fetch every connection starts (issue 16); this test is about what follows.
    app.take_outbox();
    app.update(Action::ShowView(View::Map));
    app
}

fn telemetry(app: &mut App, mode: Mode, (x, y, h): (f64, f64, f64)) {
    let t = Telemetry {
        mode,
        pose: Pose {
            x_mm: (x * 1000.0) as i32,
            y_mm: (y * 1000.0) as i32,
            heading_mrad: (h * 1000.0) as i16,
        },
        ..Telemetry::default()
    };
    app.update(Action::Link(LinkEvent::Telemetry(t)));
}

use support::tui::screen;

fn key(app: &App, c: char) -> Action {
    support::tui::key(app, c).unwrap()
}

/// The Micro-Rato'99 simulation after 40 s of exploring: its map object and true pose.
fn explored() -> (Vec<u8>, (f64, f64, f64)) {
    let arena = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let cfg = emulator::sim::SimConfig::new(&robot_firmware::MICRO_RATO);
    let mut sim = emulator::sim::Sim::new(arena, cfg).unwrap();
    let reply = sim.robot_mut().apply(Command::StartExploration, 0);
    assert!(
        matches!(reply, robot_firmware::link::Reply::Ack(_)),
        "{reply:?}"
    );
    sim.run_for(40_000);
    let mut out = vec![0; MAP_OBJECT_MAX];
    let n = sim.robot().objects().map_object(&mut out).unwrap();
    out.truncate(n);
    let p = sim.believed();
    (out, (p.x, p.y, p.heading))
}

/// Plays the robot's side of the download the app has asked for: answers its `Download`
/// command, then sends `bytes` with the protocol's `Sender`, feeding the app's acks back.
/// Returns the chunks sent.
fn serve_download(app: &mut App, now: &mut u64, bytes: &[u8]) -> usize {
    let out = app.take_outbox();
    let (id, command) = out
        .into_iter()
        .find(|(_, c)| matches!(c, Command::Download { .. }))
        .expect("a Download command");
    let Command::Download { object, .. } = command else {
        unreachable!()
    };
    let mut s = Sender::for_object(object, bytes, 1).unwrap();
    let b = s.begin();
    let info = AckInfo::Object {
        object,
        id: b.id,
        len: b.len,
        crc: b.crc,
    };
    app.update(Action::Link(LinkEvent::CommandDone {
        id,
        command,
        outcome: CommandOutcome::Acked {
            info,
            sends: 1,
            rtt_ms: 3,
        },
    }));
    let mut chunks = 0;
    for _ in 0..200 {
        *now += 5;
        let mut frames = Vec::new();
        s.poll(*now as u32, bytes, |m| {
            frames.push((*m).into_owned_in());
            true
        });
        for f in frames {
            chunks += usize::from(matches!(f, TransferIn::Chunk { .. }));
            app.update(Action::Link(LinkEvent::Transfer(f)));
        }
        for f in app.transfers.take_frames() {
            if let TransferOut::Ack(a) = f {
                s.on_ack(&a, *now as u32);
            }
        }
        app.update(Action::Tick { now_ms: *now });
        if s.is_done() {
            return chunks;
        }
    }
    panic!("the download never ended: {:?}", s.outcome());
}

/// `Message` to the owned `TransferIn` the link would forward.
trait IntoIn {
    fn into_owned_in(self) -> TransferIn;
}

impl IntoIn for Message<'_> {
    fn into_owned_in(self) -> TransferIn {
        match self {
            Message::TransferBegin(b) => TransferIn::Begin(b),
            Message::TransferData(c) => TransferIn::Chunk {
                tag: c.tag,
                offset: c.offset,
                data: c.data.to_vec(),
            },
            Message::TransferAck(a) => TransferIn::Ack(a),
            other => panic!("not a transfer frame: {other:?}"),
        }
    }
}

#[test]
fn the_map_grows_on_screen_while_the_robot_explores() {
    let (map, pose) = explored();
    let mut app = app();
    let mut now = 1_000;
    telemetry(&mut app, Mode::Explore, pose);
    app.update(Action::Tick { now_ms: now });
    let chunks = serve_download(&mut app, &mut now, &map);
    assert!(chunks >= 1);
    let shown = app.map.plan.map().unwrap();
    assert_eq!(shown.name, "robot map");
    let (free, obstacle, unknown) = shown.counts();
    println!("after 40 s of exploring: {free} free, {obstacle} obstacle, {unknown} unknown");
    assert!(free > 0 && unknown > 0, "partially known");
    // A second later the map is asked for again; unchanged, nothing travels but the chunks
    // the robot puts behind its Begin before the answer says the station holds it: the
    // object's first 256 bytes at most, four of the 64-byte chunks a sender probes a line
    // with (PROTOCOL.md §8).
    now += 1_000;
    app.update(Action::Tick { now_ms: now });
    assert!(
        serve_download(&mut app, &mut now, &map) <= 4,
        "already held"
    );
    // The robot kept reporting meanwhile (else the header rightly calls its mode stale).
    telemetry(&mut app, Mode::Explore, pose);
    insta::assert_snapshot!(screen(&app, 100, 30));
}

#[test]
fn keys_upload_plan_on_the_robot_and_execute_its_plan() {
    let mut app = app();
    let mut now = 100;
    // `u` opens the prompt with the arena shown; Enter uploads it (a TransferBegin goes out).
    app.update(key(&app, 'u'));
    assert_eq!(
        app.transfers.prompt.as_deref(),
        Some(emulator::builtin::MICRO_RATO_99)
    );
    let enter = TermEvent::Key(KeyEvent::new(KeyCode::Enter, KeyModifiers::NONE));
    let commit = station::input::action_for(&app, &enter).unwrap();
    assert_eq!(commit, Action::Transfer(TransferAction::PromptCommit));
    app.update(commit);
    app.update(Action::Tick { now_ms: now });
    let frames = app.transfers.take_frames();
    assert!(
        matches!(frames.first(), Some(TransferOut::Begin(b)) if b.object == ObjectKind::Map),
        "{frames:?}"
    );
    let progress = screen(&app, 100, 30);
    assert!(
        progress.contains("upload map builtin:micro-rato-99"),
        "{progress}"
    );
    // `X` with no plan known says how to get one.
    app.update(key(&app, 'X'));
    let last = app.log.window(1).last().unwrap().text.clone();
    assert!(last.contains("no plan on the robot"), "{last}");
    // `O`: Segment and Plan; the robot's PlanInstalled brings its plan here.
    app.update(key(&app, 'O'));
    let sent: Vec<Command> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    assert_eq!(
        sent,
        vec![
            Command::Segment,
            Command::Plan {
                from: None,
                to: None
            }
        ]
    );
    let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).unwrap();
    let map_id = map_object(&map).unwrap().id;
    let planner = Planner::new(map).unwrap();
    let r = planner.plan(Some((0.5, 0.5)), None, false).unwrap();
    let plan = plan_object(&planner, &r, map_id).unwrap();
    let plan_id = crc32c(&plan);
    app.update(Action::Link(LinkEvent::Robot(Event {
        code: EventCode::PlanInstalled,
        value: plan_id as i32,
    })));
    // The upload is still the running job; the plan's download waits its turn. End the
    // upload as a robot would (already held), then serve the plan.
    let tag = frames
        .iter()
        .find_map(|f| match f {
            TransferOut::Begin(b) => Some(b.tag),
            _ => None,
        })
        .unwrap();
    let held = protocol::TransferAck {
        tag,
        next: 0,
        status: protocol::TransferStatus::AlreadyHave,
        sack: 0,
    };
    app.update(Action::Link(LinkEvent::Transfer(TransferIn::Ack(held))));
    now += 10;
    app.update(Action::Tick { now_ms: now });
    serve_download(&mut app, &mut now, &plan);
    let (got, points) = app.transfers.robot_plan.clone().unwrap();
    assert_eq!(got, plan_id);
    assert_eq!(points.len(), r.waypoints.len());
    let s = screen(&app, 120, 40);
    assert!(s.contains('◆'), "the robot's plan is drawn:\n{s}");
    // `X` executes exactly that plan; `E` starts exploring.
    app.update(key(&app, 'X'));
    app.update(key(&app, 'E'));
    let sent: Vec<Command> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    assert_eq!(
        sent,
        vec![Command::ExecutePlan { plan_id }, Command::StartExploration]
    );
}

#[test]
fn the_upload_prompt_suggestion_is_replaced_by_typing_kept_by_end_and_cleared_by_ctrl_u() {
    let mut app = app();
    let press = |app: &mut station::app::App, code: KeyCode, m: KeyModifiers| {
        let ev = TermEvent::Key(KeyEvent::new(code, m));
        if let Some(a) = station::input::action_for(app, &ev) {
            app.update(a);
        }
    };
    let type_text = |app: &mut station::app::App, s: &str| {
        for c in s.chars() {
            press(app, KeyCode::Char(c), KeyModifiers::NONE);
        }
    };
    app.update(key(&app, 'u'));
    assert!(app.transfers.prompt_suggested);
    type_text(&mut app, "plan.obj");
    assert_eq!(app.transfers.prompt.as_deref(), Some("plan.obj"));
    // Typing on an edited path appends; Ctrl-U clears it all.
    type_text(&mut app, "2");
    assert_eq!(app.transfers.prompt.as_deref(), Some("plan.obj2"));
    press(&mut app, KeyCode::Char('u'), KeyModifiers::CONTROL);
    assert_eq!(app.transfers.prompt.as_deref(), Some(""));
    press(&mut app, KeyCode::Esc, KeyModifiers::NONE);
    // End keeps the suggestion for editing.
    app.update(key(&app, 'u'));
    press(&mut app, KeyCode::End, KeyModifiers::NONE);
    type_text(&mut app, "x");
    assert_eq!(
        app.transfers.prompt.as_deref(),
        Some(format!("{}x", emulator::builtin::MICRO_RATO_99).as_str())
    );
}

/// `O` for a chosen target, refused: `X` must not execute the robot's earlier plan (to the
/// map's goal) while the footer names the chosen target. After the refusal there is no plan
/// for that target, and `X` says so; `G` names the goal again, whose plan `X` then runs.
#[test]
fn x_executes_only_the_plan_the_screen_names() {
    let mut app = app();
    let done = |app: &mut App, command, outcome| {
        app.update(Action::Link(LinkEvent::CommandDone {
            id: 0,
            command,
            outcome,
        }));
    };
    let ack = CommandOutcome::Acked {
        info: AckInfo::Done,
        sends: 1,
        rtt_ms: 5,
    };
    // A plan to the map's goal, installed.
    app.update(key(&app, 'O'));
    app.take_outbox();
    done(&mut app, Command::Segment, ack);
    done(
        &mut app,
        Command::Plan {
            from: None,
            to: None,
        },
        ack,
    );
    let goal_plan = 0x600d_0001;
    app.update(Action::Link(LinkEvent::Robot(Event {
        code: EventCode::PlanInstalled,
        value: goal_plan as i32,
    })));
    app.take_outbox();

    // The cursor becomes the target; the robot refuses to plan there.
    app.update(key(&app, 'g'));
    app.update(key(&app, 'O'));
    let sent: Vec<Command> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    let to = match sent.as_slice() {
        [Command::Segment, Command::Plan { to: Some(to), .. }] => *to,
        other => panic!("{other:?}"),
    };
    done(&mut app, Command::Segment, ack);
    let refused = CommandOutcome::Nacked {
        reason: protocol::NackReason::BadPoint,
        sends: 1,
    };
    done(
        &mut app,
        Command::Plan {
            from: None,
            to: Some(to),
        },
        refused,
    );
    let footer = screen(&app, 160, 40);
    assert!(footer.contains("plan to ("), "{footer}");
    app.update(key(&app, 'X'));
    let sent: Vec<Command> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    assert!(
        sent.is_empty(),
        "X ran a plan the screen does not name: {sent:?}"
    );
    let last = app.log.window(1).last().unwrap().text.clone();
    assert!(last.contains("no plan to the chosen target ("), "{last}");
    assert!(last.contains("refused"), "{last}");

    // `G`: the map's goal again, and its plan is the robot's installed one.
    app.update(key(&app, 'G'));
    app.update(key(&app, 'X'));
    let sent: Vec<Command> = app.take_outbox().into_iter().map(|(_, c)| c).collect();
    assert_eq!(sent, vec![Command::ExecutePlan { plan_id: goal_plan }]);
}
