//! `station places`: Mächler's unsupervised landmarks and places (seed 003 ch. 3) on the
//! station. It runs the `unsupervised-places` scenario here, with the firmware's own
//! `robot_firmware::unsupervised` code (classifiers, landmark store, places) in the loop, and
//! plays the run back on screen: landmarks on the map, the three class streams, matches as
//! they happen, plain odometry, wheels plus compass heading and compass plus landmarks (the
//! corrected estimate) against the truth, and the error over time.
//!
//! Why on the station: no robot profile carries this capability (docs/reproductions.md, "Unsupervised
//! landmarks"): the Khepera firmware has neither the thesis's line camera nor a compass, and
//! the module's state (about 100 KB) is three times the Dom Dinis board's whole RAM. The code
//! is the same `no_std` code either way.
//!
//! Layer: the binary's edge (anyhow) around [`view`], which only draws. Exit codes: 0 done,
//! 1 bad arguments (clap's 2 for unknown flags).

pub mod view;

use std::io::IsTerminal;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{bail, Context as _};
use clap::Args;
use emulator::scenarios::unsupervised_places::{
    generate, run, ArenaKind, PlacesOptions, MAX_DURATION_S,
};
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind};

use view::PlacesView;

/// Arguments of `station places`.
#[derive(Debug, Args, Clone)]
pub struct PlacesArgs {
    /// The generated arena: unstructured (irregular obstacles) or structured (right angles).
    #[arg(long, default_value = "unstructured")]
    pub arena: String,
    /// Seed of the arena, the noise and the wandering.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Simulated seconds, 1 to 36000.
    #[arg(long, default_value_t = 1200.0)]
    pub duration: f64,
    /// Playback speed: simulated seconds per second, 0.1 to 1000.
    #[arg(long, default_value_t = 20.0)]
    pub speed: f64,
    /// Print the run's summary (landmarks, matches, peak errors) as JSON and exit, without a
    /// terminal.
    #[arg(long)]
    pub json: bool,
}

/// The scenario options these arguments describe, or what is wrong with them.
pub fn options(args: &PlacesArgs) -> anyhow::Result<PlacesOptions> {
    let kind = ArenaKind::parse(&args.arena).map_err(|e| anyhow::anyhow!(e))?;
    if !(args.duration.is_finite() && (1.0..=MAX_DURATION_S).contains(&args.duration)) {
        bail!(
            "--duration {}: station places runs 1 to {MAX_DURATION_S} simulated seconds",
            args.duration
        );
    }
    if !(args.speed.is_finite() && (0.1..=1000.0).contains(&args.speed)) {
        bail!("--speed {}: must be 0.1 to 1000", args.speed);
    }
    let mut o = PlacesOptions::new(kind, args.seed);
    o.duration_s = args.duration;
    o.record_labels = true;
    // Five track points a second: the map's tracks and the error plot stay smooth.
    o.series_every_s = 0.2;
    Ok(o)
}

/// Runs `station places`.
pub fn command(args: &PlacesArgs) -> anyhow::Result<ExitCode> {
    let opts = options(args)?;
    let report = run(&opts);
    if args.json {
        let summary = serde_json::json!({
            "arena": report.arena,
            "seed": report.seed,
            "duration_s": report.duration_s,
            "landmarks": report.landmarks,
            "matches": report.matches,
            "places": report.places,
            "plain_peak": report.plain_peak,
            "plain_mean": report.plain_mean,
            "compass_peak": report.compass_peak,
            "compass_mean": report.compass_mean,
            "corrected_peak": report.corrected_peak,
            "corrected_mean": report.corrected_mean,
            "revisit": report.revisit,
            "significant_classes": report.significant_classes,
            "loss": report.loss,
        });
        println!(
            "{}",
            crate::json_text::pretty(&summary).context("cannot print JSON")?
        );
        return Ok(ExitCode::SUCCESS);
    }
    if !std::io::stdout().is_terminal() {
        bail!("station places needs a terminal (or --json)");
    }
    let world = generate(opts.arena, opts.seed, opts.lamps);
    let mut view = PlacesView::new(report, &world);
    play(&mut view, args.speed)?;
    Ok(ExitCode::SUCCESS)
}

/// The playback loop: space pauses, left/right step 10 s, Home/End, +/- speed, q quits.
fn play(view: &mut PlacesView, mut speed: f64) -> anyhow::Result<()> {
    let mut terminal = crate::tui::init_terminal().context("cannot start the terminal")?;
    let result = (|| -> anyhow::Result<()> {
        let mut paused = false;
        let mut last = Instant::now();
        loop {
            let now = Instant::now();
            if !paused {
                view.advance(now.duration_since(last).as_secs_f64() * speed);
            }
            last = now;
            terminal.draw(|f| view::render(f, view, speed, paused))?;
            if !event::poll(Duration::from_millis(50))? {
                continue;
            }
            let ev = event::read()?;
            crate::tui::resize(&mut terminal, &ev)?;
            let Event::Key(k) = ev else { continue };
            if k.kind != KeyEventKind::Press {
                continue;
            }
            match k.code {
                KeyCode::Char('q') | KeyCode::Esc => return Ok(()),
                KeyCode::Char(' ') => paused = !paused,
                KeyCode::Left => view.advance(-10.0),
                KeyCode::Right => view.advance(10.0),
                KeyCode::Home => view.seek(0.0),
                KeyCode::End => view.seek(f64::INFINITY),
                KeyCode::Char('+') => speed = (speed * 2.0).min(1000.0),
                KeyCode::Char('-') => speed = (speed / 2.0).max(0.1),
                _ => {}
            }
        }
    })();
    crate::tui::restore();
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(arena: &str, duration: f64) -> PlacesArgs {
        PlacesArgs {
            arena: arena.into(),
            seed: 1,
            duration,
            speed: 20.0,
            json: false,
        }
    }

    #[test]
    fn bad_arguments_say_which_and_why() {
        let e = options(&args("bogus", 10.0)).unwrap_err().to_string();
        assert!(e.contains("--arena \"bogus\""), "{e}");
        let e = options(&args("structured", 0.0)).unwrap_err().to_string();
        assert!(e.contains("--duration 0"), "{e}");
        let e = options(&args("structured", f64::NAN))
            .unwrap_err()
            .to_string();
        assert!(e.contains("--duration NaN"), "{e}");
        let o = options(&args("structured", 30.0)).unwrap();
        assert!(o.record_labels && o.duration_s == 30.0);
    }
}
