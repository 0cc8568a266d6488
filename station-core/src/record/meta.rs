//! The header's metadata: the JSON object every recording starts with.

use serde::{Deserialize, Serialize};

/// What the header's JSON says about a recording. Every field is optional to a reader.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Meta {
    /// Wall-clock time of `t_us = 0`, milliseconds since the Unix epoch.
    #[serde(default)]
    pub created_unix_ms: u64,
    /// The program and version that wrote it.
    #[serde(default)]
    pub writer: String,
    /// The port recorded ("/dev/ttyUSB0", "built-in emulator on /dev/pts/3").
    #[serde(default)]
    pub port: String,
    #[serde(default)]
    pub baud: u32,
    /// The link protocol version and schema fingerprint (hex) of the station that recorded.
    #[serde(default)]
    pub protocol: u8,
    #[serde(default)]
    pub fingerprint: String,
    /// The arena drawn under the map (a file, or the emulator's built-in name), if known.
    #[serde(default)]
    pub arena: String,
    /// Version 2: the ports recorded, by link id ("/tmp/robot1", "/tmp/robot2"); `port` names
    /// them all. Empty in a version 1 file (one link, `port`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub links: Vec<String>,
}

impl Meta {
    /// Metadata for a recording starting now.
    pub fn now(port: &str, baud: u32) -> Meta {
        Meta {
            created_unix_ms: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_millis() as u64),
            writer: format!("station {}", env!("CARGO_PKG_VERSION")),
            port: port.to_string(),
            baud,
            protocol: protocol::PROTOCOL_VERSION,
            fingerprint: crate::link::machine::hex(&protocol::FINGERPRINT),
            arena: String::new(),
            links: vec![port.to_string()],
        }
    }

    /// A warning when the recording was made with another message schema than this
    /// station's (its fingerprint, PROTOCOL.md §3): frames whose layout changed since then do
    /// not decode (they are counted as undecodable), and the reader should know why. `None`
    /// when the schemas are the same, or the file names none (written by a test tool).
    pub fn schema_warning(&self) -> Option<String> {
        let ours = crate::link::machine::hex(&protocol::FINGERPRINT);
        (!self.fingerprint.is_empty() && self.fingerprint != ours).then(|| {
            format!(
                "recorded with message schema {} (protocol {}); this station's is {ours} \
                 (protocol {}): frames whose layout changed since do not decode and are \
                 counted as undecodable",
                crate::terminal_text::printable_text(&self.fingerprint),
                self.protocol,
                protocol::PROTOCOL_VERSION
            )
        })
    }

    /// Metadata for a recording of several ports starting now: `port` names them all.
    pub fn now_links(ports: &[String], baud: u32) -> Meta {
        Meta {
            links: ports.to_vec(),
            ..Meta::now(&ports.join(", "), baud)
        }
    }

    /// The port of each link, by link id: `links`, or in a version 1 file `port` alone.
    pub fn link_ports(&self) -> Vec<String> {
        if self.links.is_empty() {
            vec![self.port.clone()]
        } else {
            self.links.clone()
        }
    }
}
