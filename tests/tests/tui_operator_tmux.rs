//! The operator's frictions with the TUI, tried as a person at 80 x 24 in tmux: the help
//! scrolls and no key in it reaches the robot; a click on the map only places the go-to
//! cursor (its coordinates shown) until Enter; the map's scale bar, follow mode, unexplored
//! cells in a glyph of their own, the robot drawn over its start; the parameter search;
//! `R` into the recordings directory with the robot's hardware trace, retraceable.
//!
//! Fails, saying how to install it, where tmux is not installed (SKIP_TUI_TESTS=1 skips).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use e2e_tests::procs::{emulator_on, scratch_dir};
use e2e_tests::tmux::Tmux;
use e2e_tests::workspace_bin;

const WAIT: Duration = Duration::from_secs(30);

fn joined(s: &[String]) -> String {
    s.join("\n")
}

/// The sensors panel's wheel speeds line, e.g. "wheels 0 0 mm/s".
fn wheels(s: &[String]) -> String {
    s.iter()
        .find_map(|r| r.find("wheels").map(|i| r[i..].to_string()))
        .unwrap_or_default()
}

/// A left click at terminal cell (`col`, `row`), 0-based, as a terminal with mouse reporting
/// sends it (SGR 1006).
fn click(t: &Tmux, col: u16, row: u16) {
    t.type_text(&format!("\x1b[<0;{};{}M", col + 1, row + 1));
    t.type_text(&format!("\x1b[<0;{};{}m", col + 1, row + 1));
}

#[test]
fn the_help_scrolls_at_80x24_and_no_key_in_it_drives_the_robot() {
    if !Tmux::require("the_help_scrolls_at_80x24_and_no_key_in_it_drives_the_robot") {
        return;
    }
    let d = scratch_dir("operator-tmux", "help");
    let link = d.join("robot");
    let mut emu = emulator_on(&link, &["--seed", "3"]);
    let port = link.display().to_string();
    let t = Tmux::start(
        "help",
        80,
        24,
        &d,
        &workspace_bin("station"),
        &["--port", &port],
    );
    t.wait_text("mode Idle", WAIT);
    t.keys(&["?"]);
    let s = t.wait_text(" of ", WAIT);
    assert!(s.iter().any(|r| r.contains("PgUp PgDn")), "{}", joined(&s));
    assert!(
        !s.iter().any(|r| r.contains("record the link")),
        "the last key is below the fold at 24 rows:\n{}",
        joined(&s)
    );
    // The end of the help, then back: PgUp once closed the help, and the arrows after it
    // drove the robot backwards.
    t.keys(&["PageDown", "PageDown"]);
    t.wait_text("record the link", WAIT);
    t.keys(&[
        "PageUp", "Down", "Down", "Up", "Left", "w", "s", "space", "4", "g", "Enter",
    ]);
    let s = t.screen();
    assert!(s.iter().any(|r| r.contains("┌ Keys")), "{}", joined(&s));
    // q closes the help; the station goes on.
    t.keys(&["q"]);
    let s = t.wait_for("the help closed", WAIT, |s| {
        !s.iter().any(|r| r.contains("┌ Keys")) && s.iter().any(|r| r.contains("mode Idle"))
    });
    std::thread::sleep(Duration::from_millis(800));
    let s2 = t.screen();
    assert!(
        wheels(&s2).starts_with("wheels 0 0 "),
        "the robot moved: {}\n{}",
        wheels(&s2),
        joined(&s)
    );
    assert!(
        s2.iter().any(|r| r.contains("mode Idle")),
        "{}",
        joined(&s2)
    );
    t.keys(&["C-c"]);
    let _ = emu.kill();
    let _ = emu.wait();
}

#[test]
fn a_click_places_the_cursor_the_map_shows_its_scale_follows_and_names_unexplored_cells() {
    if !Tmux::require(
        "a_click_places_the_cursor_the_map_shows_its_scale_follows_and_names_unexplored_cells",
    ) {
        return;
    }
    let d = scratch_dir("operator-tmux", "map");
    let t = Tmux::start("map", 80, 24, &d, &workspace_bin("station"), &[]);
    t.wait_text("mode Idle", WAIT);
    t.keys(&["F4"]);
    let s = t.wait_text("┌ Map", WAIT);
    // A scale bar in the title row, in metres.
    let title = s.iter().find(|r| r.contains("┌ Map")).cloned().unwrap();
    assert!(title.contains('┝') && title.contains(" m "), "{title}");
    // The robot stands on its start: the robot is drawn, not the start's letter.
    let map: Vec<String> = s.iter().map(|r| r.chars().take(41).collect()).collect();
    assert!(
        map.iter().any(|r| r.contains('●')) && !map.iter().skip(2).any(|r| r.contains(" S")),
        "{}",
        joined(&s)
    );
    // A click: the cursor, its coordinates, and what Enter would do; nothing sent yet.
    click(&t, 10, 18);
    let s = t.wait_text("send the robot to (", WAIT);
    let legend = s.iter().find(|r| r.contains("● robot")).cloned().unwrap();
    assert!(legend.contains("+ ") && legend.contains(" m "), "{legend}");
    assert!(s.iter().any(|r| r.contains("mode Idle")), "{}", joined(&s));
    t.keys(&["Enter"]);
    t.wait_text("mode GoTo", WAIT);
    // Follow: the view recentres on the robot.
    t.keys(&["F"]);
    t.wait_text("⊙ follow", WAIT);
    t.keys(&["F"]);
    t.wait_for("following off", WAIT, |s| {
        !s.iter().any(|r| r.contains("⊙ follow"))
    });
    // Exploring: the robot's map, its unknown cells a shade (not a wall's block), named.
    t.keys(&["Z", "Z", "E"]);
    let s = t.wait_text("░ unexplored", WAIT);
    assert!(
        s.iter().skip(2).take(20).any(|r| r.contains("░")),
        "{}",
        joined(&s)
    );
    t.keys(&["q"]);
}

