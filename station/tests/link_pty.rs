//! The real serial path: the station's `SerialConnector` (tokio-serial, exclusive open) on the
//! slave of a pseudo-terminal served by the emulator's serving loop, with the real firmware
//! (`SimCore`) behind it. Real time, so these take a few seconds.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::time::Duration;

use emulator::link::{spawn_device, ServeOptions};
use protocol::Command;
use station::link::serial::{open_exclusive, SerialConnector};
use station::link::sim::{SimCore, SimOptions};
use station::link::{spawn_link, Connection, LinkEvent, LinkOptions, OpenError, RunningLink};
use tokio::time::Instant;

fn link_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("station-pty-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("robot")
}

async fn wait_connected(link: &mut RunningLink, within: Duration) {
    let deadline = Instant::now() + within;
    loop {
        let ev = tokio::time::timeout_at(deadline, link.events.recv())
            .await
            .expect("timed out waiting for the handshake")
            .expect("events");
        if let LinkEvent::Connection(Connection::Connected(_)) = ev {
            return;
        }
    }
}

#[tokio::test]
async fn the_station_opens_the_pty_exclusively_and_talks_to_the_firmware() {
    let path = link_path("exclusive");
    let emu = spawn_device(
        || Ok(SimCore::new(SimOptions::default())),
        ServeOptions {
            link: Some(path.clone()),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    let mut link = spawn_link(SerialConnector::new(&path, 115_200), LinkOptions::default());
    wait_connected(&mut link, Duration::from_secs(3)).await;
    assert!(link.handle.call(Command::Stop).await.is_ack());
    // A second opener is refused, and told who holds the port.
    match open_exclusive(&path, 115_200) {
        Err(OpenError::Busy { holders, .. }) => {
            assert!(holders.contains("this process"), "{holders}")
        }
        Err(e) => panic!("expected Busy, got {e}"),
        Ok(_) => panic!("a second open of an exclusive port succeeded"),
    }
    link.handle.shutdown();
    let _ = link.task.await;
    drop(emu);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}

#[tokio::test]
async fn a_missing_port_is_reported_as_not_found() {
    match open_exclusive(std::path::Path::new("/dev/does-not-exist-station"), 115_200) {
        Err(OpenError::NotFound { .. }) => {}
        Err(e) => panic!("expected NotFound, got {e}"),
        Ok(_) => panic!("opened a missing port"),
    }
}

#[tokio::test]
async fn the_station_reconnects_when_the_emulator_replugs_its_pty() {
    let path = link_path("replug");
    let emu = spawn_device(
        || Ok(SimCore::new(SimOptions::default())),
        ServeOptions {
            link: Some(path.clone()),
            disconnect_after_s: Some(1.0),
            reconnect_after_s: Some(0.5),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    let mut link = spawn_link(SerialConnector::new(&path, 115_200), LinkOptions::default());
    wait_connected(&mut link, Duration::from_secs(3)).await;
    // Unplugged at 1 s: the station notices and closes.
    let deadline = Instant::now() + Duration::from_secs(3);
    loop {
        let ev = tokio::time::timeout_at(deadline, link.events.recv())
            .await
            .expect("the station never noticed the unplug")
            .expect("events");
        if let LinkEvent::Connection(Connection::Closed { .. } | Connection::Handshaking { .. }) =
            ev
        {
            break;
        }
    }
    // Replugged 0.5 s later on a new pty behind the same symlink: connected within 1 s.
    wait_connected(&mut link, Duration::from_secs(2)).await;
    assert!(link.handle.call(Command::Stop).await.is_ack());
    link.handle.shutdown();
    let _ = link.task.await;
    drop(emu);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}
