//! Retracing: re-running a recorded run through the firmware's own code (ALICE's retracing,
//! Zimmer's thesis §3.1.2).
//!
//! Layer: pure over a recording's bytes: `load` (its frames and hardware trace), `run` (the
//! firmware's `Robot` over a `Playback` of the trace), `compare`, and [`report`], which the
//! `station retrace` command prints. With the recorded parameters, the
//! retraced robot's frames (telemetry, events, replies: pose, mode, motor output) must equal
//! the recorded ones byte for byte, and its motor and gripper commands the recorded ones pass
//! by pass; the first divergence is reported with its cycle and field. "Identical" means every
//! recorded frame the trace covers was compared: the retrace ran to the trace's end (or to
//! `--until-ms`); the only frames left uncompared are those the robot sent after the last pass
//! whose trace the recording holds (the recording ended before their trace), and the report
//! counts them and says so. A retrace stopped by a gap in the trace is not identical. With `--param`, it
//! retraces twice (recorded parameters, then changed) and reports what would have differed:
//! the believed pose track, the events, the rotation (with the emulator's truth beside it).
//!
//! The limit the thesis states: a changed algorithm would have moved the robot elsewhere and so
//! gathered other data; a retrace keeps the recorded sensor data, so it shows what the changed
//! firmware would have made of the same readings, not where the robot would have gone.
//! What can fail: an unreadable or damaged recording, no trace in it, a malformed trace or one
//! claiming more passes or robot time than a recording of its span can hold (each with the
//! file's byte offset; `run`, PROTOCOL.md §17), an unknown or refused parameter.
pub mod compare;
pub mod load;
pub mod overlay;
pub mod run;

use serde::Serialize;

use compare::{compare_frames, events, FrameDivergence};
use run::{retrace, Run, Stop};

/// Parses `NAME=VALUE` against the firmware's parameter table.
pub fn parse_param(s: &str) -> Result<(u16, f32), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("--param {s:?}: expected NAME=VALUE"))?;
    let info = crate::param_names::find(name).map_err(|e| format!("--param: {e}"))?;
    let v: f32 = value
        .trim()
        .parse()
        .ok()
        .filter(|v: &f32| v.is_finite())
        .ok_or_else(|| {
            format!(
                "--param {}: {:?} is not a number",
                info.name,
                crate::terminal_text::printable(value)
            )
        })?;
    if v < info.min || v > info.max {
        return Err(format!(
            "--param {}: {v} is outside {} ..= {} {}",
            info.name, info.min, info.max, info.unit
        ));
    }
    Ok((info.id, v))
}

/// How two retraces' believed pose tracks differ.
#[derive(Clone, Debug, Serialize)]
pub struct TrackDiff {
    pub cycles: usize,
    pub max_m: f64,
    pub mean_m: f64,
    pub final_m: f64,
    /// Final heading, changed minus recorded parameters, degrees.
    pub final_heading_deg: f64,
}

