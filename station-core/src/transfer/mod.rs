//! Map, plan and regions transfers on the station side (PROTOCOL.md §8, §12).
//!
//! Layer: above the link task, below the TUI and the headless commands. The link task only
//! moves transfer frames (`LinkRequest::Transfer`, `LinkEvent::Transfer`); [`TransferEngine`]
//! is the protocol state that drives them, with no I/O and no clock (time comes in as
//! milliseconds, like `LinkMachine`): uploads run `protocol::transfer::Sender`, downloads send
//! `Command::Download` and answer the robot's `TransferBegin` and chunks with
//! `protocol::transfer::Receiver`. Jobs run one at a time, in order. Around it:
//! - [`client`]: an async driver over a `RunningLink` for the headless commands and tests;
//! - the station crate's `commands::transfer`: `station upload-map`, `download-map`, `upload-plan`;
//! - [`objects`]: Map and Plan objects from the station's planner (`NavMap`, `PlanResult`),
//!   the robot's capacity check, ASCII pictures and atomic file writes.
//!
//! The TUI's side lives in `app::transfers` (keys, prompt, live map while exploring).
//!
//! Invariant: every job submitted ends in exactly one [`TransferEvent::Finished`] carrying a
//! [`JobReport`] whose [`JobOutcome`] is `Complete`, `AlreadyHave` or a [`TransferError`]
//! that says what happened: nothing fails silently.

pub mod client;
pub mod engine;
pub mod objects;

use protocol::{NackReason, ObjectKind};
use serde_json::{json, Value};

use crate::link::api::nack_text;
use crate::link::CommandFailure;

pub use client::TransferClient;
pub use engine::{EngineOut, JobSpec, Progress, TransferEngine};

/// Names one job of a [`TransferEngine`].
pub type JobId = u64;

/// Which way an object travels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Station to robot.
    Upload,
    /// Robot to station.
    Download,
}

impl Direction {
    pub fn name(self) -> &'static str {
        match self {
            Direction::Upload => "upload",
            Direction::Download => "download",
        }
    }
}

pub use crate::format::object_name;

/// Why a transfer failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransferError {
    #[error("not connected to a robot")]
    NotConnected,
    #[error(
        "the robot refused the object (too large for it, a kind it does not take, or malformed)"
    )]
    Rejected,
    #[error("the object's CRC-32C did not match at the receiver; nothing was installed")]
    CrcMismatch,
    #[error("the receiver kept losing the transfer (unknown id after every restart)")]
    UnknownId,
    #[error(
        "timed out: no progress for 5 retry periods of 400 ms, {attempts} attempt(s), each \
         resuming where the last stopped"
    )]
    TimedOut { attempts: u8 },
    #[error("the object changed during the transfer")]
    ObjectChanged,
    #[error("the robot is calibrating its light sensors; upload when it is done (or stop it)")]
    Busy,
    #[error("the robot refused the download: {}", nack_text(*.0))]
    Refused(NackReason),
    #[error("the download request failed: {0}")]
    Request(CommandFailure),
    #[error("the robot answered the download with {0}")]
    Unexpected(String),
    #[error("the link was down for more than {0} s")]
    LinkLost(u64),
    #[error("the object is {len} bytes; at most {max} are taken")]
    TooLarge { len: u64, max: u64 },
    #[error("the received object is malformed (its CRC matched, its layout did not)")]
    Malformed,
    #[error("cancelled")]
    Cancelled,
}

impl TransferError {
    /// A snake_case name for JSON.
    pub fn name(&self) -> &'static str {
        match self {
            TransferError::NotConnected => "not_connected",
            TransferError::Rejected => "rejected",
            TransferError::CrcMismatch => "crc_mismatch",
            TransferError::UnknownId => "unknown_id",
            TransferError::TimedOut { .. } => "timed_out",
            TransferError::ObjectChanged => "object_changed",
            TransferError::Busy => "busy",
            TransferError::Refused(_) => "refused",
            TransferError::Request(_) => "request_failed",
            TransferError::Unexpected(_) => "unexpected_answer",
            TransferError::LinkLost(_) => "link_lost",
            TransferError::TooLarge { .. } => "too_large",
            TransferError::Malformed => "malformed",
            TransferError::Cancelled => "cancelled",
        }
    }
}

