//! Maps, segmentation and plans across the link, through the robot's serial port: a scripted
//! station uploads and downloads objects with the protocol's own `Sender` and `Receiver`, and
//! the plan the robot makes is compared byte for byte with the one the host makes with the
//! same nav code over `Vec` storage (the "firmware and station produce identical plans" proof).
#![allow(clippy::unwrap_used, clippy::panic)]

mod scripted_station;

use protocol::object::{MapView, PlanView, RegionsView};
use protocol::transfer::{Outcome, Sender};
use protocol::*;
use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid};
use robot_firmware::transfer::{encode_map_object, map_object_crc, MAP_OBJECT_MAX};
use robot_firmware::{KHEPERA, MICRO_RATO};
use scripted_station::{host_plan, micro_rato_map, mm, picture, In, Station};

#[test]
fn the_plan_made_on_the_robot_is_byte_identical_to_the_hosts() {
    let (grid, map, start, goal) = micro_rato_map();
    let map_id = crc32c(&map);
    assert_eq!(map_object_crc(&grid, Some(start), Some(goal)), Ok(map_id));
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    assert!(st.events.contains(&Event {
        code: EventCode::MapUpdated,
        value: map_id as i32
    }));
    assert_eq!(st.command(Command::Segment), Ok(AckInfo::Done));
    // From the believed pose (0.5 m, 0.5 m) to the map's goal.
    assert_eq!(
        st.command(Command::Plan {
            from: None,
            to: None
        }),
        Ok(AckInfo::Done)
    );
    let (host_plan_obj, host_regions) = host_plan(&grid, map_id, mm(500, 500), goal);

    let (info, plan) = st.download(ObjectKind::Plan).unwrap();
    assert_eq!(plan, host_plan_obj, "robot and host plans differ");
    let plan_id = crc32c(&plan);
    assert_eq!(
        info,
        AckInfo::Object {
            object: ObjectKind::Plan,
            id: plan_id,
            len: plan.len() as u32,
            crc: plan_id
        }
    );
    assert_eq!(st.plan_event_id(), plan_id, "PlanInstalled carries the id");
    let view = PlanView::parse(&plan).unwrap();
    println!(
        "Micro-Rato'99 plan: {} regions, {} waypoints, {} bytes, id {plan_id:#010x}",
        view.nav.regions,
        view.waypoint_count(),
        plan.len()
    );
    assert_eq!(view.meta.map_id, map_id);
    assert_eq!(view.waypoint(view.waypoint_count() - 1), Some(goal));

    let (_, regions) = st.download(ObjectKind::Regions).unwrap();
    assert_eq!(regions, host_regions, "robot and host segmentations differ");
    assert_eq!(RegionsView::parse(&regions).unwrap().header.map_id, map_id);
    let (info, map_back) = st.download(ObjectKind::Map).unwrap();
    assert_eq!(map_back, map);
    assert!(matches!(info, AckInfo::Object { id, .. } if id == map_id));
    st.run(200);
    let flags = st.telemetry.unwrap().flags;
    assert_eq!(
        flags & (flags::HAS_MAP | flags::HAS_PLAN),
        flags::HAS_MAP | flags::HAS_PLAN
    );
}

#[test]
fn the_same_map_uploaded_again_is_already_held_and_nothing_more_is_sent() {
    let (_, map, _, _) = micro_rato_map();
    let mut st = Station::new(&KHEPERA);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let (outcome, sent) = st.upload(Sender::for_object(ObjectKind::Map, &map, 1).unwrap(), &map);
    assert_eq!(outcome, Outcome::AlreadyHave);
    // Only what went behind the Begin before its answer (PROTOCOL.md §8), never the object.
    assert!(
        sent <= EAGER_MAX,
        "{sent} bytes sent to a robot that held the map"
    );
    assert_eq!(st.map_bytes(), map);
}

/// The most bytes a sender puts behind its Begin before the answer (PROTOCOL.md §8).
const EAGER_MAX: usize = (protocol::transfer::MIN_WINDOW_UNITS * protocol::transfer::UNIT) as usize;

