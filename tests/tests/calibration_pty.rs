//! The light calibration across a real pty (PROTOCOL.md §12, §15): the `station` binary
//! downloads, uploads and downloads again the khepera robot's light -> angle network from
//! the emulator (started as `robot-emulator --profile khepera --link PATH` starts it). A file
//! `station calibrate` wrote goes to the robot and comes back byte-identical; an untrained
//! robot and a robot without light sensors are refused with what to do.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Output;

use clap::Parser;
use emulator::link::{spawn_device, RunningEmulator};
use robot_firmware::behaviour::XorShift32;
use robot_firmware::som::LightSom;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cal-e2e-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn emulator(link: &Path, profile: &str) -> RunningEmulator {
    let args = ["robot-emulator", "--link", &link.display().to_string()];
    let mut args: Vec<String> = args.map(String::from).to_vec();
    args.extend(["--profile".into(), profile.into()]);
    let cli = emulator::cli::Cli::try_parse_from(&args).unwrap();
    let opts = cli.serve.options().unwrap();
    let arena = emulator::builtin::load(&opts.arena, &opts.load).unwrap();
    let sim = emulator::sim::Sim::new(arena, opts.sim.clone()).unwrap();
    spawn_device(move || Ok(sim), opts.serve).unwrap()
}

fn station(args: &[&str]) -> Output {
    std::process::Command::new(e2e_tests::workspace_bin("station"))
        .args(args)
        .output()
        .expect("the station binary runs")
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Runs the station expecting exit status 1 and every fragment in what it printed.
fn fails_with(args: &[&str], fragments: &[&str]) {
    let out = station(args);
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    for f in fragments {
        assert!(t.contains(f), "{f:?} not in: {t}");
    }
}

#[test]
fn a_calibration_file_goes_to_the_robot_and_comes_back_byte_identical() {
    let d = dir("khepera");
    let link = d.join("robot");
    let _emu = emulator(&link, "khepera");
    let port = link.display().to_string();

    // Nothing trained yet: refused, saying what to do, and no file left behind.
    let back = d.join("back.bin");
    fails_with(
        &[
            "download-calibration",
            "--port",
            &port,
            "--out",
            back.to_str().unwrap(),
        ],
        &["no trained light calibration"],
    );
    assert!(!back.exists());

    // A network in `station calibrate`'s binary form.
    let som = LightSom::random(&mut XorShift32::new(42), (50.0, 500.0), (0.0, 180.0));
    let file = d.join("som.bin");
    std::fs::write(&file, station::calibrate::encode_bin(&som)).unwrap();
    let out = station(&[
        "upload-calibration",
        "--port",
        &port,
        "--calibration",
        file.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(
        text(&out).contains("\"outcome\": \"complete\""),
        "{}",
        text(&out)
    );

    let out = station(&[
        "download-calibration",
        "--port",
        &port,
        "--out",
        back.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(std::fs::read(&back).unwrap(), std::fs::read(&file).unwrap());

    // The JSON form holds the same network; an existing file needs --force.
    let json = d.join("back.json");
    let out = station(&[
        "download-calibration",
        "--port",
        &port,
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let again = station::calibrate::decode(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(again, som);
    let again_args = [
        "download-calibration",
        "--port",
        &port,
        "--out",
        json.to_str().unwrap(),
    ];
    fails_with(&again_args, &["exists; pass --force"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_files_and_robots_without_light_sensors_are_refused() {
    let d = dir("micro-rato");
    let link = d.join("robot");
    let _emu = emulator(&link, "micro-rato");
    let port = link.display().to_string();
    let file = d.join("som.bin");
    let som = LightSom::random(&mut XorShift32::new(7), (50.0, 500.0), (0.0, 180.0));
    std::fs::write(&file, station::calibrate::encode_bin(&som)).unwrap();
    fails_with(
        &[
            "upload-calibration",
            "--port",
            &port,
            "--calibration",
            file.to_str().unwrap(),
        ],
        &["no ambient light sensors"],
    );

    // A damaged file is refused before the port is opened, naming the file and the fault.
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[20] ^= 0xff;
    std::fs::write(&file, bytes).unwrap();
    fails_with(
        &[
            "upload-calibration",
            "--port",
            "/nonexistent",
            "--calibration",
            file.to_str().unwrap(),
        ],
        &["som.bin", "byte 850: CRC mismatch"],
    );
    let _ = std::fs::remove_dir_all(&d);
}
