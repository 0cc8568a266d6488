//! The README tour's explore -> plan -> execute at the app's level, against the real firmware
//! in the emulator's simulation of Micro-Rato'99 (the built-in emulator's world, its robot
//! told nothing over the link): `E` explores until the goal is reached, the robot's map is
//! downloaded and shown, `P` plans on the station to the goal the robot found, `O`'s
//! `Segment` and `Plan { from: None, to: None }` are accepted by the firmware, `X` executes
//! the plan it installed, and a plan to a point the robot never saw is refused with the point
//! named in the log.
#![allow(clippy::unwrap_used, clippy::panic)]

mod support;

use protocol::transfer::Sender;
use protocol::{
    caps, AckInfo, Command, Event, EventCode, Message, Mode, NackReason, Pose, ProfileId, Telemetry,
};
use robot_firmware::link::Reply;
use robot_firmware::transfer::MAP_OBJECT_MAX;
use station::action::Action;
use station::app::arena::ArenaOverlay;
use station::app::{App, AppOptions};
use station::link::{CommandOutcome, Connection, LinkEvent, PeerInfo, TransferIn, TransferOut};
use station::plan::PlanState;

fn peer() -> PeerInfo {
    support::tui::peer(
        ProfileId::MicroRato,
        caps::COMPASS | caps::BEACON | caps::TRANSFERS | caps::EMULATED,
    )
}

fn arena() -> emulator::arena::Arena {
    emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap()
}

fn app() -> App {
    let a = arena();
    let mut app = App::new(AppOptions {
        port_label: "built-in emulator".into(),
        arena: Some(ArenaOverlay::from_arena(&a)),
        ..AppOptions::default()
    });
    app.map.plan = PlanState::for_arena(&a, emulator::builtin::MICRO_RATO_99);
    app.update(Action::Link(LinkEvent::Connection(Connection::Connected(
        peer(),
    ))));
    // The parameter fetch every connection starts (issue 16); this test is about what follows.
    app.take_outbox();
    app
}

fn key(app: &App, c: char) -> Action {
    support::tui::key(app, c).unwrap()
}

/// The robot's telemetry as the app would receive it.
fn telemetry(app: &mut App, sim: &emulator::sim::Sim, mode: Mode) {
    let p = sim.believed();
    let t = Telemetry {
        mode,
        pose: Pose {
            x_mm: (p.x * 1000.0).round() as i32,
            y_mm: (p.y * 1000.0).round() as i32,
            heading_mrad: (p.heading * 1000.0).round() as i16,
        },
        ..Telemetry::default()
    };
    app.update(Action::Link(LinkEvent::Telemetry(t)));
}

/// Hands the app's commands to the firmware and its answers back to the app.
fn deliver(app: &mut App, sim: &mut emulator::sim::Sim) -> Vec<(Command, Reply)> {
    let mut done = Vec::new();
    for (id, command) in app.take_outbox() {
        let now_ms = (sim.now_us() / 1000) as u32;
        let reply = sim.robot_mut().apply(command, now_ms);
        let outcome = match reply {
            Reply::Ack(info) => CommandOutcome::Acked {
                info,
                sends: 1,
                rtt_ms: 3,
            },
            Reply::Nack(reason) => CommandOutcome::Nacked { reason, sends: 1 },
        };
        app.update(Action::Link(LinkEvent::CommandDone {
            id,
            command,
            outcome,
        }));
        done.push((command, reply));
    }
    done
}

/// Sends `bytes` as the robot's answer to the app's `Download`, feeding its acks back.
fn serve_download(app: &mut App, now: &mut u64, bytes: &[u8]) {
    let (id, command) = app
        .take_outbox()
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
    for _ in 0..500 {
        *now += 5;
        let mut frames = Vec::new();
        s.poll(*now as u32, bytes, |m| {
            frames.push(match *m {
                Message::TransferBegin(b) => TransferIn::Begin(b),
                Message::TransferData(c) => TransferIn::Chunk {
                    tag: c.tag,
                    offset: c.offset,
                    data: c.data.to_vec(),
                },
                Message::TransferAck(a) => TransferIn::Ack(a),
                ref other => panic!("not a transfer frame: {other:?}"),
            });
            true
        });
        for f in frames {
            app.update(Action::Link(LinkEvent::Transfer(f)));
        }
        for f in app.transfers.take_frames() {
            if let TransferOut::Ack(a) = f {
                s.on_ack(&a, *now as u32);
            }
        }
        app.update(Action::Tick { now_ms: *now });
        if s.is_done() {
            return;
        }
    }
    panic!("the download never ended: {:?}", s.outcome());
}

