//! Issue 16, parameters, as a person meets them in the TUI (tmux: keys in, screen out): the
//! editor shows the robot's values as soon as it connects (it showed `?` until `R`), a value
//! in 0.001 .. 10 mm shows its digits, a parameter the robot has no hardware for says so, and
//! a rate changed with `+` reaches both the header and the editor (the header stayed at
//! 10 Hz when the rate was set elsewhere).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use e2e_tests::tmux::{row, Tmux};
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(15);

fn station(tag: &str, profile: &str) -> Tmux {
    let bin = workspace_bin("station");
    Tmux::start(
        tag,
        130,
        45,
        &std::env::temp_dir(),
        &bin,
        &["--profile", profile],
    )
}

/// Waits until `ok` holds for the whole screen as one string (rows joined by newlines).
fn wait(t: &Tmux, what: &str, ok: impl Fn(&str) -> bool) -> String {
    t.wait_for(what, WAIT, |rows| ok(&rows.join("\n")))
        .join("\n")
}

/// The value column of parameter `name`'s row.
fn value<'a>(screen: &'a str, name: &str) -> Option<&'a str> {
    let r = row(screen, &format!(" {name} "))?;
    let after = r.split_once(name)?.1;
    after.split_whitespace().next()
}

#[test]
fn the_editor_shows_the_robots_values_on_connect_and_follows_a_rate_change() {
    let t = station("params-khepera", "khepera");
    wait(&t, "the handshake", |s| s.contains("connected"));
    t.keys(&["p"]);
    // No `R`: the values arrive by themselves.
    let s = wait(&t, "the values", |s| {
        value(s, "odo_mm_per_pulse").is_some_and(|v| v != "?" && v != "…")
            && value(s, "arena_max_y_m").is_some_and(|v| v != "?" && v != "…")
    });
    assert_eq!(value(&s, "odo_mm_per_pulse"), Some("0.080"), "{s}");
    assert_eq!(value(&s, "failsafe_ms"), Some("300"), "{s}");
    assert_eq!(value(&s, "telemetry_hz"), Some("10"), "{s}");
    for p in robot_firmware::params::PARAMS.iter() {
        let v = value(&s, p.name);
        assert!(v.is_some_and(|v| v != "?"), "{} unknown:\n{s}", p.name);
    }
    // The selected parameter's description is on screen.
    assert!(s.contains("manual mode: motors stop"), "{s}");

    // The rate key, not the editor: the header and the editor both follow.
    t.keys(&["+"]);
    let s = wait(&t, "20 Hz in the header and the editor", |s| {
        s.lines().next().is_some_and(|h| h.contains("20 Hz"))
            && value(s, "telemetry_hz") == Some("20")
    });
    // And the editor, not the rate key: the header follows.
    t.keys(&["j", "Enter", "5", "Enter"]);
    wait(&t, "5 Hz in the header", |s| {
        s.lines().next().is_some_and(|h| h.contains(" 5 Hz"))
            && value(s, "telemetry_hz") == Some("5")
    });
    drop(s);
}

#[test]
fn a_parameter_the_robot_has_no_hardware_for_says_so() {
    let t = station("params-rato", "micro-rato");
    wait(&t, "the handshake", |s| s.contains("connected"));
    t.keys(&["p"]);
    let s = wait(&t, "the values", |s| {
        value(s, "failsafe_ms") == Some("300") && row(s, "odo_mm_per_pulse").is_some()
    });
    let r = row(&s, "odo_mm_per_pulse").unwrap();
    assert!(r.contains("not on this robot"), "{r}");
    assert!(!r.contains(" 0 "), "{r}");
}
