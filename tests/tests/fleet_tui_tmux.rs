//! The station driving three robots, as a person does (issue 17): `robot-emulator --robots 3
//! --link DIR/robot` and `station --port DIR/robot1 --port DIR/robot2 --port DIR/robot3` in
//! tmux. Robot 2 is picked (Tab), driven, and `!` stops every robot, each one's answer in the
//! log; and with robot 2's link cut (`--disconnect-after 2:S`), its line says so while the
//! other robots keep moving on screen.
//!
//! Skipped, with a note, where tmux is not installed.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use e2e_tests::procs::scratch_dir;
use e2e_tests::tmux::Tmux;
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(30);

fn dir(name: &str) -> PathBuf {
    scratch_dir("fleet-tmux", name)
}

fn tmux_or_skip() -> bool {
    Tmux::require(module_path!())
}

struct Emulator(Child);

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Three robots on `base`1..3; returns once every pty is there (the emulator prints one line
/// per robot).
fn emulator(base: &Path, extra: &[&str]) -> Emulator {
    let mut child = Command::new(workspace_bin("robot-emulator"))
        .args(["--robots", "3", "--seed", "5", "--link"])
        .arg(base)
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("robot-emulator starts");
    let out = child.stdout.take().unwrap();
    let mut lines = BufReader::new(out).lines();
    for _ in 0..3 {
        lines.next().expect("a pty line").unwrap();
    }
    // Keep draining its stdout so that it never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    Emulator(child)
}

fn station(name: &str, d: &Path, base: &Path) -> Tmux {
    let ports: Vec<String> = (1..=3).map(|k| format!("{}{k}", base.display())).collect();
    let mut args = Vec::new();
    for p in &ports {
        args.push("--port");
        args.push(p.as_str());
    }
    Tmux::start(name, 150, 40, d, &workspace_bin("station"), &args)
}

/// The fleet panel's line of robot `k` (1-based): the row whose glyph column reads `k`.
fn fleet_line(screen: &[String], k: usize) -> String {
    screen
        .iter()
        .find(|r| {
            // Labelled by the id the robot states ("micro-rato #2"), or by its place before.
            r.contains(&format!("{k} micro-rato #"))
                || r.contains(&format!("{k} micro-rato {k} "))
                || r.contains(&format!("{k} robot {k} "))
        })
        .cloned()
        .unwrap_or_default()
}

fn all_connected(s: &[String]) -> bool {
    (1..=3).all(|k| fleet_line(s, k).contains("link ok"))
}

#[test]
fn robot_two_is_picked_and_driven_and_stop_all_stops_every_robot() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("stop-all");
    let base = d.join("robot");
    let _emu = emulator(&base, &[]);
    let t = station("stop-all", &d, &base);
    t.wait_for("three robots connected", WAIT, all_connected);
    // Every robot busy: 1 and 3 explore, 2 is picked and driven from the keyboard.
    t.keys(&["E", "Tab", "Tab", "E", "BTab"]);
    let s = t.wait_for("robot 2 picked", WAIT, |s| {
        fleet_line(s, 2).contains("▶2") && s.iter().any(|r| r.contains("Fleet: 2 of 3"))
    });
    assert!(fleet_line(&s, 1).contains("Explore"), "{}", s.join("\n"));
    t.keys(&["w", "w"]);
    let s = t.wait_for("robot 2 driving, 1 and 3 exploring", WAIT, |s| {
        fleet_line(s, 2).contains("Manual")
            && fleet_line(s, 1).contains("Explore")
            && fleet_line(s, 3).contains("Explore")
    });
    // The header is robot 2's: its drive, its port.
    assert!(
        s[0].contains("v 100 mm/s") && s[0].contains("robot2"),
        "{}",
        s[0]
    );
    // Stop all is on screen without asking for help.
    assert!(
        s.last().unwrap().contains("STOP ALL"),
        "{}",
        s.last().unwrap()
    );
    t.keys(&["!"]);
    let s = t.wait_for("every robot stopped and acknowledged", WAIT, |s| {
        (1..=3).all(|k| fleet_line(s, k).contains("Idle"))
            && s.iter().filter(|r| r.contains("stopped (acked in")).count() == 3
    });
    assert!(
        s.iter()
            .any(|r| r.contains("stop all: Stop sent to 3 of 3 robots")),
        "{}",
        s.join("\n")
    );
    // Stopped means stopped: robot 2's wheels stay still (its keyboard drive ended too).
    std::thread::sleep(Duration::from_secs(1));
    let s = t.screen();
    assert!(
        (1..=3).all(|k| fleet_line(&s, k).contains("Idle")),
        "{}",
        s.join("\n")
    );
    assert!(
        s.iter().any(|r| r.contains("wheels 0 0 mm/s")),
        "{}",
        s.join("\n")
    );
    t.keys(&["q"]);
}

