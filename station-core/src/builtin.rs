//! The built-in default: `station` with no arguments starts the emulator (the real firmware in
//! a simulated Micro-Rato'99 world) on a pty and connects to it through the real serial path,
//! exactly as it would to /dev/ttyUSB0.
//!
//! Layer: the one place that knows how the built-in emulator is started
//! (`emulator::link::spawn(EmulatorOptions::builtin_default())`). The pty's slave is reached
//! through a symlink in a private directory, so a replugged pty keeps its name; the same arena
//! the emulator simulates is loaded for the map. What can fail: creating the directory,
//! loading the arena or the simulation, creating the pty (`BuiltinError`).

use std::path::{Path, PathBuf};

use emulator::link::{spawn, EmulatorOptions, RunningEmulator};

use crate::arena::ArenaOverlay;

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
    running: Option<RunningEmulator>,
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
        self.running
            .as_mut()
            .map(|r| r.path().to_path_buf())
            .unwrap_or_default()
    }
}

impl Drop for BuiltinEmulator {
    fn drop(&mut self) {
        // Stopping the serving loop removes its symlink; then the directory is empty.
        drop(self.running.take());
        let _ = std::fs::remove_dir(&self.dir);
    }
}

/// Starts the built-in emulator. See the module documentation.
pub fn start_builtin_emulator(
    key: Option<&[u8; protocol::sign::KEY_LEN]>,
) -> Result<BuiltinEmulator, BuiltinError> {
    start_builtin_emulator_with(None, None, key, None)
}

/// Starts the built-in emulator (the default world and robot) streaming its hardware trace
/// from power-up, as `robot-emulator --hal-trace` does: the robot is held at power-up until
/// the station's first byte, so the whole trace reaches the station and a recording of it
/// retraces exactly (`station record --hal-trace`).
pub fn start_builtin_emulator_traced(
    key: Option<&[u8; protocol::sign::KEY_LEN]>,
) -> Result<BuiltinEmulator, BuiltinError> {
    let (dir, link, mut opts) = served_options(key)?;
    choose_world(&mut opts, None, None);
    let a = emulator::builtin::load(&opts.arena, &opts.load)
        .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    let arena = Some(ArenaOverlay::from_arena(&a));
    let mut sim =
        emulator::sim::Sim::new(a, opts.sim).map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    // As the station would set it, before the first pass of the main loop.
    sim.robot_mut().apply(
        protocol::Command::SetParam {
            id: protocol::ParamId(robot_firmware::params::id::HAL_TRACE),
            value: 1.0,
        },
        0,
    );
    let running = emulator::link::spawn_device(
        move || Ok(emulator::power_on::PoweredByStation::new(sim)),
        opts.serve,
    )
    .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    Ok(BuiltinEmulator {
        running: Some(running),
        link,
        dir,
        arena,
    })
}

/// Starts the built-in emulator in `arena` (a built-in name or a file; default Micro-Rato'99)
/// with `profile` (default micro-rato, or khepera in `builtin:forage`, the robot with a
/// gripper). With `key` the robot signs its frames and accepts only frames signed with it
/// (PROTOCOL.md §13), as a robot given `--key-file` does. `start` (`X,Y,HEADING_DEG`) replaces
/// the arena's start pose.
pub fn start_builtin_emulator_with(
    arena: Option<&str>,
    profile: Option<&'static robot_firmware::Profile>,
    key: Option<&[u8; protocol::sign::KEY_LEN]>,
    start: Option<[f64; 3]>,
) -> Result<BuiltinEmulator, BuiltinError> {
    let (dir, link, mut opts) = served_options(key)?;
    if let Some([x, y, deg]) = start {
        opts.sim.start = Some(emulator::arena::Pose {
            x,
            y,
            heading: deg.to_radians(),
        });
    }
    choose_world(&mut opts, arena, profile);
    let arena = emulator::builtin::load(&opts.arena, &opts.load)
        .ok()
        .map(|a| ArenaOverlay::from_arena(&a));
    let running = spawn(opts).map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    Ok(BuiltinEmulator {
        running: Some(running),
        link,
        dir,
        arena,
    })
}

/// The built-in default's options, served through a symlink `robot` in a fresh runtime
/// directory (returned with the link), with `key` if any.
fn served_options(
    key: Option<&[u8; protocol::sign::KEY_LEN]>,
) -> Result<(PathBuf, PathBuf, EmulatorOptions), BuiltinError> {
    let dir = runtime_dir()?;
    let link = dir.join("robot");
    let mut opts = EmulatorOptions::builtin_default();
    opts.serve.link = Some(link.clone());
    opts.serve.key = key.copied();
    Ok((dir, link, opts))
}

