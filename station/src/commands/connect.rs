//! Starting a link for a command and waiting for its handshake, failing at once (with the
//! reason) when the port cannot be opened or the robot refuses us.

use anyhow::bail;
use std::time::Duration;
use tokio::time::Instant;

use super::args::RequiredPort;
use crate::link::serial::SerialConnector;
use crate::link::{spawn_link, Connection, LinkEvent, LinkOptions, PeerInfo, RunningLink};

/// Starts a link and waits for the handshake; fails fast on a port that cannot be opened or a
/// robot that refuses us.
pub async fn connect(
    port: &RequiredPort,
    timeout_s: f64,
) -> anyhow::Result<(RunningLink, PeerInfo)> {
    let mut link = spawn_link(
        SerialConnector::new(&port.port, port.baud),
        LinkOptions {
            station: format!("station-cli {}", env!("CARGO_PKG_VERSION")),
            key: crate::commands::args::load_key(port.key_file.as_deref())
                .map_err(anyhow::Error::msg)?,
            ..LinkOptions::default()
        },
    );
    let deadline = Instant::now() + Duration::from_secs_f64(timeout_s);
    loop {
        let ev = match tokio::time::timeout_at(deadline, link.events.recv()).await {
            Ok(Some(ev)) => ev,
            Ok(None) => bail!("the link task ended"),
            Err(_) => bail!(
                "no handshake with a robot on {} within {timeout_s} s (is the robot on this \
                 port, at this baud rate?)",
                port.port.display()
            ),
        };
        match ev {
            LinkEvent::Connection(Connection::Connected(p)) => return Ok((link, p)),
            LinkEvent::Connection(Connection::Closed { reason }) => bail!("{reason}"),
            LinkEvent::Connection(Connection::Refused { message }) => bail!("{message}"),
            _ => {}
        }
    }
}
