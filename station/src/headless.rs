//! What each command line form does: the TUI (on a port or the built-in emulator), `ports`,
//! `send` and `stats`.
//!
//! Layer: the binary's edge (anyhow lives here and in `main`). Headless commands start the same
//! link task as the TUI, wait for the handshake (failing at once, with the reason, when the
//! port cannot be opened or the robot refuses us), do their one thing and print plain text or
//! JSON. Exit codes: 0 done, 1 refused / unanswered / port unusable, 2 usage (clap); a wait
//! (`send --wait`, `watch`) has its own for each way it ends (`commands::wait::CODES`).

use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

use clap::Parser;

use anyhow::{bail, Context as _};

use crate::app::arena::ArenaOverlay;
use crate::app::{App, AppOptions};
use crate::builtin::start_builtin_emulator_with;
use crate::cli::{Cli, Sub};
use crate::commands::ports::ports;
use crate::commands::send::{send, SendArgs};
use crate::commands::stats::stats;
use crate::link::serial::{open_exclusive, SerialConnector};
use crate::link::{spawn_link, LinkOptions};
use crate::plan::PlanState;

/// Runs what the command line asked for.
/// Runs what the command line asked for.
pub async fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        None => {
            let key = crate::commands::args::load_key_bytes(cli.port.key_file.as_deref())
                .map_err(anyhow::Error::msg)?;
            // Several robots: one link each (`fleet`).
            if cli.port.port.len() > 1 || cli.port.robots.is_some_and(|n| n > 1) {
                return crate::fleet::start::interactive(
                    &cli.port.port,
                    cli.port.robots.map_or(0, usize::from),
                    cli.port.baud,
                    cli.arena.as_deref(),
                    cli.profile.map(|p| p.profile()),
                    key,
                    &cli.tui,
                )
                .await;
            }
            interactive(
                cli.port.port.first().map(|p| p.as_path()),
                cli.port.baud,
                cli.arena.as_deref(),
                cli.profile.map(|p| p.profile()),
                key,
                cli.start,
                &cli.tui,
            )
            .await
        }
        Some(Sub::Ports { json }) => ports(json),
        Some(Sub::Send {
            port,
            json,
            timeout,
            repeat,
            wait,
            command,
        }) => {
            send(SendArgs {
                port: &port,
                json,
                timeout,
                repeat,
                wait,
                cmd: &command,
            })
            .await
        }
        Some(Sub::Watch(args)) => crate::commands::watch::run(&args).await,
        Some(Sub::Status(args)) => crate::commands::status::run(&args).await,
        Some(Sub::Stats {
            port,
            seconds,
            json,
            timeout,
        }) => stats(&port, seconds, json, timeout).await,
        Some(Sub::Params(args)) => crate::commands::params::run(&args).await,
        Some(Sub::UploadMap(args)) => crate::commands::transfer::upload_map(&args).await,
        Some(Sub::DownloadMap(args)) => crate::commands::transfer::download_map(&args).await,
        Some(Sub::UploadPlan(args)) => crate::commands::transfer::upload_plan(&args).await,
        Some(Sub::Plan(args)) => crate::commands::plan::plan(&args),
        Some(Sub::Segment(args)) => crate::commands::plan::segment(&args),
        Some(Sub::Record(args)) => crate::commands::record::run(&args).await,
        Some(Sub::Replay(args)) => crate::commands::replay::run(&args).await,
        Some(Sub::Export(args)) => crate::commands::export::run(&args),
        Some(Sub::Retrace(args)) => crate::commands::retrace::run(&args),
        Some(Sub::Calibrate(args)) => crate::commands::calibrate::dispatch(&args).await,
        Some(Sub::UploadCalibration(args)) => crate::commands::calibration::upload(&args).await,
        Some(Sub::DownloadCalibration(args)) => crate::commands::calibration::download(&args).await,
        Some(Sub::Places(args)) => crate::places::command(&args),
    }
}

