//! On the bare-metal target: cortex-m-rt's `link.x` over this board's `memory.x`. RAM is the
//! Dom Dinis board's 32 KB (the link fails if the robot's state does not fit it); the other
//! profiles' images get 64 KB of the mps2-an386's 4 MB.
use std::io::Write;

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    println!("cargo:rerun-if-changed=build.rs");
    if !target.starts_with("thumb") {
        return;
    }
    let dom_dinis = std::env::var_os("CARGO_FEATURE_DOM_DINIS").is_some();
    let ram_kb = if dom_dinis { 32 } else { 64 };
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap_or_default());
    let memory = format!(
        "/* QEMU mps2-an386 (AN386): code in ZBT SSRAM1 at 0 (the board's flash), data in\n   \
         ZBT SSRAM2&3 at 0x20000000, of which the image takes {ram_kb} KB. */\n\
         MEMORY\n{{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  \
         RAM : ORIGIN = 0x20000000, LENGTH = {ram_kb}K\n}}\n"
    );
    let written = std::fs::File::create(out.join("memory.x"))
        .and_then(|mut f| f.write_all(memory.as_bytes()));
    if let Err(e) = written {
        println!("cargo:warning=cannot write memory.x: {e}");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
}
