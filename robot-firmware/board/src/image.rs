//! The image: reset (cortex-m-rt: statics initialised, the stack painted, the FPU on), the
//! power-on exchange with the world, the robot built in place in a static, the main loop; and
//! what happens when it stops (a panic or a fault): the world is told, so the motors stop,
//! and the core sleeps.
#![allow(unsafe_code)] // cortex-m-rt's exception handlers are `unsafe fn` by its contract

use core::mem::MaybeUninit;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use protocol::hil::fault;
use robot_firmware::Robot;

use crate::mps2::{self, Mps2Ports};
use crate::profile::{Kit, PROFILE};
use robot_board::board::{self, Board};

#[entry]
fn main() -> ! {
    mps2::init();
    let mut ports = Mps2Ports;
    let Ok((setup, first, decoder)) = board::power_on(&mut ports, PROFILE) else {
        halt()
    };
    // The robot's state (most of the RAM) is built in place: never on the stack.
    let Some(slot) = cortex_m::singleton!(ROBOT: MaybeUninit<Robot<Kit>> = MaybeUninit::uninit())
    else {
        stop(fault::PANIC)
    };
    let robot = board::build_robot(slot, PROFILE, &setup);
    Board::new(robot, ports, &setup, first, decoder).run()
}

/// Tells the world and sleeps for good.
fn stop(code: u8) -> ! {
    cortex_m::interrupt::disable();
    board::send_fault(&mut Mps2Ports, code);
    halt()
}

fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    stop(fault::PANIC)
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    stop(fault::HARD_FAULT)
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    mps2::dispatch(irqn);
}
