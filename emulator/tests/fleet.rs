//! Several robots in one world (issue 17): robot-robot collisions in the physics, IR and the
//! beacon seeing other robots, starts from the arena's start areas, determinism and a fleet
//! of one being today's single robot.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;

use emulator::arena::{Arena, ArenaFormat, Beacon, Pose, Target};
use emulator::fleet::contact::{Neighbour, RobotContacts};
use emulator::fleet::{robot_seed, Fleet, RobotSpec};
use emulator::geometry::{Aabb, Disc, Point, SegmentSet};
use emulator::physics::{Body, PhysicsParams};
use emulator::rng::SimRng;
use emulator::scenarios::contest::{run_contest, ContestOptions};
use emulator::sensors::Noise;
use emulator::sim::{Sim, SimConfig};
use emulator::world::World;
use protocol::{Command, Mode, ParamId};
use robot_firmware::{MotorCommand, KHEPERA, MICRO_RATO};

/// An empty 3 x 3 m walled box with a beacon (and its goal circle) at (2.5, 1.5).
fn open_box() -> Arena {
    let beacon = Point::new(2.5, 1.5);
    Arena {
        name: "open box".into(),
        source: PathBuf::from("test"),
        format: ArenaFormat::AsciiGrid,
        bounds: Aabb::from_corners(Point::new(0.0, 0.0), Point::new(3.0, 3.0)),
        enclosed: true,
        walls: Vec::new(),
        raster: None,
        beacons: vec![Beacon {
            position: beacon,
            height_m: 0.4,
        }],
        targets: vec![Target {
            centre: beacon,
            radius_m: 0.3,
        }],
        lights: Vec::new(),
        starts: Vec::new(),
        goal: None,
        unit_m: 0.01,
        warnings: Vec::new(),
    }
}

fn pose(x: f64, y: f64, deg: f64) -> Pose {
    Pose {
        x,
        y,
        heading: deg.to_radians(),
    }
}

fn rato_at(x: f64, y: f64, deg: f64) -> RobotSpec {
    RobotSpec {
        profile: &MICRO_RATO,
        start: Some(pose(x, y, deg)),
    }
}

fn quiet() -> SimConfig {
    SimConfig {
        noise: Noise::none(),
        seed: 5,
        ..SimConfig::new(&MICRO_RATO)
    }
}

/// Puts every robot in manual mode driving straight at `v_mm_s` (failsafe raised: no link).
fn drive(fleet: &mut Fleet, v_mm_s: &[i16]) {
    for (sim, &v) in fleet.sims_mut().iter_mut().zip(v_mm_s) {
        let core = sim.robot_mut();
        let p = core.apply(
            Command::SetParam {
                id: ParamId(0),
                value: 10_000.0,
            },
            0,
        );
        assert!(matches!(p, robot_firmware::link::Reply::Ack(_)), "{p:?}");
        core.apply(Command::SetMode(Mode::Manual), 0);
        let r = core.apply(
            Command::Teleop {
                v_mm_s: v,
                w_mrad_s: 0,
            },
            0,
        );
        assert!(matches!(r, robot_firmware::link::Reply::Ack(_)), "{r:?}");
    }
}

#[test]
fn a_body_driving_into_another_robot_stops_at_its_edge_and_counts_one_contact() {
    let params = PhysicsParams::for_profile(&KHEPERA);
    let r = params.radius_m;
    let mut body = Body::new(params, pose(0.5, 0.5, 0.0));
    let other = Neighbour {
        id: 1,
        body: Disc {
            centre: Point::new(0.7, 0.5),
            radius: r,
        },
    };
    let world = World::new(open_box(), Vec::new(), None).unwrap();
    let walls = SegmentSet::default();
    let mut contacts = RobotContacts::default();
    let mut rng = SimRng::new(1, 1);
    let mut step = |body: &mut Body, contacts: &mut RobotContacts, cmd, ms| {
        for _ in 0..ms {
            let before = body.pose();
            body.step(cmd, 0.5, &walls, 1e-3, &mut rng);
            contacts.resolve(body, Point::new(before.x, before.y), &[other], &world);
            let gap =
                (Point::new(body.pose().x, body.pose().y) - other.body.centre).norm() - 2.0 * r;
            assert!(gap >= -1e-9, "overlap {gap}");
        }
    };
    step(&mut body, &mut contacts, MotorCommand::new(10, 10), 3000);
    let x = body.pose().x;
    assert!((x - (0.7 - 2.0 * r)).abs() < 1e-6, "stopped at {x}");
    assert_eq!(contacts.collisions(), 1);
    assert_eq!(body.collisions(), 0, "no wall was touched");
    // Pushing on keeps one contact; backing off and coming again is a second.
    step(&mut body, &mut contacts, MotorCommand::new(-10, -10), 500);
    step(&mut body, &mut contacts, MotorCommand::new(10, 10), 1500);
    assert_eq!(contacts.collisions(), 2);
    // Sliding: driving at 10 degrees across its side moves along it, never into it.
    let mut slide = Body::new(params, pose(0.5, 0.45, 10.0));
    let mut c2 = RobotContacts::default();
    step(&mut slide, &mut c2, MotorCommand::new(10, 10), 4000);
    assert!(slide.pose().x > 0.7, "slid past: {:?}", slide.pose());
    assert!(
        slide.pose().y < 0.5,
        "round its near side: {:?}",
        slide.pose()
    );
    assert_eq!(c2.collisions(), 1);
}

