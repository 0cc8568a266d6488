//! RAM use as the image measures it: the statics (cortex-m-rt's `.data` + `.bss` + `.uninit`,
//! from `_ram_start` to `_stack_end`) and the stack's high-water mark. cortex-m-rt's
//! `paint-stack` fills the stack (`_stack_end` .. `_stack_start`) with 0xCCCC_CCCC at reset;
//! the deepest word no longer painted is as far as the stack has ever reached.
#![allow(unsafe_code)] // linker symbols' addresses and reads of the painted stack

use core::ptr::addr_of;

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    static _ram_start: u32;
    static _stack_end: u32;
    static _stack_start: u32;
}

/// (statics, stack size, stack high-water mark), bytes.
pub fn memory() -> (u32, u32, u32) {
    // Only the symbols' addresses are taken (cortex-m-rt's link.x defines them).
    let (ram, end, top) = (
        addr_of!(_ram_start) as usize,
        addr_of!(_stack_end) as usize,
        addr_of!(_stack_start) as usize,
    );
    let mut p = end;
    // SAFETY: every word read is inside the stack region, RAM, 4-aligned (link.x asserts).
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    let used = top - p;
    ((end - ram) as u32, (top - end) as u32, used as u32)
}