#[test]
fn an_interrupted_upload_resumes_from_the_robots_next() {
    let (_, map, _, _) = micro_rato_map();
    // A 64 x 64 map: 1060 bytes, five chunks.
    let mut big = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(64, 64)]).unwrap();
    big.fill(Cell::Free);
    let mut bytes = vec![0; MAP_OBJECT_MAX];
    let n = encode_map_object(&big, None, None, &mut bytes).unwrap();
    bytes.truncate(n);
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let mut first = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    // Chunks of the largest size, as on a line measured clean.
    first.set_chunk(224);
    // Two chunks (448 bytes) get through, then the line takes no more: the scripted line
    // delivers at once, so without a limit the whole window would land in one millisecond.
    let mut chunks = 0;
    for _ in 0..10_000 {
        if st.robot.objects().upload_progress().map_or(0, |p| p.2) >= 448 {
            break;
        }
        first.poll(st.now_ms(), &bytes, |m| {
            if matches!(m, Message::TransferData(_)) {
                if chunks == 2 {
                    return false;
                }
                chunks += 1;
            }
            st.send(m);
            true
        });
        st.run(1);
        while let Some(In::TAck(a)) = st.inbox.pop_front() {
            first.on_ack(&a, st.now_ms());
        }
    }
    assert!(st.robot.objects().upload_progress().map_or(0, |p| p.2) >= 448);
    // The station goes away mid-transfer (`first` is abandoned); the old map is still in use.
    st.inbox.clear();
    st.run(100);
    assert_eq!(st.map_bytes(), map);
    let held = st.robot.objects().upload_progress().unwrap().2;
    let (outcome, sent) = st.upload(
        Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap(),
        &bytes,
    );
    assert_eq!(outcome, Outcome::Complete);
    // Only the missing bytes, besides what went behind the Begin before its answer named the
    // resume offset (PROTOCOL.md §8).
    let missing = bytes.len() - held as usize;
    assert!(
        sent >= missing && sent <= missing + EAGER_MAX,
        "{sent} bytes sent for {missing} missing"
    );
    assert_eq!(st.map_bytes(), bytes);
}

#[test]
fn a_corrupted_object_is_a_crc_mismatch_and_the_old_map_stays() {
    let (_, map, _, _) = micro_rato_map();
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let mut other = map.clone();
    other[40] ^= 0x01;
    // The bytes changed after their CRC was taken (id and CRC of the original).
    let id = crc32c(&map) ^ 1;
    let sender = Sender::new(ObjectKind::Map, id, other.len() as u32, crc32c(&map), 2);
    assert_eq!(st.upload(sender, &other).0, Outcome::CrcMismatch);
    assert_eq!(st.map_bytes(), map);
    // A well-formed CRC over a malformed object (reserved cell code 3) is refused too.
    let mut bad = map.clone();
    bad[40] |= 0b11;
    assert_eq!(st.upload_object(ObjectKind::Map, &bad), Outcome::Rejected);
    assert_eq!(st.map_bytes(), map);
}

#[test]
fn oversize_objects_and_uploaded_regions_are_rejected_at_the_begin() {
    let mut st = Station::new(&MICRO_RATO);
    let huge = vec![0u8; MAP_OBJECT_MAX + 1];
    let (outcome, sent) = st.upload(
        Sender::for_object(ObjectKind::Map, &huge, 1).unwrap(),
        &huge,
    );
    // Refused by the Begin's answer: at most what went behind the Begin, and nothing held.
    assert_eq!(outcome, Outcome::Rejected);
    assert!(sent <= EAGER_MAX, "{sent} bytes of a refused object sent");
    assert!(!st.robot.objects().has_map());
    let small = [1u8, 2, 0, 0];
    let (outcome, sent) = st.upload(
        Sender::for_object(ObjectKind::Regions, &small, 1).unwrap(),
        &small,
    );
    assert_eq!(outcome, Outcome::Rejected);
    assert!(sent <= EAGER_MAX);
    // A 100 x 10 map is small in bytes but wider than the robot's 64 x 64 grid: it travels,
    // then is refused at install.
    let g = Grid::new(100, 10, Geometry::SEED_004, vec![0; grid_bytes(100, 10)]).unwrap();
    let mut bytes = vec![0; 2048];
    let n = encode_map_object(&g, None, None, &mut bytes).unwrap();
    assert!(st.upload_object(ObjectKind::Map, &bytes[..n]) == Outcome::Rejected);
    assert!(!st.robot.objects().has_map());
}

