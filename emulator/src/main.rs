//! `robot-emulator`: thin binary over the emulator library (see `cli.rs`).

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::Parser;
use emulator::cli::{Cli, Command, RunArgs, ServeArgs};

fn main() -> ExitCode {
    emulator::cli::exit_quietly_on_broken_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Run(args)) => run(&args),
        Some(Command::Serve(args)) => serve(&args),
        Some(Command::Arena(args)) => arena(&args),
        Some(Command::Bench(args)) => bench(&args),
        Some(Command::Hil(args)) => hil(&args),
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

fn arena(args: &emulator::cli::ArenaArgs) -> Result<(), String> {
    match &args.command {
        emulator::cli::ArenaCommand::Generate(g) => {
            // Refuse a bad --out before generating anything.
            emulator::arena_gen::out_paths(g.kind, &g.out).map_err(|e| e.to_string())?;
            let arena = emulator::arena_gen::generate(g.kind, g.seed).map_err(|e| e.to_string())?;
            let written =
                emulator::arena_gen::write(&arena, &g.out, g.force).map_err(|e| e.to_string())?;
            for p in written {
                println!("{}", p.display());
            }
            Ok(())
        }
    }
}

/// `hil`: the world for a board running the firmware itself (emulator::hil).
fn hil(args: &emulator::cli::HilArgs) -> Result<(), String> {
    let port = args.port()?;
    let when = args.stop_when()?;
    let key = args
        .key_file
        .as_deref()
        .map(|p| emulator::link::read_key_file(p).map_err(|e| format!("--key-file: {e}")))
        .transpose()?;
    let cfg = args.world.sim_config(emulator::uart::DEFAULT_BAUD)?;
    let arena =
        load_arena(args.world.arena(), &args.world.load_options()).map_err(|e| e.to_string())?;
    let sim = emulator::sim::Sim::new(arena, cfg).map_err(|e| e.to_string())?;
    let mut world = emulator::hil::HilWorld::new(sim, key, args.power_on_mode.mode())
        .map_err(|e| e.to_string())?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
    let link = args.link.clone();
    let profile = args.world.profile.profile().name;
    let arena_name = args.world.arena().to_string();
    let mut link_err = None;
    let summary = emulator::hil::serve::serve(&mut world, &port, &stop, when, &mut |pty| {
        // The one line a script waits for: the station's port.
        println!("{}", pty.display());
        if let Some(l) = &link {
            let _ = std::fs::remove_file(l);
            if let Err(e) = std::os::unix::fs::symlink(pty, l) {
                link_err = Some(format!("--link {}: {e}", l.display()));
            }
        }
        eprintln!(
            "robot-emulator: {profile} in {arena_name}, board in the loop, station port {}",
            pty.display()
        );
    });
    if let Some(l) = &link {
        let _ = std::fs::remove_file(l);
    }
    if let Some(e) = link_err {
        return Err(e);
    }
    let summary = summary?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&summary).map_err(|e| e.to_string())?
        );
    }
    match summary.fault {
        Some(f) => Err(format!("the board stopped: {f}")),
        None => Ok(()),
    }
}

fn bench(args: &emulator::cli::BenchArgs) -> Result<(), String> {
    let opts = args.options()?;
    if opts.robots > 1 {
        let report = emulator::scenarios::fleet_bench::run(&opts);
        if args.json {
            println!(
                "{}",
                emulator::json_text::compact(&report).map_err(|e| e.to_string())?
            );
        } else {
            print!("{}", emulator::scenarios::fleet_bench::render(&report));
        }
        return Ok(());
    }
    let report = emulator::scenarios::bench::run(&opts);
    if args.json {
        println!(
            "{}",
            emulator::json_text::compact(&report).map_err(|e| e.to_string())?
        );
    } else {
        print!("{}", emulator::scenarios::bench::render(&report));
    }
    Ok(())
}

