//! When a task ends, the screen says so; and `X` acts only on the plan the screen names. The
//! station's TUI on its built-in emulator in tmux, keys in, screen out, as a person uses it.
//!
//! - A go-to that arrives leaves the robot Idle: the header drops the go-to's progress ("m
//!   left", "stuck ... s") instead of counting on at the end of a finished task, and the log
//!   says where the robot arrived and that it was the go-to point (not "goal reached").
//! - After `O` is refused for a chosen target, `X` does not run the robot's earlier plan (to
//!   the map's goal): the footer names the chosen target, and `X` says there is no plan to
//!   it. `G` names the goal again, and `X` then runs the goal's plan.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use e2e_tests::procs::scratch_dir;
use e2e_tests::tmux::Tmux;

/// The header row (the first), as the operator reads it.
fn header(t: &Tmux) -> String {
    t.screen().first().cloned().unwrap_or_default()
}

/// Shows the log view (full width) and waits for `what`.
fn log_shows(t: &Tmux, what: &str, secs: u64) -> String {
    t.keys(&["F6"]);
    t.wait_text(what, Duration::from_secs(secs)).join("\n")
}

fn station(name: &str) -> Option<Tmux> {
    if !Tmux::require(name) {
        return None;
    }
    let d = scratch_dir("task-end", name);
    let t = Tmux::start(name, 160, 48, &d, &e2e_tests::workspace_bin("station"), &[]);
    t.wait_text("connected: robot-firmware", Duration::from_secs(30));
    // The arena's map on the robot, so that plans and go-tos have known ground.
    t.keys(&["u"]);
    t.wait_text("upload", Duration::from_secs(5));
    t.keys(&["Enter"]);
    log_shows(&t, "showing the robot's map", 20);
    Some(t)
}

#[test]
fn a_go_to_that_arrives_leaves_the_robot_idle_and_its_progress_off_the_header() {
    let Some(t) = station("goto") else { return };
    // Half a metre up from the start, in the open.
    t.keys(&["g", "Up", "Up", "Up", "Up", "Up", "Enter"]);
    t.wait_for("the go-to's progress", Duration::from_secs(10), |s| {
        s.first()
            .is_some_and(|h| h.contains("mode GoTo") && h.contains("m left"))
    });
    let log = log_shows(&t, "the go-to point", 60);
    assert!(log.contains("arrived at ("), "{log}");
    assert!(!log.contains("goal reached"), "{log}");
    let s = t.wait_for("mode Idle in the header", Duration::from_secs(5), |s| {
        s.first().is_some_and(|h| h.contains("mode Idle"))
    });
    // Seconds later, nothing of the finished go-to comes back.
    std::thread::sleep(Duration::from_secs(3));
    let h = header(&t);
    assert!(h.contains("mode Idle"), "{h}\n{}", s.join("\n"));
    for stale in ["m left", "stuck", "no progress", "GoTo"] {
        assert!(!h.contains(stale), "the header kept {stale:?}: {h}");
    }
    t.keys(&["q"]);
}

#[test]
fn x_after_a_refused_plan_runs_nothing_and_says_there_is_no_plan_to_that_target() {
    let Some(t) = station("refused") else { return };
    // A plan to the map's goal, installed on the robot.
    t.keys(&["O"]);
    log_shows(&t, "X executes it", 20);
    // The cursor 0.6 m right of the start is in a wall: the robot refuses to plan there.
    t.keys(&[
        "g", "Right", "Right", "Right", "Right", "Right", "Right", "O",
    ]);
    let log = log_shows(&t, "refused: plan", 10);
    assert!(log.contains("chosen target (1.10, 0.50)"), "{log}");
    assert!(log.contains("plan to (1.1, 0.5)"), "the footer: {log}");
    t.keys(&["X"]);
    log_shows(&t, "X: no plan to the chosen target (1.10, 0.50)", 5);
    std::thread::sleep(Duration::from_secs(2));
    let h = header(&t);
    assert!(h.contains("mode Idle"), "X started something: {h}");
    // `G`: the map's goal again; its plan is the one installed, and X runs it.
    t.keys(&["G", "X"]);
    t.wait_for("the goal's plan running", Duration::from_secs(10), |s| {
        s.first()
            .is_some_and(|h| h.contains("mode ExecutePlan: waypoint"))
    });
    t.keys(&["Space", "q"]);
}
