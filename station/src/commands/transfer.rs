//! `station upload-map`, `station download-map`, `station upload-plan`, and the plan object
//! written by `station plan --out-object`.
//!
//! Layer: the binary's edge for transfers (clap arguments, printing, exit codes); the work is
//! [`TransferClient`] and [`objects`](super::objects). Each command checks what it can before
//! opening the port (the file, its layout), then what it can before sending (the robot takes
//! transfers, the map fits its `map_capacity`), then runs one transfer and prints one report:
//! text, or with `--json` one object with `bytes`, `id`, `crc`, `outcome` and `elapsed_ms`
//! (failures too, with `error`). Exit codes: 0 the robot (or the file) holds the object; 1
//! anything else, with the reason; 2 usage errors (clap).

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use protocol::{caps, EventCode, ObjectKind};
use serde_json::{json, Value};

use crate::commands::args::{parse_seconds, RequiredPort};
use crate::commands::plan::MapArgs;
use crate::link::{LinkEvent, PeerInfo};
use crate::output_file::{check as check_output, write_atomically};
use crate::plan::{MapOptions, PlanResult, Planner};
use station_core::transfer::client::TransferClient;
use station_core::transfer::engine::JobSpec;
use station_core::transfer::objects::{
    check_capacity, load_for_upload, map_ascii, map_object, plan_object, plan_waypoints,
    read_plan_file, MapObject,
};
use station_core::transfer::{JobOutcome, JobReport};

/// `station upload-map`.
#[derive(Debug, Args, Clone)]
pub struct UploadMapArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    #[command(flatten)]
    pub map: MapArgs,
    /// Print JSON: bytes, id, crc, outcome, elapsed_ms, and the map's size.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// `station download-map`.
#[derive(Debug, Args, Clone)]
#[group(id = "output", required = true, multiple = true, args = ["out", "ascii"])]
pub struct DownloadMapArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Write the Map object here (a temporary file renamed when complete); `station
    /// upload-map --map FILE` and `station plan --map FILE` read it back.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Overwrite --out if it exists (a device, FIFO or directory is never replaced).
    #[arg(long, requires = "out")]
    pub force: bool,
    /// Print the map: top row first, # obstacle, . free, ? unknown, S start, G goal.
    #[arg(long)]
    pub ascii: bool,
    /// Print JSON: bytes, id, crc, outcome, elapsed_ms, the map's size (and rows with --ascii).
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// `station upload-plan`.
#[derive(Debug, Args, Clone)]
pub struct UploadPlanArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// A Plan object file, e.g. from `station plan --map F --out-object FILE`.
    #[arg(long, value_name = "FILE")]
    pub plan: PathBuf,
    /// Print JSON: bytes, id, crc, outcome, elapsed_ms, waypoints.
    #[arg(long)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = parse_seconds,
          allow_negative_numbers = true)]
    pub timeout: f64,
}

/// Prints a failure (JSON on stdout with `--json`, else a line on stderr); exit status 1.
pub(super) fn fail(
    json: bool,
    command: &str,
    outcome: &str,
    error: &str,
    extra: Value,
) -> ExitCode {
    if json {
        let mut v = json!({"command": command, "outcome": outcome, "ok": false, "error": error});
        merge(&mut v, extra);
        println!("{}", crate::json_text::pretty(&v).unwrap_or_default());
    } else {
        eprintln!(
            "station {command}: {}",
            crate::terminal_text::printable_text(error)
        );
    }
    ExitCode::FAILURE
}

fn merge(into: &mut Value, extra: Value) {
    if let (Some(a), Value::Object(b)) = (into.as_object_mut(), extra) {
        a.extend(b);
    }
}

fn map_json(m: &MapObject) -> Value {
    let p = |p: Option<protocol::PointMm>| {
        p.map(|p| [f64::from(p.x_mm) / 1000.0, f64::from(p.y_mm) / 1000.0])
    };
    json!({
        "width": m.width,
        "height": m.height,
        "cell_m": f64::from(m.cell_mm) / 1000.0,
        "start": p(m.start),
        "goal": p(m.goal),
    })
}