async fn interactive(
    port: Option<&Path>,
    baud: u32,
    arena: Option<&Path>,
    profile: Option<&'static robot_firmware::Profile>,
    key: Option<[u8; protocol::sign::KEY_LEN]>,
    start: Option<[f64; 3]>,
    tui: &crate::cli::TuiArgs,
) -> anyhow::Result<ExitCode> {
    if !std::io::stdout().is_terminal() {
        bail!("the TUI needs a terminal; for scripts use `station send` or `station stats`");
    }
    let arena_path = arena;
    // One load gives the drawing and the planner's grid (`plan::PlanState::for_arena`).
    let mut plan = PlanState::default();
    let mut arena = match arena {
        Some(p) => {
            // Built-in names (`builtin:forage`) as well as files.
            let name = p.to_string_lossy();
            // Without --port the built-in emulator simulates it: its world limit applies here
            // too, so a world it would refuse is refused before the drawing's walls are built.
            let load = if port.is_none() {
                emulator::arena::LoadOptions::for_simulation()
            } else {
                emulator::arena::LoadOptions::default()
            };
            let a = emulator::builtin::load(&name, &load)
                .with_context(|| format!("cannot load arena {}", p.display()))?;
            let overlay = ArenaOverlay::from_arena(&a);
            // Foraging does not plan, and a 0.3 m planning grid over a 1 m box is all walls.
            if overlay.forage.is_none() {
                plan = PlanState::for_arena(&a, &p.display().to_string());
            }
            Some(overlay)
        }
        None => None,
    };
    // Keeps the built-in emulator alive for the whole session.
    let mut builtin = None;
    let (path, label) = match port {
        Some(p) => {
            // Fail now, with the reason, rather than open a TUI on a port that cannot work
            // (busy, not a tty, no permission). A port that is not there yet is waited for, as
            // after an unplug: people start the station before plugging the robot in.
            match open_exclusive(p, baud) {
                Ok(port) => drop(port),
                Err(crate::link::transport::OpenError::NotFound { .. }) => {}
                Err(e) => return Err(e.into()),
            }
            (p.to_path_buf(), p.display().to_string())
        }
        None => {
            let simulated = arena_path.map(|p| p.to_string_lossy().into_owned());
            let mut emu =
                start_builtin_emulator_with(simulated.as_deref(), profile, key.as_ref(), start)?;
            let label = format!("built-in emulator on {}", emu.pty_path().display());
            if arena.is_none() {
                arena = emu.arena.clone();
                plan = PlanState::for_builtin();
            }
            let path = emu.path().to_path_buf();
            builtin = Some(emu);
            (path, label)
        }
    };
    // The tap feeds the record key (`R`); the recorder drops it while not recording.
    let (tap, taps) = tokio::sync::mpsc::unbounded_channel();
    let mut meta = crate::record::Meta::now(&label, baud);
    meta.arena = match (arena_path, &builtin) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(_)) => emulator::builtin::MICRO_RATO_99.to_string(),
        (None, None) => String::new(),
    };
    let epoch = tokio::time::Instant::now();
    // Paced: the TUI shows the link at most 10 times a second, so reading it every 25 ms on
    // the TUI's own timer grid costs nobody anything and saves most wake-ups
    // (docs/performance.md, the TUI CPU rows).
    let link = spawn_link(
        SerialConnector::new(&path, baud).paced(true),
        LinkOptions {
            tap: Some(tap),
            paced: true,
            key: key.map(|k| protocol::LinkKey::new(&k)),
            ..LinkOptions::default()
        },
    );
    let recorder =
        crate::record::live::TuiRecorder::new(taps, epoch, meta).in_dir_or(tui.record_dir());
    let mut app = App::new(AppOptions {
        port_label: label,
        arena,
        click_goes: tui.click_goes,
        record_hal_trace: tui.record_hal_trace,
    });
    app.map.plan = plan;
    // The squares are busy on a small map panel: `r` shows them.
    app.map.hidden.push(crate::ui::map_layers::REGIONS);
    let (link, shared) = crate::fleet::start::share_link(link, &path, &mut app);
    crate::tui::run(app, link, recorder).await?;
    drop(shared);
    drop(builtin);
    Ok(ExitCode::SUCCESS)
}

/// Parses the process arguments and runs; the exit code to return.
pub fn run() -> ExitCode {
    // Before the TUI's own hook, which chains to this one.
    emulator::cli::exit_quietly_on_broken_pipe();
    let cli = Cli::parse();
    // Just before the runtime's clock starts: the TUI's timers then share its wake-ups.
    crate::pace::start();
    let rt = match tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
    {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("station: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    match rt.block_on(crate::headless::dispatch(cli)) {
        Ok(code) => code,
        Err(e) => {
            // Errors quote file names, file contents and robot refusals.
            eprintln!(
                "station: {}",
                crate::terminal_text::printable_text(&error_text(&e))
            );
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, `: `-separated, leaving out a cause the message before it
/// already ends with (our file errors say "{path}: {source}" and keep the source as a cause).
fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.ends_with(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_that_already_quotes_its_cause_prints_it_once() {
        let read = crate::record::RecordError::Read {
            path: "x.rec".into(),
            source: crate::record::ReadError::Truncated { offset: 12 },
        };
        let e = anyhow::Error::new(read).context("cannot replay");
        assert_eq!(
            error_text(&e),
            "cannot replay: x.rec: truncated at byte 12: the file ends inside a record (a torn tail)"
        );
    }
}
