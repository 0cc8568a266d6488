//! SIGTERM, SIGHUP and SIGINT end the TUI as `q` does: the terminal is restored (mouse capture
//! off, alternate screen left, which a killed TUI never writes) and the process exits 0. The
//! TUI runs on a real pty with its built-in emulator.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::fs::{File, OpenOptions};
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

use emulator::pty::{Pty, ReadState};

const ENTER_ALT: &[u8] = b"\x1b[?1049h";
const LEAVE_ALT: &[u8] = b"\x1b[?1049l";
const MOUSE_OFF: &[u8] = b"\x1b[?1000l";
/// Bounds on waiting, never assertions on time.
const PATIENCE: Duration = Duration::from_secs(30);

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Reads the pty into `out` until `needle` appears after `from`, the child exits, or
/// `PATIENCE` runs out.
fn read_until(pty: &Pty, child: &mut Child, out: &mut Vec<u8>, from: usize, needle: &[u8]) {
    let end = Instant::now() + PATIENCE;
    let mut buf = [0u8; 4096];
    while Instant::now() < end {
        if out.get(from..).is_some_and(|o| find(o, needle).is_some()) {
            return;
        }
        match pty.read(&mut buf) {
            ReadState::Data(n) => out.extend_from_slice(&buf[..n]),
            _ if child.try_wait().unwrap().is_some() => return,
            _ => std::thread::sleep(Duration::from_millis(10)),
        }
    }
}

fn wait(child: &mut Child) -> ExitStatus {
    let end = Instant::now() + PATIENCE;
    while Instant::now() < end {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    panic!("the station did not stop");
}

fn stops_cleanly_on(signal: &str) {
    let pty = Pty::open(None).unwrap();
    let tty = || -> File {
        OpenOptions::new()
            .read(true)
            .write(true)
            .open(pty.slave_path())
            .unwrap()
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_station"))
        .stdin(tty())
        .stdout(tty())
        .stderr(tty())
        .spawn()
        .unwrap();
    let mut out = Vec::new();
    read_until(&pty, &mut child, &mut out, 0, ENTER_ALT);
    let Some(entered) = find(&out, ENTER_ALT) else {
        let _ = child.kill();
        panic!(
            "the TUI never started: {}",
            String::from_utf8_lossy(&out).escape_debug()
        );
    };
    let kill = Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    read_until(&pty, &mut child, &mut out, entered, b"stopped by");
    let status = wait(&mut child);
    // Whatever the pty still holds.
    read_until(&pty, &mut child, &mut out, entered, b"\n");
    let after = &out[entered..];
    let text = String::from_utf8_lossy(after);
    assert!(status.success(), "{signal}: exit {status}");
    assert!(
        find(after, LEAVE_ALT).is_some(),
        "{signal}: alternate screen not left"
    );
    assert!(
        find(after, MOUSE_OFF).is_some(),
        "{signal}: mouse capture not switched off"
    );
    assert!(
        text.contains(&format!("stopped by SIG{signal}")),
        "{signal}: {}",
        text.escape_debug()
    );
}

#[test]
fn sigterm_restores_the_terminal_and_exits_0() {
    stops_cleanly_on("TERM");
}

#[test]
fn sighup_restores_the_terminal_and_exits_0() {
    stops_cleanly_on("HUP");
}

#[test]
fn sigint_restores_the_terminal_and_exits_0() {
    stops_cleanly_on("INT");
}
