//! Robot-supplied text never reaches the terminal raw (issue 13, item 8): a robot whose
//! HelloReply names its firmware `ESC ] 0; ... BEL ESC [2J` (retitle the terminal, clear it)
//! is shown through the real `station` binary, in the schema-mismatch refusal and in `station
//! stats`' text output, and no ESC or BEL byte comes out. The robot is the real firmware on an
//! emulator pty, its HelloReply rewritten on the way out. And a recording's header text (issue
//! 31 item 5: CSI, U+009B, came out raw in `station replay --json`) in every JSON report.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use emulator::link::{spawn_device, Device, Running, ServeOptions};
use protocol::{Feed, FrameDecoder, Message, MAX_FRAME};
use station::link::sim::{SimCore, SimOptions};

const HOSTILE: &str = "evil\u{1b}]0;pwned\u{7}\u{1b}[2J";

/// The firmware, with every HelloReply's firmware name replaced (and, if `mismatch`, its
/// schema fingerprint changed, so the station refuses it).
struct Liar {
    core: SimCore,
    decoder: FrameDecoder,
    raw: Vec<u8>,
    mismatch: bool,
}

impl Device for Liar {
    fn now_us(&self) -> u64 {
        self.core.now_us()
    }
    fn step_ms(&mut self) {
        self.core.step_ms();
    }
    fn push_inbound(&mut self, bytes: &[u8]) {
        self.core.push_inbound(bytes);
    }
    fn take_outbound(&mut self, out: &mut Vec<u8>) {
        self.raw.clear();
        self.core.take_outbound(&mut self.raw);
        let mut input = self.raw.as_slice();
        let mut buf = [0u8; MAX_FRAME];
        loop {
            match self.decoder.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { rest, .. } => input = rest,
                Feed::Frame { frame, rest } => {
                    input = rest;
                    let mut msg = frame.message;
                    if let Message::HelloReply(r) = &mut msg {
                        r.firmware = HOSTILE;
                        r.firmware_version = "1.0\u{1b}[31m";
                        if self.mismatch {
                            r.fingerprint[0] ^= 0xff;
                        }
                    }
                    let n = protocol::encode(frame.header.seq, &msg, &mut buf).unwrap();
                    out.extend_from_slice(&buf[..n]);
                }
            }
        }
    }
    fn cycles(&self) -> u32 {
        self.core.cycles()
    }
    fn cycle_us(&self) -> u32 {
        self.core.cycle_us()
    }
}

fn robot(d: &Path, mismatch: bool) -> (Running, PathBuf) {
    let link = d.join("robot");
    let emu = spawn_device(
        move || {
            Ok(Liar {
                core: SimCore::new(SimOptions::default()),
                decoder: FrameDecoder::new(),
                raw: Vec::new(),
                mismatch,
            })
        },
        ServeOptions {
            link: Some(link.clone()),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    (emu, link)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("term-esc-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn station(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// stdout and stderr together, checked free of every character the terminal-text rule escapes
/// (ESC, BEL, DEL, the C1 controls, bidirectional overrides) but line breaks and tabs.
fn clean_output(o: &Output) -> String {
    let all = [o.stdout.as_slice(), o.stderr.as_slice()].concat();
    let text = String::from_utf8_lossy(&all).into_owned();
    assert!(
        !text
            .chars()
            .any(|c| c != '\n' && c != '\t' && station::terminal_text::must_escape(c)),
        "a control character reached the terminal: {}",
        text.escape_debug()
    );
    text
}

#[test]
fn a_hostile_firmware_name_in_a_refused_handshake_is_printed_escaped() {
    let d = dir("mismatch");
    let (_emu, link) = robot(&d, true);
    let link = link.display().to_string();
    let o = station(&["send", "--port", &link, "--timeout", "3", "stop"]);
    let text = clean_output(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(
        text.contains("robot firmware evil\\x1b]0;pwned\\x07\\x1b[2J 1.0\\x1b[31m has schema"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_hostile_firmware_name_in_station_stats_is_printed_escaped() {
    let d = dir("stats");
    let (_emu, link) = robot(&d, false);
    let link = link.display().to_string();
    let o = station(&["stats", "--port", &link, "--seconds", "0.5"]);
    let text = clean_output(&o);
    assert!(o.status.success(), "{text}");
    assert!(
        text.contains("robot       evil\\x1b]0;pwned\\x07\\x1b[2J 1.0\\x1b[31m"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue 31 item 5: serde_json escapes only C0, so `replay --json` copied a header's CSI
/// (U+009B), DEL and bidirectional overrides to the terminal raw. Every JSON report now
/// escapes them as JSON does (`\u009b`), and the JSON reads back the same text.
#[test]
fn a_recordings_header_text_in_json_reports_is_escaped() {
    let d = dir("json");
    let hostile = "robot\u{9b}31m\u{1b}]0;x\u{7}\u{7f}\u{202e}gnp";
    let meta = station::record::Meta {
        created_unix_ms: 1_700_000_000_000,
        writer: hostile.into(),
        port: hostile.into(),
        baud: 115_200,
        arena: hostile.into(),
        ..station::record::Meta::default()
    };
    let mut s = station::record::synth::Synth::new(&meta);
    s.handshake(station::record::synth::demo_peer());
    let rec = d.join("hostile.rec");
    std::fs::write(&rec, s.finish(2_000_000, "end")).unwrap();
    let rec = rec.display().to_string();
    let o = station(&["replay", &rec, "--json"]);
    let text = clean_output(&o);
    assert!(o.status.success(), "{text}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        v.to_string().contains("robot\u{9b}31m") && text.contains("robot\\u009b31m"),
        "{text}"
    );
    // The summary's text form, and the export's report, by the terminal-text rule.
    let o = station(&["replay", &rec, "--summary"]);
    clean_output(&o);
    let out = d.join("out.mcap").display().to_string();
    let o = station(&["export", &rec, "--mcap", &out]);
    clean_output(&o);
    let _ = std::fs::remove_dir_all(&d);
}
