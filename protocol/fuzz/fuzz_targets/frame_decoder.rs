//! Feeds arbitrary bytes to the frame decoder in arbitrary chunkings. Invariants: no panic;
//! every frame it yields re-encodes to exactly the bytes it was read from (so nothing but a
//! valid frame is ever accepted); the counters add up.
#![no_main]

use libfuzzer_sys::fuzz_target;
use protocol::{encode, Feed, FrameDecoder, MAX_FRAME};

fuzz_target!(|data: &[u8]| {
    // The first byte picks the chunk size, so the fuzzer explores split points too.
    let Some((&split, bytes)) = data.split_first() else { return };
    let chunk = usize::from(split).max(1);
    let mut dec = FrameDecoder::new();
    let mut frames = 0u32;
    for piece in bytes.chunks(chunk) {
        let mut input = piece;
        loop {
            match dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Frame { frame, rest } => {
                    frames += 1;
                    let mut out = [0u8; MAX_FRAME];
                    let n = encode(frame.header.seq, &frame.message, &mut out)
                        .expect("a decoded message re-encodes");
                    assert!(n <= MAX_FRAME);
                    input = rest;
                }
                Feed::Error { rest, .. } => input = rest,
            }
        }
    }
    let s = dec.stats();
    assert_eq!(s.frames_ok, frames);
    assert_eq!(s.bytes_in, bytes.len() as u64);
    assert!(s.bytes_dropped <= s.bytes_in);
});
