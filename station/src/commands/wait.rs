//! Waiting for the end of a task the station started (`station send --wait`), and the exit
//! codes that say how a wait ended, listed once here for `--help`, the docs and the tests.
//!
//! Layer: the binary's edge around `station_core::task_end`, which decides from the link's
//! events; this reads them off the link with the time limits and gives a code to each ending.

use std::process::ExitCode;
use std::time::Duration;

use crate::task_end::{Ended, Ending, TaskWatch};
use protocol::{Mode, Telemetry};
use tokio::time::Instant;

use crate::format::task_name;
use crate::link::RunningLink;

/// An exit code, its name and what it means.
pub struct Code {
    pub code: u8,
    pub name: &'static str,
    pub meaning: &'static str,
}

/// Every exit code of a wait, in order (`station watch` ends with `link_lost` too). 1 and 2
/// are every command's.
pub const CODES: [Code; 8] = [
    Code {
        code: 0,
        name: "arrived",
        meaning: "the go-to point, the plan's end, or the goal area (exploring) was reached",
    },
    Code {
        code: 1,
        name: "error",
        meaning: "the port, the handshake or a file failed, or the robot did not answer",
    },
    Code {
        code: 2,
        name: "usage",
        meaning: "bad arguments",
    },
    Code {
        code: 3,
        name: "refused",
        meaning: "the robot refused the command (nack); nothing started",
    },
    Code {
        code: 4,
        name: "gave_up",
        meaning: "the robot gave up: no progress for stuck_limit_s, or its plan was aborted",
    },
    Code {
        code: 5,
        name: "stopped",
        meaning: "the task ended without arriving: a stop, another mode, another station",
    },
    Code {
        code: 6,
        name: "timeout",
        meaning: "--timeout passed first; the robot goes on with its task",
    },
    Code {
        code: 7,
        name: "link_lost",
        meaning: "the port closed or the robot fell silent; its state is not known",
    },
];

/// The usage code (clap's own).
pub const USAGE: u8 = 2;

/// The exit code of `ending`.
pub fn code(ending: Ending) -> u8 {
    CODES
        .iter()
        .find(|c| c.name == ending.name())
        .map_or(1, |c| c.code)
}

/// The exit codes as a table for `--help`.
pub fn help_table() -> String {
    let mut out = String::from(
        "Exit codes with --wait (a line on stderr says how the wait ended, and why):\n",
    );
    for c in &CODES {
        out.push_str(&format!("  {}  {:<10} {}\n", c.code, c.name, c.meaning));
    }
    out
}

/// Prints a usage error as clap does, and gives its exit code.
pub fn usage(message: &str) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(USAGE)
}

/// How a wait ended.
pub struct Waited {
    pub ended: Ended,
    /// Seconds since the command started.
    pub seconds: f64,
    /// The robot's last telemetry frame since the command was acknowledged.
    pub telemetry: Option<Telemetry>,
}

impl Waited {
    /// The line on stderr: the ending's name, when, and why.
    pub fn line(&self) -> String {
        format!(
            "{} after {:.1} s: {}",
            self.ended.ending.name(),
            self.seconds,
            self.ended.reason
        )
    }

    /// The `wait` object of `--json`.
    pub fn json(&self) -> serde_json::Value {
        let m = |mm: i32| f64::from(mm) / 1000.0;
        let pose = self.telemetry.map(|t| {
            serde_json::json!({"x_m": m(t.pose.x_mm), "y_m": m(t.pose.y_mm),
                               "heading_rad": f64::from(t.pose.heading_mrad) / 1000.0})
        });
        serde_json::json!({
            "outcome": self.ended.ending.name(),
            "exit_code": code(self.ended.ending),
            "reason": self.ended.reason,
            "seconds": (self.seconds * 1000.0).round() / 1000.0,
            "pose": pose,
        })
    }

    pub fn exit_code(&self) -> ExitCode {
        ExitCode::from(code(self.ended.ending))
    }
}

/// The sooner of `deadline` and the end of a lost session's grace (`grace_us` after
/// `started`), if either is set: when a wait must look at the clock without an event.
pub fn wake_at(
    started: Instant,
    deadline: Option<Instant>,
    grace_us: Option<u64>,
) -> Option<Instant> {
    let grace = grace_us.map(|us| started + Duration::from_micros(us));
    [deadline, grace].into_iter().flatten().min()
}

/// Follows the task in `mode`, its command just acknowledged with the robot `at` the pose of
/// that telemetry frame, until it ends, the link is lost or `deadline` passes. Times count
/// from `started`.
pub async fn until_end(
    link: &mut RunningLink,
    mode: Mode,
    at: Option<Telemetry>,
    deadline: Option<Instant>,
    started: Instant,
) -> Waited {
    let mut watch = TaskWatch::new(mode, at);
    let t_us = || started.elapsed().as_micros() as u64;
    let ended = loop {
        let next = match wake_at(started, deadline, watch.deadline_us()) {
            Some(at) => tokio::time::timeout_at(at, link.events.recv()).await.ok(),
            None => Some(link.events.recv().await),
        };
        match next {
            Some(Some(ev)) => {
                if let Some(end) = watch.on_event(t_us(), &ev) {
                    break end;
                }
            }
            Some(None) => {
                break Ended::new(Ending::LinkLost, "link lost: the link task ended");
            }
            None => {
                if let Some(end) = watch.poll(t_us()) {
                    break end;
                }
                if deadline.is_some_and(|d| Instant::now() >= d) {
                    break Ended::new(
                        Ending::TimedOut,
                        format!(
                            "the {} had not ended by --timeout; the robot goes on with it \
                             (`station send --port P stop` stops it)",
                            task_name(mode)
                        ),
                    );
                }
            }
        }
    };
    Waited {
        ended,
        seconds: started.elapsed().as_secs_f64(),
        telemetry: watch.telemetry().copied(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_ending_has_its_own_code_and_the_codes_are_distinct() {
        let mut codes: Vec<u8> = Ending::ALL.iter().map(|&e| code(e)).collect();
        assert_eq!(code(Ending::Arrived), 0);
        codes.extend([1, USAGE]);
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), CODES.len());
        for (i, c) in CODES.iter().enumerate() {
            assert_eq!(usize::from(c.code), i);
        }
    }

    #[test]
    fn the_scripting_guide_lists_every_code() {
        let guide =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/scripting.md"))
                .expect("docs/scripting.md");
        for c in &CODES {
            let row = format!("| {} | `{}` |", c.code, c.name);
            assert!(guide.contains(&row), "docs/scripting.md lacks {row:?}");
        }
    }
}
