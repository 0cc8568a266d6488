//! The MCAP export's protobuf schemas (`proto/`, see its README) compiled without `protoc`:
//! protox parses them into a `FileDescriptorSet`, which is kept in `OUT_DIR` for the schema
//! records (`export::mcap_proto`), and prost-build makes their Rust types from that set.

use std::path::PathBuf;

use prost::Message as _;

/// The files whose messages are written; what they import comes along.
const FILES: &[&str] = &[
    "foxglove/PoseInFrame.proto",
    "foxglove/FrameTransform.proto",
    "station/Telemetry.proto",
    "station/Truth.proto",
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo:rerun-if-changed=proto");
    // With the comments, which become the Rust types' docs.
    let set = protox::compile(FILES, ["proto"])?;
    // The schema records without them (`protoc --include_imports` writes none either).
    let mut bare = set.clone();
    for f in &mut bare.file {
        f.source_code_info = None;
    }
    let out = PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out.join("mcap_schemas.bin"), bare.encode_to_vec())?;
    prost_build::Config::new().compile_fds(set)?;
    Ok(())
}
