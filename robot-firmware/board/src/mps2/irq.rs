//! The board's interrupts: their numbers on the AN386 (QEMU's mps2.c wires UART n's receive
//! interrupt to 2n and transmit to 2n + 1, TIMER0 to 8, TIMER1 to 9) and the dispatch from
//! cortex-m-rt's default handler, which receives the interrupt's number (no device crate:
//! these six are all the image uses).
#![allow(unsafe_code)] // NVIC unmasking and the global interrupt enable are unsafe in cortex-m

use cortex_m::interrupt::InterruptNumber;
use cortex_m::peripheral::NVIC;

#[derive(Clone, Copy)]
#[repr(u16)]
enum Irq {
    Uart0Rx = 0,
    Uart0Tx = 1,
    Uart1Rx = 2,
    Timer0 = 8,
    Timer1 = 9,
}

// SAFETY: each number is a valid AN386 interrupt (table above), below the 32 QEMU models.
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self as u16
    }
}

const ALL: [Irq; 5] = [
    Irq::Uart0Rx,
    Irq::Uart0Tx,
    Irq::Uart1Rx,
    Irq::Timer0,
    Irq::Timer1,
];

/// Unmasks the board's interrupts in the NVIC, then globally.
pub fn enable() {
    for irq in ALL {
        // SAFETY: each handler (below) only touches state behind critical sections, so
        // unmasking cannot break a critical section in progress.
        unsafe { NVIC::unmask(irq) };
    }
    // SAFETY: as above; called once, from the main thread, after the devices are set up.
    unsafe { cortex_m::interrupt::enable() };
}

/// Runs the handler of interrupt `irqn` (cortex-m-rt's DefaultHandler).
pub fn dispatch(irqn: i16) {
    match irqn {
        0 => super::station_rx_isr(),
        1 => super::station_tx_isr(),
        2 => super::hil_rx_isr(),
        8 => super::timer::clock_isr(),
        9 => super::timer::alarm_isr(),
        _ => {}
    }
}
