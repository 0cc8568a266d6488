//! The `robot-emulator` command line: `serve` (the default) puts the simulated robot on a
//! pseudo-terminal; `run` runs a headless scenario and prints a JSON report.
//!
//! Layer: argument parsing and validation at the edge. Every bad argument is reported with the
//! flag's name and why, and nothing starts.
//!
//! One module a subcommand, its arguments and what they turn into: `serve`, `run`, `arena`,
//! `bench`, `hil`; the robot and world every simulating subcommand takes (`world`), several
//! robots (`fleet`) and the value parsers they share (`parse`).

use clap::{Parser, Subcommand};

mod arena;
mod bench;
mod fleet;
mod hil;
mod parse;
mod run;
mod serve;
mod world;

pub use arena::{ArenaArgs, ArenaCommand, GenerateArgs};
pub use bench::{BenchArgs, MAX_BENCH_JOBS, MAX_BENCH_SEEDS};
pub use fleet::{for_robot, FleetArgs, PerRobot, RobotArg};
pub use hil::HilArgs;
pub use parse::{parse_pose, parse_stall};
pub use run::{RunArgs, SearchArg, TaskArg};
pub use serve::ServeArgs;
pub use world::{ProfileArg, WorldArgs};

/// The robot's firmware, unchanged, in a simulated world, on a serial port.
#[derive(Debug, Parser)]
#[command(
    name = "robot-emulator",
    version,
    about = "Runs the robot firmware in a simulated arena and exposes its serial link on a \
             pseudo-terminal, so the station (or any serial tool) talks to it as to a real \
             robot on /dev/ttyUSB0.",
    after_help = "Examples:\n  \
        robot-emulator                                   # Micro-Rato'99, micro-rato robot, real time\n  \
        robot-emulator --link /tmp/robot                 # and a stable path to the port\n  \
        station --port /tmp/robot                        # drive it\n  \
        robot-emulator --arena maze.txt --profile khepera --speed 10\n  \
        robot-emulator run --arena lab.xml --profile micro-rato --task go-to --seed 3 --json\n  \
        robot-emulator --profile alice   # ALICE (Zimmer's thesis) in builtin:alice"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub serve: ServeArgs,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Serve the robot on a pseudo-terminal (the default).
    Serve(ServeArgs),
    /// Run a scenario headless at maximum speed and print a report.
    Run(RunArgs),
    /// Arena files: `arena generate` writes a generated arena.
    Arena(ArenaArgs),
    /// Run one task over many arenas and seeds in parallel and report success rate, times,
    /// collisions, final error and failures by cause (the generalisation benchmark: does a
    /// task succeed in arenas nobody tuned it for?).
    Bench(BenchArgs),
    Hil(HilArgs),
}

/// Ends the process quietly, status 141 (128 + SIGPIPE, what a shell expects), when printing
/// to stdout fails because the reader went away (`robot-emulator run --json | head -1`):
/// Rust ignores SIGPIPE, so `println!` would panic with "failed printing to stdout" instead
/// of the program ending as `cat` does. Every other panic goes to the hook before it.
pub fn exit_quietly_on_broken_pipe() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(141);
        }
        previous(info);
    }));
}

#[cfg(test)]
mod tests;
