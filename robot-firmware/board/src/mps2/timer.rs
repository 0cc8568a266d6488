//! The CMSDK APB timers (DDI 0479, §4.4): CTRL 0x00 (bit 0 enable, bit 3 interrupt enable),
//! VALUE 0x04 (counts down at PCLK, 25 MHz), RELOAD 0x08 (loaded at zero, when the interrupt
//! is raised), INTSTATUS/INTCLEAR 0x0C.
//!
//! TIMER0 runs free from 0xFFFF_FFFF; its interrupt counts the wraps (every 171.8 s), which
//! extend it to 64 bits. TIMER1 is the alarm that ends a sleep. Under QEMU's
//! `-icount shift=0` one tick is 40 instructions (1 ns each), which is how the measures count
//! instructions.

use core::cell::Cell;

use critical_section::Mutex;

use super::regs;

const TIMER0: usize = 0x4000_0000;
const TIMER1: usize = 0x4000_1000;
const CTRL: usize = 0x00;
const VALUE: usize = 0x04;
const RELOAD: usize = 0x08;
const INT: usize = 0x0C;
const ENABLE: u32 = 1 << 0;
const IRQ_ENABLE: u32 = 1 << 3;

static WRAPS: Mutex<Cell<u32>> = Mutex::new(Cell::new(0));

pub fn start_clock() {
    regs::write(TIMER0 + CTRL, 0);
    regs::write(TIMER0 + RELOAD, u32::MAX);
    regs::write(TIMER0 + VALUE, u32::MAX);
    regs::write(TIMER0 + INT, 1);
    regs::write(TIMER0 + CTRL, ENABLE | IRQ_ENABLE);
}

/// Ticks since the clock started.
pub fn ticks() -> u64 {
    critical_section::with(|cs| {
        let wraps = WRAPS.borrow(cs).get();
        let value = regs::read(TIMER0 + VALUE);
        // A wrap not yet counted (its interrupt waits for this critical section to end): the
        // value has restarted near the top. A small value means the wrap came after it was
        // read.
        let pending = regs::read(TIMER0 + INT) & 1 != 0 && value > u32::MAX / 2;
        let wraps = u64::from(wraps) + u64::from(pending);
        (wraps << 32) | u64::from(u32::MAX - value)
    })
}

/// TIMER0's interrupt: one more wrap.
pub fn clock_isr() {
    regs::write(TIMER0 + INT, 1);
    critical_section::with(|cs| {
        let w = WRAPS.borrow(cs);
        w.set(w.get().wrapping_add(1));
    });
}

/// Raises TIMER1's interrupt at `at` ticks (at once if that has passed).
pub fn alarm_at(at: u64) {
    let delta = at.saturating_sub(ticks()).clamp(1, u64::from(u32::MAX));
    regs::write(TIMER1 + CTRL, 0);
    regs::write(TIMER1 + RELOAD, delta as u32);
    regs::write(TIMER1 + VALUE, delta as u32);
    regs::write(TIMER1 + INT, 1);
    regs::write(TIMER1 + CTRL, ENABLE | IRQ_ENABLE);
}

/// TIMER1's interrupt: the alarm has done its work (woken the loop); stop it.
pub fn alarm_isr() {
    regs::write(TIMER1 + CTRL, 0);
    regs::write(TIMER1 + INT, 1);
}
