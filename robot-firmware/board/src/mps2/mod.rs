//! The mps2-an386's peripherals as the board's `Ports` (ARM AN386, "Cortex-M4 SMM on V2M-MPS2";
//! the CMSDK APB UART and timer are in ARM's Cortex-M System Design Kit TRM, DDI 0479):
//!
//! | what | where | IRQ | used for |
//! | --- | --- | --- | --- |
//! | UART0 | 0x4000_4000 | RX 0, TX 1 | the station link, 256-byte receive FIFO |
//! | UART1 | 0x4000_5000 | RX 2 | the HIL link to the world (sensors in, motors out) |
//! | TIMER0 | 0x4000_0000 | 8 | the clock: free-running at 25 MHz, wraps counted |
//! | TIMER1 | 0x4000_1000 | 9 | the wake-up alarm while the loop sleeps |
//!
//! QEMU (`-M mps2-an386`) maps `-serial` options to UART0, UART1, ... in order; its UARTs do
//! not model the baud rate (a byte is sent when written) and hold one received byte until it
//! is read, so nothing is lost in the UART itself: the FIFO's counters are what a flood
//! measures. The interrupt handlers and the loop share the FIFOs under critical sections
//! (single core: interrupts masked).
//!
//! The loop is woken for a frame, not a byte: each received byte interrupts the core, but
//! `idle` goes back to sleep until a frame's 0x00 delimiter has arrived (both links are
//! COBS-framed), the station FIFO is half full, or the deadline passes. The firmware acts on
//! whole frames, so waking for each byte only cost passes (issue 35: 57 wake-ups a cycle).

mod irq;
mod regs;
mod stack;
pub mod timer;
mod uart;

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use critical_section::Mutex;

use robot_board::board::Ports;
use robot_board::fifo::Fifo;

pub use irq::dispatch;

/// The station link's receive FIFO (issue 35: 256 bytes).
pub const STATION_RX_FIFO: usize = 256;
/// The station link's transmit FIFO: the link hands over whole frames (at most 256 bytes).
const STATION_TX_FIFO: usize = 512;
/// The world's frames are at most `protocol::hil::MAX_FRAME` (130) bytes, one at a time.
const HIL_RX_FIFO: usize = 256;

static STATION_RX: Mutex<RefCell<Fifo<STATION_RX_FIFO>>> = Mutex::new(RefCell::new(Fifo::new()));
static STATION_TX: Mutex<RefCell<Fifo<STATION_TX_FIFO>>> = Mutex::new(RefCell::new(Fifo::new()));
static HIL_RX: Mutex<RefCell<Fifo<HIL_RX_FIFO>>> = Mutex::new(RefCell::new(Fifo::new()));
static SLEEPS: AtomicU32 = AtomicU32::new(0);
/// A frame's delimiter (or half a FIFO) has arrived and the loop has not read it all yet.
static STATION_WAKE: AtomicBool = AtomicBool::new(false);
static HIL_WAKE: AtomicBool = AtomicBool::new(false);

/// Sets up the UARTs, the timers and their interrupts, then unmasks interrupts.
pub fn init() {
    timer::start_clock();
    uart::STATION.init(true);
    uart::HIL.init(false);
    irq::enable();
}

/// Every byte `uart` holds into `fifo` (a receive interrupt); `wake` is raised at a frame's
/// delimiter, and at half a FIFO when `at_half` (so a flood of bytes without delimiters is
/// drained before it overflows).
fn drain_rx<const N: usize>(
    uart: &uart::Uart,
    fifo: &Mutex<RefCell<Fifo<N>>>,
    wake: &AtomicBool,
    at_half: bool,
) {
    uart.clear_rx_irq();
    critical_section::with(|cs| {
        let mut f = fifo.borrow_ref_mut(cs);
        while let Some(b) = uart.read() {
            f.push(b);
            if b == 0 || (at_half && f.len() >= N / 2) {
                wake.store(true, Ordering::Relaxed);
            }
        }
    });
}

/// Bytes from `fifo` into `buf` (the main loop); `wake` falls once it is empty.
fn take<const N: usize>(
    fifo: &Mutex<RefCell<Fifo<N>>>,
    wake: &AtomicBool,
    buf: &mut [u8],
) -> usize {
    critical_section::with(|cs| {
        let mut f = fifo.borrow_ref_mut(cs);
        let n = f.pop_into(buf);
        if f.is_empty() {
            wake.store(false, Ordering::Relaxed);
        }
        n
    })
}

fn station_rx_isr() {
    drain_rx(&uart::STATION, &STATION_RX, &STATION_WAKE, true);
}

/// Transmit interrupt of UART0 (the last byte left): the next byte of the FIFO.
fn station_tx_isr() {
    uart::STATION.clear_tx_irq();
    critical_section::with(|cs| feed_station_tx(&mut STATION_TX.borrow_ref_mut(cs)));
}

fn feed_station_tx(f: &mut Fifo<STATION_TX_FIFO>) {
    while !uart::STATION.tx_full() {
        match f.pop() {
            Some(b) => uart::STATION.write(b),
            None => break,
        }
    }
}

fn hil_rx_isr() {
    drain_rx(&uart::HIL, &HIL_RX, &HIL_WAKE, false);
}

/// The mps2-an386 as the board's ports (no state of its own: it is the hardware's).
pub struct Mps2Ports;

impl Ports for Mps2Ports {
    fn ticks(&mut self) -> u64 {
        timer::ticks()
    }

    fn station_read(&mut self, buf: &mut [u8]) -> usize {
        take(&STATION_RX, &STATION_WAKE, buf)
    }

    fn station_write(&mut self, bytes: &[u8]) -> usize {
        critical_section::with(|cs| {
            let mut f = STATION_TX.borrow_ref_mut(cs);
            let n = f.push_some(bytes);
            // Idle transmitter: start it; its interrupt sends the rest.
            feed_station_tx(&mut f);
            n
        })
    }

    fn hil_read(&mut self, buf: &mut [u8]) -> usize {
        take(&HIL_RX, &HIL_WAKE, buf)
    }

    fn hil_write(&mut self, bytes: &[u8]) {
        uart::HIL.write_blocking(bytes);
    }

    fn idle(&mut self, until: Option<u64>) {
        let mut slept = false;
        loop {
            // Interrupts masked from the check to the WFI, so a delimiter that arrives in
            // between is not slept through: its interrupt, pending, ends the WFI at once.
            let done = critical_section::with(|_| {
                let frame =
                    STATION_WAKE.load(Ordering::Relaxed) || HIL_WAKE.load(Ordering::Relaxed);
                if frame || until.is_some_and(|t| timer::ticks() >= t) {
                    return true;
                }
                if let Some(t) = until {
                    timer::alarm_at(t);
                }
                cortex_m::asm::wfi();
                false
            });
            if done {
                if slept {
                    SLEEPS.fetch_add(1, Ordering::Relaxed);
                }
                return;
            }
            slept = true;
        }
    }

    fn station_fifo(&self) -> (u32, u32, u32) {
        critical_section::with(|cs| {
            let f = STATION_RX.borrow_ref(cs);
            (f.pushed(), f.max() as u32, f.dropped())
        })
    }

    fn memory(&self) -> (u32, u32, u32) {
        stack::memory()
    }

    fn sleeps(&self) -> u32 {
        SLEEPS.load(Ordering::Relaxed)
    }
}