/// The per-process directory the built-in emulator's ptys live in: `$XDG_RUNTIME_DIR` when it
/// is a directory, else the temporary directory.
fn runtime_dir() -> Result<PathBuf, BuiltinError> {
    let base = std::env::var_os("XDG_RUNTIME_DIR")
        .map(PathBuf::from)
        .filter(|p| p.is_dir())
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("station-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(BuiltinError::Dir)?;
    Ok(dir)
}

/// The arena and robot of a built-in run, one rule for one robot and a fleet: `arena`, else
/// ALICE's arena for ALICE, else the default; `profile`, else the Khepera where the arena
/// needs its gripper (`builtin:forage`) or line sensor (`builtin:floor-grid`, seed 003, whose
/// floor lines are set here too), else the default robot.
fn choose_world(
    opts: &mut EmulatorOptions,
    arena: Option<&str>,
    profile: Option<&'static robot_firmware::Profile>,
) {
    if let Some(a) = arena.or_else(|| alice_arena(profile)) {
        opts.arena = a.to_string();
    }
    let forage = opts.arena == emulator::forage::BUILTIN_FORAGE;
    opts.sim.floor_grid_m = emulator::builtin::floor_grid_pitch(&opts.arena);
    let grid = opts.sim.floor_grid_m.is_some();
    if let Some(p) = profile.or_else(|| (forage || grid).then_some(&robot_firmware::KHEPERA)) {
        opts.sim.profile = p;
    }
}

/// ALICE's own scene (`builtin:alice`, seed 001 §4.5) when no arena is named for it.
fn alice_arena(profile: Option<&'static robot_firmware::Profile>) -> Option<&'static str> {
    profile
        .filter(|p| p.id == protocol::ProfileId::Alice)
        .map(|_| emulator::builtin::alice::BUILTIN_ALICE)
}

/// The built-in emulator with several robots in one world (`station --robots N`): one pty
/// each, reached through `robot1`, `robot2`, ... symlinks in a private directory. Stops (and
/// removes the ptys) when dropped.
pub struct BuiltinFleet {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
    links: Vec<PathBuf>,
    ptys: Vec<PathBuf>,
    dir: PathBuf,
    /// The arena the emulator simulates, for the map.
    pub arena: Option<ArenaOverlay>,
}

impl BuiltinFleet {
    /// The paths to open, robot by robot: symlinks that follow each robot's current pty.
    pub fn paths(&self) -> &[PathBuf] {
        &self.links
    }

    /// Each robot's pty when it started.
    pub fn pty_paths(&self) -> &[PathBuf] {
        &self.ptys
    }
}

impl Drop for BuiltinFleet {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        let _ = std::fs::remove_dir(&self.dir);
    }
}

/// Starts `robots` robots of `profile` (default micro-rato; khepera in `builtin:forage` and
/// `builtin:floor-grid`, as `start_builtin_emulator_with`) in `arena`, each on its own pty,
/// from the arena's start areas (`emulator::fleet::starts`). With `key` every robot signs
/// its frames. Returns once every robot's pty exists.
pub fn start_builtin_fleet(
    robots: usize,
    arena: Option<&str>,
    profile: Option<&'static robot_firmware::Profile>,
    key: Option<&[u8; protocol::sign::KEY_LEN]>,
) -> Result<BuiltinFleet, BuiltinError> {
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    let dir = runtime_dir()?;
    let mut opts = EmulatorOptions::builtin_default();
    choose_world(&mut opts, arena, profile);
    let loaded = emulator::builtin::load(&opts.arena, &opts.load)
        .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    let overlay = Some(ArenaOverlay::from_arena(&loaded));
    let specs = vec![
        emulator::fleet::RobotSpec {
            profile: opts.sim.profile,
            start: None,
        };
        robots
    ];
    let mut fleet = emulator::fleet::Fleet::new(loaded, &opts.sim, &specs)
        .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    let links: Vec<PathBuf> = (1..=robots)
        .map(|k| emulator::fleet::serve::link_for(&dir.join("robot"), k, robots))
        .collect();
    let serve: Vec<emulator::link::ServeOptions> = links
        .iter()
        .enumerate()
        .map(|(i, l)| emulator::link::ServeOptions {
            link: Some(l.clone()),
            key: key.copied(),
            seed: emulator::fleet::robot_seed(opts.sim.seed, i),
            ..opts.serve.clone()
        })
        .collect();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = Arc::clone(&stop);
    let (tx, rx) = std::sync::mpsc::channel::<Result<(usize, PathBuf), String>>();
    let thread = std::thread::Builder::new()
        .name("robot-emulator-fleet".into())
        .spawn(move || {
            let ready = tx.clone();
            let result = emulator::fleet::serve::serve(&mut fleet, &serve, &stop2, &mut |i, p| {
                let _ = ready.send(Ok((i, p.to_path_buf())));
            });
            if let Err(e) = result {
                let _ = tx.send(Err(e.to_string()));
            }
        })
        .map_err(|e| BuiltinError::Spawn(e.to_string()))?;
    let mut started = BuiltinFleet {
        stop,
        thread: Some(thread),
        ptys: vec![PathBuf::new(); robots],
        links,
        dir,
        arena: overlay,
    };
    let mut ready = 0;
    while ready < robots {
        match rx.recv_timeout(std::time::Duration::from_secs(10)) {
            Ok(Ok((i, p))) => {
                if let Some(slot) = started.ptys.get_mut(i) {
                    if slot.as_os_str().is_empty() {
                        ready += 1;
                    }
                    *slot = p;
                }
            }
            Ok(Err(e)) => return Err(BuiltinError::Spawn(e)),
            Err(_) => {
                return Err(BuiltinError::Spawn(
                    "the emulator's ptys did not appear within 10 s".into(),
                ))
            }
        }
    }
    Ok(started)
}
