//! The station's TUI as a person uses it: the `station` binary in a tmux session, keys sent
//! with `send-keys`, the screen read with `capture-pane`. Covers what the operator reads:
//! the log (severity, repeats coalesced, filters, scrolling), stale values after link loss,
//! the map's zoom and legend, the link panel's command counts.
//!
//! Skipped, with a note, where tmux is not installed.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use e2e_tests::tmux::{columns, Tmux};
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(30);

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tui-tmux-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn tmux_or_skip() -> bool {
    Tmux::require(module_path!())
}

/// The log panel of the 150-column dashboard: its last 43 columns.
fn log_panel(screen: &[String]) -> Vec<String> {
    screen.iter().map(|r| columns(r, 106, 150)).collect()
}

fn count_rows(rows: &[String], text: &str) -> usize {
    rows.iter().filter(|r| r.contains(text)).count()
}

#[test]
fn the_log_coalesces_repeats_filters_and_the_map_zooms_with_a_legend_in_glyphs() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("tour");
    let t = Tmux::start("tour", 150, 40, &d, &workspace_bin("station"), &[]);
    t.wait_text("mode Idle", WAIT);
    // Exploring, the robot calibrates on the beacon about once a second: one line.
    t.keys(&["E"]);
    let s = t.wait_for("a beacon calibration repeated", WAIT, |s| {
        log_panel(s).iter().any(|r| r.contains("×"))
            && count_rows(&log_panel(s), "beacon calibration") == 1
    });
    // Severity reads without colour: a letter after the time.
    assert!(
        log_panel(&s)
            .iter()
            .any(|r| r.contains(" D event beacon calibration")),
        "{}",
        s.join("\n")
    );
    std::thread::sleep(Duration::from_secs(3));
    let s = t.screen();
    assert_eq!(
        count_rows(&log_panel(&s), "beacon calibration"),
        1,
        "still one line:\n{}",
        s.join("\n")
    );

    // `R` in the parameter editor: one summary line, not one per parameter. The fetch on
    // connect wrote the first such line; `R` adds exactly one more.
    let before = count_rows(&log_panel(&t.screen()), "parameters read");
    t.keys(&["p", "R"]);
    std::thread::sleep(Duration::from_secs(2));
    t.keys(&["Escape"]);
    let s = t.wait_text("parameters read", WAIT);
    assert_eq!(
        count_rows(&log_panel(&s), "parameters read"),
        before + 1,
        "{}",
        s.join("\n")
    );
    assert_eq!(
        count_rows(&log_panel(&s), "ok: param"),
        0,
        "{}",
        s.join("\n")
    );

    // L steps the minimum severity: from info up, the debug beacon line is hidden.
    t.keys(&["L"]);
    let s = t.wait_text("≥info", WAIT);
    assert_eq!(
        count_rows(&log_panel(&s), "beacon calibration"),
        0,
        "{}",
        s.join("\n")
    );
    t.keys(&["L", "L", "L"]);
    let s = t.wait_for("all severities again", WAIT, |s| {
        !s.iter().any(|r| r.contains('≥'))
    });
    assert_eq!(count_rows(&log_panel(&s), "beacon calibration"), 1);

    // `/` filters by text; `/` then Esc clears the filter.
    t.keys(&["/"]);
    t.type_text("explore");
    t.keys(&["Enter"]);
    let s = t.wait_text("/explore/", WAIT);
    let panel = log_panel(&s);
    assert!(count_rows(&panel, "ok: explore") == 1, "{}", s.join("\n"));
    assert_eq!(count_rows(&panel, "parameters read"), 0, "{}", s.join("\n"));
    t.keys(&["/", "Escape"]);
    t.wait_for("the filter cleared", WAIT, |s| {
        !s.iter().any(|r| r.contains("/explore/"))
            && count_rows(&log_panel(s), "parameters read") == before + 1
    });

    // The map: beacon and goal both readable, the legend in glyphs, zoom in and back out.
    let s = t.screen();
    assert!(
        s.iter().any(|r| r.contains("BG") || r.contains("GB")),
        "{}",
        s.join("\n")
    );
    // Exploring, the robot's map is shown: its unknown cells named beside its walls.
    let legend = s
        .iter()
        .find(|r| r.contains("└ ● "))
        .cloned()
        .unwrap_or_default();
    for mark in [
        "○ true",
        "░ unexplored",
        "█ wall",
        "◎ plan",
        "G goal",
        "B beacon",
    ] {
        assert!(legend.contains(mark), "{mark}: {}", s.join("\n"));
    }
    t.keys(&["z"]);
    t.wait_text("×1.5", WAIT);
    t.keys(&["Z"]);
    t.wait_for("the whole arena again", WAIT, |s| {
        !s.iter().any(|r| r.contains("×1.5"))
    });
    t.keys(&["q"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn at_80_by_24_page_up_stops_at_the_top_with_a_marker_and_end_follows_again() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("scroll");
    let t = Tmux::start("scroll", 80, 24, &d, &workspace_bin("station"), &[]);
    t.wait_text("mode Idle", WAIT);
    // Some news: mode changes (Wander is refused by this robot) and their answers, more than
    // the panel's four rows.
    for k in ["3", "0", "3", "0"] {
        t.keys(&[k]);
        std::thread::sleep(Duration::from_millis(300));
    }
    t.wait_for("six log entries", WAIT, |s| {
        s.iter().filter(|r| r.contains("ok: mode Idle")).count() == 2
    });
    // The log is the last 6 rows of an 80 x 24 dashboard (4 inside its border), above the
    // footer.
    let log = |s: &[String]| -> Vec<String> { s[17..23].to_vec() };
    t.keys(&["PageUp"; 12]);
    let s = t.wait_text("scrolled", WAIT);
    let rows = log(&s);
    assert!(rows[0].contains("End to follow"), "{}", s.join("\n"));
    // The oldest entry on the first row (where the link is shared, logged before the
    // handshake), and a full page under it (not one line).
    assert!(rows[1].contains("shared:"), "{}", s.join("\n"));
    assert!(
        rows[1..5]
            .iter()
            .all(|r| r.trim_matches(['│', ' ']).len() > 2),
        "a full page at the top:\n{}",
        s.join("\n")
    );
    t.keys(&["End"]);
    let s = t.wait_for("following again", WAIT, |s| {
        !s.iter().any(|r| r.contains("scrolled"))
    });
    assert!(!log(&s)[1].contains("handshaking on"), "{}", s.join("\n"));

    // The link panel's counts each follow their word.
    t.keys(&["F5"]);
    let s = t.wait_text("commands: ", WAIT);
    let row = s.iter().find(|r| r.contains("commands: ")).unwrap();
    // Idle twice, Wander refused twice by this robot (no such mode on a Dom Dinis); the
    // parameter reads of the fetch on connect are commands too, and each is answered.
    let ok: u32 = row
        .split("commands: ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(
        ok >= 2 && row.contains(" ok, 2 refused, 0 failed, 0 superseded"),
        "{}",
        s.join("\n")
    );
    t.keys(&["q"]);
    let _ = std::fs::remove_dir_all(&d);
}

/// An emulator process, killed when dropped (also when the test fails before killing it).
struct Emulator(Child);

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `robot-emulator serve --link PATH`, once the link exists.
fn emulator(link: &Path) -> Emulator {
    let _ = std::fs::remove_file(link);
    let emu = Emulator(
        Command::new(workspace_bin("robot-emulator"))
            .args(["serve", "--seed", "3", "--link"])
            .arg(link)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let end = Instant::now() + Duration::from_secs(10);
    while std::fs::metadata(link).is_err() {
        assert!(Instant::now() < end, "the emulator made no pty");
        std::thread::sleep(Duration::from_millis(5));
    }
    emu
}

#[test]
fn after_link_loss_the_header_and_the_sensors_say_their_values_are_stale() {
    if !tmux_or_skip() {
        return;
    }
    let d = dir("linkloss");
    let link = d.join("robot");
    let mut emu = emulator(&link);
    let t = Tmux::start(
        "linkloss",
        100,
        30,
        &d,
        &workspace_bin("station"),
        &["--port", &link.display().to_string()],
    );
    let s = t.wait_text("mode Idle │ 10 Hz", WAIT);
    assert!(!s.join("\n").contains("stale"), "{}", s.join("\n"));
    emu.0.kill().unwrap();
    emu.0.wait().unwrap();
    let s = t.wait_for("stale values marked", WAIT, |s| {
        s.first()
            .is_some_and(|h| h.contains("mode Idle (stale") && h.contains("10 Hz?"))
            && s.iter().any(|r| r.contains("no telemetry"))
    });
    assert!(
        s.iter()
            .any(|r| r.contains(" stale ") && r.contains("s: no telemetry")),
        "{}",
        s.join("\n")
    );
    t.keys(&["q"]);
    let _ = std::fs::remove_dir_all(&d);
}
