//! Twenty emulator crashes during one station session: the real `station record` binary
//! records from a `robot-emulator` process on a pty symlink; the emulator is killed (SIGKILL,
//! so it cannot clean up) and started again on the same path twenty times. The station must
//! survive every one, reconnect after every restart, keep recording, mark each outage as a
//! gap, and finish the file cleanly on Ctrl-C.
//!
//! The test moves on by what the recording says, not by sleeping: after each kill it waits
//! for the gap, after each restart for the reconnect, reading the `.partial` file the station
//! flushes every second (each wait bounded by `WAIT`, a failure, not a pace). Reconnect times
//! are printed (the recording's own timestamps against the moment each new emulator's pty
//! appeared; `-- --nocapture`): they are the figure docs/reliability.md quotes, measured, not
//! asserted (timings are figures, not test verdicts).
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use e2e_tests::procs::scratch_dir;
use e2e_tests::workspace_bin;
use station::record::{LinkState, RecordKind, Recording};

const RESTARTS: usize = 20;
/// Longest wait for the station to record a gap or a reconnect: a bound for a failure, far
/// above the second the recording takes to be flushed.
const WAIT: Duration = Duration::from_secs(20);

/// (gaps, connects) in the recording so far, read from the station's `.partial` file.
fn so_far(partial: &Path) -> (usize, usize) {
    let Ok(rec) = Recording::open(partial) else {
        return (0, 0);
    };
    let count = |state| {
        rec.records
            .iter()
            .filter(|r| r.link().is_some_and(|(s, _)| s == state))
            .count()
    };
    (count(LinkState::Closed), count(LinkState::Connected))
}

/// Waits until the recording holds at least `gaps` gaps and `connects` connects.
fn wait_for(partial: &Path, gaps: usize, connects: usize, what: &str) {
    let end = Instant::now() + WAIT;
    loop {
        let (g, c) = so_far(partial);
        if g >= gaps && c >= connects {
            return;
        }
        assert!(
            Instant::now() < end,
            "{what}: after {WAIT:?} the recording has {g} gaps and {c} connects"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn unix_ms() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

fn dir() -> PathBuf {
    scratch_dir("reconnect", "run")
}

/// Starts an emulator on `link`; returns it once the symlink points at its new pty. A killed
/// emulator leaves its symlink dangling; it is removed first, so the new one is seen even when
/// the kernel hands out the same pty number again.
// The child is handed to the caller, which kills and waits for it.
#[allow(clippy::zombie_processes)]
fn emulator(link: &Path, seed: usize) -> Child {
    let _ = std::fs::remove_file(link);
    let mut child = Command::new(workspace_bin("robot-emulator"))
        .args(["serve", "--seed", &seed.to_string(), "--link"])
        .arg(link)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("robot-emulator starts");
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        if std::fs::metadata(link).is_ok() {
            return child;
        }
        if Instant::now() >= deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("the emulator made no pty");
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn kill(mut c: Child) {
    c.kill().unwrap();
    c.wait().unwrap();
}

#[test]
fn the_station_survives_twenty_emulator_crashes_and_records_every_gap() {
    let d = dir();
    let link = d.join("robot");
    let out = d.join("crashes.rec");
    let mut emu = emulator(&link, 1);
    let mut station = Command::new(workspace_bin("station"))
        .args(["record", "--port"])
        .arg(&link)
        .arg("--out")
        .arg(&out)
        .args(["--seconds", "600"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("station starts");
    let partial = d.join("crashes.rec.partial");
    wait_for(&partial, 0, 1, "the first connect");
    // Wall-clock moments (unix ms) at which each new pty appeared.
    let mut back_at = Vec::new();
    for i in 0..RESTARTS {
        kill(emu);
        assert!(
            station.try_wait().unwrap().is_none(),
            "the station exited after crash {i}"
        );
        wait_for(&partial, i + 1, i + 1, &format!("the gap of crash {i}"));
        emu = emulator(&link, i + 2);
        back_at.push(unix_ms());
        wait_for(
            &partial,
            i + 1,
            i + 2,
            &format!("the reconnect after crash {i}"),
        );
    }
    let status = Command::new("kill")
        .args(["-INT", &station.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let output = station.wait_with_output().unwrap();
    kill(emu);
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        output.status.success(),
        "station record ended with {:?}: {err}",
        output.status
    );

    let rec = Recording::open(&out).expect("the recording was finished cleanly");
    assert!(rec.damage.is_none(), "{:?}", rec.damage);
    assert!(rec.end.is_some(), "an End record");
    let t0 = rec.meta.created_unix_ms;
    let links: Vec<(u64, LinkState)> = rec
        .records
        .iter()
        .filter_map(|r| r.link().map(|(s, _)| (r.t_us, s)))
        .collect();
    let connects: Vec<u64> = links
        .iter()
        .filter(|(_, s)| *s == LinkState::Connected)
        .map(|(t, _)| t0 + t / 1000)
        .collect();
    let gaps = links
        .iter()
        .filter(|(_, s)| *s == LinkState::Closed)
        .count();
    println!(
        "{} link records, {gaps} gaps, {} connects",
        links.len(),
        connects.len()
    );
    assert!(gaps >= RESTARTS, "a gap marker per crash: {gaps}");
    assert!(
        connects.len() > RESTARTS,
        "connected once plus after every restart: {}",
        connects.len()
    );
    // The first connect after each restart, and that robot bytes kept coming after it.
    let mut delays = Vec::new();
    for (i, &back) in back_at.iter().enumerate() {
        let next_back = back_at.get(i + 1).copied().unwrap_or(u64::MAX);
        let c = connects
            .iter()
            .copied()
            .find(|&c| c + 5 >= back)
            .unwrap_or(u64::MAX);
        assert!(
            c < next_back,
            "no reconnect between restart {i} and the next"
        );
        delays.push(c.saturating_sub(back));
        let bytes_after = rec
            .records
            .iter()
            .filter(|r| r.kind == RecordKind::FromRobot && t0 + r.t_us / 1000 >= c)
            .filter(|r| t0 + r.t_us / 1000 < next_back.min(c + 1000))
            .map(|r| r.data.len())
            .sum::<usize>();
        assert!(bytes_after > 0, "no robot bytes recorded after restart {i}");
    }
    delays.sort_unstable();
    println!(
        "reconnect after the port came back, ms: min {} median {} max {} (all: {delays:?})",
        delays[0],
        delays[delays.len() / 2],
        delays[delays.len() - 1]
    );
    let names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.ends_with(".partial")),
        "a stray partial file: {names:?}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