#[test]
fn a_cut_link_marks_its_robot_while_the_others_keep_updating() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("cut");
    let base = d.join("robot");
    // Robot 2's port is unplugged for good 8 s in.
    let _emu = emulator(&base, &["--disconnect-after", "2:8"]);
    let t = station("cut", &d, &base);
    t.wait_for("three robots connected", WAIT, all_connected);
    // Robot 1 (selected) and robot 3 explore.
    t.keys(&["E", "Tab", "Tab", "E", "Tab"]);
    let s = t.wait_for("robot 2's link down", WAIT, |s| {
        let two = fleet_line(s, 2);
        two.contains("link down") || two.contains("stale")
    });
    assert!(fleet_line(&s, 1).contains("link ok"), "{}", s.join("\n"));
    assert!(fleet_line(&s, 3).contains("link ok"), "{}", s.join("\n"));
    // Robot 1 keeps moving on screen: its pose line changes.
    let pose = |s: &[String]| {
        s.iter()
            .find_map(|r| {
                r.find("pose ")
                    .map(|i| r[i..].chars().take(24).collect::<String>())
            })
            .unwrap_or_default()
    };
    let before = pose(&t.screen());
    let s = t.wait_for("robot 1's pose to change", WAIT, |s| {
        let p = pose(s);
        !p.is_empty() && p != before
    });
    assert!(fleet_line(&s, 1).contains("Explore"), "{}", s.join("\n"));
    assert!(!fleet_line(&s, 1).contains("stale"), "{}", s.join("\n"));
    assert!(fleet_line(&s, 3).contains("Explore") && fleet_line(&s, 3).contains("link ok"));
    // Picking robot 2 shows why it is gone, and stop all says it cannot reach it.
    t.keys(&["Tab", "!"]);
    let s = t.wait_for("stop all's report", WAIT, |s| {
        s.iter().filter(|r| r.contains("stopped (acked in")).count() == 2
            && s.iter().any(|r| r.contains("NOT STOPPED"))
    });
    assert!(
        s.iter().any(|r| r.contains("Fleet: 2 of 3")),
        "{}",
        s.join("\n")
    );
    t.keys(&["q"]);
}

#[test]
fn the_built_in_emulator_runs_three_robots_in_one_world() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("builtin");
    let t = Tmux::start(
        "builtin",
        150,
        40,
        &d,
        &workspace_bin("station"),
        &["--robots", "3"],
    );
    let s = t.wait_for("three robots connected", WAIT, all_connected);
    // One arena for all, each robot on its own pty, each drawn on the map by its number.
    assert!(
        s.iter().any(|r| r.contains("Map — Ciber-Rato 1999")),
        "{}",
        s.join("\n")
    );
    assert!(
        s.iter().any(|r| r.contains(" 1-3 robots ")),
        "{}",
        s.join("\n")
    );
    // Robot 3's own panels after Alt-3: its pty in the header.
    t.keys(&["M-3"]);
    let s = t.wait_text("Fleet: 3 of 3", WAIT);
    assert!(fleet_line(&s, 3).contains("▶3"), "{}", s.join("\n"));
    t.keys(&["q"]);
}
