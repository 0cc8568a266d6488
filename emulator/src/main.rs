//! `robot-emulator`: thin binary over the emulator library (see `cli.rs`).

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::Parser;
use emulator::cli::{Cli, Command, RunArgs, ServeArgs};

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Run(args)) => run(&args),
        Some(Command::Serve(args)) => serve(&args),
        None => serve(&cli.serve),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("robot-emulator: {message}");
            ExitCode::FAILURE
        }
    }
}

fn serve(args: &ServeArgs) -> Result<(), String> {
    let opts = args.options()?;
    let profile = opts.sim.profile.name;
    let arena_name = opts.arena.clone();
    let arena = emulator::builtin::load(&opts.arena, &opts.load).map_err(|e| e.to_string())?;
    let sim = emulator::sim::Sim::new(arena, opts.sim.clone()).map_err(|e| e.to_string())?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
    let link = opts.serve.link.clone();
    let mut sim = sim;
    let stats = emulator::link::serve(&mut sim, &opts.serve, &stop, &mut |path| {
        // The one line a script waits for: the port to open.
        println!("{}", path.display());
        if let Some(l) = &link {
            eprintln!(
                "robot-emulator: {profile} in {arena_name} on {} (link {})",
                path.display(),
                l.display()
            );
        } else {
            eprintln!(
                "robot-emulator: {profile} in {arena_name} on {}",
                path.display()
            );
        }
    })
    .map_err(|e| e.to_string())?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&stats).map_err(|e| e.to_string())?
        );
    }
    Ok(())
}

fn run(args: &RunArgs) -> Result<(), String> {
    let opts = args.options()?;
    let arena = emulator::builtin::load(&args.world.arena, &load_options(args))
        .map_err(|e| e.to_string())?;
    let report = emulator::scenario::run_scenario(arena, opts).map_err(|e| e.to_string())?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&report).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "{}: {} in {:.1} s simulated ({:.3} s wall), {} collisions, {:.2} m travelled, \
             pose error {:.3} m, goal error {:.3} m",
            report.arena,
            if report.reached {
                "reached"
            } else {
                "NOT reached"
            },
            report.sim_s,
            report.wall_s,
            report.collisions,
            report.distance_m,
            report.pose_error_m,
            report.goal_error_m
        );
    }
    Ok(())
}

fn load_options(args: &RunArgs) -> emulator::arena::LoadOptions {
    let mut load = emulator::arena::LoadOptions::default();
    if let Some(g) = &args.world.grid {
        load.ciberrato_grid = emulator::arena::GridFile::Path(g.clone());
    }
    load
}
