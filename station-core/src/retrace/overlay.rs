//! What `station replay --retrace` draws over a replay: the retraced robot's believed track
//! (with `--param` changed, or as recorded) and the events that differ from the recorded
//! parameters' retrace, as log lines.
//!
//! Layer: pure over a recording's bytes; the map layer (`ui::retrace_layer`) and the replay's
//! notes read it.

use super::compare::{diff_events, events};
use super::load::load;
use super::run::retrace;

/// The retrace drawn over a replay.
#[derive(Clone, Debug, Default)]
pub struct RetraceOverlay {
    /// "as recorded" or the parameters changed.
    pub label: String,
    /// The believed pose after each control cycle: robot time ms, x, y (metres).
    pub track: Vec<(u32, f64, f64)>,
    /// What differed, one line each (events only in one run, the track's difference).
    pub lines: Vec<String>,
}

/// Retraces `bytes` with `params` changed. Err: what and where, as `station retrace` says it.
pub fn overlay(bytes: &[u8], params: &[(u16, f32)]) -> Result<RetraceOverlay, String> {
    let loaded = load(bytes)?;
    if loaded.trace.is_empty() {
        return Err("no hardware trace in it (parameter 34 hal_trace)".into());
    }
    let base = retrace(&loaded, &[], None)?;
    let changed = if params.is_empty() {
        base.clone()
    } else {
        retrace(&loaded, params, None)?
    };
    let label = if params.is_empty() {
        "as recorded".to_string()
    } else {
        params
            .iter()
            .map(|&(id, v)| {
                let name = robot_firmware::params::info(id).map_or("?", |i| i.name);
                format!("{name}={v}")
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let track = changed
        .poses
        .iter()
        .map(|(t, p)| (*t, f64::from(p.x), f64::from(p.y)))
        .collect();
    let (only_recorded, only_retraced) =
        diff_events(&events(&base.frames), &events(&changed.frames));
    let max_m = base
        .poses
        .iter()
        .zip(&changed.poses)
        .map(|((_, p), (_, q))| f64::from(p.x - q.x).hypot(f64::from(p.y - q.y)))
        .fold(0.0, f64::max);
    let mut lines = vec![format!(
        "retrace ({label}): {} cycles; the track differs by {max_m:.3} m at most; {} events only \
         as recorded, {} only retraced; the sensor data stay the recorded ones",
        changed.cycles,
        only_recorded.len(),
        only_retraced.len()
    )];
    for (sign, list) in [("-", &only_recorded), ("+", &only_retraced)] {
        for e in list.iter().take(20) {
            lines.push(format!(
                "retrace {sign} {:.1} s {:?} {}",
                f64::from(e.time_ms) / 1000.0,
                e.code,
                e.value
            ));
        }
    }
    Ok(RetraceOverlay {
        label,
        track,
        lines,
    })
}
