//! Issue 15: the robot answers a command as soon as its frame is complete, as a real
//! microcontroller's receive path does (an RX interrupt, or a main loop polling the UART far
//! faster than the control cycle), not at the start of the next 1 ms simulation step.
//!
//! Served on a pseudo-terminal in real time, as `robot-emulator --link` serves it, a client
//! writes Stop frames at random moments (so their last bits land anywhere within a step). A
//! wrapper around the simulation notes, in SIMULATED time, when each command's last bit
//! reached the robot and when the first bit of its answer left. Judged in simulated time only:
//! the wall-clock round trip is the benchmark's (`tests/tools/min_client_rtt.py`,
//! docs/performance.md).
//!
//! No handshake: the robot is then quiet and answers every command (`Nack NoHandshake`)
//! through the same receive path as an Ack, so the line is idle whenever a command arrives
//! and the answer can start the moment the command is complete.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::io::{Read, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use emulator::link::{serve, Device, ServeOptions, Speed};
use emulator::sim::{Sim, SimConfig, STEP_US};
use protocol::{encode, Command, Message, MAX_FRAME};

/// What the wrapper saw, in simulated µs.
#[derive(Clone, Copy, Debug)]
enum Seen {
    /// Bytes ending a frame reached the line: when that frame's last bit reaches the robot,
    /// and how far the serving loop had already run the simulation (it runs a step as soon as
    /// the clock reaches its start, so the step under way is already done). `read` is when
    /// the serving loop had the bytes from the pty (wall clock, for the printed breakdown).
    Command {
        end_us: u64,
        stepped_to_us: u64,
        read: Instant,
    },
    /// A whole frame from the robot: when its last bit left, its length in bytes, and when
    /// the serving loop handed it to the pty (simulated `handed_us`; wall `handed`).
    Answer {
        end_us: u64,
        bytes: usize,
        handed_us: u64,
        handed: Instant,
    },
}

/// The simulation as `serve` drives it, with every command's and answer's timing noted.
struct Watched {
    sim: Sim,
    log: Arc<Mutex<Vec<Seen>>>,
    /// Bytes of the robot's frame being taken.
    answer_bytes: usize,
}

impl Device for Watched {
    fn now_us(&self) -> u64 {
        Device::now_us(&self.sim)
    }
    fn step_ms(&mut self) {
        self.sim.step_ms();
    }
    fn push_inbound(&mut self, bytes: &[u8]) {
        Device::push_inbound(&mut self.sim, bytes);
    }
    fn take_outbound(&mut self, out: &mut Vec<u8>) {
        self.take_outbound_until(u64::MAX, out);
    }
    fn cycles(&self) -> u32 {
        self.sim.cycles()
    }
    fn cycle_us(&self) -> u32 {
        self.sim.cycle_us()
    }
    fn to_robot_dropped(&self) -> u64 {
        self.sim.to_robot_dropped()
    }
    fn next_due_us(&self) -> u64 {
        self.sim.next_due_us()
    }
    fn sync_line(&mut self, now_us: u64) {
        Device::sync_line(&mut self.sim, now_us);
    }
    fn push_inbound_at(&mut self, bytes: &[u8], at_us: u64) {
        self.sim.push_inbound_at(bytes, at_us);
        if bytes.contains(&0) {
            let end_us = self.sim.uart().next_inbound_frame_end_us().unwrap();
            self.log.lock().unwrap().push(Seen::Command {
                end_us,
                stepped_to_us: Device::now_us(&self.sim),
                read: Instant::now(),
            });
        }
    }
    fn take_outbound_until(&mut self, until_us: u64, out: &mut Vec<u8>) {
        let frame_end = self.sim.next_frame_end_us();
        let before = out.len();
        self.sim.take_outbound_until(until_us, out);
        for &b in &out[before..] {
            self.answer_bytes += 1;
            if b == 0 {
                // One frame at a time: the robot sends nothing but answers.
                self.log.lock().unwrap().push(Seen::Answer {
                    end_us: frame_end.unwrap(),
                    bytes: self.answer_bytes,
                    handed_us: until_us,
                    handed: Instant::now(),
                });
                self.answer_bytes = 0;
            }
        }
    }
    fn next_frame_end_us(&self) -> Option<u64> {
        self.sim.next_frame_end_us()
    }
}

