//! Transfers end to end against the real robot firmware, in-process (`FirmwareSim` behind an
//! in-memory port, tokio time paused): the station's `TransferClient` uploads a map, is told
//! `AlreadyHave` the second time, downloads it back byte for byte, plans on the robot and
//! downloads the plan (identical to the station's own plan object for the same map), sees a
//! corrupted or oversize object refused with the reason, and completes byte-identical
//! transfers while the bench drops frames both ways.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use protocol::object::{MapView, PlanView};
use protocol::{crc32c, Command, ObjectKind};
use robot_firmware::nav::{grid_bytes, Cell, Geometry, Grid};
use robot_firmware::transfer::{encode_map_object, MAP_OBJECT_MAX};
use station::link::memory::memory_port;
use station::link::sim::{FirmwareSim, SimCore, SimOptions};
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions};
use station::plan::{MapOptions, NavMap, Planner};
use station::transfer::objects::{map_object, plan_object, MapObject};
use station::transfer::{JobOutcome, JobSpec, TransferClient, TransferError};

async fn bench() -> (FirmwareSim, TransferClient) {
    let (connector, peer) = memory_port();
    let sim = FirmwareSim::spawn(peer, SimCore::new(SimOptions::default()));
    let link = spawn_link(
        connector,
        LinkOptions {
            nonce_seed: Some(7),
            ..LinkOptions::default()
        },
    );
    let mut client = TransferClient::new(link, false);
    let up = client
        .wait_for(Duration::from_secs(2), |e| match e {
            LinkEvent::Connection(Connection::Connected(p)) => Some(p.clone()),
            _ => None,
        })
        .await;
    assert!(up.is_some(), "no handshake");
    (sim, client)
}

fn arena_map() -> (NavMap, MapObject) {
    let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).unwrap();
    let obj = map_object(&map).unwrap();
    (map, obj)
}

/// The robot's map as its own Map object.
fn robot_map(sim: &FirmwareSim) -> Option<Vec<u8>> {
    sim.with(|s| {
        let mut out = vec![0; MAP_OBJECT_MAX];
        let n = s.robot.objects().map_object(&mut out).ok()?;
        out.truncate(n);
        Some(out)
    })
}

/// A full 64 x 64 map (1060 bytes, five chunks) of mixed cells.
fn big_map(seed: usize) -> Vec<u8> {
    let mut g = Grid::new(64, 64, Geometry::SEED_004, vec![0; grid_bytes(64, 64)]).unwrap();
    for i in 0..64 * 64 {
        let c = [Cell::Free, Cell::Obstacle, Cell::Unknown][(i * seed) % 7 % 3];
        g.set(i % 64, i / 64, c).unwrap();
    }
    let mut bytes = vec![0; MAP_OBJECT_MAX];
    let n = encode_map_object(&g, None, None, &mut bytes).unwrap();
    bytes.truncate(n);
    bytes
}

