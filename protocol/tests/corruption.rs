//! The decoder against hostile input: a million corrupted frames, none accepted; garbage,
//! truncation and splices never panic and never cost the frame after the next delimiter.

#![allow(clippy::unwrap_used, clippy::panic)]

mod common;

use common::any_message;
use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::TestRunner;
use protocol::*;

/// xorshift64*: a fixed-seed generator so a failure reproduces exactly.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Valid encoded frames (without their delimiter) of every kind, from the proptest strategies.
fn sample_frames(count: usize) -> Vec<Vec<u8>> {
    let mut runner = TestRunner::deterministic();
    let strategy = any_message();
    (0..count)
        .map(|i| {
            let msg = strategy.new_tree(&mut runner).expect("strategy").current();
            let mut buf = [0u8; MAX_FRAME];
            let n = encode(i as u16, &msg.as_message(), &mut buf).expect("fits");
            buf[..n - 1].to_vec()
        })
        .collect()
}

/// One of eight corruptions of `frame`, guaranteed to differ from it and from `other`.
fn corrupt(rng: &mut Rng, frame: &[u8], other: &[u8]) -> Vec<u8> {
    loop {
        let mut f = frame.to_vec();
        match rng.below(8) {
            0 => {
                // 1..=8 bit flips anywhere.
                for _ in 0..=rng.below(8) {
                    let i = rng.below(f.len());
                    f[i] ^= 1 << rng.below(8);
                }
            }
            1 => {
                let i = rng.below(f.len());
                f[i] = rng.next() as u8;
            }
            2 => {
                let cut = 1 + rng.below(f.len() - 1);
                f.truncate(f.len() - cut);
            }
            3 => {
                f.remove(rng.below(f.len()));
            }
            4 => {
                let i = rng.below(f.len() + 1);
                f.insert(i, rng.next() as u8);
            }
            5 => {
                // A burst of up to 16 random bytes, as a line glitch makes.
                let start = rng.below(f.len());
                let end = (start + 2 + rng.below(15)).min(f.len());
                for b in &mut f[start..end] {
                    *b = rng.next() as u8;
                }
            }
            6 => {
                // The head of one frame joined to the tail of another: a lost delimiter.
                let a = 1 + rng.below(f.len() - 1);
                let b = 1 + rng.below(other.len() - 1);
                f.truncate(a);
                f.extend_from_slice(&other[b..]);
            }
            _ => {
                let n = 1 + rng.below(300);
                f = (0..n).map(|_| rng.next() as u8).collect();
            }
        }
        // An inserted 0x00 at a frame's edge leaves the frame itself intact on the wire: that is
        // a delimiter, not a corruption, so no piece between delimiters may be a sample.
        let intact = f
            .split(|&b| b == 0)
            .any(|piece| piece == frame || piece == other);
        if !intact && !f.is_empty() {
            return f;
        }
    }
}

#[test]
fn a_million_corrupted_frames_are_all_rejected_and_the_next_frame_always_survives() {
    const CORRUPTED: usize = 1_000_000;
    let frames = sample_frames(2048);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut dec = FrameDecoder::new();
    let mut accepted = 0usize;
    let mut survivors = 0usize;
    let mut checked = 0usize;
    let mut wire = Vec::with_capacity(1024);
    for i in 0..CORRUPTED {
        let a = &frames[rng.below(frames.len())];
        let b = &frames[rng.below(frames.len())];
        let bad = corrupt(&mut rng, a, b);
        wire.clear();
        wire.extend_from_slice(&bad);
        wire.push(0);
        let check_next = i % 8 == 0;
        if check_next {
            wire.extend_from_slice(b);
            wire.push(0);
        }
        let mut input = &wire[..];
        let mut good = Vec::new();
        loop {
            match dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Frame { frame, rest } => {
                    good.push(frame.header.seq);
                    input = rest;
                }
                Feed::Error { rest, .. } => input = rest,
            }
        }
        // Only the clean frame after the delimiter may come out.
        let expected_good = usize::from(check_next);
        accepted += good.len().saturating_sub(expected_good);
        if check_next {
            checked += 1;
            let b_seq = u16::from_le_bytes(decoded_seq(b));
            if good.last() == Some(&b_seq) {
                survivors += 1;
            }
        }
    }
    let stats = dec.stats();
    println!(
        "{CORRUPTED} corrupted frames: {accepted} accepted; {survivors}/{checked} following frames \
         recovered; {} errors counted, {} bytes dropped",
        stats.errors(),
        stats.bytes_dropped
    );
    assert_eq!(accepted, 0, "corrupted frames were accepted");
    assert_eq!(survivors, checked, "a frame after a delimiter was lost");
    assert!(stats.errors() as usize >= CORRUPTED);
}