#[test]
fn chunks_with_an_unknown_tag_are_answered_unknown_id() {
    let mut st = Station::new(&KHEPERA);
    st.send(&Message::TransferData(TransferData {
        tag: 0xbe,
        offset: 0,
        data: &[1, 2, 3],
    }));
    st.run(5);
    assert_eq!(
        st.inbox.pop_front(),
        Some(In::TAck(TransferAck {
            tag: 0xbe,
            next: 0,
            status: TransferStatus::UnknownId,
            sack: 0,
        }))
    );
}

/// A 64 x 64 map object of mixed cells: 1060 bytes.
fn big_map() -> Vec<u8> {
    let mut big = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(64, 64)]).unwrap();
    for i in 0..64 * 64 {
        let c = [Cell::Free, Cell::Obstacle, Cell::Unknown][i % 7 % 3];
        big.set(i % 64, i / 64, c).unwrap();
    }
    let mut bytes = vec![0; MAP_OBJECT_MAX];
    let n = encode_map_object(&big, None, None, &mut bytes).unwrap();
    bytes.truncate(n);
    bytes
}

/// Sends `bytes` as a Map upload under `tag` up to (not including) byte `upto`, in 64-byte
/// chunks on a clean line; returns the answers' last `next`.
fn upload_part(st: &mut Station, tag: u8, bytes: &[u8], upto: usize) -> u32 {
    let crc = crc32c(bytes);
    st.send(&Message::TransferBegin(TransferBegin {
        object: ObjectKind::Map,
        id: crc,
        len: bytes.len() as u32,
        crc,
        tag,
    }));
    for offset in (0..upto).step_by(64) {
        st.send(&Message::TransferData(TransferData {
            tag,
            offset: offset as u32,
            data: &bytes[offset..(offset + 64).min(upto)],
        }));
    }
    st.run(5);
    let mut next = 0;
    while let Some(item) = st.inbox.pop_front() {
        if let In::TAck(a) = item {
            next = a.next;
        }
    }
    next
}

/// PROTOCOL.md §8: protocol 1's chunk (kind 8, named by id) is refused with tag 0, and the
/// upload in progress, its bytes and the map in use are as they were.
#[test]
fn a_retired_kind_8_chunk_is_refused_and_changes_nothing() {
    let map = big_map();
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(upload_part(&mut st, 3, &map, 256), 256);
    let before = st.robot.objects().upload_progress();
    st.send(&Message::TransferChunk(TransferChunk {
        id: crc32c(&map),
        offset: 256,
        data: &map[256..480],
    }));
    st.run(5);
    assert_eq!(
        st.inbox.pop_front(),
        Some(In::TAck(TransferAck {
            tag: 0,
            next: 0,
            status: TransferStatus::Rejected,
            sack: 0,
        }))
    );
    assert_eq!(st.robot.objects().upload_progress(), before);
    assert!(!st.robot.objects().has_map());
    // The transfer goes on under its tag.
    assert_eq!(
        upload_part(&mut st, 3, &map, map.len()),
        map.len() as u32,
        "resumed and completed"
    );
    assert_eq!(st.map_bytes(), map);
}

/// PROTOCOL.md §8 "Tags": after a handshake a chunk under the old session's tag lands
/// nowhere (`UnknownId`); a Begin of the new session resumes the bytes held.
#[test]
fn a_new_session_forgets_the_tag_and_a_new_begin_resumes() {
    let map = big_map();
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(upload_part(&mut st, 3, &map, 320), 320);
    st.handshake(8);
    st.inbox.clear();
    st.send(&Message::TransferData(TransferData {
        tag: 3,
        offset: 320,
        data: &map[320..384],
    }));
    st.run(5);
    let a = st.inbox.iter().find_map(|i| match i {
        In::TAck(a) => Some(*a),
        _ => None,
    });
    assert_eq!(
        a.map(|a| (a.tag, a.status)),
        Some((3, TransferStatus::UnknownId))
    );
    assert_eq!(st.robot.objects().upload_progress().map(|p| p.2), Some(320));
    st.inbox.clear();
    assert_eq!(
        upload_part(&mut st, 4, &map, 0),
        320,
        "the new Begin resumes at 320"
    );
    let crc = crc32c(&map);
    for offset in (320..map.len()).step_by(64) {
        st.send(&Message::TransferData(TransferData {
            tag: 4,
            offset: offset as u32,
            data: &map[offset..(offset + 64).min(map.len())],
        }));
    }
    st.run(5);
    assert_eq!(st.map_bytes(), map);
    assert_eq!(crc32c(&st.map_bytes()), crc);
}

