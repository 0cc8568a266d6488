//! `station upload-calibration` and `station download-calibration`: the light -> angle network
//! (seed 000 §5.3) between a file and the robot, as a LightCalibration object (PROTOCOL.md §12).
//!
//! Layer: the binary's edge, like `command.rs`; the file formats are `crate::calibrate`'s
//! (`station calibrate --out som.json|som.bin`), the object layout `protocol::object`'s. The
//! upload checks the file before opening the port and that the robot has light sensors before
//! sending; the download refuses to overwrite the file it would write unless `--force`, and
//! writes a temporary file renamed when complete. Exit codes as `command.rs`: 0 done, 1 any
//! failure with its reason, 2 usage.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use protocol::{caps, NackReason, ObjectKind};
use serde_json::{json, Value};

use super::transfer::{connect, download_object, fail, finish, progress_printer};
use crate::calibrate;
use crate::commands::args::{parse_seconds, RequiredPort};
use crate::output_file::write_atomically;
use station_core::transfer::engine::JobSpec;
use station_core::transfer::{JobOutcome, TransferError};

/// `station upload-calibration`.
#[derive(Debug, Args, Clone)]
pub struct UploadCalibrationArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// The network: a file `station calibrate --out` or `download-calibration --out` wrote
    /// (FILE.json, or the binary form).
    #[arg(long, value_name = "FILE")]
    pub calibration: PathBuf,
    /// Print JSON: bytes, id, crc, outcome, elapsed_ms.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// `station download-calibration`.
#[derive(Debug, Args, Clone)]
pub struct DownloadCalibrationArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Write the network here: FILE.json for JSON, any other name for the binary form (the
    /// formats of `station calibrate`). A temporary file is renamed when complete.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: PathBuf,
    /// Overwrite FILE if it exists (a device, FIFO or directory is never replaced).
    #[arg(long)]
    pub force: bool,
    /// Print JSON: bytes, id, crc, outcome, elapsed_ms, out.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// Runs `station upload-calibration`.
pub async fn upload(args: &UploadCalibrationArgs) -> anyhow::Result<ExitCode> {
    const CMD: &str = "upload-calibration";
    let json = args.json;
    let file = args.calibration.display().to_string();
    let object =
        calibrate::decode_file(&args.calibration).and_then(|som| calibrate::light_object(&som));
    let bytes = match object {
        Ok(b) => b,
        Err(e) => {
            let e = format!("{e:#}");
            return Ok(fail(json, CMD, "bad_calibration", &e, Value::Null));
        }
    };
    let extra = json!({"file": file});
    let (mut client, peer) = match connect(&args.port, args.timeout).await {
        Ok(c) => c,
        Err(e) => return Ok(fail(json, CMD, "not_connected", &e, extra)),
    };
    if !peer.has(caps::AMBIENT_LIGHT) {
        client.shutdown().await;
        let e = format!(
            "the robot ({} {}, {:?}) has no ambient light sensors to use a light calibration",
            peer.firmware, peer.firmware_version, peer.profile
        );
        return Ok(fail(json, CMD, "unsupported", &e, extra));
    }
    let spec = JobSpec::Upload {
        object: ObjectKind::LightCalibration,
        bytes,
    };
    let report = client
        .run(spec, progress_printer(json, "upload calibration"))
        .await;
    client.shutdown().await;
    Ok(finish(json, CMD, &report, extra))
}

/// Runs `station download-calibration`.
pub async fn download(args: &DownloadCalibrationArgs) -> anyhow::Result<ExitCode> {
    const CMD: &str = "download-calibration";
    let json = args.json;
    let out = args.out.display().to_string();
    // Before the link: a download that cannot be kept is not worth the robot's time.
    if let Err(e) = crate::output_file::check(&args.out, args.force) {
        let reason = match e {
            crate::output_file::OutputError::Exists { .. } => "exists",
            _ => "bad_output",
        };
        return Ok(fail(json, CMD, reason, &e.to_string(), Value::Null));
    }
    let object = ObjectKind::LightCalibration;
    let download = download_object(
        &args.port,
        args.timeout,
        json,
        object,
        "download calibration",
    );
    let report = match download.await {
        Ok(r) => r,
        Err(e) => return Ok(fail(json, CMD, "not_connected", &e, Value::Null)),
    };
    if report.outcome == JobOutcome::Failed(TransferError::Refused(NackReason::BadState)) {
        // The generic "not allowed in the current mode" would send the user looking for a mode.
        let e = "the robot holds no trained light calibration: calibrate it first (station send \
                 --port P mode calibrate-light, about 7.5 minutes) or upload one";
        return Ok(fail(json, CMD, "no_calibration", e, report.json()));
    }
    let (JobOutcome::Complete, Some(bytes)) = (&report.outcome, &report.bytes) else {
        return Ok(finish(json, CMD, &report, Value::Null));
    };
    let file = calibrate::from_light_object(bytes).and_then(|som| {
        if calibrate::is_json(&args.out) {
            calibrate::encode_json(&som, None)
        } else {
            Ok(calibrate::encode_bin(&som))
        }
    });
    let written = file.and_then(|f| {
        write_atomically(&args.out, &f, args.force)
            .map_err(|e| anyhow::anyhow!("cannot write {out}: {e}"))
    });
    if let Err(e) = written {
        return Ok(fail(
            json,
            CMD,
            "write_failed",
            &format!("{e:#}"),
            report.json(),
        ));
    }
    let code = finish(json, CMD, &report, json!({"out": out}));
    if !json {
        println!("written to {out}");
    }
    Ok(code)
}
