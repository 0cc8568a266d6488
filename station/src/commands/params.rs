//! `station params --port P get | set | list | save | load | diff`: the robot's parameters
//! from a script, as MAVProxy's `param` module gives them.
//!
//! Layer: the binary's edge over the link task (`headless::connect`) and `params::file`.
//! A file to load or compare is read and checked whole before the port is opened, so a
//! typo costs no robot time and changes nothing; `save` writes through `output_file` (a
//! temporary renamed when complete; an existing file only with `--force`). Exit status: 0
//! done (`diff`: no difference), 1 refused, unanswered, unusable file or port (`diff`: the
//! robot differs from the file), 2 usage.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::{Args, Subcommand};
use protocol::{AckInfo, Command, NackReason, ParamId};
use robot_firmware::params::{ParamInfo, PARAMS};
use serde_json::json;

use crate::app::params::{format_param, format_value, range_text};
use crate::commands::args::RequiredPort;
use crate::link::api::refusal_text;
use crate::link::{CommandOutcome, PeerInfo, RunningLink};
use crate::terminal_text::printable_text;

/// Arguments of `station params`.
#[derive(Debug, Args, Clone)]
pub struct ParamsArgs {
    #[command(flatten)]
    pub port: RequiredPort,
    /// Print JSON.
    #[arg(long, global = true)]
    pub json: bool,
    /// Seconds to wait for the handshake.
    #[arg(long, default_value_t = 5.0, value_parser = crate::commands::args::parse_seconds, global = true,
          allow_negative_numbers = true)]
    pub timeout: f64,
    #[command(subcommand)]
    pub op: ParamsOp,
}

#[derive(Debug, Subcommand, Clone)]
pub enum ParamsOp {
    /// Print one parameter's value in force.
    Get {
        #[arg(value_parser = crate::commands::args::parse_param)]
        name: u16,
    },
    /// Set a parameter; prints the value the robot put in force, or its reason for refusing.
    #[command(allow_negative_numbers = true)]
    Set {
        #[arg(value_parser = crate::commands::args::parse_param)]
        name: u16,
        #[arg(value_parser = crate::commands::args::parse_value)]
        value: f32,
    },
    /// Every parameter: value, unit, range and what it does.
    List,
    /// Write every parameter to FILE (`name = value  # unit, range: description` lines).
    Save {
        file: PathBuf,
        /// Overwrite FILE if it exists (a device, FIFO or directory is never replaced).
        #[arg(long)]
        force: bool,
    },
    /// Set the parameters FILE names; reports each change and each refusal (exit 1 if any).
    Load { file: PathBuf },
    /// Compare the robot's parameters with FILE (exit 1 when they differ).
    Diff { file: PathBuf },
}

/// Runs `station params`.
pub async fn run(args: &ParamsArgs) -> anyhow::Result<ExitCode> {
    // Files first: a bad file is reported before any port is opened.
    let entries = match &args.op {
        ParamsOp::Load { file } | ParamsOp::Diff { file } => Some(read_file(file)?),
        ParamsOp::Save { file, force } => {
            crate::output_file::check(file, *force)?;
            None
        }
        _ => None,
    };
    let (mut link, peer) = crate::commands::connect::connect(&args.port, args.timeout).await?;
    let result = match &args.op {
        ParamsOp::Get { name } => get_one(&mut link, *name, args.json).await,
        ParamsOp::Set { name, value } => set_one(&mut link, *name, *value, args.json).await,
        ParamsOp::List => list(&mut link, &peer, args.json).await,
        ParamsOp::Save { file, force } => save(&mut link, &peer, file, *force, args.json).await,
        ParamsOp::Load { .. } => load(&mut link, entries.unwrap_or_default(), args.json).await,
        ParamsOp::Diff { .. } => diff(&mut link, entries.unwrap_or_default(), args.json).await,
    };
    link.handle.shutdown();
    let _ = tokio::time::timeout(std::time::Duration::from_secs(1), link.task).await;
    result
}

fn read_file(path: &std::path::Path) -> anyhow::Result<Vec<station_core::param_file::Entry>> {
    let bytes = crate::input_file::read(path, &station_core::param_file::PARAMETER_FILE)?;
    let label = path.display().to_string();
    station_core::param_file::parse(&label, &bytes)
        .map_err(|e| anyhow::anyhow!(printable_text(&e).into_owned()))
}

