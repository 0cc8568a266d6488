//! How a task the station started ends: what `station send --wait` waits for.
//!
//! Layer: pure state over the link events that follow the command's Ack; no I/O, and no clock
//! of its own (the caller gives the time). The robot ends a task with an event and goes Idle:
//! `GoalReached` when it arrived (after `PlanFinished` for a plan), `NoProgress` when it gave
//! up, `PlanAborted` when its plan was replaced; a `ModeChanged` to another mode means
//! something else ended it (a stop, another command, another station). The robot answers a
//! command as it reads it and sends each cycle's events before that cycle's telemetry, so all
//! that follows the Ack is about this task. An event can be lost on the wire, so telemetry
//! decides too: a frame in another mode arrived if it has the `ARRIVED` flag, and ended
//! otherwise if not.

use protocol::{flags, EventCode, Mode, Progress, Telemetry};

use crate::format::{arrival_text, mode_from_index, mode_name, mode_name_i32, task_name};
use crate::link::LinkEvent;
use crate::watch::LinkLoss;

/// How a wait for a task ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// The robot reached its go-to point, its plan's end, or (exploring) the goal area.
    Arrived,
    /// The robot refused the command; nothing started.
    Refused,
    /// The robot gave up: no progress for its limit, or its plan was aborted.
    GaveUp,
    /// The task ended without arriving: stopped, or another mode was set.
    Stopped,
    /// The wait's time limit passed; the robot goes on with its task.
    TimedOut,
    /// The link was lost; what the robot does now is not known.
    LinkLost,
}

impl Ending {
    pub const ALL: [Ending; 6] = [
        Ending::Arrived,
        Ending::Refused,
        Ending::GaveUp,
        Ending::Stopped,
        Ending::TimedOut,
        Ending::LinkLost,
    ];

    /// The name JSON and the reason line give.
    pub fn name(self) -> &'static str {
        match self {
            Ending::Arrived => "arrived",
            Ending::Refused => "refused",
            Ending::GaveUp => "gave_up",
            Ending::Stopped => "stopped",
            Ending::TimedOut => "timeout",
            Ending::LinkLost => "link_lost",
        }
    }
}

/// The end of a wait and why, in words.
#[derive(Clone, Debug, PartialEq)]
pub struct Ended {
    pub ending: Ending,
    pub reason: String,
}

impl Ended {
    pub fn new(ending: Ending, reason: impl Into<String>) -> Ended {
        Ended {
            ending,
            reason: reason.into(),
        }
    }
}

/// Follows a task in `mode` from its command's Ack to its end.
#[derive(Clone, Debug)]
pub struct TaskWatch {
    mode: Mode,
    telemetry: Option<Telemetry>,
    progress: Option<Progress>,
    loss: LinkLoss,
}

impl TaskWatch {
    /// A task in `mode` (GoTo, ExecutePlan, Explore), its command just acknowledged; `before`
    /// is the last telemetry frame before the Ack (where the robot was), if one came.
    pub fn new(mode: Mode, before: Option<Telemetry>) -> TaskWatch {
        TaskWatch {
            mode,
            telemetry: before,
            progress: None,
            loss: LinkLoss::default(),
        }
    }

    /// The next link event, at `t_us`; `Some` once the task has ended.
    pub fn on_event(&mut self, t_us: u64, ev: &LinkEvent) -> Option<Ended> {
        match ev {
            LinkEvent::Connection(c) => {
                let why = self.loss.on_connection(t_us, c)?;
                Some(Ended::new(Ending::LinkLost, format!("link lost: {why}")))
            }
            LinkEvent::Progress(p) => {
                self.progress = Some(*p);
                None
            }
            LinkEvent::Telemetry(t) => {
                self.telemetry = Some(*t);
                if t.mode == self.mode {
                    return None;
                }
                Some(if t.flags & flags::ARRIVED != 0 {
                    Ended::new(Ending::Arrived, self.arrived())
                } else {
                    Ended::new(
                        Ending::Stopped,
                        format!(
                            "{} ended without arriving: the robot is in mode {} (the event that \
                             said why was not received)",
                            task_name(self.mode),
                            mode_name(t.mode)
                        ),
                    )
                })
            }
            LinkEvent::Robot(e) => match e.code {
                EventCode::GoalReached => Some(Ended::new(Ending::Arrived, self.arrived())),
                EventCode::NoProgress => Some(Ended::new(
                    Ending::GaveUp,
                    crate::format::no_progress_text(
                        Some(self.mode),
                        self.progress.and_then(|p| p.distance_left_mm),
                        e.value,
                    ),
                )),
                EventCode::PlanAborted => Some(Ended::new(
                    Ending::GaveUp,
                    format!(
                        "plan execution aborted at waypoint {} (the robot's plan was replaced); \
                         the robot stopped",
                        e.value
                    ),
                )),
                EventCode::ModeChanged if mode_from_index(e.value) != Some(self.mode) => {
                    Some(Ended::new(
                        Ending::Stopped,
                        format!(
                            "{} ended without arriving: the robot's mode changed to {} (a stop, \
                             another command or another station)",
                            task_name(self.mode),
                            mode_name_i32(e.value)
                        ),
                    ))
                }
                _ => None,
            },
            _ => None,
        }
    }

    /// When `poll` must be called next: while a session is gone, the end of its grace.
    pub fn deadline_us(&self) -> Option<u64> {
        self.loss.deadline_us()
    }

