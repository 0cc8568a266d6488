//! A `Sender` and a `Receiver` joined by a channel that drops, duplicates, delays and reorders
//! frames both ways: the transfer ends with a byte-identical object or a reported failure,
//! never with anything else installed; a restarted sender resumes where the receiver is.
#![allow(clippy::unwrap_used, clippy::panic)]

use proptest::prelude::*;
use protocol::transfer::{Outcome, Receiver, Sender, Verified};
use protocol::*;

/// A frame in flight, owned.
#[derive(Clone, Debug)]
enum Wire {
    Begin(TransferBegin),
    Chunk { tag: u8, offset: u32, data: Vec<u8> },
    Ack(TransferAck),
}

/// xorshift32: deterministic, seedable, good enough for fault injection.
struct Rng(u32);

impl Rng {
    fn new(seed: u32) -> Self {
        Rng(seed.max(1))
    }
    fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }
    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        f64::from(self.next()) / f64::from(u32::MAX) < p
    }
}

/// Faults of one direction.
#[derive(Clone, Copy, Debug)]
struct Faults {
    drop: f64,
    dup: f64,
    /// Delay is 1 + uniform(0..jitter) ms, so frames overtake each other.
    jitter_ms: u32,
}

const CLEAN: Faults = Faults {
    drop: 0.0,
    dup: 0.0,
    jitter_ms: 0,
};

struct Channel {
    faults: Faults,
    rng: Rng,
    queue: Vec<(u32, u64, Wire)>,
    order: u64,
    sent: usize,
}

impl Channel {
    fn new(faults: Faults, seed: u32) -> Self {
        Channel {
            faults,
            rng: Rng::new(seed),
            queue: Vec::new(),
            order: 0,
            sent: 0,
        }
    }

    fn push(&mut self, now: u32, w: Wire) {
        self.sent += 1;
        let copies = if self.rng.chance(self.faults.dup) {
            2
        } else {
            1
        };
        for _ in 0..copies {
            if self.rng.chance(self.faults.drop) {
                continue;
            }
            let delay = 1 + self.rng.next() % self.faults.jitter_ms.max(1);
            self.order += 1;
            self.queue.push((now + delay, self.order, w.clone()));
        }
    }

    fn due(&mut self, now: u32) -> Vec<Wire> {
        self.queue.sort_by_key(|(t, o, _)| (*t, *o));
        let n = self.queue.iter().take_while(|(t, _, _)| *t <= now).count();
        self.queue.drain(..n).map(|(_, _, w)| w).collect()
    }
}

fn to_wire(m: &Message<'_>) -> Wire {
    match m {
        Message::TransferBegin(b) => Wire::Begin(*b),
        Message::TransferData(c) => Wire::Chunk {
            tag: c.tag,
            offset: c.offset,
            data: c.data.to_vec(),
        },
        Message::TransferAck(a) => Wire::Ack(*a),
        other => panic!("unexpected {other:?}"),
    }
}

/// The receiving end: a receiver, its staging buffer and what it installed.
struct Station {
    rx: Receiver,
    staging: Vec<u8>,
    /// (id, crc, bytes) of the installed object.
    installed: Option<(u32, u32, Vec<u8>)>,
    installs: usize,
}

impl Station {
    fn new(capacity: usize) -> Self {
        Station {
            rx: Receiver::new(),
            staging: vec![0; capacity],
            installed: None,
            installs: 0,
        }
    }

    fn handle(&mut self, w: Wire) -> Option<Wire> {
        match w {
            Wire::Begin(b) => {
                let have = self
                    .installed
                    .as_ref()
                    .is_some_and(|(id, crc, _)| (*id, *crc) == (b.id, b.crc));
                Some(Wire::Ack(self.rx.on_begin(&b, self.staging.len(), have)))
            }
            Wire::Chunk { tag, offset, data } => {
                let c = TransferData {
                    tag,
                    offset,
                    data: &data,
                };
                let installed = &mut self.installed;
                let installs = &mut self.installs;
                let a = self.rx.on_chunk(&c, &mut self.staging, |v: Verified<'_>| {
                    *installed = Some((v.id, v.crc, v.bytes.to_vec()));
                    *installs += 1;
                    true
                });
                Some(Wire::Ack(a))
            }
            Wire::Ack(_) => None,
        }
    }
}