#[test]
fn an_upload_with_ten_percent_of_frames_lost_both_ways_completes_byte_identical() {
    let (grid, map, _, goal) = micro_rato_map();
    let (plan, _) = host_plan(&grid, crc32c(&map), mm(450, 450), goal);
    let mut lost = 0;
    for seed in 1..=20u32 {
        let mut st = Station::new(&MICRO_RATO);
        st.rng = seed.wrapping_mul(0x9E37_79B9) | 1;
        st.drop = 0.10;
        // A full 64 x 64 map of random cells (five chunks), then the arena, planned on.
        let mut big = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(64, 64)]).unwrap();
        for i in 0..64 * 64 {
            let c = [Cell::Free, Cell::Obstacle, Cell::Unknown][(i * seed as usize) % 7 % 3];
            big.set(i % 64, i / 64, c).unwrap();
        }
        let mut bytes = vec![0; MAP_OBJECT_MAX];
        let n = encode_map_object(&big, None, None, &mut bytes).unwrap();
        assert_eq!(
            st.upload_object(ObjectKind::Map, &bytes[..n]),
            Outcome::Complete
        );
        assert_eq!(st.map_bytes(), &bytes[..n]);
        assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
        assert_eq!(st.map_bytes(), map);
        let from = Some(mm(450, 450));
        let c = Command::Plan { from, to: None };
        assert_eq!(st.command(c), Ok(AckInfo::Done));
        assert_eq!(st.download(ObjectKind::Plan).unwrap().1, plan);
        let (_, back) = st.download(ObjectKind::Map).unwrap();
        assert_eq!(MapView::parse(&back).unwrap().cells(), &map[36..]);
        lost += st.lost;
    }
    assert!(lost > 50, "the line lost only {lost} frames");
}

