//! The parameter editor's state: the firmware's parameter table, the values read back, and
//! what the robot said about the last read or write of each.
//!
//! Layer: app state, no I/O. The list is `robot_firmware::params::PARAMS`, the same table the
//! robot uses, so names, units and ranges cannot drift. A value typed by the operator is
//! checked against the range here first (a quick local hint), but the robot's Ack or Nack is
//! what is shown as the outcome.

use protocol::NackReason;
use robot_firmware::params::{ParamInfo, PARAMS};

use crate::link::api::nack_text;

/// What is known of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamStatus {
    Unknown,
    /// A read or write is on its way.
    Pending,
    /// The value the robot reported in force.
    Value(f32),
    /// The robot refused; the value it had is kept if known.
    Refused {
        reason: NackReason,
        last: Option<f32>,
    },
    /// No answer (timeout, link lost).
    Failed(String),
}

/// The editor.
#[derive(Clone, Debug)]
pub struct ParamEditor {
    pub selected: usize,
    pub status: Vec<ParamStatus>,
    /// Text being typed for the selected parameter.
    pub input: Option<String>,
    /// Why the typed text was not sent (shown on the edit line until the next key).
    pub input_error: Option<String>,
}

impl Default for ParamEditor {
    fn default() -> Self {
        ParamEditor {
            selected: 0,
            status: vec![ParamStatus::Unknown; PARAMS.len()],
            input: None,
            input_error: None,
        }
    }
}

impl ParamEditor {
    pub fn params(&self) -> &'static [ParamInfo] {
        &PARAMS
    }

    pub fn selected_info(&self) -> Option<&'static ParamInfo> {
        PARAMS.get(self.selected)
    }

    pub fn select(&mut self, delta: i32) {
        let n = PARAMS.len() as i64;
        if n == 0 {
            return;
        }
        self.selected = (self.selected as i64 + i64::from(delta)).rem_euclid(n) as usize;
        self.input = None;
    }

    /// The index of parameter `id` in the table.
    pub fn index_of(&self, id: u16) -> Option<usize> {
        PARAMS.iter().position(|p| p.id == id)
    }

    fn last_value(&self, i: usize) -> Option<f32> {
        match self.status.get(i)? {
            ParamStatus::Value(v) => Some(*v),
            ParamStatus::Refused { last, .. } => *last,
            _ => None,
        }
    }

    pub fn set_pending(&mut self, id: u16) {
        if let Some(s) = self.index_of(id).and_then(|i| self.status.get_mut(i)) {
            *s = ParamStatus::Pending;
        }
    }

    pub fn set_value(&mut self, id: u16, v: f32) {
        if let Some(s) = self.index_of(id).and_then(|i| self.status.get_mut(i)) {
            *s = ParamStatus::Value(v);
        }
    }

    /// Records a refusal; `before` is the value known before the request was sent.
    pub fn set_refused(&mut self, id: u16, reason: NackReason, before: Option<f32>) {
        if let Some(i) = self.index_of(id) {
            let last = before.or_else(|| self.last_value(i));
            if let Some(s) = self.status.get_mut(i) {
                *s = ParamStatus::Refused { reason, last };
            }
        }
    }

    pub fn set_failed(&mut self, id: u16, why: String) {
        if let Some(s) = self.index_of(id).and_then(|i| self.status.get_mut(i)) {
            *s = ParamStatus::Failed(why);
        }
    }

    /// The known value of parameter `id`.
    pub fn value_of(&self, id: u16) -> Option<f32> {
        self.index_of(id).and_then(|i| self.last_value(i))
    }

    /// Parses the typed text for the selected parameter. The range check is a hint; the robot
    /// decides.
    pub fn parse_input(&self) -> Result<(u16, f32), String> {
        let info = self.selected_info().ok_or("no parameter selected")?;
        let text = self.input.as_deref().unwrap_or("").trim();
        let v: f32 = text
            .parse()
            .map_err(|_| format!("{text:?} is not a number"))?;
        Ok((info.id, v))
    }
}

/// A short text for a parameter's status column.
pub fn status_text(s: &ParamStatus) -> String {
    match s {
        ParamStatus::Unknown => "?".into(),
        ParamStatus::Pending => "…".into(),
        ParamStatus::Value(v) => format_value(*v),
        ParamStatus::Refused { reason, last } => match last {
            Some(v) => format!("{} (refused: {})", format_value(*v), nack_text(*reason)),
            None => format!("refused: {}", nack_text(*reason)),
        },
        ParamStatus::Failed(why) => format!("failed: {why}"),
    }
}

/// A value without needless decimals.
pub fn format_value(v: f32) -> String {
    if v.fract() == 0.0 && v.abs() < 1e7 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_keeps_the_last_known_value_and_names_the_reason() {
        let mut p = ParamEditor::default();
        p.set_value(0, 300.0);
        p.set_pending(0);
        p.set_refused(0, NackReason::OutOfRange, Some(300.0));
        let text = status_text(&p.status[0]);
        assert_eq!(text, "300 (refused: value out of range)");
    }

    #[test]
    fn selection_wraps_around_the_table() {
        let mut p = ParamEditor::default();
        p.select(-1);
        assert_eq!(p.selected, PARAMS.len() - 1);
        p.select(1);
        assert_eq!(p.selected, 0);
    }
}
