//! The parameter editor's state: the firmware's parameter table, the values read back, and
//! what the robot said about the last read or write of each.
//!
//! Layer: app state, no I/O. The list is `robot_firmware::params::PARAMS`, the same table the
//! robot uses, so names, units and ranges cannot drift. A value typed by the operator is
//! checked against the range here first (a quick local hint), but the robot's Ack or Nack is
//! what is shown as the outcome.

use protocol::NackReason;
use robot_firmware::params::{ParamInfo, PARAMS};
pub use station_core::format::{format_param, format_param_id, format_value, range_text};

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
    /// This robot lacks the hardware the parameter is for (`ParamInfo::requires`).
    Absent,
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
    /// A fetch of every parameter in progress: reads left, values read, reads that failed.
    fetch: Option<(usize, usize, usize)>,
    /// The search (`/`): only parameters whose name or description contains it are listed.
    pub search: String,
    /// The search is being typed.
    pub searching: bool,
}

impl Default for ParamEditor {
    fn default() -> Self {
        ParamEditor {
            selected: 0,
            status: vec![ParamStatus::Unknown; PARAMS.len()],
            input: None,
            input_error: None,
            fetch: None,
            search: String::new(),
            searching: false,
        }
    }
}

impl ParamEditor {
    pub fn params(&self) -> &'static [ParamInfo] {
        &PARAMS
    }

    /// The selected parameter, if it is listed (a search may hide every one).
    pub fn selected_info(&self) -> Option<&'static ParamInfo> {
        PARAMS
            .get(self.selected)
            .filter(|p| matches(p, &self.search))
    }

    /// The indices (into the table) of the parameters listed: those the search finds.
    pub fn shown(&self) -> Vec<usize> {
        PARAMS
            .iter()
            .enumerate()
            .filter(|(_, p)| matches(p, &self.search))
            .map(|(i, _)| i)
            .collect()
    }

    /// Moves the selection `delta` rows through the listed parameters, wrapping around.
    pub fn select(&mut self, delta: i32) {
        let shown = self.shown();
        let n = shown.len() as i64;
        if n == 0 {
            return;
        }
        let at = shown.iter().position(|&i| i >= self.selected).unwrap_or(0) as i64;
        let to = (at + i64::from(delta)).rem_euclid(n) as usize;
        self.selected = shown.get(to).copied().unwrap_or(0);
        self.input = None;
    }

    /// Changes the search; the selection moves to the first match if it no longer is one.
    pub fn set_search(&mut self, text: String) {
        self.search = text;
        let shown = self.shown();
        if !shown.contains(&self.selected) {
            if let Some(&first) = shown.first() {
                self.selected = first;
            }
        }
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

    pub fn set_absent(&mut self, id: u16) {
        if let Some(s) = self.index_of(id).and_then(|i| self.status.get_mut(i)) {
            *s = ParamStatus::Absent;
        }
    }

    /// A fetch of `reads` parameters starts (a new one replaces any in progress).
    pub fn start_fetch(&mut self, reads: usize) {
        self.fetch = (reads > 0).then_some((reads, 0, 0));
    }

    /// One read of the fetch ended; at the last, the fetch's (read, not read) counts.
    pub fn fetch_step(&mut self, ok: bool) -> Option<(usize, usize)> {
        let (left, read, missed) = self.fetch.as_mut()?;
        *left = left.saturating_sub(1);
        if ok {
            *read += 1;
        } else {
            *missed += 1;
        }
        if *left == 0 {
            let done = (*read, *missed);
            self.fetch = None;
            return Some(done);
        }
        None
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

/// Whether a parameter's name or description contains `search` (any case); an empty search
/// finds every parameter.
pub fn matches(p: &ParamInfo, search: &str) -> bool {
    let needle = search.trim().to_lowercase();
    needle.is_empty()
        || p.name.to_lowercase().contains(&needle)
        || p.desc.to_lowercase().contains(&needle)
}

/// A short text for a parameter's status column.
pub fn status_text(info: &ParamInfo, s: &ParamStatus) -> String {
    match s {
        ParamStatus::Unknown => "?".into(),
        ParamStatus::Pending => "…".into(),
        ParamStatus::Value(v) => format_param(info, *v),
        ParamStatus::Refused { reason, last } => match last {
            Some(v) => format!(
                "{} (refused: {})",
                format_param(info, *v),
                nack_text(*reason)
            ),
            None => format!("refused: {}", nack_text(*reason)),
        },
        ParamStatus::Failed(why) => format!("failed: {why}"),
        ParamStatus::Absent => "not on this robot".into(),
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
        let text = status_text(&PARAMS[0], &p.status[0]);
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

    /// Issue 16: odo_mm_per_pulse (0.001..10 mm) showed as 0. Every value in a parameter's
    /// range shows non-zero unless it is zero, and its bounds read back as themselves.
    #[test]
    fn display_precision_follows_the_parameters_range() {
        for info in PARAMS.iter() {
            for v in [info.min, info.max] {
                let text = format_param(info, v);
                let back: f32 = text.parse().unwrap_or(f32::NAN);
                assert!(
                    (back - v).abs() <= v.abs() * 1e-6,
                    "{}: {v} shows as {text}",
                    info.name
                );
            }
        }
        let mm = robot_firmware::params::by_name("odo_mm_per_pulse").copied();
        let mm = mm.unwrap_or(PARAMS[0]);
        assert_eq!(format_param(&mm, 0.08), "0.080");
        assert_eq!(range_text(&mm), "0.001 .. 10.000");
        assert_eq!(format_param(&PARAMS[0], 300.0), "300");
    }

    #[test]
    fn a_search_lists_the_matching_parameters_and_selects_among_them() {
        let mut p = ParamEditor::default();
        p.set_search("WHEEL".into());
        let names: Vec<&str> = p.shown().iter().map(|&i| PARAMS[i].name).collect();
        assert!(names.contains(&"odo_wheel_distance_mm"), "{names:?}");
        assert!(names.iter().all(|n| {
            let i = PARAMS.iter().position(|q| q.name == *n).unwrap();
            matches(&PARAMS[i], "wheel")
        }));
        assert!(names.len() < PARAMS.len());
        // The selection jumped to the first match and steps among the matches only.
        assert_eq!(p.selected_info().map(|i| i.name), names.first().copied());
        p.select(1);
        assert_eq!(p.selected_info().map(|i| i.name), names.get(1).copied());
        p.select(-2);
        assert_eq!(p.selected_info().map(|i| i.name), names.last().copied());
        // Found by its description too.
        p.set_search("failsafe".into());
        assert!(p.shown().iter().any(|&i| PARAMS[i].name == "failsafe_ms"));
        // Nothing found: nothing selected to edit.
        p.set_search("no such words".into());
        assert!(p.shown().is_empty());
        assert_eq!(p.selected_info(), None);
        p.set_search(String::new());
        assert_eq!(p.shown().len(), PARAMS.len());
    }

    #[test]
    fn a_fetch_reports_once_when_its_last_read_ends() {
        let mut p = ParamEditor::default();
        p.start_fetch(3);
        assert_eq!(p.fetch_step(true), None);
        assert_eq!(p.fetch_step(false), None);
        assert_eq!(p.fetch_step(true), Some((2, 1)));
        assert_eq!(p.fetch_step(true), None, "a stray answer after the fetch");
    }
}
