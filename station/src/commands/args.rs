//! The arguments every command shares and how they are parsed: the port (`--port`, `--baud`,
//! `--key-file`), distinct ports, key files, seconds, baud rates, parameters, values, plan ids.
//! Parsing turns every argument into a checked value or a clear error (clap exits 2 on usage
//! errors); a name that is not a parameter is refused here, before any port is opened.

use std::path::PathBuf;

use clap::Args;

use crate::link::serial::DEFAULT_BAUD;

/// The ports `station stats` watches: one, or several at once (`--port A --port B`), each
/// reported on its own with its robot's id.
#[derive(Debug, Args, Clone)]
pub struct StatsPorts {
    /// Serial port (or pty) of a robot; repeat it to watch several.
    #[arg(long, short = 'p', value_name = "PATH", required = true)]
    pub port: Vec<PathBuf>,
    /// Baud rate (ignored by ptys).
    #[arg(long, short = 'b', default_value_t = DEFAULT_BAUD, value_parser = parse_baud)]
    pub baud: u32,
    /// Link authentication key (PROTOCOL.md §13), for every port.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
}

impl StatsPorts {
    /// Each port as a one-port argument set.
    pub fn each(&self) -> Vec<RequiredPort> {
        self.port
            .iter()
            .map(|p| RequiredPort {
                port: p.clone(),
                baud: self.baud,
                key_file: self.key_file.clone(),
                via: None,
            })
            .collect()
    }
}

/// A port that headless commands require.
#[derive(Debug, Args, Clone)]
pub struct RequiredPort {
    /// Serial port (or pty) of the robot.
    #[arg(long, short = 'p', value_name = "PATH")]
    pub port: PathBuf,
    /// Baud rate (ignored by ptys).
    #[arg(long, short = 'b', default_value_t = DEFAULT_BAUD, value_parser = parse_baud)]
    pub baud: u32,
    /// Link authentication key: a file of 64 hex digits, the robot's key (PROTOCOL.md §13).
    /// Every frame is then signed, and only frames signed with it are accepted.
    #[arg(long, value_name = "PATH")]
    pub key_file: Option<PathBuf>,
    /// Reach the robot through the shared link of the station holding its port, at this
    /// socket. Without it, a station holding --port is found and used by itself (its socket
    /// is in $XDG_RUNTIME_DIR/station); with neither, the port is opened directly.
    #[arg(long, value_name = "SOCKET")]
    pub via: Option<PathBuf>,
}

/// Refuses a port named twice among several `--port`s (two link tasks would fight over one
/// device); the one check for `station`, `record` and `stats`.
pub fn distinct_ports<'a>(
    ports: impl IntoIterator<Item = &'a std::path::Path>,
) -> Result<(), String> {
    let mut seen: Vec<&std::path::Path> = Vec::new();
    for p in ports {
        if seen.contains(&p) {
            return Err(format!(
                "--port {} is given twice; each link needs its own port",
                crate::terminal_text::printable(&p.display().to_string())
            ));
        }
        seen.push(p);
    }
    Ok(())
}

/// The key in a `--key-file`, if one was given; the error names the file and the fault.
pub fn load_key(path: Option<&std::path::Path>) -> Result<Option<protocol::LinkKey>, String> {
    Ok(load_key_bytes(path)?.map(|k| protocol::LinkKey::new(&k)))
}

/// The raw key in a `--key-file`, for a built-in emulator that must share it.
pub fn load_key_bytes(
    path: Option<&std::path::Path>,
) -> Result<Option<[u8; protocol::sign::KEY_LEN]>, String> {
    path.map(|p| emulator::link::read_key_file(p).map_err(|e| format!("--key-file: {e}")))
        .transpose()
}

/// A plan id: `0x`-prefixed hex (as printed) or decimal.
pub fn parse_plan_id(s: &str) -> Result<u32, String> {
    let t = s.trim();
    let parsed = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => t.parse::<u32>(),
    };
    parsed.map_err(|_| format!("{s:?} is not a plan id (0x-hex like 0x7692f253, or decimal)"))
}

pub fn parse_baud(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(b) if (50..=4_000_000).contains(&b) => Ok(b),
        Ok(b) => Err(format!("{b} is not a usable baud rate (50 ..= 4000000)")),
        Err(_) => Err(format!("{s:?} is not a number")),
    }
}

pub fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 86_400.0 => Ok(v),
        Ok(v) => Err(format!("{v} s is out of range (> 0, at most a day)")),
        Err(_) => Err(format!("{s:?} is not a number of seconds")),
    }
}

pub fn parse_metres(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= 1000.0 => Ok(v),
        Ok(v) if v.is_finite() => Err(format!("{v} m is too far (at most 1000 m)")),
        _ => Err(format!("{s:?} is not a distance in metres")),
    }
}

pub fn parse_value(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{s:?} is not a finite number")),
    }
}

/// A parameter by name or id; an unknown name gets the closest names
/// (`station_core::param_names`).
pub fn parse_param(s: &str) -> Result<u16, String> {
    station_core::param_names::find(s).map(|p| p.id)
}
