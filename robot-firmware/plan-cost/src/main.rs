//! Seed 004 §6's planning cost (< 5 s on the 68HC11) measured for a Cortex-M4: the firmware's
//! planner (`work.rs`) run on QEMU's mps2-an386 board (Cortex-M4F) under `-icount shift=0`,
//! where every instruction takes 1 ns of virtual time, read from the board's CMSDK timer
//! (25 MHz: one tick is 40 instructions). Results go out by semihosting. On the host the same
//! workloads print wall-clock times. `robot-firmware/plan-cost.sh` builds and runs both.
//!
//! Instructions, not cycles: QEMU does not model the pipeline. A Cortex-M4 takes 1 cycle for
//! most instructions and 2 or more for loads, taken branches and divisions, so cycles are
//! about 1.2-1.5x these counts (no wait states assumed); the figures are a lower bound.
#![cfg_attr(target_os = "none", no_std, no_main)]

mod work;

#[cfg(target_os = "none")]
mod m4 {
    use core::fmt::Write;

    use robot_firmware::nav::{Geometry, Nav64};

    use crate::work::CASES;

    /// CMSDK APB timer 0 of the mps2-an386 board (counts down at 25 MHz).
    const TIMER0: usize = 0x4000_0000;
    /// Virtual nanoseconds (= instructions under `-icount shift=0`) per timer tick.
    const NS_PER_TICK: u64 = 40;

    #[allow(unsafe_code)] // memory-mapped registers of the board, this one thread only
    fn timer_value() -> u32 {
        // SAFETY: the timer's VALUE register; a read has no side effect.
        unsafe { core::ptr::read_volatile((TIMER0 + 4) as *const u32) }
    }

    #[allow(unsafe_code)]
    fn timer_start() {
        // SAFETY: the timer's RELOAD, VALUE and CTRL registers (enable, no interrupt).
        unsafe {
            core::ptr::write_volatile((TIMER0 + 8) as *mut u32, u32::MAX);
            core::ptr::write_volatile((TIMER0 + 4) as *mut u32, u32::MAX);
            core::ptr::write_volatile(TIMER0 as *mut u32, 1);
        }
    }

    /// An ARM semihosting call (`bkpt 0xAB`), served by QEMU.
    #[allow(unsafe_code)]
    fn semihost(op: u32, arg: usize) -> u32 {
        let r: u32;
        // SAFETY: the debugger's calling convention; `arg` points at live data if the call
        // reads memory.
        unsafe {
            core::arch::asm!("bkpt #0xab", inout("r0") op => r, in("r1") arg, options(nostack))
        };
        r
    }

    /// A line buffer printed with SYS_WRITE0.
    struct Line {
        buf: [u8; 160],
        len: usize,
    }

    impl Write for Line {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for &b in s.as_bytes() {
                if self.len + 1 < self.buf.len() {
                    self.buf[self.len] = b;
                    self.len += 1;
                }
            }
            Ok(())
        }
    }

    fn print(args: core::fmt::Arguments<'_>) {
        let mut l = Line {
            buf: [0; 160],
            len: 0,
        };
        let _ = l.write_fmt(args);
        l.buf[l.len] = 0;
        semihost(0x04, l.buf.as_ptr() as usize);
    }

    fn exit(ok: bool) -> ! {
        // SYS_EXIT with ADP_Stopped_ApplicationExit (0x20026) or RunTimeErrorUnknown (0x20023).
        semihost(0x18, if ok { 0x20026 } else { 0x20023 });
        // Not reached under QEMU; without a debugger, wait for one.
        loop {
            core::hint::spin_loop();
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        print(format_args!("panic\n"));
        exit(false)
    }

    extern "C" fn fault() -> ! {
        print(format_args!("fault\n"));
        exit(false)
    }

    /// Reset, NMI, HardFault, MemManage, BusFault, UsageFault (after the initial stack pointer
    /// the linker script puts first).
    #[allow(unsafe_code)] // the vector table must sit where the linker script puts it
    #[link_section = ".vectors.handlers"]
    #[used]
    static HANDLERS: [extern "C" fn() -> !; 6] = [reset, fault, fault, fault, fault, fault];

    extern "C" {
        static mut _sbss: u32;
        static mut _ebss: u32;
    }

    #[no_mangle]
    #[allow(unsafe_code)]
    pub extern "C" fn reset() -> ! {
        // SAFETY: reset code, nothing else runs: enable the FPU (CPACR: CP10, CP11 full access;
        // the hard-float code uses it) and zero .bss.
        unsafe {
            let cpacr = 0xE000_ED88 as *mut u32;
            core::ptr::write_volatile(cpacr, core::ptr::read_volatile(cpacr) | 0xF << 20);
            core::arch::asm!("dsb", "isb");
            let mut p = core::ptr::addr_of_mut!(_sbss);
            while p < core::ptr::addr_of_mut!(_ebss) {
                core::ptr::write_volatile(p, 0);
                p = p.add(1);
            }
        }
        main()
    }

    /// A loop of exactly 2 * `n` + 1 instructions (`subs`, `bne` per turn, and a `mov`).
    #[allow(unsafe_code)]
    fn known_loop(n: u32) {
        // SAFETY: registers only.
        unsafe {
            core::arch::asm!(
                "mov {0}, {1}",
                "2:",
                "subs {0}, {0}, #1",
                "bne 2b",
                out(reg) _, in(reg) n, options(nomem, nostack)
            );
        }
    }

    fn main() -> ! {
        timer_start();
        // The counter's check: a loop whose instruction count is known.
        let t0 = timer_value();
        known_loop(500_000);
        let t1 = timer_value();
        let insns = u64::from(t0.wrapping_sub(t1)) * NS_PER_TICK;
        print(format_args!(
            "check: a 1,000,001-instruction loop (not a case)\t{insns}\t-\t-\n"
        ));
        let mut nav = Nav64::new(Geometry::SEED_004);
        for case in CASES.iter() {
            (case.setup)(&mut nav);
            let t0 = timer_value();
            let (sum, method) = core::hint::black_box((case.run)(core::hint::black_box(&mut nav)));
            let t1 = timer_value();
            let insns = u64::from(t0.wrapping_sub(t1)) * NS_PER_TICK;
            let m = method.name();
            print(format_args!(
                "{}\t{}\t{:08x}\t{}\n",
                case.name, insns, sum, m
            ));
        }
        exit(true)
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    use robot_firmware::nav::{Geometry, Nav64};
    use std::time::Instant;
    // Fastest of 31 runs: the machine is shared; the minimum is the least disturbed.
    let mut nav = Box::new(Nav64::new(Geometry::SEED_004));
    for case in work::CASES.iter() {
        (case.setup)(&mut nav);
        let mut best = u128::MAX;
        let mut out = (0, work::Method::Failed);
        for _ in 0..31 {
            let t = Instant::now();
            out = std::hint::black_box((case.run)(std::hint::black_box(&mut nav)));
            best = best.min(t.elapsed().as_nanos());
        }
        println!("{}\t{}\t{:08x}\t{}", case.name, best, out.0, out.1.name());
    }
}
