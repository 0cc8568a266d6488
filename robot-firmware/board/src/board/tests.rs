//! The board's loop on the host: the same `Board` the image runs, its ports a fake whose HIL
//! UART is the emulator's `HilWorld` and whose timer moves only when the loop sleeps (and a
//! little per read, as instructions take time).

// Test helpers fail the test that called them.
#![allow(clippy::panic)]

use std::collections::VecDeque;

use emulator::hil::HilWorld;
use emulator::sim::{Sim, SimConfig};
use protocol::{Command, Mode};
use robot_firmware::robot::DomDinis;
use robot_firmware::MICRO_RATO;

use super::*;

struct FakePorts {
    world: HilWorld,
    now: u64,
    to_board: VecDeque<u8>,
    station_in: VecDeque<u8>,
    station_out: Vec<u8>,
    sleeps: u32,
    /// Times `idle` was asked to wait for a byte with none coming: the loop would hang.
    stuck: u32,
}

impl Ports for FakePorts {
    fn ticks(&mut self) -> u64 {
        self.now += 3;
        self.now
    }
    fn station_read(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.station_in.len());
        for (slot, b) in buf.iter_mut().zip(self.station_in.drain(..n)) {
            *slot = b;
        }
        n
    }
    fn station_write(&mut self, bytes: &[u8]) -> usize {
        self.station_out.extend_from_slice(bytes);
        bytes.len()
    }
    fn hil_read(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.to_board.len());
        for (slot, b) in buf.iter_mut().zip(self.to_board.drain(..n)) {
            *slot = b;
        }
        n
    }
    fn hil_write(&mut self, bytes: &[u8]) {
        let mut out = Vec::new();
        self.world
            .feed(bytes, &mut out)
            .expect("the world accepts the board");
        self.to_board.extend(out);
    }
    fn idle(&mut self, until: Option<u64>) {
        if !self.to_board.is_empty() || !self.station_in.is_empty() {
            return;
        }
        match until {
            Some(t) => self.now = self.now.max(t),
            None => self.stuck += 1,
        }
        self.sleeps += 1;
    }
    fn station_fifo(&self) -> (u32, u32, u32) {
        (0, 0, 0)
    }
    fn memory(&self) -> (u32, u32, u32) {
        (0, 0, 0)
    }
    fn sleeps(&self) -> u32 {
        self.sleeps
    }
}

fn sim(seed: u64) -> Sim {
    let arena = emulator::builtin::load(emulator::builtin::MICRO_RATO_99, &Default::default())
        .expect("built-in arena");
    let mut cfg = SimConfig::new(&MICRO_RATO);
    cfg.seed = seed;
    Sim::new(arena, cfg).expect("sim")
}

fn boot(
    seed: u64,
    mode: Mode,
) -> (
    Box<MaybeUninit<Robot<DomDinis>>>,
    FakePorts,
    Setup,
    hil::Sensors,
    HilDecoder,
) {
    let mut ports = FakePorts {
        world: HilWorld::new(sim(seed), None, mode).expect("world"),
        now: 0,
        to_board: VecDeque::new(),
        station_in: VecDeque::new(),
        station_out: Vec::new(),
        sleeps: 0,
        stuck: 0,
    };
    let (setup, first, dec) = power_on(&mut ports, &MICRO_RATO).expect("powers on");
    (Box::new(MaybeUninit::uninit()), ports, setup, first, dec)
}

/// The image's loop, its clock the timer's and the world's, reproduces the emulator's own
/// run of the seed bit for bit (the robot exploring from power-on): lockstep.
#[test]
fn the_boards_loop_drives_the_world_exactly_as_the_emulator_does() {
    let seed = 6;
    let (mut slot, ports, setup, first, dec) = boot(seed, Mode::Explore);
    let robot = build_robot(&mut slot, &MICRO_RATO, &setup);
    let mut board = Board::new(robot, ports, &setup, first, dec);
    let mut reference = sim(seed);
    reference
        .robot_mut()
        .apply(Command::SetMode(Mode::Explore), 0);
    let period_ms = u64::from(MICRO_RATO.cycle_us) / 1000;
    let mut periods = 0;
    for _ in 0..20_000 {
        board.pass_and_sleep();
        let w = board.hal.ports.world.summary();
        while periods < w.exchanges {
            reference.run_for(period_ms);
            periods += 1;
        }
        assert_eq!(
            board.hal.ports.world.sim().truth(),
            reference.truth(),
            "after {periods} periods"
        );
        if periods >= 400 {
            break;
        }
    }
    assert!(periods >= 400, "the loop ran {periods} periods");
    assert!(reference.distance_m() > 1.0, "the robot explored");
    assert_eq!(board.hal.ports.stuck, 0);
}

/// With no station the loop has nothing to do between cycles: it sleeps until the next
/// frame is due, once or twice a cycle (the frame arrives, then its time comes).
#[test]
fn without_a_station_the_loop_sleeps_from_cycle_to_cycle() {
    let (mut slot, ports, setup, first, dec) = boot(2, Mode::Idle);
    let robot = build_robot(&mut slot, &MICRO_RATO, &setup);
    let mut board = Board::new(robot, ports, &setup, first, dec);
    let mut passes = 0u32;
    while board.hal.ports.world.summary().exchanges < 100 {
        board.pass_and_sleep();
        passes += 1;
        assert!(passes < 10_000, "the loop does not advance the world");
    }
    assert!(passes <= 2 * 100 + 2, "{passes} passes for 100 cycles");
    assert_eq!(board.hal.ports.stuck, 0);
}