fn serve(args: &ServeArgs) -> Result<(), String> {
    if let Some(robots) = args.robots()? {
        return serve_fleet(args, &robots);
    }
    let opts = args.options()?;
    let profile = opts.sim.profile.name;
    let arena_name = opts.arena.clone();
    let arena = load_arena(&opts.arena, &opts.load).map_err(|e| e.to_string())?;
    let sim = emulator::sim::Sim::new(arena, opts.sim.clone()).map_err(|e| e.to_string())?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
    let link = opts.serve.link.clone();
    let mut sim = sim;
    let bias = sim.wheel_bias();
    if args.hal_trace {
        // As the station would set it, before the first pass of the main loop.
        let on = protocol::Command::SetParam {
            id: protocol::ParamId(robot_firmware::params::id::HAL_TRACE),
            value: 1.0,
        };
        sim.robot_mut().apply(on, 0);
        let mut dev = emulator::power_on::PoweredByStation::new(sim);
        let stats = serve_device(&mut dev, &opts.serve, &stop, profile, &arena_name, link)?;
        return print_stats(args, stats, bias);
    }
    let stats = serve_device(&mut sim, &opts.serve, &stop, profile, &arena_name, link)?;
    print_stats(args, stats, bias)
}

/// `--json`: the link's counters, and the truth a calibration is judged against (never sent
/// to the station).
fn print_stats(args: &ServeArgs, stats: serde_json::Value, bias: [f64; 2]) -> Result<(), String> {
    if args.json {
        let mut v = stats;
        if let Some(o) = v.as_object_mut() {
            o.insert("wheel_bias".into(), serde_json::json!(bias));
            o.insert(
                "true_ratio_ppm".into(),
                serde_json::json!(((1.0 + bias[1]) / (1.0 + bias[0]) - 1.0) * 1e6),
            );
        }
        println!(
            "{}",
            emulator::json_text::compact(&v).map_err(|e| e.to_string())?
        );
    }
    Ok(())
}

