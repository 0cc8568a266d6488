//! The CMSDK APB UART (DDI 0479, §4.3): DATA 0x00, STATE 0x04 (bit 0 TX buffer full, bit 1
//! RX buffer full, 2-3 overruns), CTRL 0x08 (bit 0 TX enable, 1 RX enable, 2 TX interrupt,
//! 3 RX interrupt), INTSTATUS/INTCLEAR 0x0C (bit 0 TX, bit 1 RX), BAUDDIV 0x10 (PCLK / baud,
//! at least 16). One byte of buffer each way.

use super::regs;

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTCLEAR: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const TX_FULL: u32 = 1 << 0;
const RX_FULL: u32 = 1 << 1;
const OVERRUNS: u32 = 0b1100;
const TX_EN: u32 = 1 << 0;
const RX_EN: u32 = 1 << 1;
const TX_INT: u32 = 1 << 2;
const RX_INT: u32 = 1 << 3;

/// 25 MHz / 115200 baud (the station link's rate; QEMU does not model it, a board does).
const DIV_115200: u32 = 217;
/// Spins on a full transmitter before a byte is given up (a world not reading).
const TX_SPIN_LIMIT: u32 = 1_000_000;

pub struct Uart {
    base: usize,
}

pub const STATION: Uart = Uart { base: 0x4000_4000 };
pub const HIL: Uart = Uart { base: 0x4000_5000 };

impl Uart {
    /// 115200 baud, both directions on, the receive interrupt, and the transmit interrupt
    /// when `tx_interrupt` (the station link's transmitter is interrupt-driven, the HIL's
    /// writes wait).
    pub fn init(&self, tx_interrupt: bool) {
        regs::write(self.base + BAUDDIV, DIV_115200);
        regs::write(self.base + STATE, OVERRUNS);
        let tx = if tx_interrupt { TX_INT } else { 0 };
        regs::write(self.base + CTRL, TX_EN | RX_EN | RX_INT | tx);
    }

    /// The received byte, if one is waiting.
    pub fn read(&self) -> Option<u8> {
        (regs::read(self.base + STATE) & RX_FULL != 0).then(|| regs::read(self.base + DATA) as u8)
    }

    pub fn tx_full(&self) -> bool {
        regs::read(self.base + STATE) & TX_FULL != 0
    }

    pub fn write(&self, b: u8) {
        regs::write(self.base + DATA, u32::from(b));
    }

    /// Writes every byte, waiting for the transmitter (bounded: a byte the line never takes
    /// is dropped rather than hanging the board).
    pub fn write_blocking(&self, bytes: &[u8]) {
        for &b in bytes {
            let mut spins = 0;
            while self.tx_full() && spins < TX_SPIN_LIMIT {
                spins += 1;
            }
            self.write(b);
        }
    }

    pub fn clear_rx_irq(&self) {
        regs::write(self.base + INTCLEAR, 1 << 1);
    }

    pub fn clear_tx_irq(&self) {
        regs::write(self.base + INTCLEAR, 1 << 0);
    }
}
