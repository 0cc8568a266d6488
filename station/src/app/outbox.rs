//! What the operator's keys send: teleop, go-to, parameter reads and writes, the telemetry
//! rate; and `send`, which queues every command and remembers it until its outcome.

use protocol::units::point_mm;
use protocol::Command;

use super::log::{Level, Source};
use super::{plan_target, App, Pending, Teleop, RATES, V_MAX, W_MAX};
use crate::link::{CommandId, SendWhen};

impl App {
    pub(super) fn drive(&mut self, dv: i16, dw: i16) {
        if !self.connected() {
            self.note(Level::Warn, Source::Command, "teleop: not connected".into());
            return;
        }
        let t = &mut self.teleop;
        t.v_mm_s = t.v_mm_s.saturating_add(dv).clamp(-V_MAX, V_MAX);
        t.w_mrad_s = t.w_mrad_s.saturating_add(dw).clamp(-W_MAX, W_MAX);
        t.driving = true;
        self.send_teleop(SendWhen::Now);
    }

    /// Sends the teleop in force: a key press `Now`, a repeat `QuietLine`.
    pub(super) fn send_teleop(&mut self, when: SendWhen) {
        self.teleop.last_sent_ms = Some(self.now_ms);
        let command = Command::Teleop {
            v_mm_s: self.teleop.v_mm_s,
            w_mrad_s: self.teleop.w_mrad_s,
        };
        self.send_when(command, when);
    }

    pub(super) fn stop_driving(&mut self) {
        self.teleop = Teleop::default();
        self.send(Command::Stop);
    }

    /// Plans on the station from the believed pose (else the map's start) to the plan's
    /// target (`app::plan_target`: the cursor while shown, else the chosen target, else the
    /// map's goal).
    pub(super) fn plan_locally(&mut self) {
        let from = self.pose().map(|(x, y, _)| (x, y));
        let to = match self.take_plan_target() {
            plan_target::PlanTarget::Chosen(p) => Some(p),
            plan_target::PlanTarget::MapGoal(_) => None,
        };
        let (level, text) = match self.map.plan.plan(from, to) {
            Ok(line) => (Level::Info, line),
            Err(e) => (Level::Warn, e),
        };
        self.note(level, Source::Command, text);
    }

    pub(super) fn go_to(&mut self, x: f64, y: f64) {
        let goal = match point_mm(["go-to x", "go-to y"], (x, y)) {
            Ok(p) => p,
            Err(e) => {
                self.note(Level::Warn, Source::Command, format!("not sent: {e}"));
                return;
            }
        };
        self.teleop.driving = false;
        self.map.goal = Some((x, y));
        self.send(Command::GoTo(goal));
    }

    pub(super) fn read_param(&mut self, id: u16) {
        self.params.set_pending(id);
        self.send(Command::GetParam {
            id: protocol::ParamId(id),
        });
    }

    /// Reads a parameter without a log line of its own (see `Pending::quiet`).
    pub(super) fn read_param_quietly(&mut self, id: u16) {
        self.params.set_pending(id);
        let cid = self.send(Command::GetParam {
            id: protocol::ParamId(id),
        });
        if let Some(p) = self.pending.get_mut(&cid) {
            p.quiet = true;
        }
    }

    /// Reads every parameter this robot has (on connect and on `R`); the ones its hardware
    /// lacks (`ParamInfo::requires`) are marked as such without asking.
    pub(super) fn fetch_params(&mut self) {
        let caps = self.peer.as_ref().map_or(u32::MAX, |p| p.capabilities);
        let mut asked = 0;
        for p in self.params.params() {
            if caps & p.requires == p.requires {
                self.read_param_quietly(p.id);
                asked += 1;
            } else {
                self.params.set_absent(p.id);
            }
        }
        self.params.start_fetch(asked);
    }

    pub(super) fn commit_param(&mut self) {
        match self.params.parse_input() {
            Ok((id, value)) => {
                self.params.input = None;
                let before = self.params.value_of(id);
                self.params.set_pending(id);
                let command = Command::SetParam {
                    id: protocol::ParamId(id),
                    value,
                };
                let cid = self.send(command);
                if let Some(p) = self.pending.get_mut(&cid) {
                    p.before = before;
                }
            }
            Err(e) => {
                self.params.input_error = Some(e.clone());
                self.note(Level::Warn, Source::Command, format!("param: {e}"));
            }
        }
    }

    #[cfg(test)]
    pub(crate) fn rate_asked_for_test(&self) -> Option<(CommandId, u8)> {
        self.rate_asked
    }

    pub(super) fn step_rate(&mut self, d: i32) {
        let current = self
            .rate_asked
            .map(|(_, hz)| hz)
            .or(self.rate_hz)
            .or(self.peer.as_ref().map(|p| p.telemetry_hz))
            .unwrap_or(protocol::timing::TELEMETRY_DEFAULT_HZ);
        // The nearest step at or above the current rate, then one step along.
        let i = RATES
            .iter()
            .position(|&r| r >= current)
            .unwrap_or(RATES.len() - 1) as i32;
        let j = (i + d).clamp(0, RATES.len() as i32 - 1) as usize;
        let hz = RATES.get(j).copied().unwrap_or(current);
        let id = self.send(Command::SetTelemetryRate { hz });
        self.rate_asked = Some((id, hz));
    }

    /// Queues a command to go at once; returns its id.
    pub(super) fn send(&mut self, command: Command) -> CommandId {
        self.send_when(command, SendWhen::Now)
    }

    /// Queues a command to go `when` says; returns its id.
    pub(super) fn send_when(&mut self, command: Command, when: SendWhen) -> CommandId {
        let id = self.next_id;
        self.next_id += 1;
        self.pending.insert(
            id,
            Pending {
                before: None,
                quiet: false,
            },
        );
        self.outbox.push((id, command, when));
        id
    }
}