/// The sequence number of an encoded frame, read back through the decoder.
fn decoded_seq(encoded: &[u8]) -> [u8; 2] {
    let mut raw = encoded.to_vec();
    let n = cobs::decode_in_place(&mut raw).expect("valid sample");
    assert!(n >= 4);
    [raw[2], raw[3]]
}

#[test]
fn random_garbage_in_any_chunking_never_panics_and_is_all_counted_as_dropped() {
    let mut rng = Rng(7);
    let mut dec = FrameDecoder::new();
    let mut total = 0u64;
    for _ in 0..2000 {
        let n = 1 + rng.below(4096);
        let chunk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
        total += n as u64;
        let mut input = &chunk[..];
        loop {
            match dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Frame { .. } => panic!("random bytes accepted as a frame"),
                Feed::Error { rest, .. } => input = rest,
            }
        }
    }
    dec.feed(&[0]);
    let s = dec.stats();
    assert_eq!(s.bytes_in, total + 1);
    // Every byte but the empty frames' lone delimiters was dropped.
    assert!(s.bytes_dropped <= total + 1 && s.bytes_dropped + 2000 * 20 > total);
    assert!(s.oversize > 0 && s.bad_crc + s.bad_cobs + s.too_short > 0);
}

#[test]
fn an_endless_run_without_delimiters_is_reported_once_as_oversize() {
    let mut dec = FrameDecoder::new();
    let junk = [0x55u8; 4096];
    for _ in 0..10 {
        assert!(matches!(dec.feed(&junk), Feed::NeedMore));
    }
    match dec.feed(&[0]) {
        Feed::Error {
            error: FrameError::Oversize { len },
            rest,
        } => {
            assert_eq!(len, 40_960);
            assert!(rest.is_empty());
        }
        other => panic!("expected oversize, got {other:?}"),
    }
    assert_eq!(dec.stats().bytes_dropped, 40_961);
}

#[test]
fn each_error_kind_is_reported_with_its_details() {
    let mut buf = [0u8; MAX_FRAME];
    let mut dec = FrameDecoder::new();
    let mut first_error = |wire: &[u8]| -> FrameError {
        match dec.feed(wire) {
            Feed::Error { error, .. } => error,
            other => panic!("expected an error, got {other:?}"),
        }
    };
    let n = encode_raw(2, 3, 0, &[], &mut buf).expect("fits");
    assert_eq!(
        first_error(&buf[..n]),
        FrameError::UnsupportedVersion { version: 2 }
    );
    let n = encode_raw(PROTOCOL_VERSION, 200, 0, &[], &mut buf).expect("fits");
    assert_eq!(
        first_error(&buf[..n]),
        FrameError::UnknownKind { kind: 200 }
    );
    // A heartbeat with one byte too many.
    let n = encode_raw(
        PROTOCOL_VERSION,
        Kind::Heartbeat as u8,
        0,
        &[1, 9],
        &mut buf,
    )
    .expect("fits");
    assert_eq!(
        first_error(&buf[..n]),
        FrameError::Undecodable {
            kind: Kind::Heartbeat,
            reason: PayloadError::TrailingBytes { count: 1 }
        }
    );
    // A command whose enum tag has no variant.
    let n = encode_raw(PROTOCOL_VERSION, Kind::Command as u8, 0, &[99], &mut buf).expect("fits");
    assert_eq!(
        first_error(&buf[..n]),
        FrameError::Undecodable {
            kind: Kind::Command,
            reason: PayloadError::BadEnum
        }
    );
    // A log line that is not UTF-8.
    let n = encode_raw(
        PROTOCOL_VERSION,
        Kind::Log as u8,
        0,
        &[1, 2, 0xC3, 0x28],
        &mut buf,
    )
    .expect("fits");
    assert_eq!(
        first_error(&buf[..n]),
        FrameError::Undecodable {
            kind: Kind::Log,
            reason: PayloadError::BadUtf8
        }
    );
    assert_eq!(
        first_error(&[0x03, 0x01, 0x02, 0x00]),
        FrameError::TooShort { len: 2 }
    );
    assert_eq!(first_error(&[0x09, 0x01, 0x00]), FrameError::BadCobs);
    let n = encode(5, &Message::Heartbeat(Heartbeat { time_ms: 5 }), &mut buf).expect("fits");
    buf[3] ^= 0x10;
    assert!(matches!(first_error(&buf[..n]), FrameError::BadCrc { .. }));
}
