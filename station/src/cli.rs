//! The command line: `station [--port P]`, `station ports`, `station send ...`,
//! `station stats ...`, `station upload-map ...`, `station download-map ...`,
//! `station upload-plan ...`, `station plan ...`, `station segment ...`, `station record ...`,
//! `station replay ...`, `station export ...`, `station watch ...`, `station status ...`.
//!
//! Layer: argument parsing (clap derive) and dispatch; `main.rs` only calls `run`. Parsing
//! turns every argument into a checked value or a clear error (clap exits 2 on usage errors);
//! a name that is not a parameter or a mode is refused here, before any port is opened. What
//! can fail afterwards is reported by the subcommand with a non-zero exit: 1 when the robot
//! refused or did not answer, or the port could not be used.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::commands::args::{parse_baud, parse_seconds, RequiredPort, StatsPorts};
use crate::commands::send::SendCmd;
use crate::link::serial::DEFAULT_BAUD;

/// Terminal control station for small mobile robots over a serial link.
///
/// With no arguments, starts the built-in emulator (the micro-rato robot, modelled on Dom
/// Dinis, in the Micro-Rato'99 labyrinth) on a pseudo-terminal and opens the TUI on it, as
/// it would open /dev/ttyUSB0; with --port, the TUI on a robot. `?` in the TUI lists the
/// keys. The commands below do one thing each without the TUI. Guide: docs/station.md.
///
/// Examples:
///   station                                  (the built-in emulator)
///   station --port /dev/ttyUSB0              (a robot on a serial port)
///   station --arena builtin:forage           (a simulated Khepera in the foraging arena)
///   station --robots 3                       (three robots in one simulated world)
#[derive(Debug, Parser)]
#[command(name = "station", version, about, verbatim_doc_comment)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Sub>,
    #[command(flatten)]
    pub port: PortArgs,
    /// An arena file to draw under the map and plan on with P (CiberRato XML, maze text, ROS
    /// YAML, ASCII grid), or a built-in one (`builtin:micro-rato-99`, `builtin:forage`,
    /// `builtin:floor-grid`, `builtin:alice`, `builtin:alice-navigation`).
    /// Without --port the built-in emulator simulates it.
    #[arg(long, value_name = "FILE", global = false)]
    pub arena: Option<PathBuf>,
    /// The built-in emulator's robot (without --port): default micro-rato (the Dom Dinis
    /// robot), or khepera in `builtin:forage` (the foraging robot, with its gripper); `alice`
    /// (the robot of Zimmer's thesis: its situations feed the QT world model, `T`) in
    /// `builtin:alice` unless --arena names another.
    #[arg(long, value_enum, global = false)]
    pub profile: Option<emulator::cli::ProfileArg>,
    /// The built-in emulator's start pose `X,Y[,HEADING_DEG]` in metres (without --port;
    /// default: the arena's start), e.g. next to a lamp of `builtin:forage` to calibrate.
    #[arg(long, value_name = "X,Y[,DEG]", value_parser = emulator::cli::parse_pose,
          allow_negative_numbers = true, conflicts_with = "port")]
    pub start: Option<[f64; 3]>,
    #[command(flatten)]
    pub tui: TuiArgs,
}

/// How the TUI behaves (not its subcommands).
#[derive(Debug, Args, Clone, Default)]
pub struct TuiArgs {
    /// A click on the map sends the robot there at once. Without it a click places the go-to
    /// cursor and Enter sends the robot (as `g` does).
    #[arg(long)]
    pub click_goes: bool,
    /// Where `R` writes its recordings [default: $XDG_DATA_HOME/station/recordings, else
    /// ~/.local/share/station/recordings]. Created, readable by you alone, when `R` first
    /// records; the log says each file's full path.
    #[arg(long, value_name = "DIR")]
    pub record_dir: Option<PathBuf>,
    /// While `R` records, the robot streams its hardware trace (parameter 34 hal_trace set to
    /// 1, and put back when the recording ends), so `station retrace` can re-run the
    /// recording through the firmware's code.
    #[arg(long)]
    pub record_hal_trace: bool,
}

