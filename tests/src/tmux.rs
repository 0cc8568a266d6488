//! Driving a TUI as a person does: in a tmux session of a fixed size, keys sent with
//! `send-keys`, the screen read back with `capture-pane`.
//!
//! Each session has its own tmux server (`-L`, a socket named after the test and process),
//! so tests run in parallel and a failing test never touches the user's tmux. The session and
//! its server end when the [`Tmux`] is dropped. Tests that need tmux call [`Tmux::require`]
//! first: without tmux they fail, unless `SKIP_TUI_TESTS=1` skips them loudly.
// A test helper: panicking, with the screen, is how it fails the test that uses it.
#![allow(clippy::panic)]

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A program running in a detached tmux session.
pub struct Tmux {
    socket: String,
}

impl Tmux {
    /// Whether a `tmux` binary can be run.
    pub fn available() -> bool {
        Command::new("tmux")
            .arg("-V")
            .output()
            .is_ok_and(|o| o.status.success())
    }

    /// For a test that drives the TUI: true when tmux is there. Without it the test fails,
    /// saying how to install it, unless `SKIP_TUI_TESTS=1` asks to skip such tests knowingly;
    /// then it says loudly that it did not run, and the caller returns. A TUI test must
    /// never pass without running.
    pub fn require(test: &str) -> bool {
        if Self::available() {
            return true;
        }
        if std::env::var_os("SKIP_TUI_TESTS").is_some_and(|v| v == "1") {
            eprintln!("SKIPPED (SKIP_TUI_TESTS=1, tmux not installed): {test} did not run");
            return false;
        }
        panic!(
            "{test} drives the TUI in tmux, which is not installed (Debian: apt-get install \
             tmux); set SKIP_TUI_TESTS=1 to skip the TUI tests knowingly"
        );
    }

    /// Starts `program args` in a `cols` x `rows` session named after `name` (unique per
    /// test), in `dir`.
    pub fn start(
        name: &str,
        cols: u16,
        rows: u16,
        dir: &Path,
        program: &Path,
        args: &[&str],
    ) -> Tmux {
        let socket = format!("e2e-{}-{name}", std::process::id());
        let t = Tmux { socket };
        let mut cmd = vec![program.display().to_string()];
        cmd.extend(args.iter().map(|a| a.to_string()));
        let o = t.tmux(&[
            "new-session",
            "-d",
            "-s",
            "main",
            "-x",
            &cols.to_string(),
            "-y",
            &rows.to_string(),
            "-c",
            &dir.display().to_string(),
            // Keep the pane after the program exits, so its last screen can be read.
            &format!("{} ; sleep 30", shell_words(&cmd)),
        ]);
        assert!(
            o.status.success(),
            "tmux new-session: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        t
    }

    fn tmux(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
            .unwrap_or_else(|e| panic!("tmux: {e}"))
    }

    /// Sends keys as tmux names them (`"p"`, `"Escape"`, `"PageUp"`, `"End"`, `"C-c"`); each
    /// is one key press.
    pub fn keys(&self, keys: &[&str]) {
        for k in keys {
            let o = self.tmux(&["send-keys", "-t", "main", k]);
            assert!(
                o.status.success(),
                "send-keys {k}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            // A person does not type faster than the TUI's tick.
            std::thread::sleep(Duration::from_millis(60));
        }
    }

    /// Types `text` literally.
    pub fn type_text(&self, text: &str) {
        let o = self.tmux(&["send-keys", "-t", "main", "-l", text]);
        assert!(o.status.success());
        std::thread::sleep(Duration::from_millis(60));
    }

    /// The screen now, one string per row.
    pub fn screen(&self) -> Vec<String> {
        let o = self.tmux(&["capture-pane", "-p", "-t", "main"]);
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .map(str::to_string)
            .collect()
    }

    /// Waits until `ok(screen)` holds; the screen then, or a panic with the last screen.
    pub fn wait_for(
        &self,
        what: &str,
        timeout: Duration,
        ok: impl Fn(&[String]) -> bool,
    ) -> Vec<String> {
        let end = Instant::now() + timeout;
        loop {
            let s = self.screen();
            if ok(&s) {
                return s;
            }
            if Instant::now() >= end {
                panic!(
                    "waited {timeout:?} for {what}; the screen:\n{}",
                    s.join("\n")
                );
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Waits until `text` is on the screen.
    pub fn wait_text(&self, text: &str, timeout: Duration) -> Vec<String> {
        self.wait_for(&format!("{text:?}"), timeout, |s| {
            s.iter().any(|l| l.contains(text))
        })
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.tmux(&["kill-server"]);
    }
}

/// `words` as one `sh` command line, each single-quoted.
fn shell_words(words: &[String]) -> String {
    words
        .iter()
        .map(|w| format!("'{}'", w.replace('\'', r"'\''")))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Columns `from..to` (characters, not bytes) of a screen row: one panel of a layout.
pub fn columns(row: &str, from: usize, to: usize) -> String {
    row.chars()
        .skip(from)
        .take(to.saturating_sub(from))
        .collect()
}

/// The first row of `screen` (rows joined by newlines) that contains `needle`.
pub fn row<'a>(screen: &'a str, needle: &str) -> Option<&'a str> {
    screen.lines().find(|l| l.contains(needle))
}
