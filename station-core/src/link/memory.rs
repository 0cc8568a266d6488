//! An in-memory port for tests: `MemoryConnector` is the station's side, `MemoryPeer` the
//! robot's, and the test can unplug and replug the cable.
//!
//! Layer: a `Connector` over tokio duplex pipes (postcard-rpc's `test_channels`). Each `open`
//! makes a new pipe and hands the far end to the peer, as plugging a USB adapter in gives a
//! fresh device. `unplug` makes the station's reads end (EOF), its `present()` false and its
//! opens fail until `replug`. Cannot fail otherwise; a poisoned lock is recovered because the
//! shared state is two plain fields.

use std::sync::{Arc, Mutex, MutexGuard};

use tokio::io::DuplexStream;
use tokio::sync::mpsc;

use super::transport::{Connector, OpenError, Transport};

/// Bytes each direction of the pipe buffers (more than a second of 115200 baud).
pub const PIPE_BYTES: usize = 64 * 1024;

#[derive(Debug)]
struct Cable {
    plugged: bool,
    /// Bumped by each unplug, so the peer drops the end it holds.
    generation: u64,
}

/// The station's side.
pub struct MemoryConnector {
    cable: Arc<Mutex<Cable>>,
    ends: mpsc::UnboundedSender<(u64, DuplexStream)>,
}

/// The robot's side and the cable's plug.
pub struct MemoryPeer {
    cable: Arc<Mutex<Cable>>,
    ends: mpsc::UnboundedReceiver<(u64, DuplexStream)>,
    current: Option<(u64, DuplexStream)>,
}

/// A plugged-in in-memory port.
pub fn memory_port() -> (MemoryConnector, MemoryPeer) {
    let cable = Arc::new(Mutex::new(Cable {
        plugged: true,
        generation: 0,
    }));
    let (tx, rx) = mpsc::unbounded_channel();
    (
        MemoryConnector {
            cable: Arc::clone(&cable),
            ends: tx,
        },
        MemoryPeer {
            cable,
            ends: rx,
            current: None,
        },
    )
}

fn lock(c: &Mutex<Cable>) -> MutexGuard<'_, Cable> {
    c.lock().unwrap_or_else(|e| e.into_inner())
}

impl Connector for MemoryConnector {
    fn name(&self) -> String {
        "memory".into()
    }

    fn open(&mut self) -> Result<Box<dyn Transport>, OpenError> {
        let generation = {
            let c = lock(&self.cable);
            if !c.plugged {
                return Err(OpenError::Unplugged);
            }
            c.generation
        };
        let (station, robot) = tokio::io::duplex(PIPE_BYTES);
        self.ends
            .send((generation, robot))
            .map_err(|_| OpenError::Other {
                path: "memory".into(),
                message: "the robot side is gone".into(),
            })?;
        Ok(Box::new(station))
    }

    fn present(&self) -> bool {
        lock(&self.cable).plugged
    }
}

/// The cable's plug, for a test to pull and push while the peer runs elsewhere.
#[derive(Clone, Debug)]
pub struct Plug {
    cable: Arc<Mutex<Cable>>,
}

impl Plug {
    /// Pulls the cable: the station's stream ends and it cannot reopen until `replug`.
    pub fn unplug(&self) {
        let mut c = lock(&self.cable);
        c.plugged = false;
        c.generation += 1;
    }

    /// Plugs the cable back in.
    pub fn replug(&self) {
        lock(&self.cable).plugged = true;
    }
}

impl MemoryPeer {
    /// A handle on the cable's plug.
    pub fn plug(&self) -> Plug {
        Plug {
            cable: Arc::clone(&self.cable),
        }
    }

    /// Pulls the cable: the station's stream ends and it cannot reopen until `replug`.
    pub fn unplug(&self) {
        let mut c = lock(&self.cable);
        c.plugged = false;
        c.generation += 1;
    }

    /// Plugs the cable back in.
    pub fn replug(&self) {
        lock(&self.cable).plugged = true;
    }

    /// Whether the cable is plugged in.
    pub fn plugged(&self) -> bool {
        lock(&self.cable).plugged
    }

    /// The robot's end of the pipe the station opened last, if the cable still carries it.
    pub fn end(&mut self) -> Option<&mut DuplexStream> {
        let generation = lock(&self.cable).generation;
        while let Ok(e) = self.ends.try_recv() {
            self.current = Some(e);
        }
        if self.current.as_ref().is_some_and(|(g, _)| *g != generation) {
            // Unplugged since: dropping our end ends the station's stream.
            self.current = None;
        }
        self.current.as_mut().map(|(_, e)| e)
    }

    /// Drops the current end (the robot side saw it end).
    pub fn drop_end(&mut self) {
        self.current = None;
    }
}
