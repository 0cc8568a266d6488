//! Every arena importer on arbitrary bytes: CiberRato lab XML, micromouse maze text, ASCII
//! grids, and ROS map YAML with its PGM (the data is split between the two files). Invariants:
//! no panic; an accepted arena rasterises without panicking.
#![no_main]

use std::path::Path;

use emulator::arena::{ascii, ciberrato, micromouse, rasterise, LoadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, bytes)) = data.split_first() else { return };
    let opts = LoadOptions::default();
    let text = String::from_utf8_lossy(bytes);
    let arena = match which % 4 {
        0 => ciberrato::parse_lab(Path::new("fuzz.xml"), &text, opts.ciberrato_unit_m).ok(),
        1 => micromouse::parse(Path::new("fuzz.txt"), &text, &opts).ok(),
        2 => ascii::parse(Path::new("fuzz.grid"), &text, &opts).ok(),
        _ => ros(bytes),
    };
    if let Some(a) = arena {
        let _ = rasterise(&a, 0.3, 0.12);
    }
});

fn ros(bytes: &[u8]) -> Option<emulator::arena::Arena> {
    let dir = std::env::temp_dir().join(format!("arena-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    let split = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    let (yaml, pgm) = bytes.split_at(split);
    std::fs::write(dir.join("m.pgm"), pgm.get(1..).unwrap_or(&[])).ok()?;
    let yaml_path = dir.join("m.yaml");
    std::fs::write(&yaml_path, yaml).ok()?;
    emulator::arena::load(&yaml_path, &LoadOptions::default()).ok()
}
