//! `station retrace`: re-run a recorded run through the firmware's own code (ALICE's
//! retracing, Zimmer's thesis §3.1.2), and print what `station_core::retrace` found. Exit
//! codes: 0 retraced (and identical, without --param), 1 diverged or could not retrace, 2 usage.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use station_core::retrace::{self, parse_param, Report};

/// Arguments of `station retrace`.
#[derive(Debug, Args, Clone)]
pub struct RetraceArgs {
    /// A recording (`station record`) of a robot streaming its hardware trace (parameter 34
    /// hal_trace; `robot-emulator --hal-trace` streams it from power-up).
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,
    /// Retrace with this parameter changed (a name from `station params`, or an id); repeat
    /// for several. Without it, the retrace checks that the firmware does what it did.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(u16, f32)>,
    /// Retrace up to this robot time, milliseconds.
    #[arg(long, value_name = "MS")]
    pub until_ms: Option<u32>,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `station retrace`.
pub fn run(args: &RetraceArgs) -> anyhow::Result<ExitCode> {
    let name = args.recording.display().to_string();
    let params = args.params.clone();
    let bytes = station_core::record::read_file(&args.recording)?;
    let report =
        retrace::report(&name, &bytes, &params, args.until_ms).map_err(anyhow::Error::msg)?;
    if args.json {
        println!("{}", station_core::json_text::pretty(&report)?);
    } else {
        print_text(&report);
    }
    Ok(if params.is_empty() && !report.identical {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn print_text(r: &Report) {
    println!(
        "{}: retraced {} passes, {} control cycles, {:.1} s of robot time ({})",
        r.recording, r.steps, r.cycles, r.robot_time_s, r.stopped
    );
    if !r.trace_complete_from_power_up {
        println!(
            "the trace began after power-up: the robot's state before it is not known, so the \
             retrace cannot match (start tracing at power-up: robot-emulator --hal-trace)"
        );
    }
    if r.trace_dropped_steps > 0 {
        println!(
            "the robot dropped {} passes of its trace (its link could not keep up)",
            r.trace_dropped_steps
        );
    }
    if r.identical {
        println!(
            "identical: every recorded frame the trace covers ({}) compared byte for byte, every \
             motor command the same",
            r.frames_compared
        );
        if let Some(why) = &r.frames_not_compared_why {
            println!(
                "not compared: the last {} of {} recorded frames, {why}",
                r.frames_not_compared, r.frames_recorded
            );
        }
    } else if let Some(d) = &r.first_divergence {
        println!(
            "first divergence: {}",
            station_core::json_text::compact(d).unwrap_or_default()
        );
    } else {
        println!(
            "not retraced to the end ({}): the {} frames before it are identical, the other {} \
             not compared",
            r.stopped, r.frames_compared, r.frames_not_compared
        );
    }
    if let Some(t) = &r.track_difference {
        println!(
            "with {}: the believed track differs by {:.3} m at most, {:.3} m at the end; heading \
             {:+.1} deg",
            r.params
                .iter()
                .map(|p| format!("{}={}", p["name"].as_str().unwrap_or("?"), p["value"]))
                .collect::<Vec<_>>()
                .join(", "),
            t.max_m,
            t.final_m,
            t.final_heading_deg
        );
    }
    if let Some(rot) = &r.rotation {
        match rot.truth_deg {
            Some(t) => println!(
                "rotation: {:.1} deg believed with the recorded parameters, {:.1} deg retraced, \
                 {t:.1} deg true",
                rot.recorded_deg, rot.retraced_deg
            ),
            None => println!(
                "rotation: {:.1} deg believed with the recorded parameters, {:.1} deg retraced",
                rot.recorded_deg, rot.retraced_deg
            ),
        }
    }
    if let (Some(a), Some(b)) = (&r.events_only_recorded, &r.events_only_retraced) {
        println!(
            "events only in the recorded run: {}; only in the retrace: {}",
            a.len(),
            b.len()
        );
        for e in a.iter().take(20) {
            println!("  - {:>9} ms {} {}", e.time_ms, e.code, e.value);
        }
        for e in b.iter().take(20) {
            println!("  + {:>9} ms {} {}", e.time_ms, e.code, e.value);
        }
    }
    let l = &r.link;
    println!(
        "link: the trace takes {:.0} bytes a {:.0} ms cycle on average, {} at most ({:.1} % of a \
         115200-baud line, {:.1} % in its worst cycle); telemetry {:.1} %, all frames {:.1} %",
        l.trace_bytes_per_cycle_mean,
        l.cycle_ms,
        l.trace_bytes_per_cycle_max,
        l.trace_percent_of_115200,
        l.trace_worst_cycle_percent_of_115200,
        l.telemetry_percent_of_115200,
        l.all_frames_percent_of_115200
    );
    println!("limit: {}", r.limit);
}
