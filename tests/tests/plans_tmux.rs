//! The README tour's plans and missions, as a person runs it (issue 16): the station's TUI on
//! its built-in emulator in tmux, keys in, screen out. Upload the arena, go-to somewhere, `O`
//! plans to the map's goal (not the go-to point) and says so, `X` shows the waypoint it drives
//! to, `g` + `O` chooses another target, `Esc` goes back to the goal. And `station send goto
//! 100 100` on a 5 m arena exits 1 naming the robot's bounds.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use e2e_tests::procs::{emulator_in_process, scratch_dir};
use e2e_tests::tmux::Tmux;

#[test]
fn station_send_goto_outside_the_arena_exits_1_naming_the_robots_bounds() {
    let d = scratch_dir("plans", "goto");
    let link = d.join("robot");
    let _emu = emulator_in_process(&link, &["--seed", "5"]);
    let out = std::process::Command::new(e2e_tests::workspace_bin("station"))
        .args(["send", "--port"])
        .arg(&link)
        .args(["goto", "100", "100"])
        .output()
        .expect("the station binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stderr}");
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("outside the robot's arena"), "{stderr}");
    // Micro-Rato'99 is 5 x 5 m: the robot was told so and says so.
    assert!(
        stderr.contains("x 0.00 .. 5.00 m, y 0.00 .. 5.00 m"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Shows the log view (full width: its lines are not wrapped) and waits for `what`.
fn log_shows(t: &Tmux, what: &str, secs: u64) -> String {
    t.keys(&["F6"]);
    see(t, what, secs)
}

/// Waits for `what` on the screen; fails with the screen as the operator saw it.
fn see(t: &Tmux, what: &str, secs: u64) -> String {
    t.wait_text(what, Duration::from_secs(secs)).join("\n")
}

#[test]
fn the_plan_goes_to_the_maps_goal_after_a_go_to_and_the_target_is_explicit() {
    if !e2e_tests::tmux::Tmux::require(
        "the_plan_goes_to_the_maps_goal_after_a_go_to_and_the_target_is_explicit",
    ) {
        return;
    }
    let d = scratch_dir("plans", "tour");
    let t = Tmux::start(
        "plans",
        160,
        48,
        &d,
        &e2e_tests::workspace_bin("station"),
        &[],
    );
    see(&t, "connected: robot-firmware", 30);
    // The footer names where a plan would go; the map marks it.
    let s = see(&t, "plan to goal", 5);
    assert!(s.contains('◎'), "{s}");

    // Upload the arena the station shows (the prompt suggests it).
    t.keys(&["u"]);
    see(&t, "upload", 5);
    t.keys(&["Enter"]);
    log_shows(&t, "showing the robot's map", 20);

    // Go-to half a metre up from where the robot is, then stop it there.
    t.keys(&["g", "Up", "Up", "Up", "Up", "Up", "Enter"]);
    let s = see(&t, "m left", 10);
    assert!(s.contains("mode GoTo"), "{s}");
    t.keys(&["Space"]);
    log_shows(&t, "ok: stop", 5);

    // `O` plans to the map's goal, not to the go-to point, and says so.
    t.keys(&["O"]);
    log_shows(&t, "planning on the robot to the map's goal (", 5);
    let s = log_shows(&t, "X executes it", 20);
    assert!(!s.contains("chosen target"), "{s}");

    // `X`: the header says which waypoint; nothing says finished while it drives.
    t.keys(&["X"]);
    let s = see(&t, "mode ExecutePlan: waypoint", 10);
    assert!(s.contains(" of "), "{s}");
    std::thread::sleep(Duration::from_secs(2));
    let s = t.screen().join("\n");
    if s.contains("mode ExecutePlan") {
        assert!(!s.contains("plan finished"), "finished while driving:\n{s}");
    }
    t.keys(&["Space"]);

    // `g`, move, `O`: the cursor becomes the plan's target; `Esc` goes back to the goal.
    t.keys(&["g", "Right", "Right", "O"]);
    let s = log_shows(&t, "planning on the robot to the chosen target (", 5);
    // The footer says where `O` plans now, and that `G` goes back to the goal.
    assert!(s.contains("plan to (0.7"), "{s}");
    assert!(s.contains(" G  goal "), "{s}");
    t.keys(&["Escape"]);
    log_shows(&t, "plans go to the map's goal (", 5);
    see(&t, "plan to goal", 5);
    t.keys(&["q"]);
    let _ = std::fs::remove_dir_all(&d);
}
