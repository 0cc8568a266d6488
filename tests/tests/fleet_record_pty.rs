//! Two robots, two ptys, one recording (issue 17): `robot-emulator --robots 2` numbers its
//! robots 1 and 2, and says so in every handshake and in its ground truth; `station stats`
//! reports each link with its robot's id; `station record --port A --port B` writes one file of
//! two links that `station replay --json` summarises per link and `station export` turns into
//! one CSV file and one MCAP topic prefix per robot; a robot given another's id is warned of.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command as Process, Output, Stdio};
use std::time::{Duration, Instant};

use e2e_tests::procs::scratch_dir;
use e2e_tests::{workspace_bin, Received, TestStation};
use protocol::{Heartbeat, Message};

fn dir() -> PathBuf {
    scratch_dir("fleet-record", "run")
}

struct Emulator(Child);

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn station(args: &[&str], cwd: &Path) -> Output {
    Process::new(workspace_bin("station"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn json(o: &Output) -> serde_json::Value {
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

/// The robot id in robot `k`'s handshake and in its truth frames, read by a station of the
/// tests' own (not the product's), so the wire itself is checked.
fn ids_on_the_wire(link: &Path) -> (u8, Vec<u8>) {
    let mut st = TestStation::open(link, 115_200).unwrap();
    assert!(st.handshake(Duration::from_secs(3)).is_some(), "handshake");
    let _ = st.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
    let truth: Vec<u8> = st
        .collect(Duration::from_millis(500))
        .into_iter()
        .filter_map(|(_, r)| match r {
            Received::Truth(t) => Some(t.robot_id),
            _ => None,
        })
        .collect();
    (st.last_robot_id.unwrap(), truth)
}

#[test]
fn two_robots_are_told_apart_recorded_in_one_file_and_exported_per_robot() {
    let d = dir();
    let base = d.join("robot");
    let _emu = Emulator(
        Process::new(workspace_bin("robot-emulator"))
            .args(["--robots", "2", "--seed", "5", "--link"])
            .arg(&base)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("robot-emulator starts"),
    );
    let (r1, r2) = (d.join("robot1"), d.join("robot2"));
    let until = Instant::now() + Duration::from_secs(10);
    while !(r1.exists() && r2.exists()) {
        assert!(Instant::now() < until, "the emulator made its links");
        std::thread::sleep(Duration::from_millis(50));
    }
    let (p1, p2) = (r1.to_str().unwrap(), r2.to_str().unwrap());

    // The ids on the wire: robot k is robot id k, in its HelloReply and its EmuTruth.
    for (k, link) in [(1u8, &r1), (2, &r2)] {
        let (hello, truth) = ids_on_the_wire(link);
        assert_eq!(hello, k, "robot {k}'s HelloReply");
        assert!(
            !truth.is_empty() && truth.iter().all(|&t| t == k),
            "robot {k}: {truth:?}"
        );
    }

    // `station stats` on both: each link with its robot's id, no warning.
    let o = station(
        &[
            "stats",
            "--port",
            p1,
            "--port",
            p2,
            "--seconds",
            "1",
            "--json",
        ],
        &d,
    );
    let s = json(&o);
    let ids: Vec<_> = s["links"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["peer"]["robot_id"].as_u64())
        .collect();
    assert_eq!(ids, [Some(1), Some(2)], "{s}");
    assert_eq!(s["duplicate_robot_ids"], serde_json::json!([]));

    // Both links into one file.
    let o = station(
        &[
            "record",
            "--port",
            p1,
            "--port",
            p2,
            "--out",
            "two.rec",
            "--seconds",
            "3",
            "--rate",
            "20",
            "--json",
        ],
        &d,
    );
    let r = json(&o);
    assert_eq!(r["links"][0]["robot_id"], 1, "{r}");
    assert_eq!(r["links"][1]["robot_id"], 2, "{r}");
    assert_eq!(&std::fs::read(d.join("two.rec")).unwrap()[8..10], &[2, 0]);

    // The replay summary, per link.
    let sum = json(&station(&["replay", "two.rec", "--json"], &d));
    assert_eq!(sum["format_version"], 2);
    let links = sum["links"].as_array().unwrap();
    assert_eq!(links.len(), 2, "{sum}");
    let mut frames = Vec::new();
    for (k, l) in links.iter().enumerate() {
        assert_eq!(l["robot_id"], k + 1, "{l}");
        assert_eq!(l["port"], [p1, p2][k]);
        let s = &l["summary"];
        assert_eq!(s["sessions"], 1, "{s}");
        let n = s["telemetry"]["frames"].as_u64().unwrap();
        // About 3 s at 20 Hz once the rate is set.
        assert!(n >= 30, "link {k}: {n} telemetry frames");
        // One truth frame follows each telemetry frame; the recording's time limit can fall
        // between the last two (seen on a loaded machine: 61 telemetry, 60 truth).
        let truth = s["frames_from_robot"]["EmuTruth"].as_u64().unwrap_or(0);
        assert!(
            truth == n || truth + 1 == n,
            "{n} telemetry, {truth} truth: {s}"
        );
        frames.push(n);
    }

    // Both exports: a CSV file per robot with a row per telemetry frame; MCAP topics per robot.
    let o = station(
        &[
            "export", "two.rec", "--csv", "two.csv", "--mcap", "two.mcap",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (k, n) in frames.iter().enumerate() {
        let csv = std::fs::read_to_string(d.join(format!("two.robot{}.csv", k + 1))).unwrap();
        assert_eq!(csv.lines().count() as u64 - 1, *n, "robot {}", k + 1);
    }
    assert!(!d.join("two.csv").exists());
    let mcap = std::fs::read(d.join("two.mcap")).unwrap();
    let has = |topic: &str| mcap.windows(topic.len()).any(|w| w == topic.as_bytes());
    for topic in [
        "/robot1/telemetry",
        "/robot2/telemetry",
        "/robot1/tf",
        "/robot2/truth",
    ] {
        assert!(has(topic), "{topic} in the MCAP file");
    }

    // Robot 2 told to be robot 1: the next look at both links says so.
    let o = station(&["params", "--port", p2, "set", "robot_id", "1"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = station(&["stats", "--port", p1, "--port", p2, "--seconds", "1"], &d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "robot id 1 is stated by the robots on {p1} and {p2}"
        )),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
