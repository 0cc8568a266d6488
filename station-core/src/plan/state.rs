//! What the TUI keeps of planning: the map's [`Planner`] (segmented once), the last plan and
//! the last failure.
//!
//! Layer: app state, no I/O and no clock of its own (timings are measured around the nav
//! calls, for display only). The map comes from `--arena FILE` or the built-in emulator's
//! arena ([`PlanState::for_arena`]); a map received from the robot enters through
//! [`PlanState::show_map_object`] (the seam for map downloads: the Map object's bytes, parsed
//! by `protocol::object::MapView`), or [`PlanState::show_map`] for a map built otherwise. Planning is always smoothed too: the map layers choose
//! what to show. Cannot fail: failures become a message for the log and the map title.

use super::map::{MapOptions, NavMap};
use super::solve::{PlanResult, Planner};
use super::NavError;

/// The station-side planning state the map layers draw.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlanState {
    planner: Option<Planner>,
    /// The last plan made.
    pub result: Option<PlanResult>,
    /// Why the last attempt failed (cleared by a success).
    pub error: Option<String>,
}

impl PlanState {
    /// State over a map (segments it now, so the regions layer has something to draw).
    pub fn from_map(map: NavMap) -> Result<PlanState, NavError> {
        Ok(PlanState {
            planner: Some(Planner::new(map)?),
            ..PlanState::default()
        })
    }

    /// State for an arena the TUI draws, gridded with the `station plan` defaults; a map
    /// that cannot be gridded leaves no planner and says why.
    pub fn for_arena(arena: &emulator::arena::Arena, source: &str) -> PlanState {
        let map = NavMap::from_arena(arena, source, &MapOptions::default());
        match map.and_then(PlanState::from_map) {
            Ok(s) => s,
            Err(e) => PlanState {
                error: Some(format!("no planning grid for {source}: {e}")),
                ..PlanState::default()
            },
        }
    }

    /// State for the built-in emulator's arena (Micro-Rato'99).
    pub fn for_builtin() -> PlanState {
        let name = emulator::builtin::MICRO_RATO_99;
        match emulator::builtin::load(name, &emulator::arena::LoadOptions::default()) {
            Ok(a) => PlanState::for_arena(&a, name),
            Err(e) => PlanState {
                error: Some(format!("no planning grid: {e}")),
                ..PlanState::default()
            },
        }
    }

    /// Replaces the map (e.g. one received from the robot) and forgets the old plan.
    pub fn show_map(&mut self, map: NavMap) -> Result<(), NavError> {
        let planner = Planner::new(map)?;
        *self = PlanState {
            planner: Some(planner),
            ..PlanState::default()
        };
        Ok(())
    }

    /// The seam for map downloads: shows the Map object `bytes` (PROTOCOL.md §12) as the
    /// planning map. On an error the current map stays.
    pub fn show_map_object(&mut self, name: &str, bytes: &[u8]) -> Result<(), NavError> {
        self.show_map(NavMap::from_map_object(name, bytes)?)
    }

    /// The segmented map, if there is one.
    pub fn planner(&self) -> Option<&Planner> {
        self.planner.as_ref()
    }

    /// The map, if there is one.
    pub fn map(&self) -> Option<&NavMap> {
        self.planner.as_ref().map(Planner::map)
    }

    /// Plans from `from` (else the map's start) to `to` (else the map's goal) and keeps the
    /// result; returns the line for the log, `Err` with the reason when it failed.
    pub fn plan(
        &mut self,
        from: Option<(f64, f64)>,
        to: Option<(f64, f64)>,
    ) -> Result<String, String> {
        let Some(planner) = &self.planner else {
            let e = self
                .error
                .clone()
                .unwrap_or_else(|| "no map to plan on: start the station with --arena FILE".into());
            self.error = Some(e.clone());
            return Err(e);
        };
        match planner.plan(from, to, true) {
            Ok(r) => {
                let (s, g) = (r.start(), r.goal());
                let smooth = r
                    .smoothed
                    .as_ref()
                    .map_or(String::new(), |s| format!(", smoothed {:.2} m", s.length_m));
                let line = format!(
                    "planned on the station: ({:.2}, {:.2}) -> ({:.2}, {:.2}), {} regions, \
                     {:.2} m{smooth} (A* {} µs)",
                    s.0,
                    s.1,
                    g.0,
                    g.1,
                    r.path.len(),
                    r.length_m,
                    r.search_us
                );
                self.result = Some(r);
                self.error = None;
                Ok(line)
            }
            Err(e) => {
                let e = format!("plan: {e}");
                self.error = Some(e.clone());
                Err(e)
            }
        }
    }

    /// Forgets the plan (the map stays).
    pub fn clear(&mut self) {
        self.result = None;
        self.error = None;
    }
}