#[test]
fn a_command_completed_mid_step_is_answered_at_once_not_at_the_next_step() {
    let arena = emulator::builtin::micro_rato_99(&emulator::arena::LoadOptions::default()).unwrap();
    let cfg = SimConfig::new(&robot_firmware::MICRO_RATO);
    let baud = f64::from(cfg.baud);
    let log = Arc::new(Mutex::new(Vec::new()));
    let mut dev = Watched {
        sim: Sim::new(arena, cfg).unwrap(),
        log: Arc::clone(&log),
        answer_bytes: 0,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let (path_tx, path_rx) = mpsc::channel::<PathBuf>();
    let serving = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            let opts = ServeOptions {
                speed: Speed::Factor(1.0),
                ..ServeOptions::default()
            };
            serve(&mut dev, &opts, &stop, &mut |p| {
                let _ = path_tx.send(p.to_path_buf());
            })
            .unwrap()
        })
    };
    let path = path_rx.recv_timeout(Duration::from_secs(10)).unwrap();
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .custom_flags(nix::libc::O_NONBLOCK)
        .open(&path)
        .unwrap();

    // Stop commands at pseudo-random moments (a fixed LCG: the gaps only spread the commands'
    // phase within a step; nothing asserted below depends on wall time).
    const COMMANDS: u16 = 40;
    let mut lcg: u32 = 0x1234_5678;
    let mut frame = [0u8; MAX_FRAME];
    let mut client = Vec::new();
    let stop_len = encode(0, &Message::Command(Command::Stop), &mut frame).unwrap();
    for seq in 0..COMMANDS {
        lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        std::thread::sleep(Duration::from_micros(2_000 + u64::from(lcg >> 20)));
        let n = encode(seq, &Message::Command(Command::Stop), &mut frame).unwrap();
        let written = Instant::now();
        port.write_all(&frame[..n]).unwrap();
        let deadline = written + Duration::from_secs(5);
        let mut buf = [0u8; 64];
        let answered = loop {
            assert!(Instant::now() < deadline, "no answer to command {seq}");
            match port.read(&mut buf) {
                Ok(n) if buf[..n].contains(&0) => break Instant::now(),
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_micros(50));
                }
                Err(e) => panic!("{e}"),
            }
        };
        client.push((written, answered));
    }
    stop.store(true, Ordering::Relaxed);
    serving.join().unwrap();

    let log = log.lock().unwrap().clone();
    let commands: Vec<_> = log
        .iter()
        .filter(|s| matches!(s, Seen::Command { .. }))
        .collect();
    let answers: Vec<_> = log
        .iter()
        .filter(|s| matches!(s, Seen::Answer { .. }))
        .collect();
    assert_eq!(commands.len(), usize::from(COMMANDS), "{log:?}");
    assert_eq!(answers.len(), usize::from(COMMANDS), "{log:?}");

    // (command end, loop's step, answer start, answer end) in simulated µs.
    let mut judged = Vec::new();
    // Where a round trip goes, µs: pty in, the command's bytes, the robot's wait, the
    // answer's bytes, the loop's hand-over after its last bit, pty out (printed, not judged).
    let mut parts = [const { Vec::new() }; 6];
    for ((c, a), (written, answered)) in commands.iter().zip(&answers).zip(&client) {
        let (
            &&Seen::Command {
                end_us: command_end,
                stepped_to_us,
                read,
            },
            &&Seen::Answer {
                end_us: answer_end,
                bytes,
                handed_us,
                handed,
            },
        ) = (c, a)
        else {
            unreachable!()
        };
        // When the answer's first bit left: its last bit's time less its bytes' time.
        let answer_start = answer_end as f64 - bytes as f64 * 10.0 * 1e6 / baud;
        judged.push((command_end, stepped_to_us, answer_start));
        let us = |d: Duration| d.as_secs_f64() * 1e6;
        let command_bytes = stop_len as f64 * 10.0 * 1e6 / baud;
        parts[0].push(us(read.saturating_duration_since(*written)));
        parts[1].push(command_bytes);
        parts[2].push(answer_start - command_end as f64);
        parts[3].push(answer_end as f64 - answer_start);
        parts[4].push(handed_us.saturating_sub(answer_end) as f64);
        parts[5].push(us(answered.saturating_duration_since(handed)));
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let names = [
        "pty in (wall)",
        "command bytes",
        "robot's wait (sim)",
        "answer bytes",
        "loop hand-over (sim)",
        "pty out (wall)",
    ];
    for (name, v) in names.iter().zip(parts.iter_mut()) {
        println!("median {name}: {:.0} us", median(v));
    }

    // The line's bit clock counts whole bits: a byte written between two starts at the next,
    // and times are rounded up to the µs.
    let slack = 1e6 / baud + 2.0;
    let mut mid_step = 0;
    for &(command_end, stepped_to, answer_start) in &judged {
        let next_step = command_end.next_multiple_of(STEP_US);
        assert!(
            answer_start >= command_end as f64 - 1.0,
            "answered at {answer_start:.1} us, before the command was complete ({command_end} us): {log:?}"
        );
        if command_end > stepped_to {
            // Completes in a step not yet run: answered the moment its last bit arrived
            // (within a bit of the line's clock), where the robot used to read it at the next
            // step's start, 0.5 ms later on average.
            assert!(
                answer_start - command_end as f64 <= slack,
                "command complete at {command_end} us, answer started at {answer_start:.1} us \
                 (next step at {next_step} us)"
            );
            if command_end % STEP_US != 0 {
                mid_step += 1;
            }
        } else {
            // A frame shorter than a step can complete inside the step the loop had already
            // run when its bytes came (its last 45 us for a Stop): the robot reads it at the
            // next step's start.
            assert!(
                answer_start <= stepped_to as f64 + slack,
                "command complete at {command_end} us, the loop at {stepped_to} us, answer \
                 started at {answer_start:.1} us"
            );
        }
    }
    // The commands' phase is spread over the step, so most complete mid-step and are answered
    // before the next step boundary would have allowed.
    assert!(
        mid_step >= usize::from(COMMANDS) / 2,
        "only {mid_step} of {COMMANDS} commands were answered mid-step: {log:?}"
    );
}