fn run_until_arrived(sim: &mut emulator::sim::Sim) -> bool {
    for _ in 0..300_000 {
        sim.step();
        if sim.robot().arrived() {
            return true;
        }
    }
    false
}

fn last_log(app: &App) -> String {
    app.log.window(1).last().unwrap().text.clone()
}

#[test]
fn after_exploring_o_plans_on_the_robot_x_executes_and_p_plans_to_the_goal_found() {
    let a = arena();
    let target = *a.target().unwrap();
    let mut sim = emulator::sim::Sim::new(
        a,
        emulator::sim::SimConfig::new(&robot_firmware::MICRO_RATO),
    )
    .unwrap();
    let mut app = app();
    let mut now = 1_000;

    // `E`, then the robot explores until it reports the goal reached.
    app.update(key(&app, 'E'));
    let done = deliver(&mut app, &mut sim);
    assert!(
        matches!(done[..], [(Command::StartExploration, Reply::Ack(_))]),
        "{done:?}"
    );
    assert!(
        run_until_arrived(&mut sim),
        "exploration reached the goal area"
    );

    // `M`: the robot's map, shown.
    telemetry(&mut app, &sim, Mode::Idle);
    app.update(key(&app, 'M'));
    app.update(Action::Tick { now_ms: now });
    let mut map = vec![0; MAP_OBJECT_MAX];
    let n = sim.robot().objects().map_object(&mut map).unwrap();
    map.truncate(n);
    serve_download(&mut app, &mut now, &map);
    let shown = app.map.plan.map().unwrap();
    assert_eq!(shown.source, "robot map");
    let goal = shown.goal.unwrap().centre;
    let off = (goal.0 - target.centre.x).hypot(goal.1 - target.centre.y);
    println!(
        "the robot found the goal area at ({:.3}, {:.3}), {off:.2} m from the beacon",
        goal.0, goal.1
    );
    assert!(
        off < target.radius_m + 0.3,
        "the map's goal is where the robot found the goal area"
    );

    // `P`: the station plans on the robot's map to that goal.
    app.update(key(&app, 'P'));
    let line = last_log(&app);
    assert!(line.starts_with("planned on the station"), "{line}");
    let planned = app.map.plan.result.as_ref().unwrap().goal();
    assert!(
        (planned.0 - goal.0).abs() < 0.002 && (planned.1 - goal.1).abs() < 0.002,
        "{line}"
    );

    // `O`: Segment and Plan { from: None, to: None }; the firmware accepts both.
    app.update(key(&app, 'O'));
    let done = deliver(&mut app, &mut sim);
    let sent: Vec<Command> = done.iter().map(|(c, _)| *c).collect();
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
    for (c, r) in &done {
        assert!(matches!(r, Reply::Ack(_)), "{c:?} refused: {r:?}");
    }
    let (plan_id, _) = sim.robot().objects().plan().unwrap();
    app.update(Action::Link(LinkEvent::Robot(Event {
        code: EventCode::PlanInstalled,
        value: plan_id as i32,
    })));
    let plan = sim.robot().objects().plan_bytes().to_vec();
    now += 10;
    app.update(Action::Tick { now_ms: now });
    serve_download(&mut app, &mut now, &plan);
    assert_eq!(
        app.transfers.robot_plan.as_ref().map(|p| p.0),
        Some(plan_id)
    );

    // `X`: the firmware executes that plan and arrives.
    app.update(key(&app, 'X'));
    let done = deliver(&mut app, &mut sim);
    assert!(
        matches!(done[..], [(Command::ExecutePlan { plan_id: p }, Reply::Ack(_))] if p == plan_id),
        "{done:?}"
    );
    assert!(
        run_until_arrived(&mut sim),
        "the plan is executed to its end"
    );

    // A plan to the beacon itself (the cursor there, `O`): its cell was never seen, and the
    // refusal names the point and its cell.
    app.map.cursor_mode = true;
    app.map.cursor = (target.centre.x, target.centre.y);
    app.update(key(&app, 'O'));
    let done = deliver(&mut app, &mut sim);
    assert!(
        matches!(
            done[1],
            (Command::Plan { .. }, Reply::Nack(NackReason::BadPoint))
        ),
        "{done:?}"
    );
    let line = last_log(&app);
    println!("{line}");
    assert!(
        line.contains("point outside the map or in an obstacle"),
        "{line}"
    );
    assert!(line.contains("goal (3.000, 2.571) is in an"), "{line}");
}
