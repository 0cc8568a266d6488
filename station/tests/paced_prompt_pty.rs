//! The paced port reads a busy port once per `pace` slot, except while a reply is awaited:
//! then bytes that have come are read at once, so an ack never waits for the next slot (the
//! TUI's round trip was a slot, 33 ms, for 2.1-2.4 ms of bytes). Deterministic: each case
//! starts just after a slot boundary, so the next slot is some 30 ms away when the port is
//! polled once, a few milliseconds after the reply's bytes were written.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::pin::Pin;
use std::task::{Context, Poll, Waker};
use std::time::Duration;

use emulator::pty::Pty;
use station::link::serial::SerialConnector;
use station::link::{Connector, Transport};
use station::pace;
use tokio::io::{AsyncRead, AsyncReadExt, ReadBuf};

/// Whether one poll of the port, a moment after `reply` was written, hands it over.
async fn reply_read_without_waiting_for_the_slot(awaiting: bool) -> bool {
    let pty = Pty::open(None).unwrap();
    let mut connector = SerialConnector::new(pty.slave_path(), 115_200).paced(true);
    let mut port: Box<dyn Transport> = connector.open().unwrap();
    // Just after a slot boundary: the next one is nearly a whole slot away.
    let boundary = pace::next_slot();
    tokio::time::sleep_until(boundary + Duration::from_millis(1)).await;
    // Busy: telemetry came, the port reads it and goes onto the grid.
    assert_eq!(pty.write(b"telemetry\0"), 10);
    let mut buf = [0u8; 256];
    let n = tokio::time::timeout(Duration::from_secs(5), port.read(&mut buf))
        .await
        .expect("the first bytes are read at once (the port was quiet)")
        .unwrap();
    assert!(n > 0);
    // A command goes out; its ack comes back.
    connector.awaiting_reply(awaiting);
    assert_eq!(pty.write(b"ack\0"), 4);
    std::thread::sleep(Duration::from_millis(3));
    assert!(
        tokio::time::Instant::now() < boundary + pace::SLOT - Duration::from_millis(5),
        "the machine stalled past the slot: this run proves nothing"
    );
    let mut rb = ReadBuf::new(&mut buf);
    let mut cx = Context::from_waker(Waker::noop());
    match Pin::new(&mut port).poll_read(&mut cx, &mut rb) {
        Poll::Ready(r) => {
            r.unwrap();
            assert_eq!(rb.filled(), b"ack\0");
            true
        }
        Poll::Pending => false,
    }
}

#[tokio::test]
async fn an_awaited_reply_is_read_at_once() {
    assert!(reply_read_without_waiting_for_the_slot(true).await);
}

#[tokio::test]
async fn without_a_reply_awaited_the_busy_port_still_waits_for_its_slot() {
    assert!(!reply_read_without_waiting_for_the_slot(false).await);
}
