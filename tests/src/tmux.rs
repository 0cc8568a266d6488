//! Driving a terminal program as a person does: in a private tmux server (its own socket, so
//! no user's session is touched), keys go in with `send-keys` and the screen comes out with
//! `capture-pane`. For tour tests of the station's TUI: what is asserted is what an operator
//! would read on the screen.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A program running in a detached tmux session; the server is killed on drop.
pub struct Tmux {
    socket: String,
}

impl Tmux {
    /// Whether tmux is installed (tests skip, saying so, without it).
    pub fn available() -> bool {
        Command::new("tmux")
            .arg("-V")
            .output()
            .is_ok_and(|o| o.status.success())
    }

    /// Starts `program args` in a `cols` x `rows` window. `name` makes the socket unique per
    /// test (with the process id).
    pub fn start(
        name: &str,
        cols: u16,
        rows: u16,
        program: &Path,
        args: &[&str],
    ) -> std::io::Result<Tmux> {
        let t = Tmux {
            socket: format!("e2e-{name}-{}", std::process::id()),
        };
        let (c, r) = (cols.to_string(), rows.to_string());
        let program = program.to_string_lossy().into_owned();
        // remain-on-exit keeps a crashed program's last screen for the failure message.
        let mut argv = vec![
            "start-server",
            ";",
            "set-option",
            "-g",
            "remain-on-exit",
            "on",
            ";",
            "new-session",
            "-d",
            "-x",
            &c,
            "-y",
            &r,
            "--",
            &program,
        ];
        argv.extend_from_slice(args);
        let out = t.tmux(&argv)?;
        if !out.status.success() {
            return Err(std::io::Error::other(format!(
                "tmux new-session: {}",
                String::from_utf8_lossy(&out.stderr)
            )));
        }
        Ok(t)
    }

    fn tmux(&self, args: &[&str]) -> std::io::Result<Output> {
        Command::new("tmux")
            .args(["-L", &self.socket, "-f", "/dev/null"])
            .args(args)
            .output()
    }

    /// Presses keys, by tmux's names: "g", "O", "Right", "Enter", "Escape", "Space".
    pub fn keys(&self, keys: &[&str]) {
        let mut argv = vec!["send-keys"];
        argv.extend_from_slice(keys);
        let _ = self.tmux(&argv);
    }

    /// The screen as text, one line per row.
    pub fn screen(&self) -> String {
        self.tmux(&["capture-pane", "-p"])
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
            .unwrap_or_default()
    }

    /// Waits until the screen shows `what`; returns that screen, or the last one seen.
    pub fn wait_for(&self, what: &str, within: Duration) -> Result<String, String> {
        self.wait_until(|s| s.contains(what), within)
    }

    /// Waits until `ok(screen)`; returns that screen, or the last one seen.
    pub fn wait_until(
        &self,
        ok: impl Fn(&str) -> bool,
        within: Duration,
    ) -> Result<String, String> {
        let end = Instant::now() + within;
        loop {
            let s = self.screen();
            if ok(&s) {
                return Ok(s);
            }
            if Instant::now() >= end {
                return Err(s);
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = self.tmux(&["kill-server"]);
    }
}