impl TuiArgs {
    /// Where `R` records: `--record-dir`, else the data directory, else why there is none.
    pub fn record_dir(&self) -> Result<PathBuf, String> {
        match &self.record_dir {
            Some(d) => Ok(d.clone()),
            None => crate::record::default_recordings_dir(),
        }
    }
}

/// Which port to use.
#[derive(Debug, Args, Clone)]
pub struct PortArgs {
    /// Serial port (or pty) of the robot, e.g. /dev/ttyUSB0. Repeat it for several robots
    /// (at most 9), one link each: `--port /tmp/robot1 --port /tmp/robot2`.
    #[arg(long, short = 'p', value_name = "PATH")]
    pub port: Vec<PathBuf>,
    /// The built-in emulator with this many robots in one world (without --port), 1 to 9.
    #[arg(long, value_name = "N", conflicts_with_all = ["port", "start"],
          value_parser = clap::value_parser!(u8).range(1..=9))]
    pub robots: Option<u8>,
    /// Baud rate (ignored by ptys).
    #[arg(long, short = 'b', default_value_t = DEFAULT_BAUD, value_parser = parse_baud)]
    pub baud: u32,
    /// Link authentication key: a file of 64 hex digits, the robot's key (PROTOCOL.md §13).
    /// Without --port the built-in emulator is given the same key.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum Sub {
    /// List serial ports (and pseudo-terminals an emulator may be on).
    Ports {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Send one command, print the robot's Ack or Nack (exit 1 when refused or unanswered, or as --wait says)
    ///
    /// With --wait, a command that starts a task (goto, execute, explore) is followed to the
    /// task's end: the exit code says how it ended (below), a line on stderr says why, and
    /// --json adds it as `wait`. Scripting guide: docs/scripting.md.
    ///
    /// Examples:
    ///   station send --port /dev/ttyUSB0 goto 1.0 0.5
    ///   station send --port /dev/ttyUSB0 goto 1.0 0.5 --wait --timeout 60
    ///   station send --port /dev/ttyUSB0 execute 0x7692f253 --wait --json
    #[command(verbatim_doc_comment, after_help = crate::commands::wait::help_table())]
    Send {
        #[command(flatten)]
        port: RequiredPort,
        /// Print JSON (before or after the command: `send --port P plan --json`).
        #[arg(long, global = true)]
        json: bool,
        /// Seconds to wait for the handshake [default: 5]; with --wait, the most to wait in
        /// all, handshake and task [default: no limit].
        #[arg(long, value_parser = parse_seconds, global = true, allow_negative_numbers = true)]
        timeout: Option<f64>,
        /// Send the command this many times, one after another, and report the round trips'
        /// p50 / p99 (the round-trip figure of docs/performance.md).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000),
          global = true)]
        repeat: u32,
        /// Wait until the task the command starts (goto, execute, explore) ends: arrived, gave
        /// up, refused, stopped, timed out or link lost, each its own exit code.
        #[arg(long, global = true)]
        wait: bool,
        #[command(subcommand)]
        command: SendCmd,
    },
    /// Print the robot's telemetry, progress, events and log lines as JSON, one object a line
    ///
    /// Until Ctrl-C, --count lines or --seconds; each line is flushed as it is written, for a
    /// pipe into jq or a script. Every line has `kind` (telemetry, progress, event, log),
    /// `time_s` (the station's clock, seconds since the command started) and `robot_time_s`
    /// (the robot's clock; for lines other than telemetry, the last telemetry frame's).
    /// Telemetry keys are the CSV export's columns (x_m, y_m, heading_rad, battery_v, ...;
    /// docs/recordings.md), null for a sensor the robot lacks. Exit status 0 at the end asked
    /// for, on Ctrl-C or when stdout closes; 7 when the link is lost (a line on stderr says
    /// why). The port is the robot's alone: not while the TUI has it. Guide: docs/scripting.md.
    ///
    /// Examples:
    ///   station watch --port /dev/ttyUSB0 --count 10
    ///   station watch --port /dev/ttyUSB0 --fields x_m,y_m,heading_rad | jq -c .
    ///   station watch --port /dev/ttyUSB0 --kind event,log --seconds 60
    #[command(verbatim_doc_comment)]
    Watch(crate::commands::watch::WatchArgs),
    /// Print the robot's state once: mode, pose, sensors, task progress, link statistics
    ///
    /// Waits for the first telemetry frame, the link's statistics and, while a task runs, its
    /// progress report (about 1.5 s at most), then prints them and exits. --json gives one
    /// object: `peer`, `telemetry` (a `station watch` telemetry line's keys), `progress`
    /// (null when no task runs) and `stats` (as `station stats --json`).
    ///
    /// Examples:
    ///   station status --port /dev/ttyUSB0
    ///   station status --port /dev/ttyUSB0 --json | jq .telemetry.x_m
    #[command(verbatim_doc_comment)]
    Status(crate::commands::status::StatusArgs),
    /// Watch the link for a while and print its statistics, with the round trip of a harmless
    /// probe (a parameter read) sent every 250 ms.
    Stats {
        #[command(flatten)]
        port: StatsPorts,
        /// Seconds to watch.
        #[arg(long, short = 's', default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
        seconds: f64,
        /// Print JSON.
        #[arg(long)]
        json: bool,
        /// Seconds to wait for the handshake.
        #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
        timeout: f64,
    },
    /// Read, write, save, load and compare the robot's parameters
    ///
    /// Names and ids are the firmware's table (`list` shows each with its unit, range and
    /// description). Files are `name = value` lines, `#` comments (docs/station.md,
    /// "Parameter files"); `load` sets each parameter the file names and reports each change
    /// and each refusal (exit 1 if any was refused); `diff` exits 1 when the robot differs
    /// from the file. A bad file is refused with FILE:LINE:COL before the port is opened.
    ///
    /// Examples:
    ///   station params --port /dev/ttyUSB0 list
    ///   station params --port /dev/ttyUSB0 set telemetry_hz 20
    ///   station params --port /dev/ttyUSB0 save robot.parm
    ///   station params --port /dev/ttyUSB0 load robot.parm
    ///   station params --port /dev/ttyUSB0 diff robot.parm
    #[command(verbatim_doc_comment)]
    Params(crate::commands::params::ParamsArgs),
    /// Upload a map to the robot: any map file `station plan` reads, or a Map object file
    ///
    /// The map is gridded as `station plan` grids it (--cell, --radius) and sent as a Map
    /// object, with its start marker and its goal (the point `station plan` plans to), in
    /// windowed, resumable, CRC-checked chunks. A map larger than the robot holds (the
    /// map_capacity of its HelloReply: 64 x 64 cells on the robot firmware) is refused
    /// before anything is sent, with a cell size that fits. Exit status 0 when the robot
    /// holds the map (installed now, or held already: then nothing is sent), else 1.
    ///
    /// Examples:
    ///   station upload-map --port /dev/ttyUSB0 --map builtin:micro-rato-99
    ///   station upload-map --port /dev/ttyUSB0 --map lab.xml --cell 0.25 --json
    #[command(verbatim_doc_comment)]
    UploadMap(crate::commands::transfer::UploadMapArgs),
    /// Download the robot's map (the one uploaded, or the one it built exploring)
    ///
    /// The file is a Map object (PROTOCOL.md §12), written to a temporary file and renamed
    /// when complete; --ascii prints the map (# obstacle, . free, ? unknown, S start, G
    /// goal, top row first). Exit status 1 when the robot holds no map or the transfer fails.
    ///
    /// Examples:
    ///   station download-map --port /dev/ttyUSB0 --out robot-map.obj
    ///   station download-map --port /dev/ttyUSB0 --ascii
    #[command(verbatim_doc_comment)]
    DownloadMap(crate::commands::transfer::DownloadMapArgs),
    /// Upload a plan to the robot: a Plan object file from `station plan --out-object`
    ///
    /// The robot installs it (any plan it was executing is aborted); `station send execute
    /// ID` then drives it. The plan's map id should be the robot's map's (upload that map
    /// with the same --cell and --radius first).
    ///
    /// Examples:
    ///   station plan --map builtin:micro-rato-99 --out-object plan.obj
    ///   station upload-plan --port /dev/ttyUSB0 --plan plan.obj
    ///   station send --port /dev/ttyUSB0 execute 0x1234abcd
    #[command(verbatim_doc_comment)]
    UploadPlan(crate::commands::transfer::UploadPlanArgs),
    /// Plan a path on a map file with the robot's own planner; no robot needed
    ///
    /// As the Dom Dinis robot plans: the map becomes a grid (0.3 m cells), its free cells squares, and A* finds
    /// the shortest chain of adjacent squares; the path runs through their centres. Points are
    /// metres in the map frame. Exit status 1, with the reason, when no plan can be made.
    ///
    /// Examples:
    ///   station plan --map builtin:micro-rato-99 --smooth
    ///   station plan --map maze.txt --json          (mazes: cells of half the pitch)
    ///   station plan --map lab.xml --from 0.5,0.5 --to 3.2,2.6 --cell 0.1 --radius 0.12
    #[command(verbatim_doc_comment)]
    Plan(crate::commands::plan::PlanArgs),
    /// Segment a map into the free squares the planner searches (Dom Dinis segmentation)
    ///
    /// Squares are in cells: x, y of the corner with the smallest column and row (row 0 is
    /// the smallest y), and the side.
    ///
    /// Example:
    ///   station segment --map builtin:micro-rato-99 --json
    #[command(verbatim_doc_comment)]
    Segment(crate::commands::plan::SegmentArgs),
    /// Record the link, both directions with timestamps, to a file
    ///
    /// The file is FILE.partial while recording (flushed every second, so a crash loses at
    /// most that) and is renamed to FILE when the recording ends: at --seconds, or on Ctrl-C.
    /// Losing and regaining the robot is recorded as a gap. Without --port, the built-in
    /// emulator is started and recorded. The format is in docs/recordings.md.
    ///
    /// Examples:
    ///   station record --port /dev/ttyUSB0 --out run.rec --seconds 60
    ///   station record --out demo.rec --seconds 20 --rate 50 --json
    #[command(verbatim_doc_comment)]
    Record(crate::commands::record::RecordArgs),
    /// Replay a recording in the TUI (pause, seek, speed), or summarise it with --json
    ///
    /// The robot's recorded bytes go through the station's own link code, so every view
    /// shows what it showed live. Nothing is sent to any port. Keys: space pause, left/right
    /// 5 s, Home/End, +/- or 1-9 speed, ? help, q quit. A damaged or unfinished (.partial)
    /// recording is replayed up to its last good record.
    ///
    /// Examples:
    ///   station replay run.rec
    ///   station replay run.rec --speed 4 --arena lab.xml
    ///   station replay run.rec --json        (duration, frames, telemetry rate, gaps, errors)
    #[command(verbatim_doc_comment)]
    Replay(crate::commands::replay::ReplayArgs),
    /// Export a recording to MCAP (Foxglove) and/or CSV (telemetry, one row per frame)
    ///
    /// Outputs are written to a temporary file and renamed when complete. A damaged
    /// recording is refused (with the byte offset) unless --salvage is given.
    ///
    /// Examples:
    ///   station export run.rec --mcap run.mcap
    ///   station export run.rec --csv run.csv --mcap run.mcap
    #[command(verbatim_doc_comment)]
    Export(crate::commands::export::ExportArgs),
    /// Re-run a recorded run through the firmware's own code (retracing, Zimmer's ALICE thesis §3.1.2)
    ///
    /// The recording must hold the robot's hardware trace (parameter 34 hal_trace, message
    /// kind 15; `robot-emulator --hal-trace` streams it from power-up). Every pass of the
    /// robot's main loop is fed to the firmware crate's own Robot (the profile's composition)
    /// through a Hal that plays the trace back. Without --param it checks that the outputs
    /// (frames: telemetry, events, replies; motor and gripper commands) are the recorded ones
    /// bit for bit, or reports the first divergence with its cycle and field (exit 1). With
    /// --param it reports what the changed firmware would have done with the same readings:
    /// the believed track's difference, the rotation, the events that differ.
    ///
    /// Limit (the thesis's): a changed algorithm would have moved the robot elsewhere; the
    /// retraced sensor data stay the recorded ones.
    ///
    /// Examples:
    ///   station retrace run.rec
    ///   station retrace run.rec --param odo_wheel_distance_mm=53.3 --json
    #[command(verbatim_doc_comment)]
    Retrace(crate::commands::retrace::RetraceArgs),
    /// Train the light -> angle map (Khepera light calibration) from a recording of a calibrating robot
    ///
    /// The Kohonen map of the Khepera foraging paper (Löffler, Klahold, Rückert 2001, §5.3):
    /// 60 neurons learn the light's bearing from the six front light sensors. Uses the
    /// telemetry recorded while a Khepera turned next to a light (mode calibrate-light):
    /// labels from each full turn (or from --light X,Y), the firmware's own network code,
    /// every fifth example held out. Prints the held-out mean/max angle error and writes the
    /// map (FILE.json, or binary for any other name) atomically.
    ///
    /// Examples:
    ///   station calibrate cal.rec --out som.json
    ///   station calibrate cal.rec --out som.bin --light 0.40,0.30 --json
    ///   station calibrate odometry --port /dev/ttyUSB0   (odometry laps on the robot)
    #[command(verbatim_doc_comment)]
    Calibrate(crate::commands::calibrate::CalibrateCommand),
    /// Upload a light -> angle calibration to the robot (Khepera light calibration)
    ///
    /// The file is what `station calibrate --out` or `station download-calibration --out`
    /// wrote (JSON or binary). The robot installs it and uses it at once (LightBearing
    /// events, the light-map and foraging tasks); it answers "busy" while it is calibrating
    /// itself (mode calibrate-light). Exit status 1 when the file is not a calibration, the
    /// robot has no light sensors, or the transfer fails.
    ///
    /// Examples:
    ///   station calibrate cal.rec --out som.json
    ///   station upload-calibration --port /dev/ttyUSB0 --calibration som.json
    #[command(verbatim_doc_comment)]
    UploadCalibration(crate::commands::calibration::UploadCalibrationArgs),
    /// Download the robot's light -> angle calibration to a file (Khepera light calibration)
    ///
    /// The network the robot trained in mode calibrate-light (or was given), as JSON
    /// (FILE.json) or binary (any other name): keep it, study it, or upload it again after
    /// the robot restarts instead of calibrating for 7.5 minutes. Exit status 1 when the
    /// robot holds no trained calibration or the transfer fails.
    ///
    /// Examples:
    ///   station download-calibration --port /dev/ttyUSB0 --out som.bin
    #[command(verbatim_doc_comment)]
    DownloadCalibration(crate::commands::calibration::DownloadCalibrationArgs),
    /// Unsupervised landmarks and places (Mächler's thesis, ch. 3), run and played back here
    ///
    /// Runs the unsupervised-places scenario on the station with the firmware's own code and
    /// plays it back: landmarks on the map, the class streams, matches as they happen,
    /// corrected vs plain odometry vs truth, the error over time. Keys: space pause, left/right
    /// 10 s, Home/End, +/- speed, q quit.
    ///
    /// Examples:
    ///   station places --arena unstructured --seed 4
    ///   station places --arena structured --seed 2 --duration 600 --json
    #[command(verbatim_doc_comment)]
    Places(crate::places::PlacesArgs),
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Command, Mode, ParamId, PointMm};

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("station").chain(args.iter().copied()))
    }

    #[test]
    fn send_parses_every_command_form() {
        let cases: &[(&[&str], Command)] = &[
            (&["mode", "manual"], Command::SetMode(Mode::Manual)),
            (
                &["teleop", "-150", "500"],
                Command::Teleop {
                    v_mm_s: -150,
                    w_mrad_s: 500,
                },
            ),
            (
                &["goto", "1.5", "-0.25"],
                Command::GoTo(PointMm {
                    x_mm: 1500,
                    y_mm: -250,
                }),
            ),
            (
                &["param", "set", "failsafe_ms", "500"],
                Command::SetParam {
                    id: ParamId(0),
                    value: 500.0,
                },
            ),
            (&["param", "get", "7"], Command::GetParam { id: ParamId(7) }),
            (&["stop"], Command::Stop),
            (&["rate", "20"], Command::SetTelemetryRate { hz: 20 }),
            (&["explore"], Command::StartExploration),
            (&["segment"], Command::Segment),
            (
                &["plan", "--to", "4.35,-0.45"],
                Command::Plan {
                    from: None,
                    to: Some(PointMm {
                        x_mm: 4350,
                        y_mm: -450,
                    }),
                },
            ),
            (
                &["execute", "0x7692f253"],
                Command::ExecutePlan {
                    plan_id: 0x7692_f253,
                },
            ),
            (&["execute", "42"], Command::ExecutePlan { plan_id: 42 }),
        ];
        for (args, want) in cases {
            let mut full = vec!["send", "--port", "/dev/null"];
            full.extend_from_slice(args);
            let cli = parse(&full).unwrap_or_else(|e| panic!("{args:?}: {e}"));
            let Some(Sub::Send { command, .. }) = cli.command else {
                panic!("not a send: {args:?}");
            };
            assert_eq!(command.to_command(), Ok(*want), "{args:?}");
        }
    }

    #[test]
    fn the_built_in_emulator_takes_a_start_pose_but_a_port_does_not() {
        let cli = parse(&["--arena", "builtin:forage", "--start", "0.1825,0.62,-90"]).unwrap();
        assert_eq!(cli.start, Some([0.1825, 0.62, -90.0]));
        let e = parse(&["--port", "/dev/ttyUSB0", "--start", "1,1"]).unwrap_err();
        assert!(e.to_string().contains("cannot be used with"), "{e}");
    }

    #[test]
    fn send_options_may_follow_the_command() {
        let cli = parse(&["send", "--port", "p", "plan", "--json", "--timeout", "2"]).unwrap();
        let Some(Sub::Send { json, timeout, .. }) = cli.command else {
            panic!("not a send");
        };
        assert!(json);
        assert_eq!(timeout, Some(2.0));
        let cli = parse(&["send", "--port", "p", "goto", "1", "1", "--wait"]).unwrap();
        let Some(Sub::Send { wait, command, .. }) = cli.command else {
            panic!("not a send");
        };
        assert!(wait);
        assert_eq!(command.task_mode(), Some(protocol::Mode::GoTo));
    }

    #[test]
    fn bad_arguments_are_refused_with_a_clear_message() {
        let cases: &[(&[&str], &str)] = &[
            (
                &["send", "--port", "p", "param", "get", "warp_factor"],
                "unknown parameter",
            ),
            (
                &["send", "--port", "p", "mode", "dance"],
                "invalid value 'dance'",
            ),
            (
                &["send", "--port", "p", "rate", "99"],
                "99 is not in 0..=50",
            ),
            (
                &["send", "--port", "p", "teleop", "fast", "0"],
                "invalid digit",
            ),
            (
                &["send", "--port", "p", "goto", "NaN", "0"],
                "not a distance",
            ),
            (&["send", "--port", "p", "goto", "1e9", "0"], "too far"),
            (
                &["send", "--port", "p", "param", "set", "failsafe_ms", "inf"],
                "not a finite",
            ),
            (&["send", "stop"], "--port <PATH>"),
            (&["--baud", "0"], "not a usable baud rate"),
            (&["stats", "--port", "p", "--seconds", "0"], "out of range"),
            (&["frobnicate"], "unrecognized subcommand"),
            (&["send", "--port", "p", "execute", "0xzz"], "not a plan id"),
            (&["download-map", "--port", "p"], "--out <FILE>"),
            (&["upload-map", "--port", "p"], "--map <FILE>"),
        ];
        for (args, needle) in cases {
            match parse(args) {
                Ok(c) => panic!("{args:?} parsed: {c:?}"),
                Err(e) => {
                    let text = e.to_string();
                    assert!(text.contains(needle), "{args:?}: {text}");
                    assert_eq!(e.exit_code(), 2, "{args:?}");
                }
            }
        }
    }

    /// `words` split as `sh` would: whitespace, with '...' and "..." quoting.
    fn shell_words(line: &str) -> Vec<String> {
        let (mut words, mut word, mut quote, mut any) = (Vec::new(), String::new(), None, false);
        for c in line.chars() {
            match (quote, c) {
                (Some(q), c) if c == q => quote = None,
                (Some(_), c) => word.push(c),
                (None, '\'' | '"') => {
                    quote = Some(c);
                    any = true;
                }
                (None, c) if c.is_whitespace() => {
                    if any || !word.is_empty() {
                        words.push(std::mem::take(&mut word));
                    }
                    any = false;
                }
                (None, c) => word.push(c),
            }
        }
        if any || !word.is_empty() {
            words.push(word);
        }
        words
    }

    /// Every `station ...` line of every help text, as typed: without the comment in
    /// parentheses after it or what it is piped into.
    fn help_examples(cmd: &clap::Command, out: &mut Vec<String>) {
        let texts = [
            cmd.get_long_about(),
            cmd.get_about(),
            cmd.get_after_help(),
            cmd.get_after_long_help(),
            cmd.get_before_help(),
        ];
        for text in texts.into_iter().flatten() {
            for line in text.to_string().lines() {
                let line = line.trim();
                if !line.starts_with("station ") && line != "station" {
                    continue;
                }
                let line = line.split(" | ").next().unwrap_or(line);
                let line = match line.find("  (") {
                    Some(i) => &line[..i],
                    None => line,
                };
                out.push(line.trim().to_string());
            }
        }
        for sub in cmd.get_subcommands() {
            help_examples(sub, out);
        }
    }

    #[test]
    fn every_example_in_the_help_parses_as_written() {
        use clap::CommandFactory;
        let mut examples = Vec::new();
        help_examples(&Cli::command(), &mut examples);
        assert!(examples.len() > 40, "{examples:?}");
        for ex in &examples {
            let words = shell_words(ex);
            if let Err(e) = Cli::try_parse_from(&words) {
                panic!("the example `{ex}` does not parse:\n{e}");
            }
        }
        // The examples that name parameters name real ones.
        assert!(examples
            .iter()
            .any(|e| e.contains("--param odo_wheel_distance_mm=")));
    }

    #[test]
    fn a_mistyped_parameter_suggests_the_real_name_wherever_one_is_named() {
        for args in [
            &["retrace", "run.rec", "--param", "wheel_distance_mm=53"][..],
            &[
                "replay",
                "run.rec",
                "--retrace",
                "--param",
                "wheel_distance_mm=53",
            ][..],
            &["send", "--port", "p", "param", "get", "wheel_distance_mm"][..],
            &["params", "--port", "p", "set", "wheel_distance_mm", "53"][..],
        ] {
            let e = parse(args).unwrap_err().to_string();
            assert!(
                e.contains("did you mean odo_wheel_distance_mm?"),
                "{args:?}: {e}"
            );
        }
    }

    #[test]
    fn no_arguments_means_the_built_in_emulator() {
        let cli = parse(&[]).expect("parses");
        assert!(cli.command.is_none());
        assert!(cli.port.port.is_empty());
    }

    #[test]
    fn ports_repeat_and_the_built_in_emulator_takes_a_robot_count() {
        let cli = parse(&[
            "--port",
            "/tmp/robot1",
            "-p",
            "/tmp/robot2",
            "--port",
            "/tmp/robot3",
        ])
        .unwrap();
        assert_eq!(cli.port.port.len(), 3);
        assert_eq!(cli.port.port[1], PathBuf::from("/tmp/robot2"));
        assert_eq!(parse(&["--robots", "3"]).unwrap().port.robots, Some(3));
        for (args, needle) in [
            (&["--robots", "0"][..], "not in 1..=9"),
            (&["--robots", "10"][..], "not in 1..=9"),
            (&["--robots", "2", "--port", "p"][..], "cannot be used with"),
        ] {
            let e = parse(args).unwrap_err();
            assert!(e.to_string().contains(needle), "{args:?}: {e}");
        }
    }
}