    /// `Some` when the link has been gone too long at `t_us`.
    pub fn poll(&self, t_us: u64) -> Option<Ended> {
        let why = self.loss.poll(t_us)?;
        Some(Ended::new(Ending::LinkLost, format!("link lost: {why}")))
    }

    /// The last telemetry frame (since the Ack, or the one before it).
    pub fn telemetry(&self) -> Option<&Telemetry> {
        self.telemetry.as_ref()
    }

    /// The last progress report since the Ack.
    pub fn progress(&self) -> Option<&Progress> {
        self.progress.as_ref()
    }

    fn arrived(&self) -> String {
        let at = self.telemetry.map(|t| {
            (
                f64::from(t.pose.x_mm) / 1000.0,
                f64::from(t.pose.y_mm) / 1000.0,
            )
        });
        arrival_text(Some(self.mode), at, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::Connection;
    use protocol::{Event, Pose};

    fn event(code: EventCode, value: i32) -> LinkEvent {
        LinkEvent::Robot(Event { code, value })
    }

    fn telemetry(mode: Mode, flags: u8) -> LinkEvent {
        LinkEvent::Telemetry(Telemetry {
            mode,
            flags,
            pose: Pose {
                x_mm: 500,
                y_mm: 860,
                heading_mrad: 0,
            },
            ..Telemetry::default()
        })
    }

    #[test]
    fn a_go_to_arrives_by_its_event_and_what_follows_is_not_read() {
        let mut w = TaskWatch::new(Mode::GoTo, None);
        assert_eq!(w.on_event(0, &event(EventCode::ModeChanged, 2)), None);
        assert_eq!(w.on_event(1, &telemetry(Mode::GoTo, 0)), None);
        let end = w.on_event(2, &event(EventCode::GoalReached, 0)).unwrap();
        assert_eq!(end.ending, Ending::Arrived);
        assert_eq!(end.reason, "arrived at (0.50, 0.86): the go-to point");
    }

    #[test]
    fn telemetry_decides_when_the_event_was_lost() {
        let mut w = TaskWatch::new(Mode::GoTo, None);
        assert_eq!(w.on_event(0, &telemetry(Mode::GoTo, 0)), None);
        let end = w
            .on_event(1, &telemetry(Mode::Idle, flags::ARRIVED))
            .unwrap();
        assert_eq!(end.ending, Ending::Arrived);
        let mut w = TaskWatch::new(Mode::Explore, None);
        let end = w.on_event(1, &telemetry(Mode::Idle, 0)).unwrap();
        assert_eq!(end.ending, Ending::Stopped);
        assert!(
            end.reason.contains("exploration ended without arriving"),
            "{}",
            end.reason
        );
    }

    #[test]
    fn giving_up_stopping_and_aborting_are_told_apart() {
        let mut w = TaskWatch::new(Mode::GoTo, None);
        let p = Progress {
            mode: Mode::GoTo,
            waypoint: 0,
            waypoints: 0,
            distance_left_mm: Some(1500),
            elapsed_ms: 9000,
            stuck_ms: 5000,
            give_up_ms: 5000,
        };
        assert_eq!(w.on_event(0, &LinkEvent::Progress(p)), None);
        let end = w.on_event(1, &event(EventCode::NoProgress, 5000)).unwrap();
        assert_eq!(end.ending, Ending::GaveUp);
        assert_eq!(
            end.reason,
            "go-to gave up: no progress for 5 s, 1.5 m from its target; the robot stopped \
             (limit: parameter stuck_limit_s)"
        );
        let mut w = TaskWatch::new(Mode::ExecutePlan, None);
        assert_eq!(w.on_event(0, &event(EventCode::PlanFinished, 4)), None);
        assert_eq!(
            w.on_event(0, &event(EventCode::GoalReached, 0))
                .unwrap()
                .ending,
            Ending::Arrived
        );
        let mut w = TaskWatch::new(Mode::ExecutePlan, None);
        let end = w.on_event(0, &event(EventCode::PlanAborted, 3)).unwrap();
        assert_eq!(end.ending, Ending::GaveUp);
        let mut w = TaskWatch::new(Mode::GoTo, None);
        let end = w.on_event(0, &event(EventCode::ModeChanged, 0)).unwrap();
        assert_eq!(end.ending, Ending::Stopped);
        assert!(end.reason.contains("changed to Idle"), "{}", end.reason);
    }

    #[test]
    fn a_closed_port_is_a_lost_link_at_once_and_a_silent_one_after_the_grace() {
        let mut w = TaskWatch::new(Mode::GoTo, None);
        let closed = LinkEvent::Connection(Connection::Closed {
            reason: "EOF".into(),
        });
        let end = w.on_event(0, &closed).unwrap();
        assert_eq!(end.ending, Ending::LinkLost);
        assert!(end.reason.contains("EOF"), "{}", end.reason);
        let mut w = TaskWatch::new(Mode::GoTo, None);
        let hs = LinkEvent::Connection(Connection::Handshaking { port: "p".into() });
        assert_eq!(w.on_event(10, &hs), None);
        let at = w.deadline_us().unwrap();
        assert_eq!(w.poll(at - 1), None);
        assert_eq!(w.poll(at).unwrap().ending, Ending::LinkLost);
    }

    #[test]
    fn ending_names_are_distinct() {
        let mut names: Vec<&str> = Ending::ALL.iter().map(|e| e.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Ending::ALL.len());
    }
}
