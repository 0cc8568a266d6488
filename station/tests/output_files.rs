//! Output files against a hostile directory, through the real `station` binary (issue 13,
//! items 2 and 3): a symlink planted at the temporary name the station used to pick
//! (`.NAME.PID.partial`, `.NAME.tmp-PID`) is never written through, and a target that is a
//! FIFO is refused, with `--force` or without, by every command that writes a file. The
//! station's PID is known before it runs: `sh` is started first and `exec`s the station (same
//! PID) once the symlinks are in place.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::Write as _;
use std::os::unix::fs::FileTypeExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use station::record::synth::demo;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("output-files-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn station(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs the station in `cwd` after `plant(pid)` has run with the PID it will have.
fn station_with_pid(args: &[&str], cwd: &Path, plant: impl FnOnce(u32)) -> Output {
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("read go; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    plant(child.id());
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(b"go\n").unwrap();
    drop(stdin);
    child.wait_with_output().unwrap()
}

fn mkfifo(path: &Path) {
    let s = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(s.success(), "mkfifo {}", path.display());
}

fn is_fifo(path: &Path) -> bool {
    std::fs::symlink_metadata(path)
        .map(|m| m.file_type().is_fifo())
        .unwrap_or(false)
}

/// Every file name in `d`, sorted.
fn files(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_symlink_planted_at_the_old_temporary_name_of_a_plan_object_is_not_written_through() {
    let d = dir("plan-symlink");
    let victim_dir = dir("plan-victim");
    let victim = victim_dir.join("precious");
    std::fs::write(&victim, b"precious").unwrap();
    let o = station_with_pid(
        &[
            "plan",
            "--map",
            "builtin:micro-rato-99",
            "--out-object",
            "plan.obj",
        ],
        &d,
        |pid| {
            std::os::unix::fs::symlink(&victim, d.join(format!(".plan.obj.{pid}.partial")))
                .unwrap();
        },
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::read(&victim).unwrap() == b"precious",
        "the station wrote through the planted symlink"
    );
    let obj = std::fs::read(d.join("plan.obj")).unwrap();
    assert!(protocol::object::PlanView::parse(&obj).is_ok());
    assert!(
        !d.join("plan.obj").is_symlink(),
        "the object is a file of its own"
    );
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_dir_all(&victim_dir);
}

#[test]
fn a_symlink_planted_at_the_old_temporary_name_of_an_export_is_not_written_through() {
    let d = dir("export-symlink");
    let victim_dir = dir("export-victim");
    let victim = victim_dir.join("precious");
    std::fs::write(&victim, b"precious").unwrap();
    std::fs::write(d.join("demo.rec"), demo(2, 10)).unwrap();
    let o = station_with_pid(&["export", "demo.rec", "--csv", "out.csv"], &d, |pid| {
        std::os::unix::fs::symlink(&victim, d.join(format!(".out.csv.tmp-{pid}"))).unwrap();
    });
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::read(&victim).unwrap() == b"precious",
        "the station wrote through the planted symlink"
    );
    let csv = std::fs::read_to_string(d.join("out.csv")).unwrap();
    assert!(csv.lines().count() > 10, "{csv}");
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_dir_all(&victim_dir);
}

#[test]
fn a_fifo_at_an_output_path_is_refused_with_and_without_force_by_every_writer() {
    let d = dir("fifo");
    std::fs::write(d.join("demo.rec"), demo(2, 10)).unwrap();
    mkfifo(&d.join("node"));
    let port = ["--port", "/nonexistent/tty"];
    let cases: Vec<Vec<&str>> = vec![
        vec![
            "plan",
            "--map",
            "builtin:micro-rato-99",
            "--out-object",
            "node",
        ],
        vec!["export", "demo.rec", "--csv", "node"],
        vec!["export", "demo.rec", "--mcap", "node"],
        vec!["calibrate", "demo.rec", "--out", "node"],
        [&["download-map"][..], &port, &["--out", "node"]].concat(),
        [&["download-calibration"][..], &port, &["--out", "node"]].concat(),
        [&["record"][..], &port, &["--out", "node"]].concat(),
    ];
    for case in cases {
        for force in [false, true] {
            let mut args = case.clone();
            if force {
                args.push("--force");
            }
            let o = station(&args, &d);
            let e = stderr(&o) + &String::from_utf8_lossy(&o.stdout);
            assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
            assert!(
                e.contains("node is a FIFO (named pipe), not a regular file"),
                "{args:?}: {e}"
            );
            assert!(!e.contains("panicked"), "{args:?}: {e}");
            assert!(is_fifo(&d.join("node")), "{args:?} replaced the FIFO");
            assert_eq!(files(&d), ["demo.rec", "node"], "{args:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn plan_out_object_and_download_map_out_keep_an_existing_file_unless_forced() {
    let d = dir("force");
    std::fs::write(d.join("plan.obj"), b"precious").unwrap();
    let plan = [
        "plan",
        "--map",
        "builtin:micro-rato-99",
        "--out-object",
        "plan.obj",
    ];
    let o = station(&plan, &d);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("plan.obj exists; pass --force to overwrite it"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(d.join("plan.obj")).unwrap(), b"precious");
    let o = station(&[&plan[..], &["--force"]].concat(), &d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(std::fs::read(d.join("plan.obj")).unwrap(), b"precious");
    let o = station(
        &[
            "download-map",
            "--port",
            "/nonexistent/tty",
            "--out",
            "plan.obj",
        ],
        &d,
    );
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o) + &String::from_utf8_lossy(&o.stdout);
    assert!(e.contains("plan.obj exists; pass --force"), "{e}");
    assert_eq!(files(&d), ["plan.obj"]);
    let _ = std::fs::remove_dir_all(&d);
}
