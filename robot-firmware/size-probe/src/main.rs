//! A bare-metal image that links `Robot::step` and the link handler for a real board
//! (thumbv7em-none-eabihf), so `size-report.sh` can read the robot's state size and the
//! call graph's stack use from what the compiler produced for that target. Not a firmware to
//! flash: it has no vector table or HAL of a board; the `ScriptedHal` stands in for one
//! (its methods are small reads and writes of fields, as a board's registers would be).
//! On the host it is an empty program, so `cargo test --all-targets` builds it too.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod probe {
    use core::mem::MaybeUninit;

    use robot_firmware::robot::DomDinis;
    use robot_firmware::scripted::ScriptedHal;
    use robot_firmware::{RobotOptions, MICRO_RATO};
    type Robot = robot_firmware::Robot<DomDinis>;

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        loop {}
    }

    /// The robot and its board live in statics, as on the microcontroller (the whole state
    /// in .bss, none of it on the stack).
    static mut ROBOT: MaybeUninit<Robot> = MaybeUninit::uninit();
    static mut HAL: MaybeUninit<ScriptedHal> = MaybeUninit::uninit();

    /// The reset handler: builds the robot in place and runs its main loop.
    #[no_mangle]
    #[allow(unsafe_code)] // statics of a bare-metal image, touched by this one thread only
    pub extern "C" fn _start() -> ! {
        let opts = RobotOptions {
            profile: &MICRO_RATO,
            seed: 1,
            start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "size-probe",
        };
        // SAFETY: single-threaded reset code; nothing else references the statics.
        let (robot, hal) = unsafe {
            (
                (*core::ptr::addr_of_mut!(ROBOT)).write(Robot::new(opts)),
                (*core::ptr::addr_of_mut!(HAL)).write(ScriptedHal::default()),
            )
        };
        loop {
            step(robot, core::hint::black_box(&mut *hal));
        }
    }

    /// `Robot::step` in a frame of its own, so the report can name it (it inlines into it).
    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_robot_step(robot: &mut Robot, hal: &mut ScriptedHal) {
        robot.step(hal);
    }
    use size_probe_robot_step as step;
}

#[cfg(not(target_os = "none"))]
fn main() {}
