//! The link task: the one owner of the port (postcard-rpc's host client pattern).
//!
//! Layer: I/O around `LinkMachine`. The task opens the port through a `Connector`, feeds the
//! machine what it reads, writes what the machine produces, runs its timers at the deadlines
//! it names, and forwards its events to the app. When the port closes, errors or disappears
//! (polled through `Connector::present`), the task closes it, keeps trying to reopen it every
//! `reopen_every`, and handshakes again once it is back: within `reopen_every` plus one
//! round trip of the port reappearing. Users hold a cloneable `LinkHandle`; all of them share
//! one event stream. What can fail: nothing is returned; every failure becomes a
//! `Connection::Closed { reason }` event and a retry.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use protocol::Command;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::sync::{mpsc, oneshot};
use tokio::time::Instant;

use super::api::{
    CommandFailure, CommandId, CommandOutcome, LinkEvent, LinkRequest, SendWhen, TransferOut,
};
use super::machine::{LinkMachine, MachineConfig};
use super::transport::{Connector, Transport};

/// Settings of the link task.
#[derive(Clone, Debug)]
pub struct LinkOptions {
    /// The station's name in `Hello`.
    pub station: String,
    /// Seed of the session nonces; `None` draws one from the OS's hasher keys.
    pub nonce_seed: Option<u64>,
    /// How often a closed port is retried, and an open one checked for presence.
    pub reopen_every: Duration,
    /// A write that takes longer than this means the port is wedged: it is closed.
    pub write_timeout: Duration,
    /// Every byte read or written, timestamped, for recording (None: no tap).
    pub tap: Option<mpsc::UnboundedSender<TapRecord>>,
    /// Link authentication key (PROTOCOL.md §13): sign and verify every frame.
    pub key: Option<protocol::LinkKey>,
    /// Put the task's timers (heartbeat, statistics, presence check) on the `pace` grid, so
    /// that they share wake-ups with the TUI's; each fires up to one slot later.
    pub paced: bool,
}

impl Default for LinkOptions {
    fn default() -> Self {
        LinkOptions {
            station: format!("station {}", env!("CARGO_PKG_VERSION")),
            nonce_seed: None,
            reopen_every: Duration::from_millis(100),
            write_timeout: Duration::from_millis(500),
            tap: None,
            key: None,
            paced: false,
        }
    }
}

/// Which way tapped bytes went.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum TapDirection {
    ToRobot,
    FromRobot,
}

/// Bytes that crossed the port, with the task's clock (µs since it started).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TapRecord {
    pub t_us: u64,
    pub direction: TapDirection,
    pub bytes: Vec<u8>,
}

/// A cloneable way to talk to the link task.
#[derive(Clone, Debug)]
pub struct LinkHandle {
    requests: mpsc::UnboundedSender<LinkRequest>,
    next_id: Arc<AtomicU64>,
}

impl LinkHandle {
    /// Submits a command with a fresh id; its outcome arrives as `LinkEvent::CommandDone`.
    pub fn submit(&self, command: Command) -> CommandId {
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        self.submit_with_id(id, command);
        id
    }

    /// Submits a command under the caller's id.
    pub fn submit_with_id(&self, id: CommandId, command: Command) {
        self.submit_when(id, command, SendWhen::Now);
    }

    /// Submits a command under the caller's id, to go out `when` says.
    pub fn submit_when(&self, id: CommandId, command: Command, when: SendWhen) {
        let _ = self.requests.send(LinkRequest::Command {
            id,
            command,
            reply: None,
            when,
        });
    }

    /// Submits a command and waits for its outcome.
    pub async fn call(&self, command: Command) -> CommandOutcome {
        let (tx, rx) = oneshot::channel();
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let req = LinkRequest::Command {
            id,
            command,
            reply: Some(tx),
            when: SendWhen::Now,
        };
        if self.requests.send(req).is_err() {
            return CommandOutcome::Failed(CommandFailure::Shutdown);
        }
        rx.await
            .unwrap_or(CommandOutcome::Failed(CommandFailure::Shutdown))
    }

