//! ALICE live in the station's TUI as a person uses it (tmux: keys in, screen out):
//! `station --profile alice` starts the built-in emulator's ALICE in `builtin:alice`; `3`
//! (Wander) sets it wandering; the map's legend counts the QT model's cells, growing from the
//! live kind-16 stream, and `T` hides and shows the layer; the sensor panel shows the
//! whiskers and photoresistors of the last situation; the arrow keys drive it (teleop is
//! executed: the mode turns Manual) and space stops it.
//!
//! Skipped, with a note, where tmux is not installed.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use e2e_tests::tmux::{row, Tmux};
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(40);

/// The legend's QT cell count, if shown.
fn cells(screen: &str) -> Option<usize> {
    let r = row(screen, " QT cells")?;
    let before = r.split(" QT cells").next()?;
    before.rsplit('•').next()?.trim().parse().ok()
}

#[test]
fn the_qt_layer_grows_live_from_a_wandering_alice_and_t_hides_it() {
    if !e2e_tests::tmux::Tmux::require(
        "the_qt_layer_grows_live_from_a_wandering_alice_and_t_hides_it",
    ) {
        return;
    }
    let d = std::env::temp_dir();
    let t = Tmux::start(
        "alice-live",
        150,
        40,
        &d,
        &workspace_bin("station"),
        &["--profile", "alice"],
    );
    let wait = |what: &str, ok: &dyn Fn(&str) -> bool| {
        t.wait_for(what, WAIT, |rows| ok(&rows.join("\n")))
            .join("\n")
    };
    let s = wait("the handshake", &|s| {
        s.contains("connected") && s.contains("Alice")
    });
    assert!(
        s.contains("ALICE test scene"),
        "builtin:alice on the map:\n{s}"
    );
    t.keys(&["3"]);
    let s = wait("wandering with a few cells", &|s| {
        s.contains("mode Wander") && cells(s).is_some_and(|n| n >= 3)
    });
    let first = cells(&s).unwrap();
    assert!(s.contains("whiskers ") && s.contains(" of 24"), "{s}");
    assert!(s.contains("situation #"), "{s}");
    let s = wait("more cells", &|s| cells(s).is_some_and(|n| n > first));
    assert!(!s.contains("no situation yet"), "{s}");
    t.keys(&["T"]);
    wait("the layer hidden", &|s| cells(s).is_none());
    t.keys(&["T"]);
    wait("the layer shown again", &|s| cells(s).is_some());
    // Teleop is executed (the robot goes Manual), space stops it.
    t.keys(&["Up"]);
    wait("driven by hand", &|s| s.contains("mode Manual"));
    t.keys(&["Space"]);
    wait("stopped", &|s| s.contains("wheels 0 0 mm/s"));
}
