//! The robot the image is built for, one per build (cargo features `dom-dinis`, the default,
//! `khepera`, `alice`): each composition's state has its own size, and the Dom Dinis robot's
//! must fit its board's 32 KB (build.rs gives the others a larger RAM).

#[cfg(feature = "dom-dinis")]
pub use robot_firmware::robot::DomDinis as Kit;
#[cfg(feature = "dom-dinis")]
pub const PROFILE: &robot_firmware::Profile = &robot_firmware::MICRO_RATO;

#[cfg(all(feature = "khepera", not(feature = "dom-dinis")))]
pub use robot_firmware::robot::Khepera as Kit;
#[cfg(all(feature = "khepera", not(feature = "dom-dinis")))]
pub const PROFILE: &robot_firmware::Profile = &robot_firmware::KHEPERA;

#[cfg(all(
    feature = "alice",
    not(any(feature = "dom-dinis", feature = "khepera"))
))]
pub use robot_firmware::robot::Alice as Kit;
#[cfg(all(
    feature = "alice",
    not(any(feature = "dom-dinis", feature = "khepera"))
))]
pub const PROFILE: &robot_firmware::Profile = &robot_firmware::ALICE;