#[test]
fn map_and_plan_commands_are_refused_precisely_and_change_nothing() {
    let mut st = Station::new(&MICRO_RATO);
    let none = [
        (Command::Segment, NackReason::NoMap),
        (
            Command::Plan {
                from: None,
                to: None,
            },
            NackReason::NoMap,
        ),
        (Command::ExecutePlan { plan_id: 1 }, NackReason::NoPlan),
        (Command::SetMode(Mode::ExecutePlan), NackReason::NoPlan),
    ];
    for (c, reason) in none {
        assert_eq!(st.command(c), Err(reason), "{c:?}");
    }
    for (object, reason) in [
        (ObjectKind::Map, NackReason::NoMap),
        (ObjectKind::Plan, NackReason::NoPlan),
        (ObjectKind::Regions, NackReason::NoMap),
    ] {
        let c = Command::Download { object };
        assert_eq!(st.command(c), Err(reason));
    }
    let (_, map, start, _) = micro_rato_map();
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let regions = Command::Download {
        object: ObjectKind::Regions,
    };
    assert_eq!(
        st.command(regions),
        Err(NackReason::BadState),
        "not segmented yet"
    );
    let plan_to = |x, y| Command::Plan {
        from: Some(start),
        to: Some(mm(x, y)),
    };
    // Cell (3, 0) is wall 1; (9000, 150) is off the map; the top right room is reachable.
    assert_eq!(st.command(plan_to(1050, 150)), Err(NackReason::BadPoint));
    assert_eq!(st.command(plan_to(9000, 150)), Err(NackReason::BadPoint));
    assert_eq!(st.command(plan_to(i32::MAX, 0)), Err(NackReason::BadPoint));
    assert!(
        !st.robot.objects().has_plan(),
        "refused plans install nothing"
    );
    assert_eq!(st.command(plan_to(4350, 4350)), Ok(AckInfo::Done));
    let id = st.plan_event_id();
    assert_eq!(
        st.command(Command::ExecutePlan { plan_id: id ^ 1 }),
        Err(NackReason::PlanIdMismatch)
    );
    assert_eq!(
        st.command(Command::SetMode(Mode::ExecutePlan)),
        Err(NackReason::BadState)
    );
    assert_eq!(st.robot.mode(), Mode::Idle);

    // Two rooms with no door: unreachable. The old plan stays installed.
    let (split, _) = picture("..#..\n..#..\n");
    let mut bytes = vec![0; 256];
    let n = encode_map_object(&split, None, None, &mut bytes).unwrap();
    assert_eq!(
        st.upload_object(ObjectKind::Map, &bytes[..n]),
        Outcome::Complete
    );
    let across = Command::Plan {
        from: Some(mm(150, 150)),
        to: Some(mm(1350, 150)),
    };
    assert_eq!(st.command(across), Err(NackReason::Unreachable));
    assert_eq!(st.robot.objects().plan().unwrap().0, id);

    // A 64 x 64 checkerboard has 2048 one-cell regions, more than the robot holds: Segment is
    // refused, and the grid planner that plans instead finds no passage (free cells touch at
    // corners only), so the plan is refused as unreachable, not for capacity.
    let mut board = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(64, 64)]).unwrap();
    for y in 0..64 {
        for x in 0..64 {
            let c = if (x + y) % 2 == 0 {
                Cell::Free
            } else {
                Cell::Obstacle
            };
            board.set(x, y, c).unwrap();
        }
    }
    let mut bytes = vec![0; MAP_OBJECT_MAX];
    let n = encode_map_object(&board, None, None, &mut bytes).unwrap();
    assert_eq!(
        st.upload_object(ObjectKind::Map, &bytes[..n]),
        Outcome::Complete
    );
    assert_eq!(
        st.command(Command::Segment),
        Err(NackReason::CapacityExceeded)
    );
    assert_eq!(st.command(across), Err(NackReason::Unreachable));

    // Cell (odd, odd) of every 2 x 2 block blocked: 3072 one-cell regions, the most a 64 x 64
    // map can have (`nav::max_regions`); the robot plans on it all the same.
    for y in 0..64 {
        for x in 0..64 {
            let c = if x % 2 == 1 && y % 2 == 1 {
                Cell::Obstacle
            } else {
                Cell::Free
            };
            board.set(x, y, c).unwrap();
        }
    }
    let n = encode_map_object(&board, None, None, &mut bytes).unwrap();
    assert_eq!(
        st.upload_object(ObjectKind::Map, &bytes[..n]),
        Outcome::Complete
    );
    assert_eq!(
        st.command(Command::Segment),
        Err(NackReason::CapacityExceeded)
    );
    let corner = Command::Plan {
        from: Some(mm(150, 150)),
        to: Some(mm(62 * 300 + 150, 61 * 300 + 150)),
    };
    assert_eq!(st.command(corner), Ok(AckInfo::Done));
    let (_, view) = st.robot.objects().plan().unwrap();
    assert_eq!(view.nav.regions, 0, "made by the grid planner");
    assert_eq!(view.waypoint_count(), 3, "along row 0, then down column 62");
}

/// Plans on the robot, starts it, and moves the believed pose onto each waypoint in turn.
fn execute_by_teleport(profile: &'static robot_firmware::Profile) {
    let (_, map, start, goal) = micro_rato_map();
    let mut st = Station::new(profile);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let set_pose = |p: PointMm| Command::SetPose {
        pose: Pose {
            x_mm: p.x_mm,
            y_mm: p.y_mm,
            heading_mrad: 0,
        },
    };
    assert_eq!(st.command(set_pose(start)), Ok(AckInfo::Done));
    assert_eq!(
        st.command(Command::Plan {
            from: None,
            to: None
        }),
        Ok(AckInfo::Done)
    );
    let id = st.plan_event_id();
    let waypoints: Vec<PointMm> = {
        let (_, view) = st.robot.objects().plan().unwrap();
        view.waypoints().collect()
    };
    assert_eq!(
        st.command(Command::ExecutePlan { plan_id: id }),
        Ok(AckInfo::Done)
    );
    st.run(200);
    assert_eq!(st.robot.mode(), Mode::ExecutePlan);
    // The start is the first region's centre here, so waypoints 0 and 1 are passed at once.
    assert_ne!(
        st.hal.motors,
        robot_firmware::MotorCommand::STOP,
        "driving to the next"
    );
    let mut legs = 0;
    while !st.robot.arrived() {
        let next = st.robot.exec().unwrap().next;
        if usize::from(next) >= waypoints.len() {
            // Past the last waypoint the micro-rato heads for the goal light until its ground
            // sensor sees the goal area (seed 004 §2): let it see it.
            st.hal.ground = true;
            st.run(200);
            continue;
        }
        assert_eq!(
            st.command(set_pose(waypoints[usize::from(next)])),
            Ok(AckInfo::Done)
        );
        st.run(200);
        assert!(st.robot.arrived() || st.robot.exec().unwrap().next > next);
        legs += 1;
        assert!(legs < waypoints.len(), "no progress");
    }
    let finished = Event {
        code: EventCode::PlanFinished,
        value: waypoints.len() as i32,
    };
    assert!(st.events.contains(&finished), "{:?}", st.events);
    assert!(st.events.iter().any(|e| e.code == EventCode::GoalReached));
    assert_eq!(st.hal.motors, robot_firmware::MotorCommand::STOP);
    assert_eq!(waypoints.last(), Some(&goal));
}

