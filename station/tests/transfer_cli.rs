//! `station upload-map`, `download-map`, `upload-plan`, `plan --out-object` and `send
//! plan / execute` as a user runs them: the binary against the real firmware on an emulator
//! pty, each with its JSON, exit code and message.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use emulator::link::{spawn_device, Running, ServeOptions};
use serde_json::Value;
use station::link::sim::{SimCore, SimOptions};
use station::plan::{MapOptions, NavMap};
use station::transfer::objects::map_object;

fn station(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .output()
        .unwrap()
}

fn json(o: &Output) -> Value {
    let out = String::from_utf8_lossy(&o.stdout);
    serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("{e}: {out}\n{}", String::from_utf8_lossy(&o.stderr)))
}

/// An emulator with the real firmware behind a stable symlink; both go when dropped.
struct Robot {
    emu: Option<Running>,
    dir: PathBuf,
    port: PathBuf,
}

impl Drop for Robot {
    fn drop(&mut self) {
        drop(self.emu.take());
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn robot(name: &str) -> Robot {
    let dir = std::env::temp_dir().join(format!("station-xfer-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let port = dir.join("robot");
    let emu = spawn_device(
        || Ok(SimCore::new(SimOptions::default())),
        ServeOptions {
            link: Some(port.clone()),
            ..ServeOptions::default()
        },
    )
    .unwrap();
    Robot {
        emu: Some(emu),
        dir,
        port,
    }
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

const MAP: &str = emulator::builtin::MICRO_RATO_99;

#[test]
fn a_map_goes_up_once_comes_back_identical_and_an_oversize_one_is_refused_first() {
    let r = robot("map");
    let port = p(&r.port);
    let o = station(&["upload-map", "--port", port, "--map", MAP, "--json"]);
    let v = json(&o);
    assert!(o.status.success(), "{v}");
    let m = map_object(&NavMap::load(MAP, &MapOptions::default()).unwrap()).unwrap();
    assert_eq!(v["outcome"], "complete");
    assert_eq!(v["bytes"], m.bytes.len());
    assert_eq!(v["id"], m.id);
    assert_eq!(v["crc"], m.id);
    assert!(v["elapsed_ms"].is_u64());
    let o = station(&["upload-map", "--port", port, "--map", MAP, "--json"]);
    assert!(o.status.success());
    assert_eq!(json(&o)["outcome"], "already_have");

    let out = r.dir.join("back.obj");
    let o = station(&["download-map", "--port", port, "--out", p(&out), "--json"]);
    let v = json(&o);
    assert!(o.status.success(), "{v}");
    assert_eq!(v["outcome"], "complete");
    assert_eq!(v["map"]["width"], 17);
    assert_eq!(std::fs::read(&out).unwrap(), m.bytes, "byte-identical");
    // An existing file is kept unless --force, with a real robot answering too.
    std::fs::write(&out, b"precious").unwrap();
    let o = station(&["download-map", "--port", port, "--out", p(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("exists; pass --force to overwrite it"),
        "{err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
    let o = station(&["download-map", "--port", port, "--out", p(&out), "--force"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(&out).unwrap(),
        m.bytes,
        "overwritten with --force"
    );
    // The downloaded file is a map file too.
    let o = station(&["upload-map", "--port", port, "--map", p(&out), "--json"]);
    assert_eq!(json(&o)["outcome"], "already_have");

    let o = station(&["upload-map", "--port", port, "--map", MAP, "--cell", "0.05"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("100 x 100 cells") && err.contains("at most 64 x 64"),
        "{err}"
    );
    let o = station(&[
        "upload-map",
        "--port",
        port,
        "--map",
        MAP,
        "--cell",
        "0.05",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(json(&o)["outcome"], "too_large");
}

#[test]
fn a_plan_made_here_is_the_plan_made_on_the_robot_and_executes_by_its_id() {
    let r = robot("plan");
    let port = p(&r.port);
    let o = station(&["download-map", "--port", port, "--ascii"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("holds no map"), "{err}");
    assert!(station(&["upload-map", "--port", port, "--map", MAP])
        .status
        .success());
    // On the robot, from where it believes it is (0.5, 0.5) to the map's goal.
    let o = station(&["send", "--port", port, "--json", "plan"]);
    let v = json(&o);
    assert!(o.status.success(), "{v}");
    let robot_id = v["info"]["plan_id"].as_u64().unwrap();
    // Here, from the map's start (0.5, 0.5): the same object, so the same id.
    let file = r.dir.join("plan.obj");
    let o = station(&["plan", "--map", MAP, "--out-object", p(&file), "--json"]);
    let v = json(&o);
    assert!(o.status.success(), "{v}");
    assert_eq!(v["object"]["id"].as_u64(), Some(robot_id));
    let o = station(&["upload-plan", "--port", port, "--plan", p(&file), "--json"]);
    let v = json(&o);
    assert!(o.status.success(), "{v}");
    assert_eq!(v["outcome"], "already_have");
    let hex = format!("{robot_id:#010x}");
    let o = station(&["send", "--port", port, "execute", &hex]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = station(&["send", "--port", port, "execute", "0x1"]);
    assert_eq!(o.status.code(), Some(1));
    // A map object is not a plan.
    let map = r.dir.join("map.obj");
    assert!(station(&["download-map", "--port", port, "--out", p(&map)])
        .status
        .success());
    let o = station(&["upload-plan", "--port", port, "--plan", p(&map)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(err.contains("is a map object, not a plan object"), "{err}");
}
