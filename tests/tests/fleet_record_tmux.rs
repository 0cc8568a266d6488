//! A fleet recorded from the TUI and replayed as a fleet (issue 17): `station --robots 3` in
//! tmux, every robot exploring, `R` records all three links into one file (version 2), `R`
//! saves it; `station replay FILE --json` finds three robots in it, each with its own
//! telemetry; `station replay FILE` in tmux shows the fleet panel's three lines, every robot
//! connected, and Alt-3 picks robot 3's panels.
//!
//! Skipped, with a note, where tmux is not installed.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use e2e_tests::procs::scratch_dir;
use e2e_tests::tmux::Tmux;
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(30);

fn dir(name: &str) -> PathBuf {
    scratch_dir("fleet-record-tmux", name)
}

/// The fleet panel's line of robot `k` (1-based): the row whose glyph column reads `k`.
fn fleet_line(screen: &[String], k: usize) -> String {
    screen
        .iter()
        .find(|r| r.contains(&format!("{k} micro-rato")))
        .cloned()
        .unwrap_or_default()
}

fn all_connected(s: &[String]) -> bool {
    (1..=3).all(|k| fleet_line(s, k).contains("link ok"))
}

#[test]
fn r_records_every_robot_of_the_fleet_and_the_replay_shows_all_three() {
    if !e2e_tests::tmux::Tmux::require(
        "r_records_every_robot_of_the_fleet_and_the_replay_shows_all_three",
    ) {
        return;
    }
    let d = dir("rec");
    let station = workspace_bin("station");
    let dir = d.display().to_string();
    let t = Tmux::start(
        "rec",
        150,
        40,
        &d,
        &station,
        &["--robots", "3", "--record-dir", &dir],
    );
    t.wait_for("three robots connected", WAIT, all_connected);
    // Every robot exploring, so each one's track is its own.
    t.keys(&["E", "Tab", "E", "Tab", "E", "Tab"]);
    t.wait_for("three robots exploring", WAIT, |s| {
        (1..=3).all(|k| fleet_line(s, k).contains("Explore"))
    });
    t.keys(&["R"]);
    let s = t.wait_text("recording all 3 robots' links to", WAIT);
    assert!(
        s[0].contains("REC 3 robots"),
        "the header says what is recorded: {}",
        s[0]
    );
    // A few seconds of all three, then saved.
    std::thread::sleep(Duration::from_secs(3));
    t.keys(&["R"]);
    t.wait_text("recording saved:", WAIT);
    t.keys(&["q"]);
    let files: Vec<PathBuf> = std::fs::read_dir(&d)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "rec"))
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let file = &files[0];

    // Three robots in the file, each with its own telemetry and its own id.
    let out = Command::new(&station)
        .arg("replay")
        .arg(file)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["format_version"], 2, "{j}");
    let links = j["links"].as_array().unwrap();
    assert_eq!(links.len(), 3, "{j}");
    for l in links {
        let frames = l["summary"]["telemetry"]["frames"].as_u64().unwrap_or(0);
        assert!(frames > 10, "each robot's telemetry is in the file: {l}");
    }
    let mut ids: Vec<u64> = links
        .iter()
        .filter_map(|l| l["robot_id"].as_u64())
        .collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), 3, "{j}");

    // The replay shows the fleet: three lines, every robot connected, the picker works.
    let name = file.file_name().unwrap().to_string_lossy().into_owned();
    let r = Tmux::start("replay", 150, 40, &d, &station, &["replay", &name]);
    let s = r.wait_for("the replay's fleet panel", WAIT, |s| {
        all_connected(s) && s.iter().any(|r| r.contains("Fleet: 1 of 3"))
    });
    assert!(
        s.iter().any(|r| r.contains("holds 3 robots")),
        "{}",
        s.join("\n")
    );
    r.keys(&["M-3"]);
    let s = r.wait_text("Fleet: 3 of 3", WAIT);
    assert!(fleet_line(&s, 3).contains("▶3"), "{}", s.join("\n"));
    r.keys(&["q"]);
}
