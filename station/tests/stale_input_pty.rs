//! What a port holds before the station opens it is not for the station: a pty keeps the
//! bytes the robot wrote while no one had the slave open (the end of the last station's
//! session: its telemetry, the refusal of its Hello), and `SerialConnector` discards them on
//! opening, plain and paced, so the first bytes read are ones written after the open.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::time::Duration;

use emulator::pty::Pty;
use station::link::serial::SerialConnector;
use station::link::Connector;
use tokio::io::AsyncReadExt;

async fn first_bytes_after_open(paced: bool) -> String {
    let pty = Pty::open(None).unwrap();
    let stale = [b'S'; 600];
    assert_eq!(
        pty.write(&stale),
        stale.len(),
        "the pty keeps bytes written while the slave is closed (else this test proves nothing)"
    );
    let mut connector = SerialConnector::new(pty.slave_path(), 115_200).paced(paced);
    let mut port = connector.open().unwrap();
    assert_eq!(pty.write(b"fresh\0"), 6);
    let mut got = Vec::new();
    let mut buf = [0u8; 1024];
    while !got.ends_with(b"\0") {
        let n = tokio::time::timeout(Duration::from_secs(5), port.read(&mut buf))
            .await
            .expect("the bytes written after opening arrive")
            .unwrap();
        assert!(n > 0, "the port closed");
        got.extend_from_slice(&buf[..n]);
    }
    String::from_utf8_lossy(&got).into_owned()
}

#[tokio::test]
async fn bytes_queued_before_the_station_opened_the_port_are_discarded() {
    assert_eq!(first_bytes_after_open(false).await, "fresh\0");
}

#[tokio::test]
async fn the_paced_port_discards_them_too() {
    assert_eq!(first_bytes_after_open(true).await, "fresh\0");
}