#[test]
fn two_robots_driving_at_each_other_meet_without_overlap_and_count_robot_not_wall_contacts() {
    let robots = [rato_at(1.0, 1.5, 0.0), rato_at(2.0, 1.5, 180.0)];
    let mut fleet = Fleet::new(open_box(), &quiet(), &robots).unwrap();
    drive(&mut fleet, &[150, 150]);
    for _ in 0..6000 {
        fleet.step();
        let [a, b] = [fleet.sims()[0].disc(), fleet.sims()[1].disc()];
        assert!(a.gap(&b) >= -1e-9, "bodies overlap by {}", -a.gap(&b));
    }
    let (a, b) = (&fleet.sims()[0], &fleet.sims()[1]);
    println!(
        "a {:?} b {:?}, robot contacts {} {}, wall {} {}",
        a.truth(),
        b.truth(),
        a.robot_collisions(),
        b.robot_collisions(),
        a.collisions(),
        b.collisions()
    );
    assert!(a.disc().gap(&b.disc()) < 1e-3, "they met");
    assert_eq!((a.robot_collisions(), b.robot_collisions()), (1, 1));
    assert_eq!((a.collisions(), b.collisions()), (0, 0));
    // Each stopped short of the middle by its own radius: neither pushed the other.
    assert!(a.truth().x < 1.5 && b.truth().x > 1.5);
}

#[test]
fn the_ir_sees_another_robot_ahead_and_nothing_without_it() {
    let fw_ir = |fleet: &mut Fleet| {
        fleet.run_for(200);
        fleet.sims()[0].robot().sensors().ir
    };
    // Robot 1 faces robot 2, 12 cm between their bodies, in the middle of an empty box.
    let pair = [rato_at(1.0, 1.0, 0.0), rato_at(1.36, 1.0, 90.0)];
    let mut fleet = Fleet::new(open_box(), &quiet(), &pair).unwrap();
    let seen = fw_ir(&mut fleet);
    let mut alone = Fleet::new(open_box(), &quiet(), &pair[..1]).unwrap();
    let clear = fw_ir(&mut alone);
    println!("with robot 2 ahead {seen:?}, alone {clear:?}");
    let threshold = robot_firmware::guided::GuidedParams::default().obstacle_ir;
    // The micro-rato's middle sensor looks ahead (profile order: left, front, right).
    let front = seen.iter().copied().max().unwrap();
    assert!(
        front >= threshold / 2,
        "front IR {front} with a robot 12 cm ahead"
    );
    assert!(
        clear.iter().all(|&v| v < 20),
        "open floor reads the floor: {clear:?}"
    );
    // Driven into it: the firmware's contact threshold (its bump) fires.
    let mut fleet = Fleet::new(open_box(), &quiet(), &pair).unwrap();
    drive(&mut fleet, &[100, 0]);
    fleet.run_for(3000);
    assert_eq!(
        fleet.sims()[0].robot_collisions(),
        1,
        "it drove into robot 2"
    );
    let bump = fw_ir(&mut fleet);
    let contact = robot_firmware::explore::ExploreParams::default().contact_ir;
    assert!(
        bump.iter().any(|&v| v >= contact),
        "touching another robot reads {bump:?}, contact threshold {contact}"
    );
}

#[test]
fn a_robot_between_the_receiver_and_the_beacon_hides_it() {
    let beacon_of = |fleet: &mut Fleet| {
        fleet.run_for(300);
        fleet.sims()[0].robot().sensors().beacon.unwrap()
    };
    // Robot 1 at (1.0, 1.5) faces the beacon at (2.5, 1.5); robot 2 stands at (1.8, 1.5).
    let blocked = [rato_at(1.0, 1.5, 0.0), rato_at(1.8, 1.5, 90.0)];
    let aside = [rato_at(1.0, 1.5, 0.0), rato_at(1.8, 2.3, 90.0)];
    let b = beacon_of(&mut Fleet::new(open_box(), &quiet(), &blocked).unwrap());
    let a = beacon_of(&mut Fleet::new(open_box(), &quiet(), &aside).unwrap());
    println!("behind robot 2: {b:?}; robot 2 aside: {a:?}");
    assert_eq!(b.strength, 0, "hidden by robot 2");
    assert!(a.strength > 0, "seen when robot 2 stands aside");
}