/// Prints a transfer's report; exit status 0 when the receiver holds the object.
pub(super) fn finish(json: bool, command: &str, r: &JobReport, extra: Value) -> ExitCode {
    if json {
        let mut v = json!({"command": command});
        merge(&mut v, r.json());
        merge(&mut v, extra);
        println!("{}", crate::json_text::pretty(&v).unwrap_or_default());
    } else if r.outcome.is_success() {
        println!("{}", crate::terminal_text::printable_text(&r.text()));
    } else {
        eprintln!("{}", crate::terminal_text::printable_text(&r.text()));
    }
    if r.outcome.is_success() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// Connects, and checks the robot takes transfers.
pub(super) async fn connect(
    port: &RequiredPort,
    timeout: f64,
) -> Result<(TransferClient, PeerInfo), String> {
    let (link, peer) = crate::commands::connect::connect(port, timeout)
        .await
        .map_err(|e| format!("{e:#}"))?;
    let client = TransferClient::new(link, true);
    if !peer.has(caps::TRANSFERS) {
        client.shutdown().await;
        return Err(format!(
            "the robot ({} {}) does not take object transfers",
            peer.firmware, peer.firmware_version
        ));
    }
    Ok((client, peer))
}

/// A progress line on stderr while a terminal watches (nothing in scripts).
pub(super) fn progress_printer(json: bool, what: &'static str) -> impl FnMut(u32, u32) {
    let show = !json && std::io::stderr().is_terminal();
    move |done, total| {
        if show && total > 0 {
            eprint!("\r{what}: {done} / {total} bytes ");
            if done == total {
                eprintln!();
            }
        }
    }
}

/// Runs `station upload-map`.
pub async fn upload_map(args: &UploadMapArgs) -> anyhow::Result<ExitCode> {
    const CMD: &str = "upload-map";
    let json = args.json;
    let opts = MapOptions {
        cell_m: args.map.cell,
        radius_m: args.map.radius,
    };
    let loaded = match load_for_upload(&args.map.map, &opts) {
        Ok(l) => l,
        Err(e) => return Ok(fail(json, CMD, "bad_map", &e.to_string(), Value::Null)),
    };
    let Some(m) = loaded.map.filter(|_| loaded.object == ObjectKind::Map) else {
        let instead = match loaded.object {
            ObjectKind::LightCalibration => "upload-calibration",
            _ => "upload-plan",
        };
        let e = format!(
            "{} is a {}, not a map (use {instead})",
            args.map.map,
            station_core::format::object_name(loaded.object)
        );
        return Ok(fail(json, CMD, "bad_map", &e, Value::Null));
    };
    let extra = json!({"file": args.map.map, "map": map_json(&m)});
    if !json {
        println!("{}", crate::terminal_text::printable_text(&loaded.summary));
    }
    let (mut client, peer) = match connect(&args.port, args.timeout).await {
        Ok(c) => c,
        Err(e) => return Ok(fail(json, CMD, "not_connected", &e, extra)),
    };
    // Refused here, before anything is sent: the robot would only reject it at the end.
    if let Err(e) = check_capacity(m.width, m.height, m.cell_mm, peer.map_capacity) {
        client.shutdown().await;
        let mut extra = extra;
        merge(&mut extra, json!({"bytes": m.bytes.len(), "id": m.id}));
        return Ok(fail(json, CMD, "too_large", &e.to_string(), extra));
    }
    let spec = JobSpec::Upload {
        object: ObjectKind::Map,
        bytes: m.bytes.clone(),
    };
    let report = client.run(spec, progress_printer(json, "upload map")).await;
    client.shutdown().await;
    Ok(finish(json, CMD, &report, extra))
}

/// Connects and downloads `object` (progress as `what` on a terminal): the report, or why
/// the link did not come up.
pub(super) async fn download_object(
    port: &RequiredPort,
    timeout: f64,
    json: bool,
    object: ObjectKind,
    what: &'static str,
) -> Result<JobReport, String> {
    let (mut client, _peer) = connect(port, timeout).await?;
    let spec = JobSpec::Download { object, have: None };
    let report = client.run(spec, progress_printer(json, what)).await;
    client.shutdown().await;
    Ok(report)
}

/// Runs `station download-map`.
pub async fn download_map(args: &DownloadMapArgs) -> anyhow::Result<ExitCode> {
    const CMD: &str = "download-map";
    let json = args.json;
    // Before the link: a download that cannot be kept is not worth the robot's time.
    if let Some(Err(e)) = args.out.as_deref().map(|o| check_output(o, args.force)) {
        return Ok(fail(json, CMD, "bad_output", &e.to_string(), Value::Null));
    }
    let download = download_object(
        &args.port,
        args.timeout,
        json,
        ObjectKind::Map,
        "download map",
    );
    let report = match download.await {
        Ok(r) => r,
        Err(e) => return Ok(fail(json, CMD, "not_connected", &e, Value::Null)),
    };
    let (JobOutcome::Complete, Some(bytes)) = (&report.outcome, &report.bytes) else {
        return Ok(finish(json, CMD, &report, Value::Null));
    };
    let mut extra = json!({});
    if let Ok(v) = protocol::object::MapView::parse(bytes) {
        let h = v.header;
        let m = MapObject {
            bytes: Vec::new(),
            id: report.id.unwrap_or(0),
            width: h.width,
            height: h.height,
            cell_mm: h.cell_mm,
            start: h.start,
            goal: h.goal,
        };
        merge(&mut extra, json!({"map": map_json(&m)}));
    }
    if let Some(out) = &args.out {
        if let Err(e) = write_atomically(out, bytes, args.force) {
            let e = format!("cannot write {}: {e}", out.display());
            return Ok(fail(json, CMD, "write_failed", &e, report.json()));
        }
        merge(&mut extra, json!({"out": out.display().to_string()}));
    }
    let art = if args.ascii {
        match map_ascii(bytes) {
            Ok(a) => a,
            Err(e) => return Ok(fail(json, CMD, "malformed", &e.to_string(), report.json())),
        }
    } else {
        Vec::new()
    };
    if json {
        if args.ascii {
            merge(&mut extra, json!({"ascii": art}));
        }
        return Ok(finish(json, CMD, &report, extra));
    }
    let code = finish(json, CMD, &report, extra);
    if let Some(out) = &args.out {
        println!("written to {}", out.display());
    }
    for row in art {
        println!("{row}");
    }
    Ok(code)
}

/// Runs `station upload-plan`.
pub async fn upload_plan(args: &UploadPlanArgs) -> anyhow::Result<ExitCode> {
    const CMD: &str = "upload-plan";
    let json = args.json;
    let bytes = match read_plan_file(&args.plan) {
        Ok(b) => b,
        Err(e) => return Ok(fail(json, CMD, "bad_plan", &e.to_string(), Value::Null)),
    };
    let view = protocol::object::PlanView::parse(&bytes).ok();
    let extra = json!({
        "file": args.plan.display().to_string(),
        "waypoints": view.map(|v| v.waypoint_count()),
        "map_id": view.map(|v| v.meta.map_id),
    });
    let (mut client, _peer) = match connect(&args.port, args.timeout).await {
        Ok(c) => c,
        Err(e) => return Ok(fail(json, CMD, "not_connected", &e, extra)),
    };
    let spec = JobSpec::Upload {
        object: ObjectKind::Plan,
        bytes,
    };
    let report = client
        .run(spec, progress_printer(json, "upload plan"))
        .await;
    client.shutdown().await;
    let code = finish(json, CMD, &report, extra);
    if !json && report.outcome.is_success() {
        if let Some(id) = report.id {
            println!(
                "execute it with: station send --port {} execute {id:#010x}",
                args.port.port.display()
            );
        }
    }
    Ok(code)
}

/// `station plan --out-object FILE [--force]`: writes the Plan object of `r` (made on
/// `planner`'s map) atomically; returns what to report (path, bytes, id, map id, waypoints).
pub fn write_plan_object(
    planner: &Planner,
    r: &PlanResult,
    path: &std::path::Path,
    force: bool,
) -> anyhow::Result<Value> {
    let map = map_object(planner.map())?;
    let bytes = plan_object(planner, r, map.id)?;
    write_atomically(path, &bytes, force)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
    let id = protocol::crc32c(&bytes);
    let waypoints = plan_waypoints(&bytes).map(|w| w.len()).unwrap_or(0);
    Ok(json!({
        "path": path.display().to_string(),
        "bytes": bytes.len(),
        "id": id,
        "id_hex": format!("{id:#010x}"),
        "map_id": map.id,
        "map_id_hex": format!("{:#010x}", map.id),
        "waypoints": waypoints,
    }))
}

/// After `send plan` was acknowledged: the new plan's id from the robot's `PlanInstalled`
/// event (waits up to a second).
pub async fn plan_id_after(
    events: &mut tokio::sync::mpsc::UnboundedReceiver<LinkEvent>,
) -> Option<u32> {
    let deadline = tokio::time::Instant::now() + Duration::from_secs(1);
    while let Ok(Some(ev)) = tokio::time::timeout_at(deadline, events.recv()).await {
        if let LinkEvent::Robot(e) = ev {
            if e.code == EventCode::PlanInstalled {
                return Some(e.value as u32);
            }
        }
    }
    None
}
