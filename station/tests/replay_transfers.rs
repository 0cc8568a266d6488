//! A replay answers nothing and keeps nothing it would have sent: the transfer engine's answers
//! to a recorded download (one `TransferAck` per chunk) are dropped, like its commands.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::{Message, TransferData, PROTOCOL_VERSION};
use station::app::AppOptions;
use station::record::synth::{demo_peer, Synth};
use station::record::{Meta, Recording};
use station::replay::session::ReplaySession;

/// A session in which the robot sends `chunks` transfer chunks, ten a second.
fn downloading(chunks: u32) -> Recording {
    let meta = Meta {
        port: "memory".into(),
        baud: 115_200,
        protocol: PROTOCOL_VERSION,
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    s.handshake(demo_peer());
    let data = [7u8; 64];
    for i in 0..chunks {
        s.from_robot(
            10_000 + u64::from(i) * 100_000,
            &Message::TransferData(TransferData {
                tag: 42,
                offset: i * 64,
                data: &data,
            }),
        );
    }
    let end = 20_000 + u64::from(chunks) * 100_000;
    Recording::parse_strict(&s.finish(end, "done")).unwrap()
}

#[test]
fn a_replayed_download_leaves_no_answers_behind() {
    let rec = downloading(50);
    let end = rec.duration_us();
    let mut s = ReplaySession::new(
        rec,
        "download.rec",
        AppOptions {
            port_label: "replay".into(),
            arena: None,
            ..AppOptions::default()
        },
        1.0,
    );
    // Played in steps, as the terminal loop does.
    for k in 1..=10 {
        s.player.seek(0, end * k / 10);
        s.sync(0);
    }
    assert_eq!(s.player.position(0), end);
    assert!(s.app_mut().take_outbox().is_empty());
    assert_eq!(s.app_mut().transfers.take_frames().len(), 0);
}
