//! Telemetry as CSV: one row per telemetry frame, in SI-ish units, with the emulator's ground
//! truth for the same robot time alongside when the recording has it.
//!
//! Layer: pure formatting over `export::walk`, writing to any `io::Write`. The columns are
//! `COLUMNS` (documented in docs/recordings.md, "CSV"); `TelemetryRow` is the same data for the
//! MCAP `/telemetry` channel. Invariants: a header line, then one line per telemetry frame in
//! recorded order; the truth columns are empty unless an `EmuTruth` with the frame's robot time
//! follows it. What can fail: the writer (`io::Error`).

use std::io::{self, Write};

use protocol::{flags, EmuTruth, Message, Telemetry};
use serde::Serialize;

use super::{walk, Direction, Item};
use crate::format::mode_name;
use crate::record::{LinkState, Recording};

/// The CSV header, in order.
pub const COLUMNS: &[&str] = &[
    "time_s",
    "robot_time_s",
    "mode",
    "x_m",
    "y_m",
    "heading_rad",
    "sigma_xy_m",
    "sigma_heading_rad",
    "v_left_m_s",
    "v_right_m_s",
    "enc_left",
    "enc_right",
    "ir0",
    "ir1",
    "ir2",
    "ir3",
    "ir4",
    "ir5",
    "ir6",
    "ir7",
    "light0",
    "light1",
    "light2",
    "light3",
    "light4",
    "light5",
    "light6",
    "light7",
    "compass_deg",
    "flags",
    "on_goal",
    "on_line",
    "contact",
    "failsafe",
    "goal_reached",
    "line_events",
    "beacon_bearing_deg",
    "beacon_strength",
    "battery_v",
    "behaviours",
    "motor_left_m_s",
    "motor_right_m_s",
    "cycle_period_ms",
    "cycle_busy_ms",
    "cycle_overruns",
    "true_x_m",
    "true_y_m",
    "true_heading_rad",
    "collisions",
];

/// One telemetry frame in SI-ish units.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TelemetryRow {
    /// Recording time, s.
    pub time_s: f64,
    /// The robot's clock, s.
    pub robot_time_s: f64,
    pub mode: &'static str,
    pub x_m: f64,
    pub y_m: f64,
    pub heading_rad: f64,
    pub sigma_xy_m: f64,
    pub sigma_heading_rad: f64,
    pub v_left_m_s: f64,
    pub v_right_m_s: f64,
    pub enc_left: u16,
    pub enc_right: u16,
    /// Raw 10-bit readings.
    pub ir: [u16; 8],
    /// Raw 10-bit readings; lower is brighter.
    pub light: [u16; 8],
    pub compass_deg: f64,
    pub flags: u8,
    pub on_goal: bool,
    pub on_line: bool,
    pub contact: bool,
    pub failsafe: bool,
    pub goal_reached: bool,
    pub line_events: u8,
    pub beacon_bearing_deg: f64,
    pub beacon_strength: u8,
    pub battery_v: f64,
    pub behaviours: u8,
    pub motor_left_m_s: f64,
    pub motor_right_m_s: f64,
    pub cycle_period_ms: f64,
    pub cycle_busy_ms: f64,
    pub cycle_overruns: u8,
    /// Ground truth (emulator only; left out when absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_x_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_y_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_heading_rad: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collisions: Option<u32>,
}

impl TelemetryRow {
    /// The row for frame `t` received at recording time `t_us`.
    pub fn new(t_us: u64, t: &Telemetry) -> TelemetryRow {
        let mm = |v: f64| v / 1000.0;
        TelemetryRow {
            time_s: t_us as f64 / 1e6,
            robot_time_s: f64::from(t.time_ms) / 1000.0,
            mode: mode_name(t.mode),
            x_m: mm(f64::from(t.pose.x_mm)),
            y_m: mm(f64::from(t.pose.y_mm)),
            heading_rad: mm(f64::from(t.pose.heading_mrad)),
            sigma_xy_m: mm(f64::from(t.sigma.xy_mm)),
            sigma_heading_rad: mm(f64::from(t.sigma.heading_mrad)),
            v_left_m_s: mm(f64::from(t.wheels.speed_mm_s[0])),
            v_right_m_s: mm(f64::from(t.wheels.speed_mm_s[1])),
            enc_left: t.wheels.encoders[0],
            enc_right: t.wheels.encoders[1],
            ir: t.ir.values(),
            light: t.light.values(),
            compass_deg: f64::from(t.compass_ddeg) / 10.0,
            flags: t.flags,
            on_goal: t.flags & flags::GROUND != 0,
            on_line: t.flags & flags::LINE != 0,
            contact: t.flags & flags::CONTACT != 0,
            failsafe: t.flags & flags::FAILSAFE != 0,
            goal_reached: t.flags & flags::ARRIVED != 0,
            line_events: t.line_events,
            beacon_bearing_deg: f64::from(t.beacon.bearing_ddeg) / 10.0,
            beacon_strength: t.beacon.strength,
            battery_v: f64::from(t.battery_mv) / 1000.0,
            behaviours: t.behaviour.active,
            motor_left_m_s: mm(f64::from(t.behaviour.motor_mm_s[0])),
            motor_right_m_s: mm(f64::from(t.behaviour.motor_mm_s[1])),
            cycle_period_ms: f64::from(t.cycle.period_us) / 1000.0,
            cycle_busy_ms: f64::from(t.cycle.busy_us) / 1000.0,
            cycle_overruns: t.cycle.overruns,
            true_x_m: None,
            true_y_m: None,
            true_heading_rad: None,
            collisions: None,
        }
    }

