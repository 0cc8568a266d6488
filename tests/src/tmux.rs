//! The station's TUI as a person uses it: a program in a detached tmux session, keys sent
//! with `send-keys`, the screen read with `capture-pane`.
//!
//! Each session has a name unique to the test process and is killed when dropped. tmux is a
//! requirement of these tests, not an option: without it they fail, saying so.
// A test helper's failure is the test's failure: it panics with the screen it saw.
#![allow(clippy::panic)]

use std::process::Command;
use std::time::{Duration, Instant};

/// A program running in a detached tmux session.
pub struct Tmux {
    name: String,
}

fn tmux(args: &[&str]) -> std::process::Output {
    Command::new("tmux")
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("tmux {args:?}: {e} (these tests need tmux installed)"))
}

impl Tmux {
    /// Starts `command` (a shell command line) in a `width` x `height` session.
    pub fn start(tag: &str, width: u16, height: u16, command: &str) -> Tmux {
        let name = format!("e2e-{}-{tag}", std::process::id());
        let _ = tmux(&["kill-session", "-t", &name]);
        let (w, h) = (width.to_string(), height.to_string());
        let o = tmux(&[
            "new-session",
            "-d",
            "-s",
            &name,
            "-x",
            &w,
            "-y",
            &h,
            command,
        ]);
        assert!(
            o.status.success(),
            "tmux new-session: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        // Keep the pane after the program exits, so a crash's last screen can be read.
        let _ = tmux(&["set-option", "-t", &name, "remain-on-exit", "on"]);
        Tmux { name }
    }

    /// Sends keys as tmux names them (`p`, `Enter`, `Escape`, `+`).
    pub fn keys(&self, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", self.name.as_str()];
        args.extend_from_slice(keys);
        let o = tmux(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }

    /// The screen as text, one line per row.
    pub fn screen(&self) -> String {
        String::from_utf8_lossy(&tmux(&["capture-pane", "-p", "-t", &self.name]).stdout)
            .into_owned()
    }

    /// Waits until `ok` holds for the screen; panics with the last screen after `within`.
    pub fn wait_for(&self, what: &str, within: Duration, ok: impl Fn(&str) -> bool) -> String {
        let end = Instant::now() + within;
        loop {
            let s = self.screen();
            if ok(&s) {
                return s;
            }
            if Instant::now() > end {
                panic!("timed out waiting for {what}; the screen:\n{s}");
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = tmux(&["kill-session", "-t", &self.name]);
    }
}

/// The row of `screen` that contains `needle`, if any.
pub fn row<'a>(screen: &'a str, needle: &str) -> Option<&'a str> {
    screen.lines().find(|l| l.contains(needle))
}
