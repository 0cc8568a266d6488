//! `station params` against the emulator over a real pty, as a script would use it: list,
//! set, save, load (each change and each refusal reported), diff; a file is written through
//! the one output helper (an existing one only with --force).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use e2e_tests::procs::scratch_dir;
use e2e_tests::workspace_bin;
use emulator::link::{spawn, EmulatorOptions};

fn dir(name: &str) -> PathBuf {
    scratch_dir("params-cli", name)
}

fn params(port: &Path, args: &[&str], cwd: &Path) -> Output {
    let mut all = vec!["params", "--port", port.to_str().unwrap()];
    all.extend_from_slice(args);
    Command::new(workspace_bin("station"))
        .args(&all)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn list_set_save_load_and_diff_against_the_emulator() {
    let d = dir("tour");
    let port = d.join("robot");
    let mut opts = EmulatorOptions::builtin_default();
    opts.serve.link = Some(port.clone());
    let _emu = spawn(opts).expect("emulator starts");

    // list: every parameter, the micro-rato's missing encoders as no value.
    let o = params(&port, &["list", "--json"], &d);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), robot_firmware::params::PARAMS.len());
    let by = |name: &str| rows.iter().find(|r| r["name"] == name).unwrap().clone();
    assert_eq!(by("failsafe_ms")["value"], 300.0);
    assert!(by("odo_mm_per_pulse")["value"].is_null());
    assert_eq!(by("odo_mm_per_pulse")["min"], 0.001_f32 as f64);
    assert!(by("light_t1")["description"]
        .as_str()
        .unwrap()
        .contains("T1"));

    let o = params(&port, &["set", "failsafe_ms", "500"], &d);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        "failsafe_ms = 500 ms"
    );

    let o = params(&port, &["save", "robot.parm"], &d);
    assert!(o.status.success(), "{}", text(&o));
    let saved = std::fs::read_to_string(d.join("robot.parm")).unwrap();
    assert!(
        saved.contains("\nfailsafe_ms = 500  # ms, 50 .. 10000: "),
        "{saved}"
    );
    assert!(!saved.contains("odo_mm_per_pulse ="), "{saved}");
    // An existing file is not replaced without --force.
    let o = params(&port, &["save", "robot.parm"], &d);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("pass --force"), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(d.join("robot.parm")).unwrap(),
        saved
    );

    // The robot and its own file agree.
    let o = params(&port, &["diff", "robot.parm"], &d);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("0 differ"), "{}", text(&o));

    // Load: one change, one value unchanged, two refusals, each reported.
    std::fs::write(
        d.join("new.parm"),
        "# tuned\nfailsafe_ms = 700\navoid_threshold = 475 # same\nlight_t1 = 5000\n\
         odo_mm_per_pulse = 0.08\n",
    )
    .unwrap();
    let o = params(&port, &["load", "new.parm"], &d);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("changed failsafe_ms: 500 -> 700 ms"), "{out}");
    assert!(
        out.contains("refused light_t1 = 5000 (line 4): value out of range: 0 to 1023 counts"),
        "{out}"
    );
    assert!(
        out.contains("refused odo_mm_per_pulse = 0.08 (line 5): unsupported by this robot"),
        "{out}"
    );
    assert!(out.contains("1 changed, 1 unchanged, 2 refused"), "{out}");
    let o = params(&port, &["get", "failsafe_ms"], &d);
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        "failsafe_ms = 700 ms"
    );

    // Diff names what differs, with the file's line.
    let o = params(&port, &["diff", "robot.parm"], &d);
    let out = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(
        out.contains("failsafe_ms: file 500 (line 3), robot 700"),
        "{out}"
    );
    assert!(out.contains("1 differ"), "{out}");
}

#[test]
fn a_bad_file_is_refused_before_any_port_is_opened() {
    let d = dir("bad");
    std::fs::write(
        d.join("bad.parm"),
        "failsafe_ms = 300\n  failsafe_ms = 1e\n",
    )
    .unwrap();
    for op in ["load", "diff"] {
        let o = params(Path::new("/nonexistent/port"), &[op, "bad.parm"], &d);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(
            text(&o).contains("bad.parm:2:17: failsafe_ms: value \"1e\" is not a finite number"),
            "{}",
            text(&o)
        );
    }
}