/// Runs `sender` against `station` until it finishes (or `limit_ms`); returns the chunk bytes
/// the sender put on the wire.
fn run(
    sender: &mut Sender,
    bytes: &[u8],
    station: &mut Station,
    down: &mut Channel,
    up: &mut Channel,
    start_ms: u32,
    limit_ms: u32,
) -> (u32, usize) {
    let mut chunk_bytes = 0usize;
    let mut t = start_ms;
    while !sender.is_done() && t < start_ms + limit_ms {
        sender.poll(t, bytes, |m| {
            if let Message::TransferData(c) = m {
                chunk_bytes += c.data.len();
            }
            down.push(t, to_wire(m));
            true
        });
        for w in down.due(t) {
            if let Some(reply) = station.handle(w) {
                up.push(t, reply);
            }
        }
        for w in up.due(t) {
            if let Wire::Ack(a) = w {
                sender.on_ack(&a, t);
            }
        }
        t += 1;
    }
    (t, chunk_bytes)
}

fn object(len: usize, seed: u32) -> Vec<u8> {
    let mut r = Rng::new(seed ^ 0x5eed);
    (0..len).map(|_| r.next() as u8).collect()
}

/// Under any fault mix: success means the receiver holds exactly the object; failure is
/// reported and the receiver holds exactly what it held before.
fn check_one(len: usize, seed: u32, down: Faults, up: Faults, wrong_crc: bool) -> Outcome {
    let bytes = object(len, seed);
    let crc = crc32c(&bytes) ^ u32::from(wrong_crc);
    let mut sender = Sender::new(ObjectKind::Map, crc32c(&bytes), len as u32, crc, 1);
    let mut station = Station::new(4096);
    let old = (1, 2, vec![9u8; 7]);
    station.installed = Some(old.clone());
    let mut d = Channel::new(down, seed);
    let mut u = Channel::new(up, seed.wrapping_mul(31).wrapping_add(7));
    run(
        &mut sender,
        &bytes,
        &mut station,
        &mut d,
        &mut u,
        0,
        600_000,
    );
    let outcome = sender
        .outcome()
        .expect("a sender always ends: 5 retry periods bound it");
    let now = station.installed.clone().unwrap();
    if outcome.is_success() || now != old {
        assert_eq!(now.2, bytes, "installed bytes differ from the object");
        assert!(!wrong_crc, "an object with a wrong CRC was installed");
    }
    assert!(station.installs <= 1, "installed twice");
    if wrong_crc {
        assert!(
            matches!(outcome, Outcome::CrcMismatch | Outcome::TimedOut),
            "{outcome:?}"
        );
    }
    outcome
}