/// What the robot answered about one parameter.
enum Answer {
    Value(f32),
    Refused(String),
}

async fn ask(link: &mut RunningLink, command: Command) -> Answer {
    match link.handle.call(command).await {
        CommandOutcome::Acked {
            info: AckInfo::Param { value, .. },
            ..
        } => Answer::Value(value),
        CommandOutcome::Acked { .. } => Answer::Refused("the robot's ack carried no value".into()),
        CommandOutcome::Nacked { reason, .. } => Answer::Refused(refusal_text(&command, reason)),
        CommandOutcome::Failed(why) => Answer::Refused(format!("no answer: {why}")),
    }
}

async fn read(link: &mut RunningLink, id: u16) -> Answer {
    ask(link, Command::GetParam { id: ParamId(id) }).await
}

fn info(id: u16) -> &'static ParamInfo {
    // `parse_param` only lets table ids through.
    robot_firmware::params::info(id).unwrap_or(&PARAMS[0])
}

fn emit(json: bool, value: serde_json::Value, text: &str, ok: bool) -> ExitCode {
    if json {
        println!("{}", crate::json_text::pretty(&value).unwrap_or_default());
    } else if ok {
        println!("{}", printable_text(text));
    } else {
        eprintln!("{}", printable_text(text));
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

async fn get_one(link: &mut RunningLink, id: u16, json: bool) -> anyhow::Result<ExitCode> {
    let p = info(id);
    Ok(match read(link, id).await {
        Answer::Value(v) => emit(
            json,
            json!({"name": p.name, "id": id, "value": v, "unit": p.unit}),
            &format!("{} = {} {}", p.name, format_param(p, v), p.unit),
            true,
        ),
        Answer::Refused(why) => emit(
            json,
            json!({"name": p.name, "id": id, "refused": why}),
            &format!("{}: {why}", p.name),
            false,
        ),
    })
}

async fn set_one(
    link: &mut RunningLink,
    id: u16,
    value: f32,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let p = info(id);
    let command = Command::SetParam {
        id: ParamId(id),
        value,
    };
    Ok(match ask(link, command).await {
        Answer::Value(v) => emit(
            json,
            json!({"name": p.name, "id": id, "value": v, "unit": p.unit}),
            &format!("{} = {} {}", p.name, format_param(p, v), p.unit),
            true,
        ),
        Answer::Refused(why) => emit(
            json,
            json!({"name": p.name, "id": id, "asked": value, "refused": why}),
            &format!("{} = {value}: refused: {why}", p.name),
            false,
        ),
    })
}

/// Every parameter the robot has, read one by one; the ones its hardware lacks are `None`.
async fn read_all(
    link: &mut RunningLink,
    peer: &PeerInfo,
) -> Vec<(&'static ParamInfo, Result<f32, String>)> {
    let mut out = Vec::new();
    for p in PARAMS.iter() {
        let r = if !peer.has(p.requires) {
            Err(NackReason::Unsupported).map_err(|r| crate::link::api::nack_text(r).to_string())
        } else {
            match read(link, p.id).await {
                Answer::Value(v) => Ok(v),
                Answer::Refused(why) => Err(why),
            }
        };
        out.push((p, r));
    }
    out
}

async fn list(link: &mut RunningLink, peer: &PeerInfo, json: bool) -> anyhow::Result<ExitCode> {
    let all = read_all(link, peer).await;
    let failed = all.iter().any(|(p, r)| r.is_err() && peer.has(p.requires));
    if json {
        let v: Vec<_> = all
            .iter()
            .map(|(p, r)| {
                json!({"name": p.name, "id": p.id, "value": r.as_ref().ok(),
                       "error": r.as_ref().err(), "unit": p.unit, "min": p.min, "max": p.max,
                       "integer": p.integer, "description": p.desc})
            })
            .collect();
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        for (p, r) in &all {
            let value = match r {
                Ok(v) => format_param(p, *v),
                Err(_) if !peer.has(p.requires) => "-".into(),
                Err(why) => format!("({why})"),
            };
            println!(
                "{:<24} {:>12} {:<11} {:<20} {}",
                p.name,
                value,
                p.unit,
                range_text(p),
                p.desc
            );
        }
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

async fn save(
    link: &mut RunningLink,
    peer: &PeerInfo,
    path: &std::path::Path,
    force: bool,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let all = read_all(link, peer).await;
    // A parameter the robot has but did not answer would make the file silently partial.
    if let Some((p, Err(why))) = all.iter().find(|(p, r)| r.is_err() && peer.has(p.requires)) {
        bail!(
            "{}: not written: {} could not be read ({why})",
            path.display(),
            p.name
        );
    }
    let values: Vec<_> = all
        .iter()
        .filter_map(|(p, r)| r.as_ref().ok().map(|v| (*p, *v)))
        .collect();
    let header = format!(
        "parameters of {} {} ({:?}), saved by station {}",
        peer.firmware,
        peer.firmware_version,
        peer.profile,
        env!("CARGO_PKG_VERSION")
    );
    let text = station_core::param_file::format(&printable_text(&header), &values);
    crate::output_file::write_atomically(path, text.as_bytes(), force)?;
    let note = format!("wrote {} ({} parameters)", path.display(), values.len());
    Ok(emit(
        json,
        json!({"file": path.display().to_string(), "parameters": values.len()}),
        &note,
        true,
    ))
}

async fn load(
    link: &mut RunningLink,
    entries: Vec<station_core::param_file::Entry>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let mut report = Vec::new();
    let (mut changed, mut same, mut refused) = (0, 0, 0);
    for e in entries {
        let p = e.info;
        let before = match read(link, p.id).await {
            Answer::Value(v) => Some(v),
            Answer::Refused(_) => None,
        };
        if before == Some(e.value) {
            same += 1;
            report.push((
                json!({"name": p.name, "line": e.line, "outcome": "unchanged",
                                "value": e.value}),
                None,
            ));
            continue;
        }
        let command = Command::SetParam {
            id: ParamId(p.id),
            value: e.value,
        };
        match ask(link, command).await {
            Answer::Value(v) => {
                changed += 1;
                let was = before.map_or("?".into(), |b| format_param(p, b));
                report.push((
                    json!({"name": p.name, "line": e.line, "outcome": "changed",
                           "before": before, "value": v}),
                    Some(format!(
                        "changed {}: {was} -> {} {}",
                        p.name,
                        format_param(p, v),
                        p.unit
                    )),
                ));
            }
            Answer::Refused(why) => {
                refused += 1;
                report.push((
                    json!({"name": p.name, "line": e.line, "outcome": "refused",
                           "asked": e.value, "reason": why}),
                    Some(format!(
                        "refused {} = {} (line {}): {why}",
                        p.name, e.value, e.line
                    )),
                ));
            }
        }
    }
    let summary = format!("{changed} changed, {same} unchanged, {refused} refused");
    if json {
        let v: Vec<_> = report.into_iter().map(|(v, _)| v).collect();
        println!(
            "{}",
            crate::json_text::pretty(&json!({"changed": changed, "unchanged": same,
                                                 "refused": refused, "parameters": v}))?
        );
    } else {
        for (_, line) in report {
            if let Some(l) = line {
                println!("{}", printable_text(&l));
            }
        }
        println!("{summary}");
    }
    Ok(if refused == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

async fn diff(
    link: &mut RunningLink,
    entries: Vec<station_core::param_file::Entry>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    let mut differ = Vec::new();
    for e in &entries {
        let p = e.info;
        let robot = match read(link, p.id).await {
            Answer::Value(v) => Ok(v),
            Answer::Refused(why) => Err(why),
        };
        if robot.as_ref().ok() != Some(&e.value) {
            differ.push((e, robot));
        }
    }
    if json {
        let v: Vec<_> = differ
            .iter()
            .map(|(e, r)| {
                json!({"name": e.info.name, "line": e.line, "file": e.value,
                                 "robot": r.as_ref().ok(), "error": r.as_ref().err()})
            })
            .collect();
        println!(
            "{}",
            crate::json_text::pretty(&json!({"compared": entries.len(), "differ": v}))?
        );
    } else {
        for (e, r) in &differ {
            let robot = match r {
                Ok(v) => format_value(*v),
                Err(why) => format!("({why})"),
            };
            println!(
                "{}",
                printable_text(&format!(
                    "{}: file {} (line {}), robot {robot}",
                    e.info.name,
                    format_value(e.value),
                    e.line
                ))
            );
        }
        println!("{} compared, {} differ", entries.len(), differ.len());
    }
    Ok(if differ.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
