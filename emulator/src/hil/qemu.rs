//! Starting the board image on QEMU's mps2-an386 (Cortex-M4): UART0 on a pty for the station,
//! UART1 on a Unix socket for the world (`serve`), optionally with `-icount` so instruction
//! counts can be read off the board's timer.
//!
//! QEMU names the pty it made on its standard output ("char device redirected to /dev/pts/N
//! (label serial0)"); that line is read here and everything else QEMU says is passed on to
//! standard error.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How to start QEMU.
#[derive(Clone, Debug)]
pub struct QemuOptions {
    /// The `qemu-system-arm` binary.
    pub binary: PathBuf,
    /// The board image (ELF), `robot-firmware/board` built for thumbv7em-none-eabihf.
    pub image: PathBuf,
    /// `-icount shift=N`: every instruction 2^N ns of virtual time.
    pub icount_shift: Option<u8>,
}

/// A running QEMU and the pty its UART0 is on (`None` when UART0 is on a socket).
pub struct Qemu {
    pub child: Child,
    pub station_pty: Option<PathBuf>,
}

/// Starts QEMU with UART1 connected to the Unix socket `hil_socket` (which must be listening)
/// and UART0 to `station_socket` (then listening too) or, without one, to a pty, whose path it
/// waits for (at most 10 s).
pub fn start(
    opts: &QemuOptions,
    hil_socket: &Path,
    station_socket: Option<&Path>,
) -> Result<Qemu, String> {
    if !opts.image.is_file() {
        return Err(format!(
            "board image {} not found (build it: cargo build -p robot-board --release --target \
             thumbv7em-none-eabihf)",
            opts.image.display()
        ));
    }
    let mut cmd = Command::new(&opts.binary);
    cmd.args(["-M", "mps2-an386", "-nographic", "-monitor", "none"]);
    match station_socket {
        Some(s) => cmd
            .arg("-chardev")
            .arg(format!("socket,id=station,path={}", s.display()))
            .args(["-serial", "chardev:station"]),
        None => cmd.args(["-serial", "pty"]),
    };
    cmd.arg("-chardev")
        .arg(format!("socket,id=hil,path={}", hil_socket.display()))
        .args(["-serial", "chardev:hil"])
        .arg("-kernel")
        .arg(&opts.image);
    if let Some(shift) = opts.icount_shift {
        cmd.args(["-icount", &format!("shift={shift}")]);
    }
    // Its own process group: a Ctrl-C at the terminal reaches the world, which then stops
    // QEMU after printing its summary, rather than both at once.
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| {
            format!(
                "cannot start {}: {e} (Debian: apt-get install qemu-system-arm)",
                opts.binary.display()
            )
        })?;
    let Some(stdout) = child.stdout.take() else {
        let _ = child.kill();
        return Err("QEMU's standard output is not readable".to_string());
    };
    if station_socket.is_some() {
        // Nothing to wait for; pass QEMU's words on.
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                eprintln!("qemu: {line}");
            }
        });
        return Ok(Qemu {
            child,
            station_pty: None,
        });
    }
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut told = false;
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if !told {
                if let Some(path) = pty_of_serial0(&line) {
                    told = true;
                    let _ = tx.send(path);
                    continue;
                }
            }
            eprintln!("qemu: {line}");
        }
    });
    match rx.recv_timeout(Duration::from_secs(10)) {
        Ok(pty) => Ok(Qemu {
            child,
            station_pty: Some(pty),
        }),
        Err(_) => {
            let _ = child.kill();
            let _ = child.wait();
            Err("QEMU did not name the pty of its UART0 within 10 s".to_string())
        }
    }
}

/// The pty path in QEMU's "char device redirected to /dev/pts/N (label serial0)".
fn pty_of_serial0(line: &str) -> Option<PathBuf> {
    let rest = line.split("redirected to ").nth(1)?;
    let (path, label) = rest.split_once(' ')?;
    label.contains("serial0").then(|| PathBuf::from(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pty_of_uart0_is_read_from_qemus_line() {
        let line = "char device redirected to /dev/pts/7 (label serial0)";
        assert_eq!(pty_of_serial0(line), Some(PathBuf::from("/dev/pts/7")));
        let prefixed = "qemu-system-arm: -serial pty: char device redirected to /dev/pts/12 \
                        (label serial0)";
        assert_eq!(pty_of_serial0(prefixed), Some(PathBuf::from("/dev/pts/12")));
        assert_eq!(
            pty_of_serial0("char device redirected to /dev/pts/8 (label serial1)"),
            None
        );
        assert_eq!(pty_of_serial0("something else"), None);
    }
}
