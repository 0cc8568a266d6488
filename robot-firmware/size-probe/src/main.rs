//! A bare-metal image that links each profile's robot (`Robot<DomDinis>`, `Robot<Khepera>`,
//! `Robot<Alice>`):
//! its construction in place, `Robot::step` and the link handler, for a real board
//! (thumbv7em-none-eabihf), so `size-report.sh` can read each composition's state size and its
//! call graph's stack use from what the compiler produced for that target. Not a firmware to
//! flash: it has no vector table or HAL of a board; the `ScriptedHal` stands in for one (its
//! methods are small reads and writes of fields, as a board's registers would be). A board
//! runs one composition; this image links both so that one build reports both.
//! On the host it is an empty program, so `cargo test --all-targets` builds it too.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod probe {
    use core::mem::MaybeUninit;
    use core::ptr::addr_of_mut;

    use robot_firmware::robot::{Alice, DomDinis, Khepera};
    use robot_firmware::scripted::ScriptedHal;
    use robot_firmware::{Profile, Robot, RobotOptions, ALICE, KHEPERA, MICRO_RATO};

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        loop {}
    }

    /// The robots and the board live in statics, as on the microcontroller (the whole state
    /// in .bss, built there in place by `Robot::init`, none of it on the stack).
    static mut DOM_DINIS: MaybeUninit<Robot<DomDinis>> = MaybeUninit::uninit();
    static mut KHEPERA_ROBOT: MaybeUninit<Robot<Khepera>> = MaybeUninit::uninit();
    static mut ALICE_ROBOT: MaybeUninit<Robot<Alice>> = MaybeUninit::uninit();
    static mut HAL: MaybeUninit<ScriptedHal> = MaybeUninit::uninit();

    fn options(profile: &'static Profile) -> RobotOptions {
        RobotOptions {
            profile,
            seed: 1,
            start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "size-probe",
        }
    }

    /// The reset handler: builds the robots in place and runs their main loops.
    #[no_mangle]
    #[allow(unsafe_code)] // statics of a bare-metal image, touched by this one thread only
    pub extern "C" fn _start() -> ! {
        // SAFETY: single-threaded reset code; nothing else references the statics.
        let (dd, kh, al, hal) = unsafe {
            (
                &mut *addr_of_mut!(DOM_DINIS),
                &mut *addr_of_mut!(KHEPERA_ROBOT),
                &mut *addr_of_mut!(ALICE_ROBOT),
                (*addr_of_mut!(HAL)).write(ScriptedHal::default()),
            )
        };
        let dd = size_probe_init_dom_dinis(dd);
        let kh = size_probe_init_khepera(kh);
        let al = size_probe_init_alice(al);
        loop {
            size_probe_step_dom_dinis(dd, core::hint::black_box(&mut *hal));
            size_probe_step_khepera(kh, core::hint::black_box(&mut *hal));
            size_probe_step_alice(al, core::hint::black_box(&mut *hal));
        }
    }

    // Each entry point in a frame of its own, so the report can name it.

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_init_dom_dinis(
        slot: &mut MaybeUninit<Robot<DomDinis>>,
    ) -> &mut Robot<DomDinis> {
        Robot::init(slot, options(&MICRO_RATO))
    }

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_init_khepera(slot: &mut MaybeUninit<Robot<Khepera>>) -> &mut Robot<Khepera> {
        Robot::init(slot, options(&KHEPERA))
    }

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_init_alice(slot: &mut MaybeUninit<Robot<Alice>>) -> &mut Robot<Alice> {
        Robot::init(slot, options(&ALICE))
    }

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_step_alice(robot: &mut Robot<Alice>, hal: &mut ScriptedHal) {
        robot.step(hal);
    }

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_step_dom_dinis(robot: &mut Robot<DomDinis>, hal: &mut ScriptedHal) {
        robot.step(hal);
    }

    #[inline(never)]
    #[no_mangle]
    #[allow(unsafe_code)] // an unmangled name the stack report finds
    pub fn size_probe_step_khepera(robot: &mut Robot<Khepera>, hal: &mut ScriptedHal) {
        robot.step(hal);
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
