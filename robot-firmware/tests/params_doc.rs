//! PROTOCOL.md §16, the parameter table, is generated from the firmware's table
//! (`robot_firmware::params::PARAMS`) and the defaults a freshly started robot of each profile
//! answers; this test fails when they disagree. After a deliberate change:
//! `UPDATE_PROTOCOL_DOC=1 cargo test -p robot-firmware --test params_doc` rewrites the block.
#![allow(clippy::unwrap_used, clippy::panic)]

use protocol::caps;
use robot_firmware::params::PARAMS;
use robot_firmware::{AnyRobot, RobotOptions, ALICE, KHEPERA, MICRO_RATO};

const BEGIN: &str = "<!-- parameter table: generated from robot-firmware/src/params.rs by \
                     robot-firmware/tests/params_doc.rs -->";
const END: &str = "<!-- end of the parameter table -->";

fn robot(profile: &'static robot_firmware::Profile) -> AnyRobot {
    AnyRobot::new(RobotOptions {
        profile,
        seed: 1,
        start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
        emulated: false,
        firmware_version: "doc",
    })
}

fn needs(bits: u32) -> String {
    let names = [
        (caps::ENCODERS, "encoders (bit 0)"),
        (caps::IR_PROXIMITY, "IR (bit 1)"),
        (caps::AMBIENT_LIGHT, "ambient light (bit 2)"),
        (caps::COMPASS, "compass (bit 3)"),
        (caps::BEACON, "beacon (bit 6)"),
    ];
    let v: Vec<&str> = names
        .iter()
        .filter(|(b, _)| bits & b != 0)
        .map(|(_, n)| *n)
        .collect();
    assert_eq!(
        v.len(),
        bits.count_ones() as usize,
        "name every capability a parameter needs"
    );
    v.join(", ")
}

/// The table as PROTOCOL.md shows it.
fn table() -> String {
    let mut khepera = robot(&KHEPERA);
    let mut rato = robot(&MICRO_RATO);
    let mut alice = robot(&ALICE);
    let mut out = String::from(
        "| id | name | unit | min | max | whole | default: khepera | default: micro-rato | \
         default: alice | needs | what it does |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let default = |r: &mut AnyRobot, id: u16| match r.param(id) {
        Ok(v) => format!("{v}"),
        Err(protocol::NackReason::Unsupported) => "(Unsupported)".into(),
        Err(e) => panic!("parameter {id}: {e:?}"),
    };
    for p in PARAMS.iter() {
        out.push_str(&format!(
            "| {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            p.id,
            p.name,
            p.unit,
            p.min,
            p.max,
            if p.integer { "yes" } else { "" },
            default(&mut khepera, p.id),
            default(&mut rato, p.id),
            default(&mut alice, p.id),
            needs(p.requires),
            p.desc.replace('|', "\\|"),
        ));
    }
    out
}

#[test]
fn protocol_md_parameter_table_is_the_firmwares() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../protocol/PROTOCOL.md");
    let doc = std::fs::read_to_string(path).unwrap();
    let start = doc
        .find(BEGIN)
        .expect("PROTOCOL.md has the generated block's start marker");
    let end = doc
        .find(END)
        .expect("PROTOCOL.md has the generated block's end marker");
    let body = &doc[start + BEGIN.len()..end];
    let want = format!("\n\n{}\n", table());
    if std::env::var_os("UPDATE_PROTOCOL_DOC").is_some() {
        let new = format!("{}{want}{}", &doc[..start + BEGIN.len()], &doc[end..]);
        std::fs::write(path, new).unwrap();
        return;
    }
    assert!(
        body == want,
        "PROTOCOL.md §16 differs from the firmware's table; regenerate it with \
         UPDATE_PROTOCOL_DOC=1 cargo test -p robot-firmware --test params_doc"
    );
}