/// Rotations over the retraced span, degrees (unwrapped, counter-clockwise positive).
#[derive(Clone, Debug, Serialize)]
pub struct Rotation {
    /// The firmware's belief with the recorded parameters.
    pub recorded_deg: f64,
    /// With the changed parameters.
    pub retraced_deg: f64,
    /// The emulator's truth over the same span (`None` off the emulator).
    pub truth_deg: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct EventRow {
    pub time_ms: u32,
    pub code: String,
    pub value: i32,
}

/// The `--json` report.
#[derive(Debug, Serialize)]
pub struct Report {
    pub recording: String,
    pub steps: u64,
    pub cycles: u64,
    pub robot_time_s: f64,
    /// The believed track with the recorded parameters: length and rotation.
    pub believed_distance_m: f64,
    pub believed_rotation_deg: f64,
    pub stopped: String,
    pub trace_bytes: usize,
    pub trace_complete_from_power_up: bool,
    pub trace_dropped_steps: u32,
    pub frames_compared: usize,
    pub frames_recorded: usize,
    pub frames_retraced: usize,
    /// Recorded frames not compared, and why.
    pub frames_not_compared: usize,
    pub frames_not_compared_why: Option<String>,
    pub identical: bool,
    pub first_divergence: Option<serde_json::Value>,
    pub misses: u64,
    pub params: Vec<serde_json::Value>,
    pub track_difference: Option<TrackDiff>,
    pub rotation: Option<Rotation>,
    pub events_only_recorded: Option<Vec<EventRow>>,
    pub events_only_retraced: Option<Vec<EventRow>>,
    pub link: LinkUse,
    pub limit: &'static str,
}

/// The reference line: 115200 baud, 8N1, 11520 bytes a second.
const LINE_BYTES_PER_S: f64 = 11_520.0;

/// What the trace costs on the link, beside telemetry (from the retraced frames, which are the
/// recorded ones when identical): bytes on the wire (COBS, delimiter and all).
#[derive(Debug, Default, Serialize)]
pub struct LinkUse {
    pub cycle_ms: f64,
    pub trace_bytes_per_cycle_mean: f64,
    pub trace_bytes_per_cycle_max: u64,
    pub trace_percent_of_115200: f64,
    /// The cycle with the most trace bytes, as a share of the line during that cycle.
    pub trace_worst_cycle_percent_of_115200: f64,
    pub telemetry_percent_of_115200: f64,
    pub all_frames_percent_of_115200: f64,
}

fn link_use(run: &Run) -> LinkUse {
    use std::collections::BTreeMap;
    let secs = f64::from(run.last_ms) / 1000.0;
    if run.cycles == 0 || secs <= 0.0 {
        return LinkUse::default();
    }
    let mut per_cycle: BTreeMap<u64, u64> = BTreeMap::new();
    let (mut trace, mut telemetry, mut all) = (0u64, 0u64, 0u64);
    for f in &run.frames {
        let wire = f.raw.len() as u64 + 1;
        all += wire;
        match compare::kind_of(&f.raw) {
            Some(protocol::Kind::HalTrace) => {
                trace += wire;
                *per_cycle.entry(f.cycle).or_default() += wire;
            }
            Some(protocol::Kind::Telemetry) => telemetry += wire,
            _ => {}
        }
    }
    let cycle_s = secs / run.cycles as f64;
    let max = per_cycle.values().copied().max().unwrap_or(0);
    let pct = |b: u64| 100.0 * b as f64 / secs / LINE_BYTES_PER_S;
    LinkUse {
        cycle_ms: cycle_s * 1000.0,
        trace_bytes_per_cycle_mean: trace as f64 / run.cycles as f64,
        trace_bytes_per_cycle_max: max,
        trace_percent_of_115200: pct(trace),
        trace_worst_cycle_percent_of_115200: 100.0 * max as f64 / cycle_s / LINE_BYTES_PER_S,
        telemetry_percent_of_115200: pct(telemetry),
        all_frames_percent_of_115200: pct(all),
    }
}

/// The thesis's limit, for --help, README and every report.
pub const LIMIT: &str = "a changed algorithm would have moved the robot elsewhere; the retraced \
                         sensor data stay the recorded ones";

/// Retraces a recording's bytes (`name` for messages): with the recorded parameters, and with
/// `params` changed if any. Err: why it cannot be retraced, naming the file.
pub fn report(
    name: &str,
    bytes: &[u8],
    params: &[(u16, f32)],
    until_ms: Option<u32>,
) -> Result<Report, String> {
    let loaded = load::load(bytes).map_err(|e| format!("cannot retrace: {name}: {e}"))?;
    if loaded.trace.is_empty() {
        return Err(format!(
            "cannot retrace: {name}: no hardware trace in it (record a robot with parameter 34 \
             hal_trace on, e.g. robot-emulator --hal-trace)"
        ));
    }
    let base =
        retrace(&loaded, &[], until_ms).map_err(|e| format!("cannot retrace: {name}: {e}"))?;
    let frame_div = compare_frames(&loaded.frames, &base.frames);
    let compared = loaded.frames.len().min(base.frames.len());
    // Bit for bit means every frame the trace covers: a retrace that stopped before the
    // trace's end (a gap, a restarted stream) compared only a part.
    let to_the_end = matches!(base.stop, Stop::End | Stop::Until);
    let identical =
        frame_div.is_none() && base.command_divergence.is_none() && base.misses == 0 && to_the_end;
    let not_compared = loaded.frames.len() - compared;
    let not_compared_why = (not_compared > 0).then(|| match base.stop {
        Stop::End => "sent after the last pass whose trace the recording holds (the recording \
                      ended before their trace was sent): no retrace can reproduce them"
            .to_string(),
        Stop::Until => "after --until-ms".to_string(),
        _ => format!("after the retrace stopped: {}", stop_text(&base.stop)),
    });

    let mut report = Report {
        recording: name.to_string(),
        steps: base.steps,
        cycles: base.cycles,
        robot_time_s: f64::from(base.last_ms) / 1000.0,
        believed_distance_m: base
            .poses
            .windows(2)
            .map(|w| f64::from(w[1].1.x - w[0].1.x).hypot(f64::from(w[1].1.y - w[0].1.y)))
            .sum(),
        believed_rotation_deg: rotation_deg(&base.poses),
        stopped: stop_text(&base.stop),
        trace_bytes: loaded.trace.len(),
        trace_complete_from_power_up: base.steps_before == 0,
        trace_dropped_steps: loaded.dropped_steps,
        frames_compared: compared,
        frames_recorded: loaded.frames.len(),
        frames_retraced: base.frames.len(),
        frames_not_compared: not_compared,
        frames_not_compared_why: not_compared_why,
        identical,
        first_divergence: first_divergence(&base, frame_div.as_ref()),
        misses: base.misses,
        params: Vec::new(),
        track_difference: None,
        rotation: None,
        events_only_recorded: None,
        events_only_retraced: None,
        link: link_use(&base),
        limit: LIMIT,
    };
    if !params.is_empty() {
        let changed = retrace(&loaded, params, until_ms)
            .map_err(|e| format!("cannot retrace: {name}: {e}"))?;
        report.params = params
            .iter()
            .map(|&(id, v)| {
                let info = robot_firmware::params::info(id);
                serde_json::json!({
                    "name": info.map_or("?", |i| i.name),
                    "id": id,
                    "value": v,
                })
            })
            .collect();
        report.track_difference = Some(track_diff(&base, &changed));
        report.rotation = Some(Rotation {
            recorded_deg: rotation_deg(&base.poses),
            retraced_deg: rotation_deg(&changed.poses),
            truth_deg: truth_rotation_deg(&loaded.truth, &base),
        });
        let (a, b) = (events(&base.frames), events(&changed.frames));
        let (only_a, only_b) = compare::diff_events(&a, &b);
        let row = |e: &compare::EventAt| EventRow {
            time_ms: e.time_ms,
            code: format!("{:?}", e.code),
            value: e.value,
        };
        report.events_only_recorded = Some(only_a.iter().map(row).collect());
        report.events_only_retraced = Some(only_b.iter().map(row).collect());
    }
    Ok(report)
}

fn stop_text(s: &Stop) -> String {
    match s {
        Stop::End => "end of the trace".into(),
        Stop::Until => "--until-ms".into(),
        Stop::Gap { steps, file_offset } => format!(
            "a gap at byte {file_offset}: the robot could not send {steps} passes of its trace \
             (the link could not keep up); nothing past it is retraced"
        ),
        Stop::Restart { file_offset } => {
            format!("tracing restarted at byte {file_offset}; the second stream is not retraced")
        }
    }
}

fn first_divergence(run: &Run, frame: Option<&FrameDivergence>) -> Option<serde_json::Value> {
    // The earlier of the two, by pass.
    let cmd = run.command_divergence.as_ref().map(|c| {
        (
            c.step,
            serde_json::json!({
                "cycle": c.cycle, "step": c.step, "time_ms": c.time_ms,
                "field": c.field, "recorded": c.recorded, "retraced": c.retraced,
            }),
        )
    });
    let frm = frame.map(|f| {
        (
            f.step,
            serde_json::json!({
                "cycle": f.cycle, "step": f.step, "time_ms": f.time_ms,
                "frame": f.index, "file_offset": f.file_offset, "kind": f.kind,
                "field": f.field, "recorded": f.recorded, "retraced": f.retraced,
            }),
        )
    });
    let miss = run.first_miss.map(|(step, what)| {
        (
            step,
            serde_json::json!({
                "step": step,
                "field": what,
                "recorded": "nothing",
                "retraced": "read",
            }),
        )
    });
    [cmd, frm, miss]
        .into_iter()
        .flatten()
        .min_by_key(|(s, _)| *s)
        .map(|(_, v)| v)
}

fn track_diff(a: &Run, b: &Run) -> TrackDiff {
    let n = a.poses.len().min(b.poses.len());
    let mut max = 0.0f64;
    let mut sum = 0.0f64;
    let mut last = 0.0;
    for ((_, p), (_, q)) in a.poses.iter().zip(&b.poses).take(n) {
        let d = f64::from(p.x - q.x).hypot(f64::from(p.y - q.y));
        max = max.max(d);
        sum += d;
        last = d;
    }
    let heading = rotation_deg(&b.poses[..n]) - rotation_deg(&a.poses[..n]);
    TrackDiff {
        cycles: n,
        max_m: max,
        mean_m: if n > 0 { sum / n as f64 } else { 0.0 },
        final_m: last,
        final_heading_deg: heading,
    }
}

/// Unwrapped heading change over a pose track, degrees.
fn rotation_deg(poses: &[(u32, robot_firmware::odometry::Pose)]) -> f64 {
    unwrapped(poses.iter().map(|(_, p)| f64::from(p.heading))).to_degrees()
}

fn unwrapped(mut headings: impl Iterator<Item = f64>) -> f64 {
    let Some(first) = headings.next() else {
        return 0.0;
    };
    let (mut prev, mut total) = (first, 0.0);
    for h in headings {
        let mut d = h - prev;
        d = (d + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        total += d;
        prev = h;
    }
    total
}

/// The truth's rotation over the retraced span (its first to its last control cycle), the
/// truth's samples (one a telemetry frame) unwrapped and interpolated to those two times: a
/// cycle's pose and the nearest truth sample can be 100 ms apart, degrees in a corner.
fn truth_rotation_deg(truth: &[(u32, i32)], run: &Run) -> Option<f64> {
    let (t0, t1) = (run.poses.first()?.0, run.poses.last()?.0);
    let mut track: Vec<(f64, f64)> = Vec::with_capacity(truth.len());
    for &(t, h) in truth {
        let h = f64::from(h) / 1000.0;
        let total = match track.last() {
            Some(&(_, prev)) => {
                let d = (h - prev).rem_euclid(2.0 * std::f64::consts::PI);
                let d = if d > std::f64::consts::PI {
                    d - 2.0 * std::f64::consts::PI
                } else {
                    d
                };
                prev + d
            }
            None => h,
        };
        track.push((f64::from(t), total));
    }
    let at = |t: f64| -> Option<f64> {
        // Clamped to the truth's span (its first sample follows the first telemetry frame).
        let i = track.partition_point(|&(s, _)| s <= t);
        let (a, b) = match (i.checked_sub(1).and_then(|j| track.get(j)), track.get(i)) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => (a, a),
            (None, Some(b)) => (b, b),
            (None, None) => return None,
        };
        let f = if b.0 > a.0 {
            (t - a.0) / (b.0 - a.0)
        } else {
            0.0
        };
        Some(a.1 + f * (b.1 - a.1))
    };
    Some((at(f64::from(t1))? - at(f64::from(t0))?).to_degrees())
}
