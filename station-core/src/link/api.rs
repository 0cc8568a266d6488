//! What the app and the link task say to each other: requests in, events out.
//!
//! Layer: plain owned data crossing the channel between the link task (which owns the port)
//! and its users (the TUI, the headless commands, and later recording, replay and transfers).
//! Nothing here does I/O. Every command a user submits carries a caller-chosen `CommandId`
//! and is answered by exactly one `LinkEvent::CommandDone` with that id (and, when asked, on a
//! oneshot channel too), whatever happens to the link in between.

use protocol::{
    AckInfo, Command, EmuTruth, Event, LogLevel, MapCapacity, Mode, NackReason, ProfileId,
};
use protocol::{Telemetry, TransferAck, TransferBegin};
use serde::Serialize;
use tokio::sync::oneshot;

use super::stats::LinkStats;

/// Names one submitted command; chosen by the caller, opaque to the link.
pub type CommandId = u64;

/// A request to the link task.
#[derive(Debug)]
pub enum LinkRequest {
    /// Send `command` (retried per PROTOCOL.md §7); the outcome comes back as
    /// `LinkEvent::CommandDone { id, .. }` and on `reply` if given.
    Command {
        id: CommandId,
        command: Command,
        reply: Option<oneshot::Sender<CommandOutcome>>,
        when: SendWhen,
    },
    /// Send a transfer frame as is (no windowing yet: the transfer engine that drives these
    /// belongs to the map/plan transfer work).
    Transfer(TransferOut),
    /// Close the port and end the task.
    Shutdown,
}

/// When a submitted command goes out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SendWhen {
    /// At once: what the operator asked for now (a key press, a mode, a parameter).
    #[default]
    Now,
    /// Right after the robot's next periodic burst if one is near (`link::line_phase`), so
    /// its answer does not queue behind it: for a command whose moment within its period
    /// does not matter, a teleop repeat. Held `line_phase::MAX_HOLD_US` at most.
    QuietLine,
}

/// An outgoing transfer frame, owned.
#[derive(Clone, Debug, PartialEq)]
pub enum TransferOut {
    Begin(TransferBegin),
    /// A `TransferData` chunk of the transfer `tag`.
    Chunk {
        tag: u8,
        offset: u32,
        data: Vec<u8>,
    },
    Ack(TransferAck),
}

/// An incoming transfer frame, owned.
#[derive(Clone, Debug, PartialEq)]
pub enum TransferIn {
    Begin(TransferBegin),
    /// A `TransferData` chunk of the transfer `tag`.
    Chunk {
        tag: u8,
        offset: u32,
        data: Vec<u8>,
    },
    Ack(TransferAck),
}

/// Something the link task reports.
#[derive(Clone, Debug, PartialEq)]
pub enum LinkEvent {
    /// The connection changed state.
    Connection(Connection),
    Telemetry(Telemetry),
    /// Ground truth from the emulator (never from a real robot).
    Truth(EmuTruth),
    /// Floor-grid line correction state (seed 003), boxed: it is the largest message.
    Localization(Box<protocol::Localization>),
    /// What the robot's mode is doing (waypoint k of n, distance left, time, stuck time).
    Progress(protocol::Progress),
    /// An ALICE's situation (kind 16): the QT world model's input.
    Situation(protocol::AliceSituation),
    /// An `Event` frame from the robot.
    Robot(Event),
    /// A `Log` line from the robot.
    Log {
        level: LogLevel,
        text: String,
    },
    /// The one answer to a submitted command.
    CommandDone {
        id: CommandId,
        command: Command,
        outcome: CommandOutcome,
    },
    /// A transfer frame from the robot (forwarded, not interpreted yet).
    Transfer(TransferIn),
    /// A snapshot of the link statistics, published periodically.
    Stats(Box<LinkStats>),
}

/// The state of the link.
#[derive(Clone, Debug, PartialEq)]
pub enum Connection {
    /// No port open: why (not present, busy and who holds it, ...). The task keeps trying.
    Closed { reason: String },
    /// The port is open and a `Hello` is out; no reply yet.
    Handshaking { port: String },
    /// Handshake done: commands can be sent.
    Connected(PeerInfo),
    /// The robot speaks another schema or protocol version; the message names both builds.
    Refused { message: String },
}

impl Connection {
    /// A one-word name for status lines and JSON.
    pub fn name(&self) -> &'static str {
        match self {
            Connection::Closed { .. } => "closed",
            Connection::Handshaking { .. } => "handshaking",
            Connection::Connected(_) => "connected",
            Connection::Refused { .. } => "refused",
        }
    }
}

/// What the robot said about itself in its `HelloReply`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PeerInfo {
    pub session: u32,
    pub firmware: String,
    pub firmware_version: String,
    #[serde(serialize_with = "ser_profile")]
    pub profile: ProfileId,
    /// `protocol::caps` bits.
    pub capabilities: u32,
    #[serde(serialize_with = "ser_capacity")]
    pub map_capacity: MapCapacity,
    pub telemetry_hz: u8,
    pub failsafe_ms: u16,
    /// Which robot this is in a fleet (its `robot_id` parameter, like MAVLink's system id).
    pub robot_id: u8,
}

