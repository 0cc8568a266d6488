//! `station export` of a known recording (`record::synth::demo`): the MCAP read back with the
//! mcap crate, message by message and channel by channel; the CSV row by row; and bad input
//! refused with its byte offset and no output file left behind.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use station::export::csv::COLUMNS;
use station::record::synth::demo;

mod support;

/// The topics of every frame, binary (protobuf) unless `--mcap-encoding json`.
const BINARY_TOPICS: &[&str] = &["/telemetry", "/pose", "/truth", "/truth_pose", "/tf"];

/// 10 s at 20 Hz: 200 telemetry frames, 200 truth frames, 40 heartbeats, one command.
const SECONDS: u32 = 10;
const HZ: u32 = 20;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("export-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn station(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_station"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

fn files(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn mcap_export_has_every_message_on_its_channel_at_its_recorded_time() {
    let d = dir("mcap");
    std::fs::write(d.join("demo.rec"), demo(SECONDS, HZ)).unwrap();
    let o = station(&["export", "demo.rec", "--mcap", "demo.mcap"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        files(&d),
        ["demo.mcap", "demo.rec"],
        "no temporary file is left"
    );

    let bytes = std::fs::read(d.join("demo.mcap")).unwrap();
    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    let mut first_telemetry = None;
    let mut last_time = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let binary = BINARY_TOPICS.contains(&m.channel.topic.as_str());
        let want = if binary { "protobuf" } else { "json" };
        assert_eq!(m.channel.message_encoding, want, "{}", m.channel.topic);
        let schema = m.channel.schema.as_ref().unwrap();
        let v = support::message_json(&m);
        assert!(m.log_time >= last_time, "messages in time order");
        last_time = m.log_time;
        if m.channel.topic == "/telemetry" && first_telemetry.is_none() {
            first_telemetry = Some((m.log_time, v.clone()));
        }
        if m.channel.topic == "/pose" {
            assert_eq!(schema.name, "foxglove.PoseInFrame");
            assert_eq!(v["frame_id"], "map");
            assert!(v["timestamp"]["sec"].as_u64().unwrap() >= 1_700_000_000);
        }
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    let n = (SECONDS * HZ) as usize;
    let want: BTreeMap<String, usize> = [
        ("/telemetry", n),
        ("/pose", n),
        ("/truth", n),
        ("/truth_pose", n),
        ("/events", 1),
        ("/log", 1),
        ("/commands", 1),
        ("/replies", 1),
        // handshaking, hello, hello reply, connected
        ("/link", 4),
        // map -> base_link per telemetry frame, map -> truth per truth frame
        ("/tf", 2 * n),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    assert_eq!(per_topic, want);
    let (t, v) = first_telemetry.unwrap();
    // Recording start 1_700_000_000_000 ms, first telemetry at 10 ms.
    assert_eq!(t, 1_700_000_000_000 * 1_000_000 + 10_000_000);
    assert_eq!(v["mode"], "Wander");
    assert_eq!(v["x_m"], 1.5);
    assert_eq!(v["ir"].as_array().unwrap().len(), 8);

    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let stats = summary.stats.unwrap();
    assert_eq!(
        stats.message_count as usize,
        per_topic.values().sum::<usize>()
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Every message of `demo.mcap` exported from `demo(SECONDS, HZ)` with `args`, as (topic,
/// channel encoding, schema name, log time, decoded value).
fn exported(name: &str, args: &[&str]) -> Vec<(String, String, String, u64, serde_json::Value)> {
    let d = dir(name);
    std::fs::write(d.join("demo.rec"), demo(SECONDS, HZ)).unwrap();
    let mut all = vec!["export", "demo.rec", "--mcap", "demo.mcap"];
    all.extend_from_slice(args);
    let o = station(&all, &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(d.join("demo.mcap")).unwrap();
    let out = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            (
                m.channel.topic.clone(),
                m.channel.message_encoding.clone(),
                schema.name.clone(),
                m.log_time,
                support::message_json(&m),
            )
        })
        .collect();
    let _ = std::fs::remove_dir_all(&d);
    out
}

/// Issue 15: the binary topics, decoded by the schema the file carries (names, numbers and
/// types from its FileDescriptorSet), hold the recording's values field by field: the third
/// telemetry frame of `demo` and the truth frame after it, as pose, transform and truth.
#[test]
fn protobuf_messages_decode_field_by_field_to_the_recordings_values() {
    use station::record::synth::telemetry;
    let msgs = exported("proto-values", &[]);
    let nth = |topic: &str, n: usize| {
        msgs.iter()
            .filter(|m| m.0 == topic)
            .nth(n)
            .unwrap_or_else(|| panic!("{topic} #{n}"))
            .clone()
    };
    let tm = telemetry(2, HZ);
    let t_us = 10_000 + 2 * 1_000_000 / u64::from(HZ);
    let base_ns = 1_700_000_000_000 * 1_000_000;
    let m = |v: f64| v / 1000.0;
    let (x, y, h) = (
        m(f64::from(tm.pose.x_mm)),
        m(f64::from(tm.pose.y_mm)),
        m(f64::from(tm.pose.heading_mrad)),
    );
    let stamp = |t_us: u64| {
        let ns = base_ns + t_us * 1000;
        serde_json::json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
    };

    let (_, enc, schema, log_time, v) = nth("/telemetry", 2);
    assert_eq!(
        (enc.as_str(), schema.as_str()),
        ("protobuf", "station.Telemetry")
    );
    assert_eq!(log_time, base_ns + t_us * 1000);
    assert_eq!(v["time_s"], t_us as f64 / 1e6);
    assert_eq!(v["robot_time_s"], f64::from(tm.time_ms) / 1000.0);
    assert_eq!(v["mode"], "Wander");
    assert_eq!((v["x_m"].clone(), v["y_m"].clone()), (x.into(), y.into()));
    assert_eq!(v["heading_rad"], h);
    let ir = tm.ir.values();
    assert_eq!(v["ir"], serde_json::json!(ir));
    assert_eq!(v["light"], serde_json::json!([500u16; 8].to_vec()));
    // The demo's Khepera has encoders, IR and light sensors, no compass, battery or beacon.
    assert_eq!(v["enc_left"], 0, "a sensor the robot has is written at 0");
    for lacks in ["compass_deg", "battery_v", "beacon_strength", "on_line"] {
        assert!(v[lacks].is_null(), "{lacks}: {}", v[lacks]);
    }
    assert_eq!(v["flags"], 0);
    assert_eq!(v["contact"], false);

    let (_, enc, schema, _, v) = nth("/pose", 2);
    assert_eq!(
        (enc.as_str(), schema.as_str()),
        ("protobuf", "foxglove.PoseInFrame")
    );
    assert_eq!(v["timestamp"], stamp(t_us));
    assert_eq!(v["frame_id"], "map");
    let p = &v["pose"];
    assert_eq!(p["position"], serde_json::json!({"x": x, "y": y, "z": 0.0}));
    let q = serde_json::json!({"x": 0.0, "y": 0.0, "z": (h / 2.0).sin(), "w": (h / 2.0).cos()});
    assert_eq!(p["orientation"], q);

    // `/tf`: map -> base_link at the telemetry frame, map -> truth at the truth frame.
    let (_, enc, schema, _, v) = nth("/tf", 4);
    assert_eq!(
        (enc.as_str(), schema.as_str()),
        ("protobuf", "foxglove.FrameTransform")
    );
    assert_eq!(v["timestamp"], stamp(t_us));
    assert_eq!(
        (v["parent_frame_id"].as_str(), v["child_frame_id"].as_str()),
        (Some("map"), Some("base_link"))
    );
    assert_eq!(
        v["translation"],
        serde_json::json!({"x": x, "y": y, "z": 0.0})
    );
    assert_eq!(v["rotation"], q);
    let (_, _, _, _, v) = nth("/tf", 5);
    assert_eq!(v["child_frame_id"], "truth");
    assert_eq!(v["timestamp"], stamp(t_us + 200));
    assert_eq!(v["translation"]["x"], m(f64::from(tm.pose.x_mm + 7)));

    let (_, enc, schema, _, v) = nth("/truth", 2);
    assert_eq!(
        (enc.as_str(), schema.as_str()),
        ("protobuf", "station.Truth")
    );
    let want = serde_json::json!({"robot_time_s": f64::from(tm.time_ms) / 1000.0,
        "x_m": m(f64::from(tm.pose.x_mm + 7)), "y_m": y, "heading_rad": h, "collisions": 0});
    assert_eq!(v, want);
    let (_, _, schema, _, v) = nth("/truth_pose", 2);
    assert_eq!(schema, "foxglove.PoseInFrame");
    assert_eq!(v["pose"]["position"]["x"], m(f64::from(tm.pose.x_mm + 7)));
    assert_eq!(v["timestamp"], stamp(t_us + 200));
}

/// The file is whole MCAP by the `mcap` crate's strictest reading (every CRC, the summary,
/// the chunk and message indexes), in both encodings, over a minute at 50 Hz (several chunks).
#[test]
fn the_exported_file_passes_every_check_of_the_mcap_reader() {
    let d = dir("container");
    std::fs::write(d.join("demo.rec"), demo(60, 50)).unwrap();
    for enc in ["protobuf", "json"] {
        let o = station(
            &[
                "export",
                "demo.rec",
                "--mcap",
                "demo.mcap",
                "--force",
                "--mcap-encoding",
                enc,
            ],
            &d,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(d.join("demo.mcap")).unwrap();
        let chunks = support::check_container(&bytes);
        assert!(chunks >= 2, "{enc}: {chunks} chunks");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Whether two decoded messages are equal, numbers to within serde_json's parsing of a
/// double's shortest text (its default parser may be a unit in the last place off).
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value::{Array, Number, Object};
    match (a, b) {
        (Number(x), Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || (x - y).abs() <= 2.0 * f64::EPSILON * x.abs().max(y.abs())
        }
        (Array(x), Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same(x, y)),
        (Object(x), Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

/// `--mcap-encoding json` writes every channel as JSON with JSON schemas (exports before issue
/// 15's binary encoding, for layouts and tools keyed on them), message for message the same
/// values as the protobuf export; a sensor the robot lacks is null there.
#[test]
fn json_encoding_writes_the_same_messages_as_json() {
    let proto = exported("enc-proto", &[]);
    let json = exported("enc-json", &["--mcap-encoding", "json"]);
    assert_eq!(proto.len(), json.len());
    for (p, j) in proto.iter().zip(&json) {
        assert_eq!(j.1, "json", "{}", j.0);
        assert_eq!((&p.0, &p.2, p.3), (&j.0, &j.2, j.3));
        assert!(same(&p.4, &j.4), "{} at {}: {} != {}", p.0, p.3, p.4, j.4);
    }
    let d = dir("enc-schema");
    std::fs::write(d.join("demo.rec"), demo(1, HZ)).unwrap();
    let o = station(
        &[
            "export",
            "demo.rec",
            "--mcap",
            "demo.mcap",
            "--mcap-encoding",
            "json",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(d.join("demo.mcap")).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let tele = summary
        .channels
        .values()
        .find(|c| c.topic == "/telemetry")
        .unwrap();
    let schema = tele.schema.as_ref().unwrap();
    assert_eq!(schema.encoding, "jsonschema");
    let sch: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
    let props = &sch["properties"];
    assert_eq!(props["flags"]["type"], "integer");
    assert_eq!(props["cycle_overruns"]["type"], "integer");
    assert_eq!(
        props["enc_left"]["type"],
        serde_json::json!(["integer", "null"])
    );
    assert_eq!(props["x_m"]["type"], "number");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn csv_export_has_one_row_per_telemetry_frame_with_truth_alongside() {
    let d = dir("csv");
    std::fs::write(d.join("demo.rec"), demo(SECONDS, HZ)).unwrap();
    let o = station(&["export", "demo.rec", "--csv", "demo.csv"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(d.join("demo.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + (SECONDS * HZ) as usize);
    assert_eq!(lines[0], COLUMNS.join(","));
    let col = |name: &str| COLUMNS.iter().position(|c| *c == name).unwrap();
    let row: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(row.len(), COLUMNS.len());
    assert_eq!(row[col("time_s")], "0.010000");
    assert_eq!(row[col("mode")], "Wander");
    assert_eq!(row[col("x_m")], "1.500");
    assert_eq!(row[col("true_x_m")], "1.507", "truth joined by robot time");
    assert_eq!(row[col("battery_v")], "7.400");
    assert_eq!(row[col("light3")], "500");
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    assert_eq!(last[col("robot_time_s")], "9.950");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_corrupted_recording_is_refused_with_its_offset_and_nothing_is_written() {
    let d = dir("bad");
    let good = demo(SECONDS, HZ);
    let mut bad = good.clone();
    let at = good.len() / 2;
    bad[at] ^= 0x40;
    std::fs::write(d.join("bad.rec"), &bad).unwrap();
    std::fs::write(d.join("torn.rec"), &good[..good.len() - 3]).unwrap();
    std::fs::write(d.join("text.rec"), b"hello, world\n").unwrap();
    let mut v3 = good.clone();
    v3[8] = 3;
    std::fs::write(d.join("v3.rec"), &v3).unwrap();
    let before = files(&d);
    let cases = [
        ("bad.rec", "corrupted record at byte"),
        ("torn.rec", "truncated at byte"),
        ("text.rec", "not a station recording"),
        ("v3.rec", "recording format version 3"),
        ("missing.rec", "does not exist"),
    ];
    for (file, needle) in cases {
        let o = station(&["export", file, "--mcap", "o.mcap", "--csv", "o.csv"], &d);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{file}: {err}");
        assert!(err.contains(needle), "{file}: {err}");
        assert!(!err.contains("panicked"), "{file}: {err}");
        assert_eq!(files(&d), before, "{file}: no output, no temporary file");
    }
    // The offset named is where the damage is, not somewhere after it.
    let o = station(&["export", "bad.rec", "--csv", "o.csv"], &d);
    let err = String::from_utf8_lossy(&o.stderr);
    let offset: usize = err
        .split("at byte ")
        .nth(1)
        .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(offset <= at && at - offset < 300, "{offset} vs {at}");

    // --salvage exports what comes before the damage.
    let o = station(&["export", "bad.rec", "--csv", "o.csv", "--salvage"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = std::fs::read_to_string(d.join("o.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert!(rows > 0 && rows < (SECONDS * HZ) as usize, "{rows}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Issue 16: Foxglove's 3D panel shows robot, map and plan together. A session with a map
/// uploaded and the robot's regions and plan downloaded (in chunks, one of them lost and sent
/// again) is exported; the MCAP read back has each scene channel in Foxglove's schema, with a
/// message that places things where the objects say; integer fields are typed integers, and
/// the micro-rato's missing sensors are null.
#[test]
fn mcap_export_carries_the_scene_for_the_3d_panel() {
    use protocol::{caps, Message, ObjectKind, ProfileId, TransferBegin, TransferData};
    use station::plan::{MapOptions, NavMap, Planner};
    use station::record::synth::{demo_peer, telemetry, Synth};
    use station::record::Meta;
    use station::transfer::objects::{map_object, plan_object};

    let map = NavMap::load(emulator::builtin::MICRO_RATO_99, &MapOptions::default()).unwrap();
    let m = map_object(&map).unwrap();
    let planner = Planner::new(map).unwrap();
    let r = planner.plan(Some((0.5, 0.5)), None, false).unwrap();
    let plan = plan_object(&planner, &r, m.id).unwrap();
    let regions = {
        let mut out = vec![0u8; 16 * 1024];
        let n = robot_firmware::transfer::encode_regions_object(
            &planner.regions().unwrap(),
            m.id,
            &mut out,
        )
        .unwrap();
        out.truncate(n);
        out
    };
    let meta = Meta {
        created_unix_ms: 1_700_000_000_000,
        port: "memory".into(),
        protocol: protocol::PROTOCOL_VERSION,
        arena: emulator::builtin::MICRO_RATO_99.into(),
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    let peer = station::link::PeerInfo {
        profile: ProfileId::MicroRato,
        capabilities: caps::IR_PROXIMITY | caps::COMPASS | caps::BEACON | caps::GROUND_SENSOR,
        ..demo_peer()
    };
    s.handshake(peer);
    let mut t = 10_000;
    for i in 0..5 {
        s.from_robot(t, &Message::Telemetry(telemetry(i, 10)));
        t += 100_000;
    }
    // Sends `bytes` as `object` in 100-byte chunks, the second one lost and sent last.
    let send = |s: &mut Synth, t: &mut u64, object, bytes: &[u8], from_robot: bool| {
        let id = protocol::crc32c(bytes);
        let tag = 1 + bytes.len() as u8;
        let begin = Message::TransferBegin(TransferBegin {
            object,
            id,
            len: bytes.len() as u32,
            crc: id,
            tag,
        });
        let mut frames = vec![begin];
        let chunks: Vec<(usize, &[u8])> = bytes.chunks(100).enumerate().collect();
        let order = (0..chunks.len()).filter(|&i| i != 1).chain([1]);
        for i in order {
            frames.push(Message::TransferData(TransferData {
                tag,
                offset: (chunks[i].0 * 100) as u32,
                data: chunks[i].1,
            }));
        }
        for f in &frames {
            *t += 1_000;
            if from_robot {
                s.from_robot(*t, f);
            } else {
                s.to_robot(*t, f);
            }
        }
    };
    send(&mut s, &mut t, ObjectKind::Map, &m.bytes, false);
    send(&mut s, &mut t, ObjectKind::Regions, &regions, true);
    send(&mut s, &mut t, ObjectKind::Plan, &plan, true);
    let d = dir("scene");
    std::fs::write(d.join("scene.rec"), s.finish(t + 1_000, "done")).unwrap();
    let o = station(&["export", "scene.rec", "--mcap", "scene.mcap"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(d.join("scene.mcap")).unwrap();

    let mut first: BTreeMap<String, (String, serde_json::Value, serde_json::Value)> =
        BTreeMap::new();
    let mut count: BTreeMap<String, usize> = BTreeMap::new();
    let mut telemetry_schema = None;
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let schema = msg.channel.schema.as_ref().unwrap();
        let v = support::message_json(&msg);
        // A JSON schema as JSON; a protobuf one is read below, by its fields.
        let sch = serde_json::from_slice(&schema.data).unwrap_or(serde_json::Value::Null);
        if msg.channel.topic == "/telemetry" {
            telemetry_schema = Some(support::descriptor_set(&schema.data));
        }
        *count.entry(msg.channel.topic.clone()).or_default() += 1;
        first
            .entry(msg.channel.topic.clone())
            .or_insert((schema.name.clone(), v, sch));
    }
    for (topic, n) in [
        ("/tf", 5),
        ("/map", 1),
        ("/regions", 1),
        ("/plan", 1),
        ("/arena", 1),
    ] {
        assert_eq!(count.get(topic), Some(&n), "{topic}: {count:?}");
    }
    let (name, tf, _) = &first["/tf"];
    assert_eq!(name, "foxglove.FrameTransform");
    assert_eq!(tf["parent_frame_id"], "map");
    assert_eq!(tf["child_frame_id"], "base_link");
    assert_eq!(tf["translation"]["x"], 1.5);
    assert!(tf["timestamp"]["sec"].as_u64().unwrap() >= 1_700_000_000);

    let (name, grid, sch) = &first["/map"];
    assert_eq!(name, "foxglove.Grid");
    assert_eq!(grid["frame_id"], "map");
    assert_eq!(grid["column_count"], u64::from(m.width));
    assert_eq!(grid["cell_size"]["x"], f64::from(m.cell_mm) / 1000.0);
    assert_eq!(grid["fields"][0]["name"], "occupancy");
    assert_eq!(sch["properties"]["column_count"]["type"], "integer");
    let data = grid["data"].as_str().unwrap();
    assert_eq!(
        data.len(),
        (usize::from(m.width) * usize::from(m.height)).div_ceil(3) * 4,
        "one base64 byte per cell"
    );

    let (name, regions_msg, _) = &first["/regions"];
    assert_eq!(name, "foxglove.SceneUpdate");
    let squares = planner.squares().len();
    let lines = &regions_msg["entities"][0]["lines"][0];
    assert_eq!(lines["points"].as_array().unwrap().len(), squares * 8);
    assert!(
        regions_msg["entities"][0]["timestamp"]["sec"]
            .as_u64()
            .unwrap()
            > 0
    );

    let (name, plan_msg, _) = &first["/plan"];
    assert_eq!(name, "foxglove.SceneUpdate");
    let points = plan_msg["entities"][0]["lines"][0]["points"]
        .as_array()
        .unwrap();
    let want = station::transfer::objects::plan_waypoints(&plan).unwrap();
    assert_eq!(points.len(), want.len());
    assert_eq!(points[0]["x"], want[0].0);

    let (_, arena, _) = &first["/arena"];
    assert!(
        arena["entities"][0]["lines"][0]["points"]
            .as_array()
            .unwrap()
            .len()
            >= 8,
        "the walls"
    );

    // The sensors the micro-rato lacks carry no value (protobuf leaves them out; a reading
    // list is then empty), the ones it has do, even at 0; counters are integers.
    let (_, tele, _) = &first["/telemetry"];
    for absent in ["enc_left", "battery_v", "on_line"] {
        assert!(tele[absent].is_null(), "{absent}: {}", tele[absent]);
    }
    assert_eq!(tele["light"], serde_json::json!([]));
    assert!(tele["compass_deg"].is_number() && tele["on_goal"].is_boolean());
    assert_eq!(tele["ir"].as_array().unwrap().len(), 8);
    let schema = telemetry_schema.unwrap();
    let field = |name: &str| {
        schema["station.Telemetry"]
            .iter()
            .find(|f| f.name == name)
            .unwrap()
            .clone()
    };
    // descriptor.proto's types: 13 uint32, 1 double.
    assert_eq!(field("flags").ty, 13);
    assert_eq!(field("cycle_overruns").ty, 13);
    assert!(field("enc_left").proto3_optional && field("enc_left").ty == 13);
    assert!(!field("flags").proto3_optional);
    assert_eq!(field("x_m").ty, 1);
    let _ = std::fs::remove_dir_all(&d);
}

/// Two robots in one file (format 2): each robot's messages under its own prefix, none on the
/// one-robot names; one CSV file per robot, named by its id.
#[test]
fn a_recording_of_two_robots_exports_per_robot_topics_and_csv_files() {
    use station::record::synth::{demo_robot, merge};
    let d = dir("fleet");
    let both = merge(
        &[
            demo_robot(SECONDS, HZ, 1, "/tmp/robot1"),
            demo_robot(SECONDS / 2, HZ, 2, "/tmp/robot2"),
        ],
        "done",
    );
    std::fs::write(d.join("two.rec"), both).unwrap();
    let o = station(
        &[
            "export", "two.rec", "--mcap", "two.mcap", "--csv", "two.csv",
        ],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        files(&d),
        ["two.mcap", "two.rec", "two.robot1.csv", "two.robot2.csv"]
    );
    let bytes = std::fs::read(d.join("two.mcap")).unwrap();
    // The second robot's channels are added after the first robot's messages.
    support::check_container(&bytes);
    let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        *per_topic
            .entry(m.unwrap().channel.topic.clone())
            .or_default() += 1;
    }
    let n = (SECONDS * HZ) as usize;
    for (topic, want) in [
        ("/robot1/telemetry", n),
        ("/robot1/truth", n),
        ("/robot1/tf", 2 * n),
        ("/robot2/telemetry", n / 2),
        ("/robot2/pose", n / 2),
    ] {
        assert_eq!(
            per_topic.get(topic).copied(),
            Some(want),
            "{topic}: {per_topic:?}"
        );
    }
    assert!(
        per_topic
            .keys()
            .all(|t| t.starts_with("/robot1/") || t.starts_with("/robot2/")),
        "{per_topic:?}"
    );
    let rows = |f: &str| std::fs::read_to_string(d.join(f)).unwrap().lines().count() - 1;
    assert_eq!(rows("two.robot1.csv"), n);
    assert_eq!(rows("two.robot2.csv"), n / 2);
}

/// A version 1 recording (made by the station before recordings had link ids; the good
/// recording the bad-input corpus is made from) still replays and exports, as one robot with
/// today's topic names.
#[test]
fn a_version_1_recording_still_replays_and_exports() {
    let d = dir("v1");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/recording-v1.rec");
    let bytes = std::fs::read(&fixture).unwrap();
    assert_eq!(&bytes[8..10], &[1, 0], "the fixture is version 1");
    std::fs::write(d.join("v1.rec"), &bytes).unwrap();
    let o = station(&["replay", "v1.rec", "--json"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["format_version"], 1);
    assert!(s["damage"].is_null());
    let frames = s["telemetry"]["frames"].as_u64().unwrap();
    assert!(frames > 0, "{s}");
    let o = station(
        &["export", "v1.rec", "--mcap", "v1.mcap", "--csv", "v1.csv"],
        &d,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = std::fs::read_to_string(d.join("v1.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(rows as u64, frames);
    let mcap_bytes = std::fs::read(d.join("v1.mcap")).unwrap();
    let telemetry = mcap::MessageStream::new(&mcap_bytes)
        .unwrap()
        .filter(|m| m.as_ref().unwrap().channel.topic == "/telemetry")
        .count();
    assert_eq!(telemetry as u64, frames);
}

/// A light map is one robot's: `calibrate` refuses a recording of several robots instead of
/// training on their readings mixed, and writes nothing.
#[test]
fn calibrate_refuses_a_recording_of_two_robots() {
    use station::record::synth::{demo_robot, merge};
    let d = dir("calibrate-two");
    let both = merge(
        &[
            demo_robot(2, HZ, 1, "/tmp/robot1"),
            demo_robot(2, HZ, 2, "/tmp/robot2"),
        ],
        "done",
    );
    std::fs::write(d.join("two.rec"), both).unwrap();
    let o = station(
        &["calibrate", "two.rec", "--out", "som.json", "--any-mode"],
        &d,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("holds 2 robots"), "{err}");
    assert_eq!(files(&d), ["two.rec"]);
}

/// What a user asked of the MCAP: events by name, not raw codes; `/log` with the station's own
/// lines (a refusal) beside the robot's; the goal, the beacon and the targets as markers. A
/// recording with the station's log lines and a go-to refused, a go-to and a plan request
/// accepted, and the beacon's parameters read on the micro-rato arena is exported and read
/// back with the mcap crate.
#[test]
fn mcap_export_names_events_logs_the_station_and_marks_goal_beacon_and_targets() {
    use protocol::{Ack, AckInfo, Command, Event, EventCode, Message, Nack, NackReason};
    use protocol::{ParamId, PointMm};
    use station::record::synth::{demo_peer, telemetry, Synth};
    use station::record::{LogSource, Meta, StationLine};

    let arena_name = emulator::builtin::MICRO_RATO_99;
    let arena = emulator::builtin::load(arena_name, &Default::default()).unwrap();
    let meta = Meta {
        created_unix_ms: 1_700_000_000_000,
        port: "memory".into(),
        protocol: protocol::PROTOCOL_VERSION,
        arena: arena_name.into(),
        ..Meta::default()
    };
    let mut s = Synth::new(&meta);
    s.handshake(demo_peer());
    s.from_robot(10_000, &Message::Telemetry(telemetry(0, 10)));
    let refusal = "refused: goto 9.000 0.500 m: bad point: outside the arena";
    let point = |x_mm, y_mm| PointMm { x_mm, y_mm };
    // Each command at `t`, answered 1 ms later by `answer(seq)`.
    let mut t = 20_000;
    let mut ask = |s: &mut Synth, c: Command, answer: &dyn Fn(u16) -> Message<'static>| {
        let seq = s.to_robot(t, &Message::Command(c));
        s.from_robot(t + 1_000, &answer(seq));
        t += 10_000;
    };
    let ack = |info| move |cmd_seq| Message::Ack(Ack { cmd_seq, info });
    ask(&mut s, Command::GoTo(point(9_000, 500)), &|cmd_seq| {
        Message::Nack(Nack {
            cmd_seq,
            reason: NackReason::BadPoint,
        })
    });
    ask(
        &mut s,
        Command::GoTo(point(1_200, 800)),
        &ack(AckInfo::Done),
    );
    let to = Some(point(500, 700));
    ask(
        &mut s,
        Command::Plan { from: None, to },
        &ack(AckInfo::Done),
    );
    for (id, value) in [(21, 2.5), (22, 1.25)] {
        let info = AckInfo::Param {
            id: ParamId(id),
            value,
        };
        ask(&mut s, Command::GetParam { id: ParamId(id) }, &ack(info));
    }
    s.station_log(
        t,
        &StationLine {
            level: protocol::LogLevel::Error,
            source: LogSource::Command,
            text: refusal.into(),
        },
    );
    s.from_robot(
        200_000,
        &Message::Event(Event {
            code: EventCode::ModeChanged,
            value: 2,
        }),
    );
    let d = dir("marks");
    std::fs::write(d.join("marks.rec"), s.finish(300_000, "done")).unwrap();
    let o = station(&["export", "marks.rec", "--mcap", "marks.mcap"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(d.join("marks.mcap")).unwrap();
    support::check_container(&bytes);
    let mut topics: BTreeMap<String, Vec<serde_json::Value>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        topics
            .entry(m.channel.topic.clone())
            .or_default()
            .push(support::message_json(&m));
    }

    let events = &topics["/events"];
    assert_eq!(events.len(), 1);
    assert_eq!(events[0]["name"], "mode changed");
    assert_eq!(events[0]["text"], "mode changed to GoTo");
    assert_eq!(events[0]["value"], 2);

    let log = &topics["/log"];
    let station_lines: Vec<&serde_json::Value> = log
        .iter()
        .filter(|l| l["name"].as_str().unwrap().starts_with("station"))
        .collect();
    assert_eq!(station_lines.len(), 1, "{log:?}");
    assert_eq!(station_lines[0]["name"], "station/command");
    assert_eq!(station_lines[0]["message"], refusal);
    assert_eq!(station_lines[0]["level"], 4, "foxglove.Log ERROR");
    assert!(station_lines[0]["timestamp"]["sec"].as_u64().unwrap() >= 1_700_000_000);

    // Each marker entity by id: its sphere's place and its label.
    let marks = |topic: &str| -> BTreeMap<String, serde_json::Value> {
        let mut by_id = BTreeMap::new();
        for update in &topics[topic] {
            for e in update["entities"].as_array().unwrap() {
                by_id.insert(e["id"].as_str().unwrap().to_string(), e.clone());
            }
        }
        by_id
    };
    let at = |e: &serde_json::Value| {
        let p = &e["spheres"][0]["pose"]["position"];
        (p["x"].as_f64().unwrap(), p["y"].as_f64().unwrap())
    };
    let plan = marks("/plan");
    assert_eq!(
        at(&plan["goal"]),
        (1.2, 0.8),
        "the accepted go-to, not the refused one"
    );
    assert_eq!(plan["goal"]["texts"][0]["text"], "goal");
    assert_eq!(at(&plan["plan_target"]), (0.5, 0.7));
    assert_eq!(topics["/plan"].len(), 2);

    // The arena's beacon at the start, then where the robot's parameters put it.
    let first = &topics["/arena"][0]["entities"];
    let ids: Vec<&str> = first
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids[0], "arena");
    assert!(ids.contains(&"beacon"), "{ids:?}");
    assert_eq!(ids.contains(&"targets"), !arena.targets.is_empty());
    assert_eq!(ids.contains(&"arena_goal"), arena.goal.is_some());
    let b = arena.beacon().unwrap().position;
    let beacon = first
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["id"] == "beacon")
        .unwrap();
    assert_eq!(at(beacon), (b.x, b.y));
    assert_eq!(at(&marks("/arena")["beacon"]), (2.5, 1.25));

    // The station's lines are skipped by a replay, which says them again from the frames.
    let o = station(&["replay", "marks.rec", "--json"], &d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&d);
}