    /// Adds the emulator's ground truth.
    pub fn with_truth(&mut self, t: &EmuTruth) {
        self.true_x_m = Some(f64::from(t.pose.x_mm) / 1000.0);
        self.true_y_m = Some(f64::from(t.pose.y_mm) / 1000.0);
        self.true_heading_rad = Some(f64::from(t.pose.heading_mrad) / 1000.0);
        self.collisions = Some(t.collisions);
    }

    /// The CSV fields, in `COLUMNS` order.
    pub fn csv_line(&self) -> String {
        let mut out = String::with_capacity(256);
        self.write_csv_line(&mut out);
        out
    }

    /// Appends the CSV fields, in `COLUMNS` order, to `out` (no newline). Writing in place
    /// with no string per field: the per-field `format!` and the join were most of a CSV
    /// export.
    pub fn write_csv_line(&self, out: &mut String) {
        let b = |v: bool| if v { "1" } else { "0" };
        fixed(out, self.time_s, 6);
        out.push(',');
        fixed(out, self.robot_time_s, 3);
        out.push(',');
        out.push_str(self.mode);
        for v in [
            self.x_m,
            self.y_m,
            self.heading_rad,
            self.sigma_xy_m,
            self.sigma_heading_rad,
            self.v_left_m_s,
            self.v_right_m_s,
        ] {
            out.push(',');
            fixed(out, v, 3);
        }
        for v in [self.enc_left, self.enc_right]
            .iter()
            .chain(&self.ir)
            .chain(&self.light)
        {
            out.push(',');
            uint(out, u64::from(*v));
        }
        out.push(',');
        fixed(out, self.compass_deg, 1);
        out.push(',');
        uint(out, u64::from(self.flags));
        for v in [
            self.on_goal,
            self.on_line,
            self.contact,
            self.failsafe,
            self.goal_reached,
        ] {
            out.push(',');
            out.push_str(b(v));
        }
        out.push(',');
        uint(out, u64::from(self.line_events));
        out.push(',');
        fixed(out, self.beacon_bearing_deg, 1);
        out.push(',');
        uint(out, u64::from(self.beacon_strength));
        out.push(',');
        fixed(out, self.battery_v, 3);
        out.push(',');
        uint(out, u64::from(self.behaviours));
        for v in [
            self.motor_left_m_s,
            self.motor_right_m_s,
            self.cycle_period_ms,
            self.cycle_busy_ms,
        ] {
            out.push(',');
            fixed(out, v, 3);
        }
        out.push(',');
        uint(out, u64::from(self.cycle_overruns));
        for v in [self.true_x_m, self.true_y_m, self.true_heading_rad] {
            out.push(',');
            if let Some(v) = v {
                fixed(out, v, 3);
            }
        }
        out.push(',');
        if let Some(c) = self.collisions {
            uint(out, u64::from(c));
        }
    }
}

/// Appends `v` with `decimals` digits after the point, exactly as `format!("{v:.decimals$}")`
/// does. The row's values are whole numbers of mm, mrad, µs, ... scaled by a power of ten, so
/// `v * 10^decimals` lies within a hair of an integer `n`, and `v` rounded to `decimals`
/// places is `n` with the point put back: written as integers, with none of the general float
/// formatting (the exact decimal expansion) that was most of a CSV export. Anything else (a
/// value halfway between, NaN, huge) takes the general path.
pub(super) fn fixed(out: &mut String, v: f64, decimals: usize) {
    use std::fmt::Write as _;
    const POW10: [f64; 7] = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6];
    const IPOW10: [u64; 7] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000];
    if let (Some(&p), Some(&ip)) = (POW10.get(decimals), IPOW10.get(decimals)) {
        let scaled = v * p;
        let n = scaled.round();
        // Within a quarter of `n`: `v` rounds to `n / p` whatever the product's rounding.
        if (scaled - n).abs() <= 0.25 && n.abs() < 1e15 {
            let n = n.abs() as u64;
            // `format!` keeps the sign of a negative value that rounds to zero ("-0.000").
            if v.is_sign_negative() {
                out.push('-');
            }
            uint(out, n / ip);
            if decimals > 0 {
                out.push('.');
                let frac = n % ip;
                let mut digits = [b'0'; 6];
                let mut f = frac;
                for d in digits[..decimals].iter_mut().rev() {
                    *d = b'0' + (f % 10) as u8;
                    f /= 10;
                }
                out.push_str(std::str::from_utf8(&digits[..decimals]).unwrap_or(""));
            }
            return;
        }
    }
    let _ = write!(out, "{v:.decimals$}");
}

