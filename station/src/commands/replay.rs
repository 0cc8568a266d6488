//! `station replay FILE`: the TUI driven by a recording, or its summary with `--json`.
//!
//! Layer: the binary's edge (anyhow). Reads the file leniently: a torn or damaged tail is
//! replayed up to the last good record and reported (on screen in red and in the log; in the
//! summary as `damage`). Exit codes: 0 done, 1 the file cannot be read as a recording (missing,
//! not a recording, another version) or, for the summary, is damaged; 2 usage.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};
use clap::Args;

use crate::app::arena::ArenaOverlay;
use crate::app::AppOptions;
use crate::record::Recording;
use crate::replay::session::ReplaySession;
use station_core::replay::summary::{summarize, text};

/// Arguments of `station replay`.
#[derive(Debug, Args, Clone)]
pub struct ReplayArgs {
    /// The recording (`station record`, or `R` in the TUI); a `.partial` one is read up to
    /// its last good record.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Playback speed, 0.1 to 128 (1 = as recorded).
    #[arg(long, default_value_t = 1.0, value_parser = parse_speed)]
    pub speed: f64,
    /// Print a summary (duration, frames by kind, telemetry rate, gaps, errors) as JSON and
    /// exit, without a terminal.
    #[arg(long)]
    pub json: bool,
    /// Print the summary as text and exit.
    #[arg(long, conflicts_with = "json")]
    pub summary: bool,
    /// An arena file to draw under the map (default: the one recorded, when it can be found).
    #[arg(long, value_name = "FILE")]
    pub arena: Option<PathBuf>,
    /// Overlay the run retraced through the firmware's own code over its hardware trace (see
    /// `station retrace`): its track in yellow, the events that differ in the log.
    #[arg(long)]
    pub retrace: bool,
    /// With --retrace: retrace with this parameter changed (NAME=VALUE; repeat for several).
    /// The sensor data stay the recorded ones: a changed algorithm would have moved the robot
    /// elsewhere.
    #[arg(long = "param", value_name = "NAME=VALUE", requires = "retrace",
          value_parser = crate::retrace::parse_param)]
    pub params: Vec<(u16, f32)>,
}

fn parse_speed(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && (0.1..=128.0).contains(&v) => Ok(v),
        Ok(v) => Err(format!("{v} is out of range (0.1 ..= 128)")),
        Err(_) => Err(format!("{s:?} is not a number")),
    }
}

/// Runs `station replay`.
pub async fn run(args: &ReplayArgs) -> anyhow::Result<ExitCode> {
    let rec = Recording::open(&args.file)?;
    let file = args.file.display().to_string();
    if let Some(w) = rec.meta.schema_warning() {
        eprintln!("station: {file}: {w}");
    }
    if (args.json || args.summary) && rec.link_count() > 1 {
        let s = station_core::replay::links::summarize_links(&rec);
        if args.json {
            println!(
                "{}",
                crate::json_text::pretty(&s).context("cannot print JSON")?
            );
        } else {
            print!(
                "{}",
                crate::terminal_text::printable_text(&station_core::replay::links::text(&file, &s))
            );
        }
        for d in &s.duplicate_robot_ids {
            eprintln!(
                "station: {file}: {}",
                crate::terminal_text::printable_text(&d.warning())
            );
        }
        if let Some(d) = &rec.damage {
            eprintln!("station: {file}: {d}");
            return Ok(ExitCode::FAILURE);
        }
        return Ok(ExitCode::SUCCESS);
    }
    if args.json || args.summary {
        let s = summarize(&rec);
        if args.json {
            println!(
                "{}",
                crate::json_text::pretty(&s).context("cannot print JSON")?
            );
        } else {
            // The summary quotes the recording's metadata and link texts.
            print!("{}", crate::terminal_text::printable_text(&text(&file, &s)));
        }
        if let Some(d) = &rec.damage {
            eprintln!("station: {file}: {d}");
            return Ok(ExitCode::FAILURE);
        }
        return Ok(ExitCode::SUCCESS);
    }
    if !std::io::stdout().is_terminal() {
        bail!("the replay needs a terminal; for a summary use `station replay FILE --json`");
    }
    let arena = arena(args.arena.as_deref(), &rec.meta.arena)?;
    let name = args
        .file
        .file_name()
        .map_or(file.clone(), |n| n.to_string_lossy().into_owned());
    let label = format!("replay {name}");
    let retrace = if args.retrace {
        let params = args.params.clone();
        let bytes = crate::record::read_file(&args.file)?;
        let o = crate::retrace::overlay::overlay(&bytes, &params)
            .map_err(|e| anyhow::anyhow!("cannot retrace: {file}: {e}"))?;
        Some(std::sync::Arc::new(o))
    } else {
        None
    };
    let session = ReplaySession::new(
        rec,
        &name,
        AppOptions {
            port_label: label.clone(),
            arena,
            ..AppOptions::default()
        },
        args.speed,
    )
    .with_retrace(retrace);
    crate::replay::tui::run(session).await?;
    Ok(ExitCode::SUCCESS)
}

/// The arena to draw: the one asked for (an error if it cannot be loaded), else the recorded
/// one if it loads (the built-in arena always does), else none.
fn arena(asked: Option<&Path>, recorded: &str) -> anyhow::Result<Option<ArenaOverlay>> {
    if let Some(p) = asked {
        return ArenaOverlay::load(p)
            .map(Some)
            .with_context(|| format!("cannot load arena {}", p.display()));
    }
    if recorded.is_empty() {
        return Ok(None);
    }
    Ok(
        emulator::builtin::load(recorded, &emulator::arena::LoadOptions::default())
            .ok()
            .map(|a| ArenaOverlay::from_arena(&a)),
    )
}
