//! Foraging progress (seed 000 §7) as the station learns it from the robot: objects gripped
//! and delivered (events `ObjectGrasped`, `ObjectDelivered`, `SourceEmpty`), whether the
//! gripper holds one (telemetry flag `CARRYING`), and which of the arena's objects have been
//! taken, for the map.
//!
//! Layer: app state, updated from link events; drawn by `ui::forage`. An object is marked
//! taken when the robot reports a grasp while an untaken object lies within `TAKEN_RADIUS_M`
//! of where it is (the true pose when the emulator sends one, else the believed pose): the
//! station has no other view of the objects. Cannot fail.

use protocol::{flags, Event, EventCode, Telemetry};

use super::arena::ForageOverlay;

/// How close to a reported grasp an object must be to count as the one taken, metres: the
/// fingers are 4 cm ahead of the centre, plus odometry error.
pub const TAKEN_RADIUS_M: f64 = 0.15;

/// What the station knows of the foraging run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ForageProgress {
    /// Objects the robot reported gripping.
    pub grasped: u32,
    /// Objects the robot reported putting down at home.
    pub delivered: u32,
    /// Sources the robot found empty.
    pub empty: u32,
    /// The gripper holds an object (last telemetry).
    pub carrying: bool,
    /// Per arena object: taken from its source.
    pub taken: Vec<bool>,
}

impl ForageProgress {
    /// Takes a robot event; `at` is where the robot is, `site` the arena's foraging site.
    pub fn on_event(&mut self, e: &Event, at: Option<(f64, f64)>, site: Option<&ForageOverlay>) {
        let count = u32::try_from(e.value).unwrap_or(0);
        match e.code {
            EventCode::ObjectGrasped => {
                self.grasped = count;
                self.carrying = true;
                if let (Some((x, y)), Some(site)) = (at, site) {
                    self.mark_nearest(x, y, site);
                }
            }
            EventCode::ObjectDelivered => {
                self.delivered = count;
                self.carrying = false;
            }
            EventCode::SourceEmpty => self.empty = count,
            _ => {}
        }
    }

    /// Takes a telemetry frame (the gripper's object-present flag).
    pub fn on_telemetry(&mut self, t: &Telemetry) {
        self.carrying = t.flags & flags::CARRYING != 0;
    }

    /// Whether object `i` of the site has been taken.
    pub fn is_taken(&self, i: usize) -> bool {
        self.taken.get(i).copied().unwrap_or(false)
    }

    fn mark_nearest(&mut self, x: f64, y: f64, site: &ForageOverlay) {
        self.taken.resize(site.objects.len(), false);
        let nearest = site
            .objects
            .iter()
            .enumerate()
            .filter(|(i, _)| !self.is_taken(*i))
            .map(|(i, (ox, oy))| (i, (ox - x).hypot(oy - y)))
            .filter(|&(_, d)| d <= TAKEN_RADIUS_M)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((i, _)) = nearest {
            if let Some(t) = self.taken.get_mut(i) {
                *t = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn site() -> ForageOverlay {
        ForageOverlay {
            home: ((0.1, 0.1), 0.1),
            objects: vec![(0.8, 0.6), (0.2, 0.6)],
            landmarks: vec![],
        }
    }

    #[test]
    fn a_grasp_marks_the_nearest_object_and_deliveries_count() {
        let mut f = ForageProgress::default();
        let grasp = Event {
            code: EventCode::ObjectGrasped,
            value: 1,
        };
        f.on_event(&grasp, Some((0.76, 0.6)), Some(&site()));
        assert!(f.is_taken(0) && !f.is_taken(1) && f.carrying);
        // Far from every object: nothing more is marked.
        f.on_event(&grasp, Some((0.5, 0.1)), Some(&site()));
        assert!(!f.is_taken(1));
        let delivered = Event {
            code: EventCode::ObjectDelivered,
            value: 2,
        };
        f.on_event(&delivered, None, None);
        assert_eq!((f.grasped, f.delivered, f.carrying), (1, 2, false));
    }
}
