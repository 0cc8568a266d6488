//! The shared link's I/O: the socket a station holding a robot's port serves, and the port
//! other station programs open instead of the serial one.
//!
//! Layer: I/O around `share::hub`. `share_link` wraps a running link: every event of the
//! holder's link goes through the hub (which writes to the clients what they should see) and
//! on to the holder, except the outcomes of the clients' own commands. Each client is one
//! connection on a Unix socket (mode 0600 in the 0700 runtime directory, `share::path`), read
//! through a `FrameDecoder`; at most `MAX_CLIENTS` at once, each with a bounded queue (a
//! client that does not read loses frames, never the holder's memory). `ShareConnector` is
//! the client's side: a `Connector` that opens the socket, so the link task, and every
//! command built on it, runs over the shared link unchanged.
//!
//! What can fail: the socket cannot be made (`share_link` returns why and the holder goes on
//! without sharing); a client's connection fails (that client is dropped).

use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use protocol::frame::{Feed, FrameDecoder};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{UnixListener, UnixStream};
use tokio::sync::mpsc;

use super::hub::{ClientId, Hub, HubOut};
use crate::link::transport::{Connector, OpenError, Transport};
use crate::link::{LinkHandle, RunningLink};

/// Most clients attached at once; more are turned away.
pub const MAX_CLIENTS: usize = 16;
/// Frames queued for one client before its newest are dropped.
const CLIENT_QUEUE: usize = 512;

type Writers = Arc<Mutex<std::collections::HashMap<ClientId, mpsc::Sender<Vec<u8>>>>>;

/// A link being shared; removes its socket when dropped.
#[derive(Debug)]
pub struct Shared {
    path: PathBuf,
    hub: Arc<Mutex<Hub>>,
}

impl Shared {
    /// The socket's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How many clients are attached now.
    pub fn clients(&self) -> usize {
        self.hub.lock().map_or(0, |h| h.clients())
    }
}

impl Drop for Shared {
    fn drop(&mut self) {
        remove_if_socket(&self.path);
    }
}

/// Shares `link` on the socket at `path`: returns the link the holder uses from now on (the
/// same handle; the events minus the clients' command outcomes) and the guard of the socket.
/// When the socket cannot be made, `Err` says why and gives the link back untouched.
pub fn share_link(
    link: RunningLink,
    path: &Path,
) -> Result<(RunningLink, Shared), (RunningLink, String)> {
    let listener = match bind(path) {
        Ok(l) => l,
        Err(e) => return Err((link, e)),
    };
    let RunningLink {
        handle,
        events: mut inner,
        task,
    } = link;
    let hub = Arc::new(Mutex::new(Hub::new()));
    let writers: Writers = Arc::default();
    let (tx, rx) = mpsc::unbounded_channel();
    {
        let (hub, writers, handle) = (hub.clone(), writers.clone(), handle.clone());
        tokio::spawn(async move {
            while let Some(ev) = inner.recv().await {
                let (owned, outs) = match hub.lock() {
                    Ok(mut h) => h.link_event(&ev),
                    Err(_) => (false, Vec::new()),
                };
                apply(outs, &writers, &handle);
                if !owned && tx.send(ev).is_err() {
                    break;
                }
            }
        });
    }
    {
        let (hub, writers, handle) = (hub.clone(), writers.clone(), handle.clone());
        tokio::spawn(async move {
            while let Ok((stream, _)) = listener.accept().await {
                let full = hub.lock().map_or(true, |h| h.clients() >= MAX_CLIENTS);
                if full {
                    continue;
                }
                tokio::spawn(serve_client(
                    stream,
                    hub.clone(),
                    writers.clone(),
                    handle.clone(),
                ));
            }
        });
    }
    Ok((
        RunningLink {
            handle,
            events: rx,
            task,
        },
        Shared {
            path: path.to_path_buf(),
            hub,
        },
    ))
}

/// Binds the socket: the directory made safe first; a socket left by a station that died is
/// replaced, anything else at the path (a live station's socket, a file) is refused.
fn bind(path: &Path) -> Result<UnixListener, String> {
    if let Some(dir) = path.parent() {
        super::path::prepare_dir(dir)?;
    }
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if !meta.file_type().is_socket() {
            return Err(format!(
                "{} exists and is not a socket; not replaced",
                path.display()
            ));
        }
        if std::os::unix::net::UnixStream::connect(path).is_ok() {
            return Err(format!(
                "{} is served by another station already",
                path.display()
            ));
        }
        std::fs::remove_file(path)
            .map_err(|e| format!("cannot remove the stale {}: {e}", path.display()))?;
    }
    let listener =
        UnixListener::bind(path).map_err(|e| format!("cannot serve {}: {e}", path.display()))?;
    // The directory is 0700 already; the socket itself is the user's alone too.
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o600))
        .map_err(|e| format!("cannot make {} private: {e}", path.display()))?;
    Ok(listener)
}

