//! On the bare-metal target the image needs a memory layout (`m4.ld`); the host build is an
//! ordinary program.
fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    println!("cargo:rerun-if-changed=m4.ld");
    if target.starts_with("thumb") {
        let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
        println!("cargo:rustc-link-arg-bins=-T{dir}/m4.ld");
    }
}