    /// Sends a transfer frame as is.
    pub fn transfer(&self, t: TransferOut) {
        let _ = self.requests.send(LinkRequest::Transfer(t));
    }

    /// Asks the task to close the port and end.
    pub fn shutdown(&self) {
        let _ = self.requests.send(LinkRequest::Shutdown);
    }
}

/// A started link: the handle, the event stream and the task.
pub struct RunningLink {
    pub handle: LinkHandle,
    pub events: mpsc::UnboundedReceiver<LinkEvent>,
    pub task: tokio::task::JoinHandle<()>,
}

/// Starts the link task on the current tokio runtime.
pub fn spawn_link<C: Connector>(connector: C, opts: LinkOptions) -> RunningLink {
    let (req_tx, req_rx) = mpsc::unbounded_channel();
    let (ev_tx, ev_rx) = mpsc::unbounded_channel();
    let seed = opts.nonce_seed.unwrap_or_else(random_seed);
    let mut machine = LinkMachine::new(MachineConfig {
        station: opts.station.clone(),
        nonce_seed: seed,
    });
    machine.set_key(opts.key.clone());
    let task = Task {
        machine,
        opts,
        requests: req_rx,
        events: ev_tx,
        replies: HashMap::new(),
        t0: Instant::now(),
    };
    let task = tokio::spawn(task.run(connector));
    RunningLink {
        handle: LinkHandle {
            requests: req_tx,
            next_id: Arc::new(AtomicU64::new(1)),
        },
        events: ev_rx,
        task,
    }
}

fn random_seed() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    // RandomState is keyed from the OS's randomness once per process; mixing in the time
    // makes two links in one process differ too.
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    h.finish()
}

struct Task {
    machine: LinkMachine,
    opts: LinkOptions,
    requests: mpsc::UnboundedReceiver<LinkRequest>,
    events: mpsc::UnboundedSender<LinkEvent>,
    replies: HashMap<CommandId, oneshot::Sender<CommandOutcome>>,
    t0: Instant,
}

/// Why the connected loop ended.
enum Ended {
    Closed(String),
    Shutdown,
}

impl Task {
    fn now_ms(&self) -> u64 {
        self.t0.elapsed().as_millis() as u64
    }

    /// The task's clock in microseconds: the machine times round trips with it.
    fn now_us(&self) -> u64 {
        u64::try_from(self.t0.elapsed().as_micros()).unwrap_or(u64::MAX)
    }

    async fn run<C: Connector>(mut self, mut connector: C) {
        loop {
            let now = self.now_ms();
            self.machine.poll(now);
            match connector.open() {
                Ok(transport) => {
                    self.machine.port_opened(self.now_ms(), &connector.name());
                    match self.connected(&connector, transport).await {
                        Ended::Shutdown => break,
                        Ended::Closed(reason) => self.machine.port_closed(reason),
                    }
                }
                Err(e) => self.machine.port_unavailable(e.to_string()),
            }
            self.forward();
            // Wait before retrying, still answering requests (commands fail: not connected).
            let retry_at = Instant::now() + self.opts.reopen_every;
            loop {
                tokio::select! {
                    req = self.requests.recv() => {
                        if !self.handle_request(req) { return self.finish(); }
                    }
                    _ = tokio::time::sleep_until(retry_at) => break,
                }
            }
        }
        self.finish();
    }

    fn finish(&mut self) {
        self.machine.shutdown();
        self.machine.port_unavailable("link stopped".into());
        self.forward();
    }