fn faults() -> impl Strategy<Value = Faults> {
    (0.0..0.6f64, 0.0..0.3f64, 1u32..200).prop_map(|(drop, dup, jitter_ms)| Faults {
        drop,
        dup,
        jitter_ms,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn a_lossy_channel_ends_in_an_identical_object_or_a_reported_failure(
        len in 1usize..3000,
        seed in any::<u32>(),
        down in faults(),
        up in faults(),
        wrong_crc in proptest::bool::weighted(0.15),
    ) {
        check_one(len, seed, down, up, wrong_crc);
    }

    #[test]
    fn a_restarted_sender_resumes_and_never_corrupts(
        len in 300usize..3000,
        seed in any::<u32>(),
        cut_ms in 1u32..200,
        down in faults(),
        up in faults(),
    ) {
        let bytes = object(len, seed);
        let mut station = Station::new(4096);
        let mut d = Channel::new(down, seed);
        let mut u = Channel::new(up, !seed);
        let mut first = Sender::for_object(ObjectKind::Plan, &bytes, 1).unwrap();
        let (t, _) = run(&mut first, &bytes, &mut station, &mut d, &mut u, 0, cut_ms);
        // The first sender is torn down; its frames still in flight arrive late.
        let mut second = Sender::for_object(ObjectKind::Plan, &bytes, 2).unwrap();
        run(&mut second, &bytes, &mut station, &mut d, &mut u, t, 600_000);
        let outcome = second.outcome().expect("ends");
        if let Some((_, _, got)) = &station.installed {
            prop_assert_eq!(got, &bytes);
        }
        if outcome.is_success() {
            prop_assert!(station.installed.is_some());
        }
    }
}

#[test]
fn ten_percent_loss_both_ways_completes_byte_identical() {
    let f = Faults {
        drop: 0.10,
        dup: 0.05,
        jitter_ms: 30,
    };
    let mut failures = 0;
    for seed in 1..=400u32 {
        let len = 200 + (seed as usize * 37) % 2900;
        if !check_one(len, seed, f, f, false).is_success() {
            failures += 1;
        }
    }
    assert_eq!(failures, 0, "transfers failed at 10 % loss");
}

#[test]
fn a_restarted_sender_sends_only_the_missing_bytes() {
    let bytes = object(2000, 3);
    let mut station = Station::new(4096);
    let (mut d, mut u) = (Channel::new(CLEAN, 1), Channel::new(CLEAN, 2));
    let mut first = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    let mut t = 0;
    while station
        .rx
        .progress()
        .is_none_or(|(_, _, next, _)| next < 1000)
    {
        t = run(&mut first, &bytes, &mut station, &mut d, &mut u, t, 1).0;
    }
    // Tear the sender down: its chunks in flight still arrive, their acks reach nobody.
    for _ in 0..50 {
        for w in d.due(t) {
            station.handle(w);
        }
        u.due(t);
        t += 1;
    }
    let held = station.rx.progress().unwrap().2;
    assert!((1000..2000).contains(&held));
    let mut second = Sender::for_object(ObjectKind::Map, &bytes, 2).unwrap();
    let (_, sent) = run(&mut second, &bytes, &mut station, &mut d, &mut u, t, 10_000);
    assert_eq!(second.outcome(), Some(Outcome::Complete));
    // Only the missing bytes travel again, besides what went behind the Begin before its
    // answer named the resume offset (PROTOCOL.md §8: one chunk or 256 bytes at most).
    assert!(
        sent >= 2000 - held as usize && sent <= 2000 - held as usize + EAGER_MAX,
        "{sent} bytes sent for {} missing",
        2000 - held
    );
    assert_eq!(station.installed.unwrap().2, bytes);
}

#[test]
fn an_object_the_receiver_holds_is_not_sent_again() {
    let bytes = object(1500, 4);
    let mut station = Station::new(4096);
    let (mut d, mut u) = (Channel::new(CLEAN, 1), Channel::new(CLEAN, 2));
    let mut s = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    run(&mut s, &bytes, &mut station, &mut d, &mut u, 0, 10_000);
    assert_eq!(s.outcome(), Some(Outcome::Complete));
    let mut again = Sender::for_object(ObjectKind::Map, &bytes, 2).unwrap();
    let (_, sent) = run(
        &mut again,
        &bytes,
        &mut station,
        &mut d,
        &mut u,
        20_000,
        10_000,
    );
    assert_eq!(again.outcome(), Some(Outcome::AlreadyHave));
    // At most what went behind the Begin before its answer said the object is held.
    assert!(sent <= EAGER_MAX, "{sent} bytes of a held object sent");
}

/// The most bytes a sender puts behind its Begin before the answer (PROTOCOL.md §8).
const EAGER_MAX: usize = (protocol::transfer::MIN_WINDOW_UNITS * protocol::transfer::UNIT) as usize;

#[test]
fn a_receiver_that_refuses_or_forgets_is_reported() {
    let bytes = object(5000, 5);
    let mut station = Station::new(4096);
    let (mut d, mut u) = (Channel::new(CLEAN, 1), Channel::new(CLEAN, 2));
    let mut s = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    run(&mut s, &bytes, &mut station, &mut d, &mut u, 0, 10_000);
    assert_eq!(s.outcome(), Some(Outcome::Rejected), "5000 bytes > 4096");
    assert!(station.installed.is_none());

    // A receiver that answers every chunk UnknownId (it keeps losing the transfer).
    let bytes = object(500, 6);
    let mut s = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    let tag = s.begin().tag;
    let mut t = 0;
    while !s.is_done() && t < 100_000 {
        let mut began = false;
        s.poll(t, &bytes, |m| {
            began |= matches!(m, Message::TransferBegin(_));
            true
        });
        let status = if began {
            TransferStatus::Receiving
        } else {
            TransferStatus::UnknownId
        };
        s.on_ack(
            &TransferAck {
                tag,
                next: 0,
                status,
                sack: 0,
            },
            t,
        );
        t += 10;
    }
    assert_eq!(s.outcome(), Some(Outcome::UnknownId));
    // Bytes that no longer match the announced length end the transfer at once.
    let mut s = Sender::for_object(ObjectKind::Map, &bytes, 1).unwrap();
    s.poll(0, &bytes[..10], |_| true);
    assert_eq!(s.outcome(), Some(Outcome::ObjectChanged));
}