#[test]
fn the_parameter_search_filters_names_and_descriptions_as_you_type() {
    if !Tmux::require("the_parameter_search_filters_names_and_descriptions_as_you_type") {
        return;
    }
    let d = scratch_dir("operator-tmux", "params");
    let t = Tmux::start("params", 80, 24, &d, &workspace_bin("station"), &[]);
    t.wait_text("mode Idle", WAIT);
    t.keys(&["p"]);
    t.wait_text("failsafe_ms", WAIT);
    t.keys(&["/"]);
    t.type_text("wheel");
    let s = t.wait_text("/ wheel", WAIT);
    assert!(
        s.iter().any(|r| r.contains("odo_wheel_distance_mm")),
        "{}",
        joined(&s)
    );
    assert!(
        !s.iter().any(|r| r.contains("failsafe_ms")),
        "{}",
        joined(&s)
    );
    // Letters in the box are text: `q` did not quit, `w` did not drive.
    t.type_text("q");
    let s = t.wait_text("no parameter matches", WAIT);
    assert!(wheels(&s).is_empty() || wheels(&s).starts_with("wheels 0 0"));
    t.keys(&["BSpace", "Enter", "Escape"]);
    t.wait_text("failsafe_ms", WAIT);
    t.keys(&["q"]);
}

#[test]
fn r_records_into_the_record_dir_with_the_hardware_trace_and_puts_it_back() {
    if !Tmux::require("r_records_into_the_record_dir_with_the_hardware_trace_and_puts_it_back") {
        return;
    }
    let d = scratch_dir("operator-tmux", "record");
    let link = d.join("robot");
    let mut emu = emulator_on(&link, &["--seed", "3"]);
    let port = link.display().to_string();
    let recs = d.join("data").join("recordings");
    let recs_arg = recs.display().to_string();
    let station = workspace_bin("station");
    let t = Tmux::start(
        "record",
        80,
        24,
        &d,
        &station,
        &[
            "--port",
            &port,
            "--record-dir",
            &recs_arg,
            "--record-hal-trace",
        ],
    );
    t.wait_text("mode Idle", WAIT);
    t.keys(&["F6", "R"]);
    // The log says where, in full (wrapped over its rows).
    let want = format!("recordingto{}", recs.join("station-").display());
    t.wait_for("the recording's path in the log", WAIT, |s| {
        flat(s).contains(&want)
    });
    t.wait_text("param set hal_trace 1", WAIT);
    std::thread::sleep(Duration::from_secs(2));
    t.keys(&["R"]);
    t.wait_text("recording saved", WAIT);
    t.wait_text("param set hal_trace 0", WAIT);
    t.keys(&["q"]);
    t.wait_for("the station quit", WAIT, |s| {
        !s.iter().any(|r| r.contains("mode Idle"))
    });
    assert_private(&recs);
    let files: Vec<_> = std::fs::read_dir(&recs)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    assert!(
        !std::fs::read_dir(&d)
            .unwrap()
            .filter_map(|e| e.ok())
            .any(|e| e.path().extension().is_some_and(|x| x == "rec")),
        "nothing recorded into the current directory"
    );
    // The recording holds the trace: retrace re-runs it (not bit for bit: the trace began
    // after power-up, and it says so).
    let out = Command::new(&station)
        .arg("retrace")
        .arg(&files[0])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("retraced"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("began after power-up"), "{text}");
    // hal_trace is off again on the robot.
    let out = Command::new(&station)
        .args(["params", "--port", &port, "get", "hal_trace"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("hal_trace = 0"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = emu.kill();
    let _ = emu.wait();
}

/// The screen's text without its borders and blanks, so that a wrapped line reads whole.
fn flat(s: &[String]) -> String {
    s.iter()
        .map(|r| r.trim_matches(|c| c == '│' || c == ' '))
        .collect::<String>()
        .replace(' ', "")
}

/// `dir` is readable by its owner alone.
fn assert_private(dir: &Path) {
    use std::os::unix::fs::PermissionsExt as _;
    let mode = std::fs::metadata(dir).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o700, "{}", dir.display());
}