#[test]
fn a_fleet_of_one_is_the_single_robot_bit_for_bit() {
    let arena = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let cfg = SimConfig {
        seed: 7,
        ..SimConfig::new(&MICRO_RATO)
    };
    let mut sim = Sim::new(arena.clone(), cfg.clone()).unwrap();
    let mut fleet = Fleet::new(
        arena,
        &cfg,
        &[RobotSpec {
            profile: &MICRO_RATO,
            start: None,
        }],
    )
    .unwrap();
    for s in [&mut sim, &mut fleet.sims_mut()[0]] {
        s.robot_mut().apply(Command::StartExploration, 0);
    }
    for _ in 0..20_000 {
        sim.step();
        fleet.step();
    }
    let (a, b) = (sim.truth(), fleet.sims()[0].truth());
    assert_eq!(
        (a.x.to_bits(), a.y.to_bits()),
        (b.x.to_bits(), b.y.to_bits())
    );
    assert_eq!(sim.believed(), fleet.sims()[0].believed());
}

#[test]
fn robots_start_at_the_arenas_start_areas_and_beside_them_when_there_are_too_few() {
    // Ciber 2005's grid file holds three starts: three robots take them in order.
    let opts = emulator::arena::LoadOptions::for_simulation();
    let lab = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data/arenas/ciberrato/Ciber2005_FinalLab.xml");
    if let Ok(arena) = emulator::arena::load(&lab, &opts) {
        assert_eq!(arena.starts.len(), 3);
        let robots = [RobotSpec {
            profile: &MICRO_RATO,
            start: None,
        }; 3];
        let fleet = Fleet::new(arena.clone(), &quiet(), &robots).unwrap();
        for (s, start) in fleet.sims().iter().zip(&arena.starts) {
            let t = s.truth();
            assert!((t.x - start.x).abs() < 1e-9 && (t.y - start.y).abs() < 1e-9);
        }
    }
    // Micro-Rato'99 has one start: robot 1 there, robots 2 and 3 beside it, all apart.
    let arena = emulator::builtin::micro_rato_99(&opts).unwrap();
    let robots = [RobotSpec {
        profile: &MICRO_RATO,
        start: None,
    }; 3];
    let fleet = Fleet::new(arena.clone(), &quiet(), &robots).unwrap();
    let s0 = arena.starts[0];
    let t: Vec<Pose> = fleet.sims().iter().map(Sim::truth).collect();
    assert!((t[0].x - s0.x).abs() < 1e-9 && (t[0].y - s0.y).abs() < 1e-9);
    for (i, ti) in t.iter().enumerate() {
        for j in 0..i {
            let gap = fleet.sims()[i].disc().gap(&fleet.sims()[j].disc());
            assert!(gap >= 0.1 - 1e-9, "robots {j} and {i}: {gap}");
        }
        let d = (ti.x - s0.x).hypot(ti.y - s0.y);
        assert!(d < 1.2, "robot {i} is {d} m from the start area");
    }
    // Two given poses that overlap are refused, naming both robots.
    let e = Fleet::new(
        arena,
        &quiet(),
        &[rato_at(0.5, 0.5, 0.0), rato_at(0.6, 0.5, 0.0)],
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("robots 1 and 2"), "{e}");
}

#[test]
fn the_same_seed_gives_the_same_three_robot_contest_and_each_robot_its_own_noise() {
    let arena =
        emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::for_simulation()).unwrap();
    let opts = ContestOptions {
        robots: vec![
            RobotSpec {
                profile: &MICRO_RATO,
                start: None
            };
            3
        ],
        seed: 11,
        timeout_s: 60.0,
        noise: Noise::default(),
    };
    let strip = |mut r: emulator::scenarios::contest::ContestReport| {
        r.wall_s = 0.0;
        r
    };
    let a = strip(run_contest(arena.clone(), &opts).unwrap());
    let b = strip(run_contest(arena.clone(), &opts).unwrap());
    assert_eq!(a, b);
    let seeds: Vec<u64> = a.robots.iter().map(|r| r.seed).collect();
    assert_eq!(seeds[0], 11, "robot 1 keeps the run's seed");
    assert!(seeds[1] != seeds[0] && seeds[2] != seeds[1] && seeds[2] != seeds[0]);
    assert_eq!(seeds[2], robot_seed(11, 2));
    let c = strip(run_contest(arena, &ContestOptions { seed: 12, ..opts }).unwrap());
    assert_ne!(a.robots, c.robots, "another seed, another contest");
    // The ranking is a permutation with ranks to match.
    let mut r = a.ranking.clone();
    r.sort_unstable();
    assert_eq!(r, vec![1, 2, 3]);
    for (place, &n) in a.ranking.iter().enumerate() {
        assert_eq!(a.robots[n - 1].rank, place + 1);
    }
}
