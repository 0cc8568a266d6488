//! Processes the end-to-end tests start the way a user does: a scratch directory, the
//! emulator on a pty (returned once the pty exists), and `station record` over it. One place,
//! so that every test waits for the pty and reports a failed start the same way.

// A test helper fails the test that called it, as a test would.
#![allow(clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::workspace_bin;

/// A fresh directory `e2e-<suite>-<name>-<pid>` under the temporary directory.
pub fn scratch_dir(suite: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("e2e-{suite}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d
}

/// `robot-emulator ARGS --link LINK`, returned once its pty is there (panics after 10 s).
/// The caller kills and waits for it.
#[allow(clippy::zombie_processes)]
pub fn emulator_on(link: &Path, args: &[&str]) -> Child {
    let _ = std::fs::remove_file(link);
    let mut child = Command::new(workspace_bin("robot-emulator"))
        .args(args)
        .arg("--link")
        .arg(link)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("robot-emulator starts");
    let deadline = Instant::now() + Duration::from_secs(10);
    while std::fs::metadata(link).is_err() {
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the emulator made no pty");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    child
}

/// `robot-emulator --link LINK ARGS` served from this process: its own command line and serve
/// options, for tests that hold it as a value (dropped: stopped).
pub fn emulator_in_process(link: &Path, args: &[&str]) -> emulator::link::RunningEmulator {
    use clap::Parser;
    let link = link.display().to_string();
    let mut argv = vec!["robot-emulator", "--link", link.as_str()];
    argv.extend_from_slice(args);
    let cli = emulator::cli::Cli::try_parse_from(argv).expect("emulator arguments");
    let opts = cli.serve.options().expect("emulator options");
    let arena = emulator::builtin::load(&opts.arena, &opts.load).expect("the arena loads");
    let sim = emulator::sim::Sim::new(arena, opts.sim.clone()).expect("the world starts");
    emulator::link::spawn_device(move || Ok(sim), opts.serve).expect("the emulator serves")
}

/// Records `seconds` of `robot-emulator EMU_ARGS` into `DIR/NAME.rec` with the real
/// `station record`, sending each of `send` once connected; returns the recording's path.
pub fn record_emulator(
    dir: &Path,
    name: &str,
    emu_args: &[&str],
    send: &[&str],
    seconds: f64,
) -> PathBuf {
    let link = dir.join(format!("{name}.pty"));
    let out = dir.join(format!("{name}.rec"));
    let mut emu = emulator_on(&link, emu_args);
    let mut cmd = Command::new(workspace_bin("station"));
    cmd.args(["record", "--port"])
        .arg(&link)
        .arg("--out")
        .arg(&out)
        .args(["--seconds", &seconds.to_string()]);
    for s in send {
        cmd.args(["--send", s]);
    }
    let status = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .expect("station record starts");
    let _ = emu.kill();
    let _ = emu.wait();
    assert!(status.success(), "station record {name}: {status}");
    out
}
