//! Starting a link for a command and waiting for its handshake, failing at once (with the
//! reason) when the port cannot be opened or the robot refuses us.

use anyhow::bail;
use std::time::Duration;
use tokio::time::Instant;

use super::args::RequiredPort;
use crate::link::serial::SerialConnector;
use crate::link::{
    spawn_link, Connection, Connector, LinkEvent, LinkOptions, OpenError, PeerInfo, RunningLink,
    Transport,
};
use crate::share::ShareConnector;

/// Starts a link and waits for the handshake; fails fast on a port that cannot be opened or a
/// robot that refuses us.
pub async fn connect(
    port: &RequiredPort,
    timeout_s: f64,
) -> anyhow::Result<(RunningLink, PeerInfo)> {
    let (connector, key) = port_connector(port)?;
    let mut link = spawn_link(
        connector,
        LinkOptions {
            station: format!("station-cli {}", env!("CARGO_PKG_VERSION")),
            key,
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

/// The robot's port as a command opens it: the shared link of a station that holds it
/// (`--via`, or found by the port's name), else the serial port itself.
pub enum PortConnector {
    Serial(SerialConnector),
    Shared(ShareConnector),
}

impl Connector for PortConnector {
    fn name(&self) -> String {
        match self {
            PortConnector::Serial(c) => c.name(),
            PortConnector::Shared(c) => c.name(),
        }
    }

    fn open(&mut self) -> Result<Box<dyn Transport>, OpenError> {
        match self {
            PortConnector::Serial(c) => c.open(),
            PortConnector::Shared(c) => c.open(),
        }
    }

    fn present(&self) -> bool {
        match self {
            PortConnector::Serial(c) => c.present(),
            PortConnector::Shared(c) => c.present(),
        }
    }

    fn awaiting_reply(&self, awaiting: bool) {
        if let PortConnector::Serial(c) = self {
            c.awaiting_reply(awaiting);
        }
    }
}

/// Which way a command reaches the robot, and the link key it uses: none over a shared link,
/// whose local leg is not signed (the holder verifies the robot's signatures); a note on
/// stderr says a shared link is used.
pub fn port_connector(
    port: &RequiredPort,
) -> anyhow::Result<(PortConnector, Option<protocol::LinkKey>)> {
    let shared = match &port.via {
        Some(via) => Some(via.clone()),
        None => crate::share::serving(&port.port),
    };
    if let Some(path) = shared {
        eprintln!(
            "station: {} is held by another station; going through its shared link {}",
            crate::terminal_text::printable(&port.port.display().to_string()),
            crate::terminal_text::printable(&path.display().to_string())
        );
        return Ok((PortConnector::Shared(ShareConnector::new(path)), None));
    }
    let key =
        crate::commands::args::load_key(port.key_file.as_deref()).map_err(anyhow::Error::msg)?;
    Ok((
        PortConnector::Serial(SerialConnector::new(&port.port, port.baud)),
        key,
    ))
}
