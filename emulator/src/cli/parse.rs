//! Value parsers shared by the subcommands' flags: numbers lists, points, poses, stalls,
//! speeds.

use crate::fault::Stall;
use crate::link::Speed;
pub(super) fn numbers(s: &str, what: &str, min: usize, max: usize) -> Result<Vec<f64>, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() < min || parts.len() > max {
        return Err(format!("expected {what}, got `{s}`"));
    }
    parts
        .iter()
        .map(|p| {
            p.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{p}` in `{s}` is not a finite number ({what})"))
        })
        .collect()
}

pub(super) fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let v = numbers(s, "X,Y in metres", 2, 2)?;
    Ok([v[0], v[1]])
}

/// `X,Y[,HEADING_DEG]` in metres and degrees (`--start`).
pub fn parse_pose(s: &str) -> Result<[f64; 3], String> {
    let v = numbers(s, "X,Y or X,Y,HEADING_DEG", 2, 3)?;
    Ok([v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
}

pub fn parse_stall(s: &str) -> Result<Stall, String> {
    let v = numbers(s, "PERIOD,DURATION in seconds", 2, 2)?;
    Ok(Stall {
        period_s: v[0],
        duration_s: v[1],
    })
}

pub(super) fn parse_speed(s: &str) -> Result<Speed, String> {
    if s.eq_ignore_ascii_case("max") {
        return Ok(Speed::Max);
    }
    match s.parse::<f64>() {
        Ok(f) if f.is_finite() && f > 0.0 => Ok(Speed::Factor(f)),
        _ => Err(format!("`{s}` is neither a positive factor nor `max`")),
    }
}