impl PeerInfo {
    /// Whether the robot has capability bit(s) `cap`.
    pub fn has(&self, cap: u32) -> bool {
        self.capabilities & cap == cap
    }
}

fn ser_profile<S: serde::Serializer>(p: &ProfileId, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&format!("{p:?}"))
}

fn ser_capacity<S: serde::Serializer>(c: &MapCapacity, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&format!("{}x{}", c.width, c.height))
}

/// How a command ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CommandOutcome {
    /// Acknowledged. `rtt_ms` is from the last send to the ack.
    Acked {
        info: AckInfo,
        sends: u32,
        rtt_ms: u64,
    },
    /// Refused by the robot; it changed nothing.
    Nacked { reason: NackReason, sends: u32 },
    /// Never answered, or could not be sent.
    Failed(CommandFailure),
}

impl CommandOutcome {
    /// Whether the robot accepted the command.
    pub fn is_ack(&self) -> bool {
        matches!(self, CommandOutcome::Acked { .. })
    }
}

/// Why a command got no answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandFailure {
    /// Sent `sends` times, 200 ms apart, without an answer.
    Timeout { sends: u32 },
    /// Submitted while no handshaken session existed.
    NotConnected,
    /// The link went down (port closed, timeout, re-handshake) before the answer.
    LinkLost,
    /// A newer teleop command replaced it before it was answered.
    Superseded,
    /// The link task ended.
    Shutdown,
}

impl std::fmt::Display for CommandFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandFailure::Timeout { sends } => write!(f, "no answer after {sends} sends"),
            CommandFailure::NotConnected => write!(f, "not connected"),
            CommandFailure::LinkLost => write!(f, "link lost before the answer"),
            CommandFailure::Superseded => write!(f, "superseded by a newer teleop"),
            CommandFailure::Shutdown => write!(f, "link closed"),
        }
    }
}

/// A refusal of `command` in words: [`nack_text`], and for a parameter out of range the range
/// the firmware's table gives (`value out of range: 0 to 2000 mm/s`); for plans, maps and
/// go-to, the limit that refused it and the way forward ([`way_forward`]).
pub fn refusal_text(command: &protocol::Command, reason: NackReason) -> String {
    let base = nack_text(reason);
    if let Some(way) = way_forward(command, reason) {
        return format!("{base}: {way}");
    }
    match (command, reason) {
        (protocol::Command::SetParam { id, .. }, NackReason::OutOfRange) => {
            match robot_firmware::params::info(id.0) {
                Some(p) => format!(
                    "{base}: {} to {}{}{}",
                    p.min,
                    p.max,
                    if p.unit.is_empty() { "" } else { " " },
                    p.unit
                ),
                None => base.to_string(),
            }
        }
        _ => base.to_string(),
    }
}

/// For a refusal of a plan, map or motion command: which limit refused it and what to do
/// instead. Only what holds for every robot of this firmware; the TUI adds what it knows of
/// the robot's map (how many squares it has, which end is not free).
pub fn way_forward(command: &Command, reason: NackReason) -> Option<String> {
    use robot_firmware::nav::fixed::{NAV64_PATH, NAV64_REGIONS, NAV64_SIDE};
    let plan_elsewhere = "plan on the station instead (P in the TUI, or `station plan --map \
                          FILE --out-object plan.obj`) and upload the plan (u, or `station \
                          upload-plan --plan plan.obj`)";
    Some(match (command, reason) {
        // The robot plans on any map it holds (squares + A*, else its grid planner); only
        // its square list and its plan object have fixed sizes.
        (Command::Segment, NackReason::CapacityExceeded) => format!(
            "the robot segments a map into at most {NAV64_REGIONS} squares; it still plans on \
             this map with its grid planner (O); to see the squares, segment on the station \
             (P in the TUI, or `station segment --map FILE`)"
        ),
        (Command::Plan { .. }, NackReason::CapacityExceeded) => format!(
            "the path needs more waypoints than the robot's plan object ({} bytes, regions \
             up to {NAV64_PATH}) holds; {plan_elsewhere}",
            robot_firmware::transfer::OBJECT_CAPACITY
        ),
        (Command::Segment | Command::Plan { .. }, NackReason::NoMap) => {
            "upload a map first (u, or `station upload-map`), or explore (E) to make one".into()
        }
        (Command::Plan { .. }, NackReason::BadPoint) => {
            "the start or the goal is off the map or not a known free cell: drive the robot \
             onto known ground, or choose another target (g, move, O)"
                .into()
        }
        (Command::Plan { .. }, NackReason::Unreachable) => {
            "no way through known free cells: explore further (E), or choose another target \
             (g, move, O)"
                .into()
        }
        (Command::ExecutePlan { .. }, NackReason::NoPlan)
        | (Command::SetMode(Mode::ExecutePlan), NackReason::NoPlan) => {
            "plan on the robot first (O, or `station send plan`), or upload a plan (u)".into()
        }
        (Command::ExecutePlan { .. }, NackReason::PlanIdMismatch) => {
            "the robot holds another plan now: plan again (O) or execute the id its last \
             PlanInstalled named"
                .into()
        }
        (Command::ExecutePlan { .. }, NackReason::Unsupported) => {
            "plan execution needs wheel encoders or a compass".into()
        }
        (Command::GoTo(_), NackReason::BadPoint) => {
            "the point is outside the robot's arena (parameters arena_min_x_m .. \
             arena_max_y_m): choose a point inside it"
                .into()
        }
        (Command::GoTo(_), NackReason::Unsupported) => {
            "go-to needs wheel encoders or a compass".into()
        }
        (Command::StartExploration, NackReason::Unsupported)
        | (Command::SetMode(Mode::Explore), NackReason::Unsupported) => {
            "exploration needs a compass and a beacon sensor (the micro-rato profile)".into()
        }
        (Command::StartExploration, NackReason::CapacityExceeded) => format!(
            "the arena (parameters arena_min_x_m .. arena_max_y_m) needs more than the \
             robot's {NAV64_SIDE} x {NAV64_SIDE} map cells of 0.3 m: set smaller bounds"
        ),
        (Command::Download { .. }, NackReason::NoMap) => {
            "the robot holds no map: upload one (u) or explore (E)".into()
        }
        (Command::Download { .. }, NackReason::NoPlan) => {
            "the robot holds no plan: plan on it (O) or upload one (u)".into()
        }
        (_, NackReason::Busy) if is_object_command(command) => {
            "another transfer is in progress: wait for it to end".into()
        }
        _ => return None,
    })
}

