//! `robot-emulator hil`: the command line of hardware in the loop (docs/hil.md §1).

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::parse::parse_stall;
use super::world::WorldArgs;
use crate::hil::serve::{Port, StopWhen};

/// Serve the world to a board running the firmware itself (hardware in the loop): its
/// sensors in and its motors out over a serial port, one control period per exchange
///
/// With --image the board is QEMU's mps2-an386 running that image: QEMU is started with the
/// board's UART1 on this world and its UART0 on a pty, whose path is printed (the line a
/// script waits for; give it to `station --port`). With --port the board is already running
/// (QEMU started with `-serial pty -serial pty`, or a real board's adapter), its HIL UART at
/// that path.
///
/// Examples:
///   robot-emulator hil --image target/thumbv7em-none-eabihf/release/robot-board --seed 3
///   robot-emulator hil --port /dev/pts/7 --arena builtin:micro-rato-99 --key-file link.key
#[derive(Debug, Clone, Args)]
#[command(verbatim_doc_comment)]
pub struct HilArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// The board image (ELF) to start on qemu-system-arm -M mps2-an386.
    #[arg(
        long,
        value_name = "ELF",
        conflicts_with = "port",
        required_unless_present = "port"
    )]
    pub image: Option<PathBuf>,
    /// The board's HIL serial port (a tty), when it is already running.
    #[arg(long, value_name = "TTY")]
    pub port: Option<PathBuf>,
    /// The QEMU binary.
    #[arg(long, default_value = "qemu-system-arm", value_name = "BIN")]
    pub qemu: PathBuf,
    /// Run QEMU with `-icount shift=N` (every instruction 2^N ns of virtual time; 0 makes the
    /// board's timer count instructions, as the measures do).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=10))]
    pub icount: Option<u8>,
    /// Link key file (PROTOCOL.md §13) handed to the image at power-on: it signs its link with
    /// it, as the emulator does with --key-file. A real board keeps its key in its own flash.
    #[arg(long, value_name = "FILE")]
    pub key_file: Option<PathBuf>,
    /// A mode the robot enters at power-on, without a station (lockstep runs and benches).
    #[arg(long, value_enum, default_value_t = PowerOnMode::None)]
    pub power_on_mode: PowerOnMode,
    /// Also create this symlink to the station's pty (like `serve --link`).
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Stop after this much world time, seconds.
    #[arg(long, value_name = "S")]
    pub seconds: Option<f64>,
    /// Stop once the robot's true position is in the target area (and 3 s more, for it to stop).
    #[arg(long)]
    pub until_target: bool,
    /// Print the run's summary as JSON on exit (the board's own measures included).
    #[arg(long)]
    pub json: bool,
    /// Probability of losing a byte of the station link, both directions (with --image: the
    /// link then runs through the world, `hil::relay`).
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    pub drop_rate: f64,
    /// Probability of flipping a bit of the station link, both directions.
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    pub flip_rate: f64,
    /// Stall the station link every PERIOD seconds for DURATION seconds.
    #[arg(long, value_name = "PERIOD,DURATION", value_parser = parse_stall)]
    pub stall: Option<crate::fault::Stall>,
    /// The station link's line rate, baud (QEMU's UART is not paced: bytes go as fast as
    /// written); the link then runs through the world.
    #[arg(long, value_name = "BAUD")]
    pub line_baud: Option<u32>,
}

/// `--power-on-mode`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PowerOnMode {
    None,
    Wander,
    Explore,
}

impl PowerOnMode {
    pub fn mode(self) -> protocol::Mode {
        match self {
            PowerOnMode::None => protocol::Mode::Idle,
            PowerOnMode::Wander => protocol::Mode::Wander,
            PowerOnMode::Explore => protocol::Mode::Explore,
        }
    }
}

impl HilArgs {
    /// Where the board is.
    pub fn port(&self) -> Result<Port, String> {
        let fault = crate::fault::FaultConfig {
            drop_rate: self.drop_rate,
            flip_rate: self.flip_rate,
            stall: self.stall,
        };
        fault.validate("--drop-rate/--flip-rate/--stall")?;
        if self.line_baud.is_some_and(|b| b == 0 || b > 4_000_000) {
            return Err("--line-baud must be 1..=4000000".into());
        }
        let relay = crate::hil::relay::RelayOptions {
            to_robot: fault,
            from_robot: fault,
            baud: self.line_baud,
            seed: self.world.seed,
        };
        match (&self.image, &self.port) {
            (Some(image), None) => Ok(Port::Qemu(
                crate::hil::qemu::QemuOptions {
                    binary: self.qemu.clone(),
                    image: image.clone(),
                    icount_shift: self.icount,
                },
                relay.wanted().then_some(relay),
            )),
            (None, Some(_)) if relay.wanted() => Err(
                "link faults and --line-baud need the station link through the world: start \
                 the board with --image"
                    .into(),
            ),
            (None, Some(tty)) => Ok(Port::Tty(tty.clone())),
            _ => Err("give the board's image (--image ELF) or its HIL port (--port TTY)".into()),
        }
    }

    /// When to stop.
    pub fn stop_when(&self) -> Result<StopWhen, String> {
        if let Some(s) = self.seconds {
            if !(s.is_finite() && s > 0.0) {
                return Err(format!("--seconds {s}: must be a positive number"));
            }
        }
        Ok(StopWhen {
            world_seconds: self.seconds,
            target: self.until_target,
            grace_s: 3.0,
            silent_s: None,
        })
    }
}
