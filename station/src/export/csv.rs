//! Telemetry as CSV: one row per telemetry frame, in SI-ish units, with the emulator's ground
//! truth for the same robot time alongside when the recording has it.
//!
//! Layer: pure formatting over `export::walk`, writing to any `io::Write`. The columns are
//! `COLUMNS` (documented in README.md, "Recordings"); `TelemetryRow` is the same data for the
//! MCAP `/telemetry` channel. Invariants: a header line, then one line per telemetry frame in
//! recorded order; the truth columns are empty unless an `EmuTruth` with the frame's robot time
//! follows it. What can fail: the writer (`io::Error`).

use std::io::{self, Write};

use protocol::{flags, EmuTruth, Message, Telemetry};
use serde::Serialize;

use super::{walk, Direction, Item};
use crate::app::mode_name;
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
        let b = |v: bool| if v { "1" } else { "0" };
        let opt = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_default();
        let mut f: Vec<String> = vec![
            format!("{:.6}", self.time_s),
            format!("{:.3}", self.robot_time_s),
            self.mode.to_string(),
            format!("{:.3}", self.x_m),
            format!("{:.3}", self.y_m),
            format!("{:.3}", self.heading_rad),
            format!("{:.3}", self.sigma_xy_m),
            format!("{:.3}", self.sigma_heading_rad),
            format!("{:.3}", self.v_left_m_s),
            format!("{:.3}", self.v_right_m_s),
            self.enc_left.to_string(),
            self.enc_right.to_string(),
        ];
        f.extend(self.ir.iter().map(u16::to_string));
        f.extend(self.light.iter().map(u16::to_string));
        f.extend([
            format!("{:.1}", self.compass_deg),
            self.flags.to_string(),
            b(self.on_goal).into(),
            b(self.on_line).into(),
            b(self.contact).into(),
            b(self.failsafe).into(),
            b(self.goal_reached).into(),
            self.line_events.to_string(),
            format!("{:.1}", self.beacon_bearing_deg),
            self.beacon_strength.to_string(),
            format!("{:.3}", self.battery_v),
            self.behaviours.to_string(),
            format!("{:.3}", self.motor_left_m_s),
            format!("{:.3}", self.motor_right_m_s),
            format!("{:.3}", self.cycle_period_ms),
            format!("{:.3}", self.cycle_busy_ms),
            self.cycle_overruns.to_string(),
            opt(self.true_x_m),
            opt(self.true_y_m),
            opt(self.true_heading_rad),
            self.collisions.map(|c| c.to_string()).unwrap_or_default(),
        ]);
        f.join(",")
    }
}

/// Every telemetry frame of `rec`, with truth joined, in order.
pub fn rows(rec: &Recording) -> Vec<TelemetryRow> {
    let mut rows = Vec::new();
    // The newest row still open to its truth frame (which follows its telemetry frame).
    let mut open: Option<(u32, usize)> = None;
    walk(rec, |item| match item {
        Item::Frame {
            t_us,
            dir: Direction::FromRobot,
            msg,
            ..
        } => match msg {
            Message::Telemetry(t) => {
                open = Some((t.time_ms, rows.len()));
                rows.push(TelemetryRow::new(t_us, t));
            }
            Message::EmuTruth(tr) => {
                if let Some((time_ms, i)) = open.take() {
                    if let (true, Some(r)) = (time_ms == tr.time_ms, rows.get_mut(i)) {
                        r.with_truth(tr);
                    }
                }
            }
            _ => {}
        },
        Item::Link {
            state: LinkState::Closed,
            ..
        } => open = None,
        _ => {}
    });
    rows
}

/// Writes the CSV; returns the number of rows.
pub fn write(rec: &Recording, w: &mut impl Write) -> io::Result<usize> {
    writeln!(w, "{}", COLUMNS.join(","))?;
    let rows = rows(rec);
    for r in &rows {
        writeln!(w, "{}", r.csv_line())?;
    }
    Ok(rows.len())
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