fn remove_if_socket(path: &Path) {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_socket()) {
        let _ = std::fs::remove_file(path);
    }
}

/// One client's connection, until it closes or the hub closes it.
async fn serve_client(
    stream: UnixStream,
    hub: Arc<Mutex<Hub>>,
    writers: Writers,
    handle: LinkHandle,
) {
    let Ok(id) = hub.lock().map(|mut h| h.add_client()) else {
        return;
    };
    let (mut reader, mut writer) = stream.into_split();
    let (out_tx, mut out_rx) = mpsc::channel::<Vec<u8>>(CLIENT_QUEUE);
    if let Ok(mut w) = writers.lock() {
        w.insert(id, out_tx);
    }
    let write = tokio::spawn(async move {
        while let Some(bytes) = out_rx.recv().await {
            if writer.write_all(&bytes).await.is_err() {
                break;
            }
        }
        let _ = writer.shutdown().await;
    });
    let mut decoder = FrameDecoder::new();
    let mut buf = vec![0u8; 4096];
    loop {
        // When the hub closes this client its writer ends and shuts the socket's write half;
        // the client then closes its end and this read ends. Frames a closed client still
        // sends are ignored by the hub.
        let n = match reader.read(&mut buf).await {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        let mut input = buf.get(..n).unwrap_or(&[]);
        loop {
            match decoder.feed(input) {
                Feed::NeedMore => break,
                Feed::Frame { frame, rest } => {
                    let outs = match hub.lock() {
                        Ok(mut h) => h.client_frame(id, &frame),
                        Err(_) => Vec::new(),
                    };
                    apply(outs, &writers, &handle);
                    input = rest;
                }
                Feed::Error { rest, .. } => input = rest,
            }
        }
    }
    let outs = hub.lock().map_or(Vec::new(), |mut h| h.client_gone(id));
    apply(outs, &writers, &handle);
    if let Ok(mut w) = writers.lock() {
        w.remove(&id);
    }
    let _ = write.await;
}

fn apply(outs: Vec<HubOut>, writers: &Writers, handle: &LinkHandle) {
    for out in outs {
        match out {
            HubOut::Send(c, bytes) => {
                if let Some(tx) = writers.lock().ok().and_then(|w| w.get(&c).cloned()) {
                    // A full queue: the client is not reading; it loses this frame.
                    let _ = tx.try_send(bytes);
                }
            }
            HubOut::Submit(id, command) => handle.submit_with_id(id, command),
            HubOut::Close(c) => {
                if let Ok(mut w) = writers.lock() {
                    w.remove(&c);
                }
            }
        }
    }
}

/// Opens a shared link's socket as the robot's port.
#[derive(Clone, Debug)]
pub struct ShareConnector {
    path: PathBuf,
}

impl ShareConnector {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        ShareConnector { path: path.into() }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Connector for ShareConnector {
    fn name(&self) -> String {
        self.path.display().to_string()
    }

    fn open(&mut self) -> Result<Box<dyn Transport>, OpenError> {
        let path = self.path.clone();
        let s =
            std::os::unix::net::UnixStream::connect(&self.path).map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => OpenError::NotFound { path: path.clone() },
                std::io::ErrorKind::PermissionDenied => OpenError::PermissionDenied {
                    path: path.clone(),
                    hint: String::new(),
                },
                _ => OpenError::Other {
                    path: path.clone(),
                    message: format!("no station serves this shared link ({e})"),
                },
            })?;
        s.set_nonblocking(true).map_err(|e| OpenError::Other {
            path: path.clone(),
            message: e.to_string(),
        })?;
        let s = UnixStream::from_std(s).map_err(|e| OpenError::Other {
            path,
            message: e.to_string(),
        })?;
        Ok(Box::new(s))
    }

    fn present(&self) -> bool {
        self.path.exists()
    }
}

/// The shared link of a station holding `port`, if one serves it now.
pub fn serving(port: &Path) -> Option<PathBuf> {
    let path = super::path::socket_path(port);
    let is_socket = std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_socket());
    (is_socket && std::os::unix::net::UnixStream::connect(&path).is_ok()).then_some(path)
}