/// Appends an unsigned integer in decimal (digit by digit: `write!` goes through the
/// formatting machinery, which was a third of a CSV export).
pub(super) fn uint(out: &mut String, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut at = digits.len();
    loop {
        at -= 1;
        if let Some(d) = digits.get_mut(at) {
            *d = b'0' + (v % 10) as u8;
        }
        v /= 10;
        if v == 0 || at == 0 {
            break;
        }
    }
    out.push_str(std::str::from_utf8(digits.get(at..).unwrap_or(&[])).unwrap_or(""));
}

/// Calls `f` with every telemetry frame of `rec` as a row, truth joined, in order: a row is
/// handed over once nothing more can join it (its truth frame, the next telemetry frame, a
/// closed port, or the end), so an export streams instead of holding every row.
pub fn for_each_row(rec: &Recording, mut f: impl FnMut(TelemetryRow)) {
    // The newest row still open to its truth frame (which follows its telemetry frame).
    let mut open: Option<(u32, TelemetryRow)> = None;
    walk(rec, |item| match item {
        Item::Frame {
            t_us,
            dir: Direction::FromRobot,
            msg,
            ..
        } => match msg {
            Message::Telemetry(t) => {
                if let Some((_, row)) = open.replace((t.time_ms, TelemetryRow::new(t_us, t))) {
                    f(row);
                }
            }
            Message::EmuTruth(tr) => {
                if let Some((time_ms, mut row)) = open.take() {
                    if time_ms == tr.time_ms {
                        row.with_truth(tr);
                    }
                    f(row);
                }
            }
            _ => {}
        },
        Item::Link {
            state: LinkState::Closed,
            ..
        } => {
            if let Some((_, row)) = open.take() {
                f(row);
            }
        }
        _ => {}
    });
    if let Some((_, row)) = open {
        f(row);
    }
}

/// Every telemetry frame of `rec`, with truth joined, in order.
pub fn rows(rec: &Recording) -> Vec<TelemetryRow> {
    let mut rows = Vec::new();
    for_each_row(rec, |r| rows.push(r));
    rows
}

/// Writes the CSV; returns the number of rows. Each row is formatted into one reused line
/// buffer and handed to `w` (`station export` gives a `BufWriter`).
pub fn write(rec: &Recording, w: &mut impl Write) -> io::Result<usize> {
    writeln!(w, "{}", COLUMNS.join(","))?;
    let mut line = String::with_capacity(512);
    let mut n = 0;
    let mut result = Ok(());
    for_each_row(rec, |r| {
        if result.is_err() {
            return;
        }
        line.clear();
        r.write_csv_line(&mut line);
        line.push('\n');
        result = w.write_all(line.as_bytes());
        n += 1;
    });
    result.map(|()| n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_column_has_a_value() {
        let r = TelemetryRow::new(1_500_000, &Telemetry::default());
        assert_eq!(r.csv_line().split(',').count(), COLUMNS.len());
        assert!(r.csv_line().starts_with("1.500000,0.000,Idle,"));
    }

    #[test]
    fn fixed_point_writing_is_format_to_the_digit() {
        let mut values = vec![
            0.0,
            -0.0,
            -0.0001,
            0.0005,
            0.0015,
            -2.5,
            1e20,
            -1e20,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            123_456.789_012_5,
        ];
        for n in (-70_000i64..70_000).step_by(7) {
            for p in [1.0, 10.0, 1e3, 1e6] {
                values.push(n as f64 / p);
            }
        }
        values.push(i32::MIN as f64 / 1000.0);
        values.push(u32::MAX as f64 / 1e6);
        let mut out = String::new();
        for v in [0, 1, 9, 10, 65_535, u64::from(u32::MAX), u64::MAX] {
            out.clear();
            uint(&mut out, v);
            assert_eq!(out, v.to_string());
        }
        for v in values {
            for k in 0..=7 {
                out.clear();
                fixed(&mut out, v, k);
                assert_eq!(out, format!("{v:.k$}"), "{v} to {k} places");
            }
        }
    }

    #[test]
    fn the_columns_are_the_row_fields_with_arrays_spread() {
        let mut row = TelemetryRow::new(0, &Telemetry::default());
        row.with_truth(&EmuTruth::default());
        let v = serde_json::to_value(row).unwrap();
        let mut fields: Vec<String> = Vec::new();
        for (k, val) in v.as_object().unwrap() {
            match val.as_array() {
                Some(a) => fields.extend((0..a.len()).map(|i| format!("{k}{i}"))),
                None => fields.push(k.clone()),
            }
        }
        fields.sort();
        let mut cols: Vec<String> = COLUMNS.iter().map(|c| c.to_string()).collect();
        cols.sort();
        assert_eq!(fields, cols);
    }
}