#[tokio::test(start_paused = true)]
async fn a_map_uploads_is_already_held_the_second_time_and_downloads_back_identical() {
    let (sim, mut client) = bench().await;
    let (_, m) = arena_map();
    let mut seen = Vec::new();
    let spec = JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: m.bytes.clone(),
    };
    let r = client.run(spec, |d, t| seen.push((d, t))).await;
    println!("{}", r.text());
    assert_eq!(r.outcome, JobOutcome::Complete);
    assert_eq!((r.id, r.len), (Some(m.id), m.bytes.len() as u32));
    assert_eq!(
        seen.last(),
        Some(&(r.len, r.len)),
        "progress reaches the end"
    );
    assert_eq!(robot_map(&sim).as_deref(), Some(&m.bytes[..]));
    let again = client.upload(ObjectKind::Map, m.bytes.clone()).await;
    assert_eq!(again.outcome, JobOutcome::AlreadyHave);
    let back = client.download(ObjectKind::Map).await;
    assert_eq!(back.outcome, JobOutcome::Complete);
    assert_eq!(back.bytes.as_deref(), Some(&m.bytes[..]), "byte-identical");
    assert_eq!(
        back.id,
        Some(m.id),
        "the robot keeps the id it was uploaded under"
    );
    client.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn a_plan_made_on_the_robot_is_the_station_plan_object_byte_for_byte() {
    let (_sim, mut client) = bench().await;
    let (map, m) = arena_map();
    assert_eq!(
        client
            .upload(ObjectKind::Map, m.bytes.clone())
            .await
            .outcome,
        JobOutcome::Complete
    );
    // From where the bench robot believes it is, (0.5, 0.5), to the map's goal.
    let (id, plan) = client.plan_on_robot(None, None).await.unwrap();
    assert_eq!(id, crc32c(&plan));
    let view = PlanView::parse(&plan).unwrap();
    assert_eq!(view.meta.map_id, m.id, "the plan names the uploaded map");
    let planner = Planner::new(map).unwrap();
    let r = planner.plan(Some((0.5, 0.5)), None, false).unwrap();
    let ours = plan_object(&planner, &r, m.id).unwrap();
    assert_eq!(plan, ours, "robot and station plan objects differ");
    println!(
        "robot plan {id:#010x}: {} regions, {} waypoints, {} bytes",
        view.nav.regions,
        view.waypoint_count(),
        plan.len()
    );
    // The id is what `ExecutePlan` takes.
    let exec = client.command(Command::ExecutePlan { plan_id: id }).await;
    assert!(exec.is_ack(), "{exec:?}");
    client.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn corrupted_and_oversize_objects_fail_clearly_and_the_old_map_stays() {
    let (sim, mut client) = bench().await;
    let (_, m) = arena_map();
    client.upload(ObjectKind::Map, m.bytes.clone()).await;
    // Reserved cell code 3: its CRC is right, its layout is not.
    let mut bad = m.bytes.clone();
    bad[40] |= 0b11;
    let r = client.upload(ObjectKind::Map, bad).await;
    assert_eq!(r.outcome, JobOutcome::Failed(TransferError::Rejected));
    assert!(r.text().contains("refused the object"), "{}", r.text());
    // More than the robot's 1060 bytes: refused at the Begin, nothing more sent.
    let huge = vec![1u8; MAP_OBJECT_MAX + 1];
    let r = client.upload(ObjectKind::Map, huge).await;
    assert_eq!(r.outcome, JobOutcome::Failed(TransferError::Rejected));
    assert!(r.elapsed_ms < 100, "refused at once: {} ms", r.elapsed_ms);
    assert_eq!(robot_map(&sim).as_deref(), Some(&m.bytes[..]));
    // Regions are never taken; a plan for nothing is refused when it is not a plan.
    let r = client.upload(ObjectKind::Regions, vec![1, 2, 0, 0]).await;
    assert_eq!(r.outcome.name(), "rejected");
    let r = client.download(ObjectKind::Plan).await;
    assert_eq!(r.outcome.name(), "refused");
    assert!(r.text().contains("holds no plan"), "{}", r.text());
    client.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn transfers_complete_byte_identical_while_frames_are_dropped_both_ways() {
    let (sim, mut client) = bench().await;
    // Each millisecond, with probability 1/4 each way, the first frame to cross is lost
    // (armed for that millisecond only, so sparse telemetry and bursts of chunks alike lose
    // about a quarter of the frames that start in an armed millisecond).
    let lost = std::cell::Cell::new(0u32);
    let faults = async {
        let mut rng = 0x2545_f491_u32;
        let mut roll = move || {
            rng ^= rng << 13;
            rng ^= rng >> 17;
            rng ^= rng << 5;
            rng.is_multiple_of(4)
        };
        let mut armed = (false, false);
        loop {
            tokio::time::sleep(Duration::from_millis(1)).await;
            let next = (roll(), roll());
            sim.with(|s| {
                let f = &mut s.faults;
                // An armed drop that is gone was used on a frame.
                let used = u32::from(armed.0 && f.drop_to_robot == 0)
                    + u32::from(armed.1 && f.drop_from_robot == 0);
                lost.set(lost.get() + used);
                f.drop_to_robot = u32::from(next.0);
                f.drop_from_robot = u32::from(next.1);
            });
            armed = next;
        }
    };
    tokio::pin!(faults);
    // Six objects: faster transfers cross fewer armed milliseconds each, and the check
    // below wants the losses this test is about.
    for seed in [3usize, 5, 11, 13, 17, 19] {
        let bytes = big_map(seed);
        let up = tokio::select! {
            r = client.upload(ObjectKind::Map, bytes.clone()) => r,
            () = &mut faults => unreachable!(),
        };
        println!("lossy {}", up.text());
        assert_eq!(up.outcome, JobOutcome::Complete, "{up:?}");
        assert_eq!(robot_map(&sim).as_deref(), Some(&bytes[..]));
        let down = tokio::select! {
            r = client.download(ObjectKind::Map) => r,
            () = &mut faults => unreachable!(),
        };
        println!("lossy {} ({} frames lost so far)", down.text(), lost.get());
        assert_eq!(down.outcome, JobOutcome::Complete, "{down:?}");
        assert_eq!(down.bytes.as_deref(), Some(&bytes[..]));
        assert!(MapView::parse(down.bytes.as_deref().unwrap()).is_ok());
    }
    assert!(lost.get() >= 10, "only {} frames were lost", lost.get());
    client.shutdown().await;
}