#[test]
fn a_plan_is_executed_waypoint_by_waypoint_with_guided_motion_on_the_micro_rato() {
    execute_by_teleport(&MICRO_RATO);
}

#[test]
fn a_plan_is_executed_waypoint_by_waypoint_with_the_arbiter_on_the_khepera() {
    execute_by_teleport(&KHEPERA);
}

#[test]
fn an_uploaded_plan_replaces_the_one_being_executed_which_is_aborted() {
    let (grid, map, start, goal) = micro_rato_map();
    let mut st = Station::new(&MICRO_RATO);
    assert_eq!(st.upload_object(ObjectKind::Map, &map), Outcome::Complete);
    let id = crc32c(&map);
    let (plan, _) = host_plan(&grid, id, start, goal);
    assert_eq!(st.upload_object(ObjectKind::Plan, &plan), Outcome::Complete);
    let plan_id = crc32c(&plan);
    assert_eq!(st.plan_event_id(), plan_id);
    assert_eq!(
        st.command(Command::ExecutePlan { plan_id }),
        Ok(AckInfo::Done)
    );
    st.run(100);
    assert_eq!(st.robot.mode(), Mode::ExecutePlan);
    let (other, _) = host_plan(&grid, id, mm(450, 4350), goal);
    assert_eq!(
        st.upload_object(ObjectKind::Plan, &other),
        Outcome::Complete
    );
    st.run(100);
    assert!(st.events.iter().any(|e| e.code == EventCode::PlanAborted));
    assert_eq!(st.robot.mode(), Mode::Idle);
    assert_eq!(st.hal.motors, robot_firmware::MotorCommand::STOP);
    assert_eq!(st.robot.objects().plan_bytes(), &other[..]);
    assert_eq!(
        st.command(Command::ExecutePlan { plan_id }),
        Err(NackReason::PlanIdMismatch)
    );
}

/// PROTOCOL.md §12's example map: a 6 x 4 picture (first line = top row y = 3).
const EXAMPLE: &str = "\
##.?..
......
...#..
...#..
";

/// The example's Map, Regions and Plan objects, made by the nav code.
fn example_objects() -> [(&'static str, Vec<u8>); 3] {
    let (rows, _) = picture(EXAMPLE);
    let geo = Geometry::new(300, -900, 0).unwrap();
    let grid = Grid::new(6, 4, geo, rows.into_storage()).unwrap();
    let (start, goal) = (mm(-750, 150), mm(750, 150));
    let mut map = vec![0; 256];
    let n = encode_map_object(&grid, Some(start), Some(goal), &mut map).unwrap();
    map.truncate(n);
    let (plan, regions) = host_plan(&grid, crc32c(&map), start, goal);
    [("map", map), ("regions", regions), ("plan", plan)]
}

/// The hex lines of object `name` in PROTOCOL.md (`0000: 01 00 ...`).
fn documented_object(doc: &str, name: &str) -> Option<Vec<u8>> {
    let start = doc.find(&format!("\nobject `{name}`\n"))?;
    let mut bytes = Vec::new();
    for line in doc[start + 1..].lines().skip(1) {
        let t = line.trim();
        if t.is_empty() && bytes.is_empty() {
            continue;
        }
        let Some((off, hex)) = t.split_once(": ") else {
            break;
        };
        if off.len() != 4 || usize::from_str_radix(off, 16) != Ok(bytes.len()) {
            break;
        }
        for h in hex.split_whitespace() {
            bytes.push(u8::from_str_radix(h, 16).ok()?);
        }
    }
    Some(bytes)
}

#[test]
fn protocol_md_object_examples_are_what_the_nav_code_produces() {
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../protocol/PROTOCOL.md"
    ))
    .unwrap();
    for (name, bytes) in example_objects() {
        if std::env::var_os("PRINT_OBJECTS").is_some() {
            println!(
                "object `{name}`: {} bytes, id {:#010x}\n",
                bytes.len(),
                crc32c(&bytes)
            );
            for (i, row) in bytes.chunks(16).enumerate() {
                let hex: Vec<String> = row.iter().map(|b| format!("{b:02x}")).collect();
                println!("    {:04x}: {}", i * 16, hex.join(" "));
            }
            println!("\n{:?}\n", protocol::object::parse(&bytes).unwrap());
            continue;
        }
        let documented = documented_object(&doc, name).unwrap_or_default();
        assert_eq!(documented, bytes, "PROTOCOL.md object `{name}` differs");
    }
}