fn is_object_command(c: &Command) -> bool {
    matches!(
        c,
        Command::Segment | Command::Plan { .. } | Command::Download { .. }
    )
}

/// A human description of a Nack reason (PROTOCOL.md §6 kind 6).
pub fn nack_text(reason: NackReason) -> &'static str {
    match reason {
        NackReason::NoHandshake => "no handshake (the robot lost the session)",
        NackReason::Unsupported => "unsupported by this robot",
        NackReason::UnknownParam => "unknown parameter",
        NackReason::OutOfRange => "value out of range",
        NackReason::BadState => "not allowed in the current mode",
        NackReason::NoMap => "the robot holds no map",
        NackReason::NoPlan => "the robot holds no plan",
        NackReason::PlanIdMismatch => "plan id mismatch",
        NackReason::BadPoint => "point outside the map or in an obstacle",
        NackReason::Unreachable => "unreachable",
        NackReason::CapacityExceeded => "capacity exceeded",
        NackReason::Busy => "busy with another transfer",
    }
}

/// A short description of a command for logs and the CLI.
pub fn command_text(c: &Command) -> String {
    match c {
        Command::SetMode(m) => format!("mode {m:?}"),
        Command::Teleop { v_mm_s, w_mrad_s } => format!("teleop {v_mm_s} mm/s {w_mrad_s} mrad/s"),
        Command::Stop => "stop".into(),
        Command::GoTo(p) => format!("goto {:.3} {:.3} m", mm_to_m(p.x_mm), mm_to_m(p.y_mm)),
        Command::SetParam { id, value } => format!("param set {} {value}", param_name(id.0)),
        Command::GetParam { id } => format!("param get {}", param_name(id.0)),
        Command::StartExploration => "explore".into(),
        Command::ExecutePlan { plan_id } => format!("execute plan {plan_id:#010x}"),
        Command::Segment => "segment".into(),
        Command::Plan { .. } => "plan".into(),
        Command::SetTelemetryRate { hz } => format!("rate {hz} Hz"),
        Command::Download { object } => {
            format!("download {}", crate::transfer::object_name(*object))
        }
        Command::SetPose { pose } => format!(
            "set pose {:.3} {:.3} m {} mrad",
            mm_to_m(pose.x_mm),
            mm_to_m(pose.y_mm),
            pose.heading_mrad
        ),
    }
}

/// The firmware's name for parameter `id`, or the number.
pub fn param_name(id: u16) -> String {
    robot_firmware::params::info(id).map_or_else(|| format!("#{id}"), |p| p.name.to_string())
}

fn mm_to_m(mm: i32) -> f64 {
    f64::from(mm) / 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::{Command, ParamId};

    #[test]
    fn a_parameter_out_of_range_is_refused_with_the_range_it_takes() {
        let set = |id, value| Command::SetParam {
            id: ParamId(id),
            value,
        };
        assert_eq!(
            refusal_text(&set(2, 5000.0), NackReason::OutOfRange),
            "value out of range: 0 to 2000 mm/s"
        );
        // Other refusals, and parameters the table does not know, keep the plain words.
        assert_eq!(
            refusal_text(&set(999, 1.0), NackReason::OutOfRange),
            "value out of range"
        );
        assert_eq!(
            refusal_text(&Command::Stop, NackReason::Busy),
            nack_text(NackReason::Busy)
        );
    }
}