fn serve_device<D: emulator::link::Device>(
    dev: &mut D,
    serve: &emulator::link::ServeOptions,
    stop: &AtomicBool,
    profile: &str,
    arena_name: &str,
    link: Option<std::path::PathBuf>,
) -> Result<serde_json::Value, String> {
    let stats = emulator::link::serve(dev, serve, stop, &mut |path| {
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
    serde_json::to_value(&stats).map_err(|e| e.to_string())
}

/// Several robots, one pty each: prints each robot's pty path on its own line, in robot
/// order (the lines a script waits for), then again after a replug.
fn serve_fleet(args: &ServeArgs, robots: &[emulator::fleet::RobotSpec]) -> Result<(), String> {
    let n = robots.len();
    let links = (1..=n)
        .map(|k| args.link_options(k, n))
        .collect::<Result<Vec<_>, String>>()?;
    let base = args.world.sim_config(args.baud)?;
    let arena =
        load_arena(args.world.arena(), &args.world.load_options()).map_err(|e| e.to_string())?;
    let arena_name = args.world.arena().to_string();
    let mut fleet = emulator::fleet::Fleet::new(arena, &base, robots).map_err(|e| e.to_string())?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
    let names: Vec<&str> = robots.iter().map(|r| r.profile.name).collect();
    let stats = emulator::fleet::serve::serve(&mut fleet, &links, &stop, &mut |i, path| {
        println!("{}", path.display());
        let link = links
            .get(i)
            .and_then(|l| l.link.as_ref())
            .map(|l| format!(" (link {})", l.display()))
            .unwrap_or_default();
        eprintln!(
            "robot-emulator: robot {} ({}) in {arena_name} on {}{link}",
            i + 1,
            names.get(i).copied().unwrap_or(""),
            path.display()
        );
    })
    .map_err(|e| e.to_string())?;
    if args.json {
        println!(
            "{}",
            emulator::json_text::compact(&stats).map_err(|e| e.to_string())?
        );
    }
    Ok(())
}

fn run(args: &RunArgs) -> Result<(), String> {
    if let Some(opts) = args.contest_options()? {
        let arena = load_arena(args.world.arena(), &args.world.load_options())
            .map_err(|e| e.to_string())?;
        let report =
            emulator::scenarios::contest::run_contest(arena, &opts).map_err(|e| e.to_string())?;
        if args.json {
            println!(
                "{}",
                emulator::json_text::compact(&report).map_err(|e| e.to_string())?
            );
        } else {
            print!("{}", emulator::scenarios::contest::render(&report));
        }
        return Ok(());
    }
    if args.task == emulator::cli::TaskArg::LineCorrect {
        return line_correct(args);
    }
    if args.task == emulator::cli::TaskArg::AliceNavigation {
        return alice_navigation(args);
    }
    if let Some(run) = alice_experiment(args.task) {
        return alice(args, run);
    }
    if args.task == emulator::cli::TaskArg::UnsupervisedPlaces {
        return unsupervised_places(args);
    }
    if args.task == emulator::cli::TaskArg::Forage {
        return forage(args);
    }
    if args.task == emulator::cli::TaskArg::LightMap {
        return light_map(args);
    }
    if args.task == emulator::cli::TaskArg::OdometryLaps {
        return odometry_laps(args);
    }
    let mut opts = args.options()?;
    let arena =
        load_arena(args.world.arena(), &args.world.load_options()).map_err(|e| e.to_string())?;
    let calibration = if args.calibrate_odometry {
        let c = emulator::scenarios::calibrate_odometry::calibrate_before(&arena, &mut opts)
            .map_err(|e| e.to_string())?;
        Some(c)
    } else {
        None
    };
    let report = emulator::scenarios::task::run_scenario(arena, opts).map_err(|e| e.to_string())?;
    if args.json {
        let mut v = serde_json::to_value(&report).map_err(|e| e.to_string())?;
        if let (Some(obj), Some(c)) = (v.as_object_mut(), &calibration) {
            obj.insert(
                "calibration".into(),
                serde_json::to_value(c).map_err(|e| e.to_string())?,
            );
        }
        println!("{}", run_json(&v)?);
    } else {
        if let Some(c) = &calibration {
            println!(
                "odometry calibration: {} in {:.0} s simulated (wheel ratio {} ppm, distance {} mm)",
                c.error.as_deref().unwrap_or("done"),
                c.sim_s,
                c.wheel_ratio_ppm.map_or("-".into(), |r| format!("{r:.0}")),
                c.wheel_distance_mm.map_or("-".into(), |d| format!("{d:.3}"))
            );
        }
        println!(
            "{}: {} in {:.1} s simulated ({:.3} s wall), {} collisions, {:.2} m travelled, \
             pose error {:.3} m, goal error {:.3} m",
            report.arena,
            if report.started_in_target {
                "started inside target"
            } else if report.unreachable && !report.reached {
                "unreachable (no way to the goal for a robot of this size: a gap narrower than it)"
            } else if report.reached {
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

fn forage(args: &RunArgs) -> Result<(), String> {
    let opts = args.options()?;
    let arena = load_arena(args.arena(), &args.world.load_options()).map_err(|e| e.to_string())?;
    let r = emulator::scenarios::forage::run_forage(arena, opts).map_err(|e| e.to_string())?;
    if args.json {
        println!("{}", run_json(&r)?);
        return Ok(());
    }
    println!(
        "{}: {} of {} objects delivered in {:.1} s simulated ({:.2} s wall), {} collisions, \
         {:.2} m travelled",
        r.arena, r.delivered, r.objects, r.sim_s, r.wall_s, r.collisions, r.distance_m
    );
    for (i, h) in r.returns.iter().enumerate() {
        println!(
            "  put-down {}: t {:.1} s, {}, {:.3} m from home centre, pose error {:.3} m, \
             heading error {:+.1} deg",
            i + 1,
            h.time_s,
            if h.delivered {
                "delivered"
            } else {
                "outside home"
            },
            h.from_home_m,
            h.pose_error_m,
            h.heading_error_deg
        );
    }
    Ok(())
}

type AliceRun = fn(
    u64,
    &world_model::Params,
) -> Result<emulator::scenarios::alice::experiments::ExperimentReport, String>;

/// The ALICE experiment a task names.
fn alice_experiment(task: emulator::cli::TaskArg) -> Option<AliceRun> {
    use emulator::cli::TaskArg;
    use emulator::scenarios::alice::experiments as x;
    match task {
        TaskArg::AliceEquilibrium => Some(x::equilibrium),
        TaskArg::AliceEpsO => Some(x::eps_o),
        TaskArg::AliceCorrelation => Some(x::correlation),
        TaskArg::AliceDynamic => Some(x::dynamic),
        TaskArg::AliceEpsOContinued => Some(x::eps_o_continued),
        _ => None,
    }
}

/// The QT parameters with the `--qt-param NAME=VALUE` changes.
fn qt_params(args: &RunArgs) -> Result<world_model::Params, String> {
    let mut params = world_model::Params::default();
    for kv in &args.qt_param {
        params.assign(kv).map_err(|e| format!("--qt-param {e}"))?;
    }
    Ok(params)
}

fn alice_navigation(args: &RunArgs) -> Result<(), String> {
    use emulator::scenarios::alice::navigation::{navigation, NavOptions};
    let mut options = NavOptions::new(args.world.seed, qt_params(args)?);
    if let Some(d) = args.static_drift {
        if !(d.is_finite() && d.abs() <= 45.0) {
            return Err(format!(
                "--static-drift {d}: expected degrees per metre within -45 ..= 45"
            ));
        }
        options.static_drift_deg_per_m = d;
    }
    options.learn = !args.no_learning;
    options.test_map = if args.adapting_map {
        emulator::scenarios::alice::navigation::TestMap::Adapting
    } else {
        args.test_map
    };
    options.true_pose = args.true_pose;
    options.step_base = args.step_from;
    options.drift = args.drift;
    options.scene = args.scene;
    let r = navigation(&options)?;
    if args.json {
        println!(
            "{}",
            emulator::json_text::compact(&r).map_err(|e| e.to_string())?
        );
        return Ok(());
    }
    println!(
        "ALICE navigation seed {}: map {} cells {} edges, test path cell {} -> {} ({:.2} m) and \
         back, static drift {} deg/m ({:.1} s wall)",
        r.options.seed,
        r.cells,
        r.edges,
        r.start_cell,
        r.target_cell,
        r.path_m,
        r.options.static_drift_deg_per_m,
        r.wall_s
    );
    println!(
        "run  reached  samples  refinements  reversals  steps  failed  blocked  pose_err_m  \
         heading_err_deg  or_applies"
    );
    for (i, t) in r.runs.iter().enumerate() {
        println!(
            "{:>3}  {:>7}  {:>7}  {:>11}  {:>9}  {:>5}  {:>6}  {:>7}  {:>10.2}  {:>15.1}  {:>10.3}",
            i + 1,
            t.legs.iter().filter(|l| l.reached).count(),
            t.samples,
            t.refinements,
            t.reversals,
            t.legs.iter().map(|l| l.steps).sum::<u32>(),
            t.legs.iter().map(|l| l.failed).sum::<u32>(),
            t.legs.iter().map(|l| l.blocked).sum::<u32>(),
            t.localisation_error_m,
            t.heading_error_deg,
            t.correlation.or_applies
        );
    }
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    println!(
        "first run / fifth: time {}x (thesis 2-3), refinements {}x (3-4), reversals {}x (about 5)",
        f(r.time_factor),
        f(r.refinement_factor),
        f(r.reversal_factor)
    );
    Ok(())
}

fn alice(args: &RunArgs, run: AliceRun) -> Result<(), String> {
    let params = qt_params(args)?;
    let r = run(args.world.seed, &params)?;
    if args.json {
        println!(
            "{}",
            emulator::json_text::compact(&r).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "ALICE {} seed {} ({:.1} s wall)",
            r.experiment, r.seed, r.wall_s
        );
        println!(
            "variant                  cells  edges  settled  abs err m  odometry m  crossings/edge  |heading| deg"
        );
        for s in &r.runs {
            println!(
                "{:<24} {:>5} {:>6} {:>8} {:>10.2} {:>11.2} {:>15.3} {:>14.1}",
                s.variant,
                s.cells,
                s.edges,
                s.equilibrium_at.map_or("-".to_string(), |v| v.to_string()),
                s.late_absolute_error_m,
                s.late_odometry_error_m,
                s.crossings_per_edge,
                s.late_heading_error_deg
            );
        }
        if let Some(g) = r.gap_edges_at_removal {
            println!(
                "edges across the wall at its removal: {g}; gap closed after {}",
                r.gap_closed_after
                    .map_or("never".to_string(), |v| format!("{v} samples"))
            );
        }
        if let Some(n) = r.gap_two_sided_at_removal {
            println!("cells winning on both sides of the standing wall: {n}");
        }
    }
    Ok(())
}

fn unsupervised_places(args: &RunArgs) -> Result<(), String> {
    let opts = args.unsupervised_places_options()?;
    let r = emulator::scenarios::unsupervised_places::run(&opts);
    if args.json {
        println!(
            "{}",
            emulator::json_text::compact(&r).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "{:?} arena, seed {}: {:.1} m in {:.0} s simulated ({:.2} s wall), wheel bias \
             {:+.2}/{:+.2} %\n\
             classes (ART-1, K-means, Fuzzy ART) {:?}; {} landmarks ({} bytes each, store {} \
             bytes), {} matches ({} made the error worse), {} places ({} recognitions)\n\
             position error, robot diameters   peak    mean\n\
             plain odometry                 {:>7.2} {:>7.2}\n\
             wheels + compass heading       {:>7.2} {:>7.2}\n\
             compass + landmarks            {:>7.2} {:>7.2}",
            r.arena,
            r.seed,
            r.distance_m,
            r.duration_s,
            r.wall_s,
            r.wheel_bias[0] * 100.0,
            r.wheel_bias[1] * 100.0,
            r.classes,
            r.landmarks,
            r.landmark_bytes,
            r.store_bytes,
            r.matches,
            r.worsening_matches,
            r.places,
            r.places_recognised,
            r.plain_peak,
            r.plain_mean,
            r.compass_peak,
            r.compass_mean,
            r.corrected_peak,
            r.corrected_mean,
        );
    }
    Ok(())
}

fn line_correct(args: &RunArgs) -> Result<(), String> {
    let opts = args.line_correct_options()?;
    let arena =
        load_arena(args.world.arena(), &args.world.load_options()).map_err(|e| e.to_string())?;
    let r = emulator::scenarios::line_correct::run_line_correct(arena, &opts)
        .map_err(|e| e.to_string())?;
    if args.json {
        println!("{}", run_json(&r)?);
    } else {
        println!(
            "{}: {:.1} m in {:.0} s simulated ({:.2} s wall), wheel bias {:+.2}/{:+.2} %, \
             {} pulses of {} true crossings, {} corrections, {} ignored\n\
             position error, mm      max    mean   final\n\
             line-corrected      {:>7.1} {:>7.1} {:>7.1}\n\
             uncorrected         {:>7.1} {:>7.1} {:>7.1}\n\
             nearest-line        {:>7.1} {:>7.1} {:>7.1}",
            r.arena,
            r.distance_m,
            r.sim_s,
            r.wall_s,
            r.wheel_bias[0] * 100.0,
            r.wheel_bias[1] * 100.0,
            r.pulses,
            r.true_crossings,
            r.corrections,
            r.rejected,
            r.corrected.max_mm,
            r.corrected.mean_mm,
            r.corrected.final_mm,
            r.uncorrected.max_mm,
            r.uncorrected.mean_mm,
            r.uncorrected.final_mm,
            r.baseline.max_mm,
            r.baseline.mean_mm,
            r.baseline.final_mm,
        );
    }
    Ok(())
}

/// Loads an arena (built-in name or file) and prints the importer's warnings on stderr: a
/// dropped wall or an unexpected grid file must never go unnoticed.
fn load_arena(
    name: &str,
    opts: &emulator::arena::LoadOptions,
) -> Result<emulator::arena::Arena, emulator::arena::ArenaError> {
    let arena = emulator::builtin::load(name, opts)?;
    for w in &arena.warnings {
        eprintln!("robot-emulator: warning: {w}");
    }
    Ok(arena)
}

/// `--task light-map`: seed 000 §6.1 without and with local correction, same seed.
fn light_map(args: &RunArgs) -> Result<(), String> {
    use emulator::scenarios::lightmap::{run_light_map, LightMapOptions};
    let seed = args.world.seed;
    let without = run_light_map(&LightMapOptions::new(seed, false)).map_err(|e| e.to_string())?;
    let with = run_light_map(&LightMapOptions::new(seed, true)).map_err(|e| e.to_string())?;
    if args.json {
        let both = serde_json::json!({ "without_correction": without, "with_correction": with });
        println!("{both}");
    } else {
        for r in [&without, &with] {
            println!(
                "{} correction: recognised {} times, then {} ({} visits, {:.0} s simulated, {:.1} m)",
                if r.correct { "with" } else { "without" },
                r.recognitions,
                r.ended,
                r.visits.len(),
                r.sim_s,
                r.distance_m
            );
        }
        println!("paper (Khepera foraging, §6.1): 5 without correction; stopped after 24 with it");
    }
    Ok(())
}

/// `--task odometry-laps`: seed 000 §3.3 Tables 1-2 from the counts the robot sends.
fn odometry_laps(args: &RunArgs) -> Result<(), String> {
    use emulator::scenarios::odometry_laps::{run_odometry_laps, OdometryLapsOptions};
    let r =
        run_odometry_laps(&OdometryLapsOptions::new(args.world.seed)).map_err(|e| e.to_string())?;
    if args.json {
        println!("{}", run_json(&r)?);
        return Ok(());
    }
    println!(
        "{} laps ({}) in {:.1} s simulated, {:.2} m, {} telemetry frames ({} moving), \
         {} collisions; true rotation {:+.1} deg, counts at d 52 / dl 0.080 say {:+.1} deg",
        r.laps,
        r.ended,
        r.sim_s,
        r.distance_m,
        r.frames,
        r.moving_deltas,
        r.collisions,
        r.true_rotation_deg,
        r.nominal_rotation_deg
    );
    println!("table  d mm  dl mm   paper    ours");
    for e in &r.tables {
        println!(
            "{:>5} {:>5.1} {:>6.3} {:>7.2} {:>7.2}",
            e.table, e.d_mm, e.dl_mm, e.paper_deg, e.ours_deg
        );
    }
    println!(
        "largest difference {:.2} deg{}",
        r.max_difference_deg,
        if r.clean_laps {
            ""
        } else {
            " (the robot turned round at a corner: not two clean laps, not the paper's run)"
        }
    );
    Ok(())
}

/// A `run` report as JSON, with the whole process's speed: `cpu_s` (user + system CPU of this
/// process so far: loading, setting up and running) and `speed_x` (simulated seconds per CPU
/// second, issue 15's "emulator speed, whole process"). CPU rather than wall time: on a loaded
/// machine wall time mostly measures the other processes.
fn run_json(report: &impl serde::Serialize) -> Result<String, String> {
    let mut v = serde_json::to_value(report).map_err(|e| e.to_string())?;
    let cpu_s = process_cpu_s();
    if let (Some(obj), Some(cpu_s)) = (v.as_object_mut(), cpu_s) {
        let sim_s = obj.get("sim_s").and_then(serde_json::Value::as_f64);
        obj.insert("cpu_s".into(), cpu_s.into());
        if let Some(sim_s) = sim_s.filter(|_| cpu_s > 0.0) {
            obj.insert("speed_x".into(), (sim_s / cpu_s).round().into());
        }
    }
    emulator::json_text::compact(&v).map_err(|e| e.to_string())
}

/// User + system CPU seconds of this process (getrusage).
fn process_cpu_s() -> Option<f64> {
    let u = nix::sys::resource::getrusage(nix::sys::resource::UsageWho::RUSAGE_SELF).ok()?;
    let s = |t: nix::sys::time::TimeVal| t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6;
    Some(s(u.user_time()) + s(u.system_time()))
}
