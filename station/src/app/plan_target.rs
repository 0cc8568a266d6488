//! What `O` (plan on the robot) and `P` (plan on the station) plan to, and what the robot's
//! motion mode is doing (its `Progress` reports).
//!
//! Layer: app state, no I/O. The plan's target is the map's goal unless the operator chose
//! one: `O` or `P` pressed while the go-to cursor is shown (`g`) makes the cursor the chosen
//! target; `G` and `Esc` go back to the map's goal. Go-to clicks never change it (they once
//! did: "click it elsewhere, then O plans back to that goal" planned to the clicked point).
//! The target is drawn on the map (`◎`), named in the footer beside `O`, and every plan
//! request's log line says where it plans to. Cannot fail.

use protocol::Progress;

use super::log::{Level, Source};
use super::App;

/// What the station calls a map it received from the robot.
pub const ROBOT_MAP_NAME: &str = "robot map";

/// Where the robot's installed plan goes, as the station knows it.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanFor {
    /// Made by the robot at `O`, for this target.
    Target(PlanTarget),
    /// Uploaded from this file.
    Uploaded(String),
    /// Installed by something else (another station on the link): not shown here.
    Elsewhere,
}

/// Where a plan goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlanTarget {
    /// The point the operator chose, metres.
    Chosen((f64, f64)),
    /// The map's goal: where the station's map puts it (metres), if it knows.
    MapGoal(Option<(f64, f64)>),
}

impl PlanTarget {
    /// The point, if known (the robot knows its own map's goal even when the station does not).
    pub fn point(&self) -> Option<(f64, f64)> {
        match *self {
            PlanTarget::Chosen(p) => Some(p),
            PlanTarget::MapGoal(p) => p,
        }
    }

    /// "the map's goal (2.90, 2.40)", "the chosen target (1.00, 2.00)".
    pub fn describe(&self) -> String {
        match *self {
            PlanTarget::Chosen((x, y)) => format!("the chosen target ({x:.2}, {y:.2})"),
            PlanTarget::MapGoal(Some((x, y))) => format!("the map's goal ({x:.2}, {y:.2})"),
            PlanTarget::MapGoal(None) => "the map's goal".into(),
        }
    }

    /// Whether two targets are the same place for a plan: the same chosen point, or both
    /// the map's goal (wherever the station's map puts it now).
    pub fn same(&self, other: &PlanTarget) -> bool {
        match (self, other) {
            (PlanTarget::Chosen(a), PlanTarget::Chosen(b)) => a == b,
            (PlanTarget::MapGoal(_), PlanTarget::MapGoal(_)) => true,
            _ => false,
        }
    }

    /// The footer's short form.
    pub fn short(&self) -> String {
        match *self {
            PlanTarget::Chosen((x, y)) => format!("plan to ({x:.1}, {y:.1})"),
            PlanTarget::MapGoal(_) => "plan to goal".into(),
        }
    }
}

impl App {
    /// What a plan goes to now: the cursor while it is shown (pressing `O` or `P` then
    /// chooses it), else the chosen target, else the map's goal.
    pub fn plan_target(&self) -> PlanTarget {
        if self.map.cursor_mode {
            return PlanTarget::Chosen(self.map.cursor);
        }
        match self.map.plan_target {
            Some(p) => PlanTarget::Chosen(p),
            None => PlanTarget::MapGoal(self.map.plan.map().and_then(|m| m.goal).map(|g| g.centre)),
        }
    }

    /// `O` or `P` pressed: the cursor, if shown, becomes the chosen target. Returns the
    /// target to plan to.
    pub(super) fn take_plan_target(&mut self) -> PlanTarget {
        if self.map.cursor_mode {
            self.map.cursor_mode = false;
            self.map.plan_target = Some(self.map.cursor);
        }
        self.plan_target()
    }

    /// `G` (or `Esc` with nothing else open): plans go to the map's goal again, and the
    /// go-to marker is cleared. True when there was something to clear.
    pub(super) fn reset_plan_target(&mut self) -> bool {
        let had = self.map.plan_target.take().is_some() | self.map.goal.take().is_some();
        if had {
            let to = self.plan_target().describe();
            self.note(
                Level::Info,
                Source::Command,
                format!("plans go to {to} again"),
            );
        }
        had
    }

    /// The `NoProgress` event in words (`format::no_progress_text`), from the last report.
    pub(super) fn no_progress_text(&self, stuck_ms: i32) -> String {
        let p = self.progress.as_ref();
        crate::format::no_progress_text(
            p.map(|p| p.mode),
            p.and_then(|p| p.distance_left_mm),
            stuck_ms,
        )
    }

    /// After a `Segment`/`Plan` refused for capacity: how many squares the robot's map has,
    /// when the station shows it (counted with the same segmentation).
    pub(super) fn squares_detail(&self) -> String {
        let robot_map = self
            .map
            .plan
            .planner()
            .filter(|p| p.map().source == ROBOT_MAP_NAME);
        match robot_map {
            Some(p) => format!(" (the robot's map has {} squares)", p.squares().len()),
            None => String::new(),
        }
    }

    /// After a `GoTo` refused as outside the arena: the robot's bounds if the parameter
    /// editor knows them; they are read now so the editor shows them.
    pub(super) fn arena_bounds_detail(&mut self) -> String {
        use robot_firmware::params::id;
        let ids = [
            id::ARENA_MIN_X_M,
            id::ARENA_MAX_X_M,
            id::ARENA_MIN_Y_M,
            id::ARENA_MAX_Y_M,
        ];
        let known: Option<Vec<f32>> = ids.iter().map(|&i| self.params.value_of(i)).collect();
        for i in ids {
            self.read_param(i);
        }
        match known.as_deref() {
            Some([x0, x1, y0, y1]) => {
                format!(" (the robot's arena: x {x0:.2} .. {x1:.2} m, y {y0:.2} .. {y1:.2} m)")
            }
            _ => " (reading the robot's arena bounds: see the parameter editor, p)".into(),
        }
    }

    /// The `GoalReached` event in words: what the task that arrived was, and where (the
    /// robot says only that its task reached its end; the goal is the goal only when
    /// exploring found it, or a plan to the map's goal got there).
    pub(super) fn arrival_text(&self) -> String {
        let at = self.pose().map(|(x, y, _)| (x, y));
        let mode = self
            .progress
            .map(|p| p.mode)
            .or_else(|| self.telemetry.map(|t| t.mode));
        let to_goal = matches!(
            &self.transfers.plan_for,
            Some(PlanFor::Target(PlanTarget::MapGoal(_)))
        );
        crate::format::arrival_text(mode, at, to_goal)
    }

    /// A `Progress` report from the robot.
    pub(super) fn on_progress(&mut self, p: Progress) {
        self.progress = Some(p);
    }

    /// What the robot's mode is doing, for the header; `None` when it reports nothing (Idle,
    /// an old firmware) or telemetry says another mode. `short` drops the time.
    pub fn progress_text(&self, short: bool) -> Option<String> {
        let p = self.progress?;
        let mode = self.telemetry.map(|t| t.mode);
        if mode.is_some_and(|m| m != p.mode) {
            return None;
        }
        crate::format::progress_text(&p, short)
    }
}

#[cfg(test)]
#[path = "plan_target_tests.rs"]
mod tests;
