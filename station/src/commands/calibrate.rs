//! `station calibrate`: the Khepera's light -> angle map trained from a recording
//! (`station_core::calibrate`), or the odometry calibrated on a robot (`calibrate_odometry`).
//! The output is written to a temporary file and renamed when complete, so it is never left
//! half written.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::Args;
use station_core::calibrate::{
    encode_bin, encode_json, errors, examples, is_json, samples, train, Reference, Report,
    HOLD_OUT, T1,
};

/// `station calibrate`: the light map from a recording (`RECORDING --out FILE`), or a
/// calibration run on a robot (`odometry --port P`, [`super::calibrate_odometry`]).
#[derive(Debug, Args, Clone)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct CalibrateCommand {
    #[command(subcommand)]
    pub what: Option<CalibrateWhat>,
    #[command(flatten)]
    pub light: Option<CalibrateArgs>,
}

/// What `station calibrate` calibrates on a robot.
#[derive(Debug, clap::Subcommand, Clone)]
pub enum CalibrateWhat {
    /// Calibrate the Khepera's odometry on the robot: hold the wall both ways, then set
    /// odo_wheel_ratio_ppm and odo_wheel_distance_mm
    ///
    /// The robot holds the wall on its right (Manual mode, a teleop command each telemetry
    /// frame) until a lap closes, turns round and holds it on its left. The wheel ratio comes
    /// from the straight stretches of wall (once they cover a metre; else from the laps), the
    /// effective wheel distance from the laps. Put it next to a wall of a closed arena.
    /// Prints each lap, then each parameter before -> after (both or neither are set). The
    /// robot is stopped at the end, on Ctrl-C and on --timeout (which still uses the laps
    /// closed so far). A calibration of the kind Borenstein's UMBmark makes, for the wheel
    /// error the Khepera foraging paper measures (Löffler et al. §3.3).
    ///
    /// Examples:
    ///   station calibrate odometry --port /dev/ttyUSB0
    ///   station calibrate odometry --port /dev/ttyUSB0 --dry-run --json
    #[command(verbatim_doc_comment)]
    Odometry(super::calibrate_odometry::OdometryArgs),
}

/// Runs `station calibrate`.
pub async fn dispatch(cmd: &CalibrateCommand) -> anyhow::Result<ExitCode> {
    match (&cmd.what, &cmd.light) {
        (Some(CalibrateWhat::Odometry(a)), _) => super::calibrate_odometry::run(a).await,
        (None, Some(light)) => run(light),
        // clap requires RECORDING and --out without a subcommand.
        (None, None) => bail!("station calibrate: give RECORDING --out FILE, or `odometry`"),
    }
}

/// Arguments of `station calibrate RECORDING --out FILE`.
#[derive(Debug, Args, Clone)]
pub struct CalibrateArgs {
    /// The recording (`station record`) of a Khepera calibrating next to a light.
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,
    /// Where to write the trained map: FILE.json for JSON, any other name for the binary form.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// The light's position in the recording's pose frame, metres; default: found from each
    /// full turn of the robot, as the robot does.
    #[arg(long, value_name = "X,Y", value_parser = super::plan::parse_point)]
    pub light: Option<(f64, f64)>,
    /// Use telemetry in every mode, not only `calibrate-light`.
    #[arg(long)]
    pub any_mode: bool,
    /// Seed of the network's initial neurons and the presentation order.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Use a damaged or torn recording up to its last good record.
    #[arg(long)]
    pub salvage: bool,
    /// Overwrite --out if it exists (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Runs `station calibrate`.
pub fn run(args: &CalibrateArgs) -> anyhow::Result<ExitCode> {
    // Before the work, and so that the map never replaces the recording it came from.
    station_core::export::check_out(&args.out, &args.recording, args.force).context("--out")?;
    let rec = station_core::export::open_whole(&args.recording, args.salvage)?;
    // One robot's light map: a recording of several robots would mix their readings.
    if rec.link_count() > 1 {
        bail!(
            "{}: the recording holds {} robots (links); calibration trains one robot's map: \
             record the calibrating robot alone",
            args.recording.display(),
            rec.link_count()
        );
    }
    let frames = samples(&rec, args.any_mode);
    if frames.is_empty() {
        bail!(
            "{}: no telemetry{}; record while the robot calibrates (station send --port P mode \
             calibrate-light), or pass --any-mode",
            args.recording.display(),
            if args.any_mode {
                ""
            } else {
                " in mode calibrate-light"
            }
        );
    }
    let (all, reference, turns) =
        examples(&frames, args.light).with_context(|| args.recording.display().to_string())?;
    if all.len() < 2 * HOLD_OUT {
        bail!(
            "{}: only {} examples with a light within 90 deg of ahead (below T1 = {T1}); need \
             at least {}",
            args.recording.display(),
            all.len(),
            2 * HOLD_OUT
        );
    }
    let (som, fit, test) = train(&all, args.seed);
    let (mean_deg, max_deg) = errors(&som, &test);
    let (train_mean_deg, train_max_deg) = errors(&som, &fit);
    let mut report = Report {
        recording: args.recording.display().to_string(),
        out: args.out.display().to_string(),
        bytes: 0,
        reference,
        frames: frames.len(),
        turns,
        examples: all.len(),
        trained_on: fit.len(),
        held_out: test.len(),
        mean_deg,
        max_deg,
        train_mean_deg,
        train_max_deg,
    };
    let bytes = if is_json(&args.out) {
        encode_json(&som, Some(&report))?
    } else {
        encode_bin(&som)
    };
    report.bytes = bytes.len();
    station_core::output_file::write_atomically(&args.out, &bytes, args.force)?;
    if args.json {
        println!("{}", station_core::json_text::compact(&report)?);
    } else {
        println!(
            "{} examples ({} reference{}), {} trained, {} held out: held-out error mean {:.2} \
             deg, max {:.2} deg (paper 1.52 / 6.52); training mean {:.2}, max {:.2}",
            report.examples,
            match reference {
                Reference::Light => "light position",
                Reference::Turns => "per-turn",
            },
            if turns > 0 {
                format!(", {turns} turns")
            } else {
                String::new()
            },
            report.trained_on,
            report.held_out,
            mean_deg,
            max_deg,
            train_mean_deg,
            train_max_deg
        );
        println!("wrote {} ({} bytes)", args.out.display(), report.bytes);
    }
    Ok(ExitCode::SUCCESS)
}