    /// Runs one open port until it closes or the task is told to stop.
    async fn connected<C: Connector>(
        &mut self,
        connector: &C,
        mut port: Box<dyn Transport>,
    ) -> Ended {
        let mut buf = vec![0u8; 4096];
        let mut presence = if self.opts.paced {
            // On the grid, and kept there when late (`Delay` would leave it).
            let period = crate::pace::slots(self.opts.reopen_every);
            let mut i = tokio::time::interval_at(crate::pace::next_slot(), period);
            i.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
            i
        } else {
            let mut i = tokio::time::interval(self.opts.reopen_every);
            i.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            i
        };
        // Paced: bytes since the last check prove the port is there (no `stat` at 50 Hz).
        let mut heard = false;
        loop {
            if let Err(reason) = self.flush(&mut port).await {
                return Ended::Closed(reason);
            }
            self.forward();
            // Set after every send and every answer, before the read is polled again.
            connector.awaiting_reply(self.machine.awaiting_reply());
            let mut deadline = self.t0 + Duration::from_millis(self.machine.next_deadline());
            if self.opts.paced {
                deadline = crate::pace::slot_at_or_after(deadline);
            }
            // A command held for a quiet line goes at its moment, off the grid.
            if let Some(at) = self.machine.next_release_us() {
                deadline = deadline.min(self.t0 + Duration::from_micros(at));
            }
            tokio::select! {
                r = port.read(&mut buf) => match r {
                    Ok(0) => return Ended::Closed(format!("{} closed", connector.name())),
                    Ok(n) => {
                        let bytes = buf.get(..n).unwrap_or(&[]);
                        heard = true;
                        self.tap(TapDirection::FromRobot, bytes);
                        let now = self.now_us();
                        self.machine.receive_us(now, bytes);
                    }
                    Err(e) => return Ended::Closed(format!("{}: {e}", connector.name())),
                },
                req = self.requests.recv() => {
                    if !self.handle_request(req) {
                        let _ = self.flush(&mut port).await;
                        return Ended::Shutdown;
                    }
                }
                _ = tokio::time::sleep_until(deadline) => {
                    let now = self.now_us();
                    self.machine.poll_us(now);
                }
                _ = presence.tick() => {
                    let heard = std::mem::take(&mut heard) && self.opts.paced;
                    if !heard && !connector.present() {
                        return Ended::Closed(format!("{} disappeared", connector.name()));
                    }
                }
            }
        }
    }

    /// Handles one request; false means stop.
    fn handle_request(&mut self, req: Option<LinkRequest>) -> bool {
        let now_us = self.now_us();
        match req {
            None | Some(LinkRequest::Shutdown) => false,
            Some(LinkRequest::Command {
                id,
                command,
                reply,
                when,
            }) => {
                if let Some(r) = reply {
                    self.replies.insert(id, r);
                }
                self.machine.submit_when(now_us, id, command, when);
                self.forward();
                true
            }
            Some(LinkRequest::Transfer(t)) => {
                self.machine.send_transfer(now_us / 1000, &t);
                true
            }
        }
    }

    async fn flush(&mut self, port: &mut Box<dyn Transport>) -> Result<(), String> {
        let out = self.machine.take_output();
        if out.is_empty() {
            return Ok(());
        }
        self.tap(TapDirection::ToRobot, &out);
        let write = async {
            port.write_all(&out).await?;
            port.flush().await
        };
        match tokio::time::timeout(self.opts.write_timeout, write).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(format!("write failed: {e}")),
            Err(_) => Err(format!(
                "write blocked for {} ms",
                self.opts.write_timeout.as_millis()
            )),
        }
    }

    fn tap(&self, direction: TapDirection, bytes: &[u8]) {
        if let Some(tap) = &self.opts.tap {
            let _ = tap.send(TapRecord {
                t_us: self.t0.elapsed().as_micros() as u64,
                direction,
                bytes: bytes.to_vec(),
            });
        }
    }

    /// Sends the machine's events to the app, answering waiting callers on the way.
    fn forward(&mut self) {
        for ev in self.machine.take_events() {
            if let LinkEvent::CommandDone { id, outcome, .. } = &ev {
                if let Some(r) = self.replies.remove(id) {
                    let _ = r.send(*outcome);
                }
            }
            // Nobody listening is fine (a headless `send` may only use `call`).
            let _ = self.events.send(ev);
        }
    }
}