/// A light network in the object's storage: neuron `i` points at `3 i` deg (angle + 90).
fn light_object() -> Vec<u8> {
    use protocol::object::{encode_light, LIGHT_NEURONS, LIGHT_OBJECT_LEN};
    let neurons = (0..LIGHT_NEURONS as u16).map(|i| {
        // A bright spot sweeping across the six front sensors as the neuron's angle grows.
        let w = core::array::from_fn(|k| {
            let d = (i as i32 / 10 - k as i32).unsigned_abs() as u16;
            5000 + 9000 * d.min(5)
        });
        (w, 300 * i)
    });
    let mut out = vec![0; LIGHT_OBJECT_LEN];
    encode_light(neurons, &mut out).unwrap();
    out
}

#[test]
fn a_light_calibration_uploads_is_used_at_once_and_downloads_byte_identical() {
    let mut st = Station::new(&KHEPERA);
    // Untrained: nothing to download, and no bearings however bright the light.
    assert_eq!(
        st.download(ObjectKind::LightCalibration).unwrap_err(),
        NackReason::BadState
    );
    st.hal.ambient = [300, 120, 90, 200, 420, 480, 500, 500];
    st.run(1200);
    assert!(!st.events.iter().any(|e| e.code == EventCode::LightBearing));

    let object = light_object();
    assert_eq!(
        st.upload_object(ObjectKind::LightCalibration, &object),
        Outcome::Complete
    );
    st.run(10);
    let installed = st
        .events
        .iter()
        .find(|e| e.code == EventCode::CalibrationInstalled)
        .expect("CalibrationInstalled event");
    assert_eq!(installed.value as u32, crc32c(&object));
    assert!(st.robot.light_cal().expect("light calibration").trained);

    st.run(1200);
    let expected = st
        .robot
        .light_cal()
        .expect("light calibration")
        .bearing(&st.hal.ambient)
        .unwrap();
    let bearing = st
        .events
        .iter()
        .rev()
        .find(|e| e.code == EventCode::LightBearing)
        .expect("the uploaded network gives bearings");
    assert_eq!(bearing.value, (expected.to_degrees() * 10.0).round() as i32);

    let (info, bytes) = st.download(ObjectKind::LightCalibration).unwrap();
    assert!(matches!(info, AckInfo::Object { len: 844, .. }));
    assert_eq!(
        bytes, object,
        "the robot sends back exactly what it was given"
    );
}

#[test]
fn a_light_calibration_upload_is_busy_while_calibrating_and_changes_nothing() {
    let mut st = Station::new(&KHEPERA);
    st.command(Command::SetMode(Mode::CalibrateLight)).unwrap();
    // Starting draws a fresh network to train: that one must survive the upload.
    let before = st.robot.light_cal().expect("light calibration").som.clone();
    let object = light_object();
    assert_eq!(
        st.upload_object(ObjectKind::LightCalibration, &object),
        Outcome::Busy
    );
    assert!(!st.robot.light_cal().expect("light calibration").trained);
    assert_eq!(st.robot.light_cal().expect("light calibration").som, before);
    assert!(!st
        .events
        .iter()
        .any(|e| e.code == EventCode::CalibrationInstalled));
    // A malformed network (an output past 180 deg) is refused after it arrives.
    st.command(Command::SetMode(Mode::Idle)).unwrap();
    let mut bad = object.clone();
    bad[16..18].copy_from_slice(&18_001u16.to_le_bytes());
    assert_eq!(
        st.upload_object(ObjectKind::LightCalibration, &bad),
        Outcome::Rejected
    );
    assert!(!st.robot.light_cal().expect("light calibration").trained);
}