/// How a job ended.
#[derive(Clone, Debug, PartialEq)]
pub enum JobOutcome {
    /// Verified and installed (upload) or received and verified (download).
    Complete,
    /// The receiver already held an object with this id and CRC: nothing (more) was sent.
    AlreadyHave,
    Failed(TransferError),
}

impl JobOutcome {
    /// Whether the receiver now holds the object.
    pub fn is_success(&self) -> bool {
        matches!(self, JobOutcome::Complete | JobOutcome::AlreadyHave)
    }

    /// A snake_case name for JSON: `complete`, `already_have`, or the error's name.
    pub fn name(&self) -> &'static str {
        match self {
            JobOutcome::Complete => "complete",
            JobOutcome::AlreadyHave => "already_have",
            JobOutcome::Failed(e) => e.name(),
        }
    }
}

/// Everything known about a finished job.
#[derive(Clone, Debug, PartialEq)]
pub struct JobReport {
    pub job: JobId,
    pub direction: Direction,
    pub object: ObjectKind,
    /// The object's id, once known (an upload always; a download after the robot's answer).
    pub id: Option<u32>,
    pub crc: Option<u32>,
    /// The object's length in bytes (0 if never learnt).
    pub len: u32,
    pub outcome: JobOutcome,
    pub elapsed_ms: u64,
    /// Attempts made (a timed-out transfer is restarted, and resumes).
    pub attempts: u8,
    /// The object received (downloads that completed).
    pub bytes: Option<Vec<u8>>,
    /// An upload's sender: where its time went (chunks, resends, losses, timer expiries) and
    /// the chunk size it started with.
    pub sender: Option<UploadCounts>,
}

/// What an upload's sender did, for the report (`station upload-map --json`, `"sender"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UploadCounts {
    pub stats: protocol::transfer::SenderStats,
    /// The chunk size the upload started with, bytes.
    pub first_chunk: u32,
    /// The chunk size when it ended, bytes.
    pub last_chunk: u32,
}

impl JobReport {
    /// JSON with bytes, id, crc, outcome and elapsed ms.
    pub fn json(&self) -> Value {
        let error = match &self.outcome {
            JobOutcome::Failed(e) => Value::String(e.to_string()),
            _ => Value::Null,
        };
        json!({
            "direction": self.direction.name(),
            "object": object_name(self.object),
            "outcome": self.outcome.name(),
            "ok": self.outcome.is_success(),
            "bytes": self.len,
            "id": self.id,
            "id_hex": self.id.map(|i| format!("{i:#010x}")),
            "crc": self.crc,
            "elapsed_ms": self.elapsed_ms,
            "attempts": self.attempts,
            "error": error,
            "sender": self.sender.map(|c| json!({
                "chunks": c.stats.chunks,
                "resent": c.stats.resent,
                "lost_units": c.stats.lost_units,
                "probes": c.stats.probes,
                "timeouts": c.stats.timeouts,
                "first_chunk": c.first_chunk,
                "last_chunk": c.last_chunk,
            })),
        })
    }

    /// One line for people: what moved, its id, how it ended, how long it took.
    pub fn text(&self) -> String {
        let what = format!("{} {}", self.direction.name(), object_name(self.object));
        let id = self
            .id
            .map_or_else(String::new, |i| format!(" id {i:#010x},"));
        let ms = self.elapsed_ms;
        match &self.outcome {
            JobOutcome::Complete => format!("{what}:{id} {} bytes, complete ({ms} ms)", self.len),
            JobOutcome::AlreadyHave => format!(
                "{what}:{id} {} bytes, already held by the {}: nothing sent ({ms} ms)",
                self.len,
                match self.direction {
                    Direction::Upload => "robot",
                    Direction::Download => "station",
                }
            ),
            JobOutcome::Failed(e) => format!("{what} failed:{id} {e} ({ms} ms)"),
        }
    }
}

/// Something a [`TransferEngine`] reports.
#[derive(Clone, Debug, PartialEq)]
pub enum TransferEvent {
    /// A job began.
    Started {
        job: JobId,
        direction: Direction,
        object: ObjectKind,
    },
    /// Bytes acknowledged (upload) or held (download) out of `total`.
    Progress { job: JobId, done: u32, total: u32 },
    /// A job ended; the one report of it.
    Finished(JobReport),
}
