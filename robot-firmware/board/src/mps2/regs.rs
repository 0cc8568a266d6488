//! Memory-mapped register access: the one place the board reads and writes device memory.
#![allow(unsafe_code)] // volatile accesses to the fixed device addresses of mps2/mod.rs

/// Reads the 32-bit register at `addr`.
pub fn read(addr: usize) -> u32 {
    // SAFETY: `addr` is one of the CMSDK device registers of the table in mps2/mod.rs:
    // aligned, always mapped on this board, a read has no effect beyond the device's own.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

/// Writes the 32-bit register at `addr`.
pub fn write(addr: usize, value: u32) {
    // SAFETY: as `read`; the devices are owned by this firmware alone.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}
