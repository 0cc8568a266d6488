//! Starting the TUI on several robots: `station --port A --port B ...` or `station --robots N`
//! (the built-in emulator with N robots in one world).
//!
//! Layer: the binary's edge for the fleet, the several-robot form of `headless::interactive`.
//! One link task per port, each exactly the single robot's (paced, its own reconnects and
//! handshakes), so a robot that is unplugged, refuses the handshake or has another key
//! changes only its own line. A port that exists but cannot be used (busy, not a tty) is
//! refused before the TUI opens, naming the port, as for one robot; a port not there yet is
//! waited for. What can fail: the terminal, the arena, the emulator, those ports.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context as _};

use super::{Fleet, Member, MAX_ROBOTS};
use crate::app::arena::ArenaOverlay;
use crate::app::{App, AppOptions};
use crate::link::serial::{open_exclusive, SerialConnector};
use crate::link::{spawn_link, LinkOptions};
use crate::plan::PlanState;

/// Runs the TUI on `ports`, or on the built-in emulator with `robots` robots when `ports` is
/// empty.
pub async fn interactive(
    ports: &[PathBuf],
    robots: usize,
    baud: u32,
    arena: Option<&Path>,
    profile: Option<&'static robot_firmware::Profile>,
    key: Option<[u8; protocol::sign::KEY_LEN]>,
    tui: &crate::cli::TuiArgs,
) -> anyhow::Result<ExitCode> {
    // Before the terminal check: a wrong command line is said as such, anywhere.
    if ports.len() > MAX_ROBOTS {
        bail!(
            "{} ports given: the station drives at most {MAX_ROBOTS} robots at once",
            ports.len()
        );
    }
    crate::commands::args::distinct_ports(ports.iter().map(PathBuf::as_path))
        .map_err(anyhow::Error::msg)?;
    if !std::io::stdout().is_terminal() {
        bail!("the TUI needs a terminal; for scripts use `station send` or `station stats`");
    }
    let mut plan = PlanState::default();
    let mut overlay: Option<ArenaOverlay> = None;
    if let Some(p) = arena {
        let name = p.to_string_lossy();
        let load = if ports.is_empty() {
            emulator::arena::LoadOptions::for_simulation()
        } else {
            emulator::arena::LoadOptions::default()
        };
        let a = emulator::builtin::load(&name, &load)
            .with_context(|| format!("cannot load arena {}", p.display()))?;
        let o = ArenaOverlay::from_arena(&a);
        if o.forage.is_none() {
            plan = PlanState::for_arena(&a, &p.display().to_string());
        }
        overlay = Some(o);
    }
    // Keeps the built-in emulator alive for the whole session.
    let mut builtin = None;
    let targets: Vec<(PathBuf, String)> = if ports.is_empty() {
        let simulated = arena.map(|p| p.to_string_lossy().into_owned());
        let emu = crate::builtin::start_builtin_fleet(
            robots,
            simulated.as_deref(),
            profile,
            key.as_ref(),
        )?;
        if overlay.is_none() {
            overlay = emu.arena.clone();
            plan = PlanState::for_builtin();
        }
        let t = emu
            .paths()
            .iter()
            .zip(emu.pty_paths())
            .map(|(link, pty)| {
                (
                    link.clone(),
                    format!("built-in emulator on {}", pty.display()),
                )
            })
            .collect();
        builtin = Some(emu);
        t
    } else {
        for p in ports {
            match open_exclusive(p, baud) {
                Ok(port) => drop(port),
                Err(crate::link::transport::OpenError::NotFound { .. }) => {}
                Err(e) => {
                    return Err(anyhow::Error::new(e).context(format!("port {}", p.display())))
                }
            }
        }
        ports
            .iter()
            .map(|p| (p.clone(), p.display().to_string()))
            .collect()
    };
    // The `R` key records every robot's link into one file (link id `i` = robot `i`): each
    // link its own tap and clock origin, taken just before it is spawned.
    let ports: Vec<String> = targets.iter().map(|(_, l)| l.clone()).collect();
    let mut meta = crate::record::Meta::now_links(&ports, baud);
    meta.arena = match (arena, &builtin) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(_)) => emulator::builtin::MICRO_RATO_99.to_string(),
        (None, None) => String::new(),
    };
    let mut taps = Vec::with_capacity(targets.len());
    let mut links = Vec::with_capacity(targets.len());
    let mut members = Vec::with_capacity(targets.len());
    let mut shares = Vec::with_capacity(targets.len());
    for (path, label) in &targets {
        let (tap, tapped) = tokio::sync::mpsc::unbounded_channel();
        taps.push((tapped, tokio::time::Instant::now()));
        let link = spawn_link(
            SerialConnector::new(path, baud).paced(true),
            LinkOptions {
                tap: Some(tap),
                paced: true,
                key: key.map(|k| protocol::LinkKey::new(&k)),
                ..LinkOptions::default()
            },
        );
        let mut app = App::new(AppOptions {
            port_label: label.clone(),
            arena: overlay.clone(),
            click_goes: tui.click_goes,
            record_hal_trace: tui.record_hal_trace,
        });
        app.map.plan = plan.clone();
        app.map.hidden.push(crate::ui::map_layers::REGIONS);
        let (link, guard) = share_link(link, path, &mut app);
        links.push(link);
        shares.push(guard);
        members.push(Member {
            app,
            port: path.display().to_string(),
        });
    }
    let recorder =
        crate::record::live::TuiRecorder::new_links(taps, meta).in_dir_or(tui.record_dir());
    crate::tui::run_fleet(Fleet::new(members), links, recorder).await?;
    drop(shares);
    drop(builtin);
    Ok(ExitCode::SUCCESS)
}

/// Shares a robot's link with the user's other station programs (`station_core::share`), and
/// says so in the robot's log: where the socket is, or why the link is not shared. The guard
/// keeps the socket until the TUI ends.
pub fn share_link(
    link: crate::link::RunningLink,
    port: &std::path::Path,
    app: &mut App,
) -> (crate::link::RunningLink, Option<crate::share::Shared>) {
    use crate::app::log::Level;
    let path = crate::share::socket_path(port);
    let shown =
        |p: &std::path::Path| crate::terminal_text::printable(&p.display().to_string()).to_string();
    match crate::share::share_link(link, &path) {
        Ok((link, shared)) => {
            app.note_link(
                Level::Info,
                format!(
                    "shared: `station ... --port {}` from another terminal goes through this \
                     station ({})",
                    shown(port),
                    shown(&path)
                ),
            );
            (link, Some(shared))
        }
        Err((link, why)) => {
            app.note_link(Level::Warn, format!("link not shared: {why}"));
            (link, None)
        }
    }
}
