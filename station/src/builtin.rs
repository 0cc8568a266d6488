//! The built-in default: `station` with no arguments starts an emulator on a pty and connects
//! to it through the real serial path, exactly as it would to /dev/ttyUSB0.
//!
//! Layer: the one place that knows how the built-in emulator is started, so switching to the
//! emulator's own `emulator::link::spawn(EmulatorOptions)` (being written) touches only
//! `start_builtin_emulator`. Until that exists, this serves the real firmware (`SimCore`: the
//! robot code with ideal wheel motion, no walls or sensors of a world) on the emulator's pty
//! serving loop, and draws the Micro-Rato'99 arena it will run in. The pty's slave is reached
//! through a symlink in a private directory, so a replugged pty keeps its name.
//! What can fail: creating the pty or its directory (`BuiltinError`).

use std::path::{Path, PathBuf};

use crate::app::arena::ArenaOverlay;
use crate::link::sim::{SimCore, SimOptions};

/// The Micro-Rato'99 lab (seed 004), as the emulator ships it.
const MICRO_RATO_99: &str = include_str!("../../emulator/arenas/wallsMicRato99.xml");

/// Why the built-in emulator did not start.
#[derive(Debug, thiserror::Error)]
pub enum BuiltinError {
    #[error("cannot create a directory for the emulator's port: {0}")]
    Dir(std::io::Error),
    #[error("cannot start the built-in emulator: {0}")]
    Spawn(String),
}

/// A running built-in emulator; stops (and removes its pty) when dropped.
pub struct BuiltinEmulator {
    running: emulator::link::Running,
    link: PathBuf,
    dir: PathBuf,
    /// The arena the emulator simulates, for the map.
    pub arena: Option<ArenaOverlay>,
}

impl BuiltinEmulator {
    /// The path to open: a symlink that follows the emulator's current pty.
    pub fn path(&self) -> &Path {
        &self.link
    }

    /// The pty behind the symlink right now.
    pub fn pty_path(&mut self) -> PathBuf {
        self.running.path().to_path_buf()
    }
}

impl Drop for BuiltinEmulator {
    fn drop(&mut self) {
        // `running` stops on its own drop and removes the symlink; the directory is ours.
        let _ = std::fs::remove_dir(&self.dir);
    }
}

/// Starts the built-in emulator. See the module documentation.
pub fn start_builtin_emulator() -> Result<BuiltinEmulator, BuiltinError> {
    let base = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_dir())
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("station-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(BuiltinError::Dir)?;
    let link = dir.join("robot");
    let opts = emulator::link::ServeOptions {
        link: Some(link.clone()),
        ..emulator::link::ServeOptions::default()
    };
    let running = emulator::link::spawn_device(
        || {
            Ok(SimCore::new(SimOptions {
                start: (1.0, 1.0, 0.0),
                ..SimOptions::default()
            }))
        },
        opts,
    )
    .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    let arena = emulator::arena::ciberrato::parse_lab(
        Path::new("wallsMicRato99.xml"),
        MICRO_RATO_99,
        emulator::arena::CIBERRATO_UNIT_M,
    )
    .ok()
    .map(|a| ArenaOverlay::from_arena(&a));
    Ok(BuiltinEmulator {
        running,
        link,
        dir,
        arena,
    })
}
