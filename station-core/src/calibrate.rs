//! The Khepera's light -> angle network (the Khepera foraging paper, §5.3) trained on the
//! station from a recording, with the robot's own code (`robot_firmware::som`, the same
//! `LightSom` the firmware trains online in `Mode::CalibrateLight`); `station calibrate` runs
//! it.
//!
//! Layer: pure functions: [`examples`] turns a recording's
//! telemetry into labelled examples, [`train`] trains and measures a network, [`encode_json`]
//! / [`encode_bin`] and [`decode`] are the map's file formats.
//!
//! Where the labels come from: every telemetry frame carries the pose and the eight ambient
//! readings. The angle of the light from the heading is either
//! - `--light X,Y` given: the bearing from the recorded position to that point minus the
//!   recorded heading (any motion will do, as long as the light is near: a reading below
//!   T1 = 470). The recorded pose must not drift over the recording: odometry heading error
//!   goes straight into the labels; or
//! - by default, as the robot does it: the frames are cut into full turns of the recorded
//!   heading, each turn's readings give the light's direction in that turn (the mean-removed
//!   centroid of the six front readings along their sensors' directions), and the label is
//!   that direction minus the heading. This needs the robot turning on the spot, as in
//!   `Mode::CalibrateLight`.
//!
//! Only frames in `Mode::CalibrateLight` are used unless `--any-mode`. Examples are those with
//! the light within 90 deg of straight ahead (§5.3: a 180 deg rotation), inputs rescaled min ->
//! 50, max -> 500, output `angle + 90` deg. Every fifth example is held out; the report gives
//! the mean and max error on the held-out ones (and on the training ones).
//!
//! File formats (by the `--out` extension, `.json` or anything else binary):
//! - JSON: `{"format": "robot-station light-som", "version": 1, "neurons": 60, "inputs": 6,
//!   "weights": [[w0..w5] x 60], "outputs": [60 angles in degrees], ...}` (figures kept too).
//! - binary, little-endian: magic `"LSOM"`, u16 version 1, u16 neurons, u16 inputs, then per
//!   neuron `inputs` weights and one output as u16 hundredths (the robot's own storage), then
//!   a u32 CRC-32C of every byte before it. 60 x 6: 854 bytes.
//!
//! What can fail: an unreadable or damaged recording (refused unless `--salvage`), one without
//! usable frames (says why), bad arguments, an output that cannot be written. The output is
//! written to a temporary file and renamed when complete, so it is never left half written.

use std::path::Path;

use anyhow::{bail, Context};
use protocol::{Message, Mode, Telemetry};
use robot_firmware::behaviour::XorShift32;
use robot_firmware::som::{rescale, Example, LightSom, Schedule};
use serde::Serialize;

use crate::export::{walk, Direction, Item};
use crate::record::Recording;

/// seed 000 §6.1 T1: a reading below this means a light is near (the robot's own threshold).
pub const T1: u16 = robot_firmware::robot::LIGHT_NEAR_T1;
/// How many front sensors (S0..S5, seed 000 §4.1) the network reads.
const FRONT: usize = 6;
/// Every `HOLD_OUT`-th example is held out for testing.
pub const HOLD_OUT: usize = 5;
const MAGIC: &[u8; 4] = b"LSOM";
const FORMAT: &str = "robot-station light-som";
const FILE_VERSION: u16 = 1;
const NEURONS: usize = 60;

/// How the labels were made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reference {
    /// From a given light position.
    Light,
    /// From each full turn's readings.
    Turns,
}

/// One telemetry frame's part that matters here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Position, metres.
    pub x: f64,
    pub y: f64,
    /// Heading, radians.
    pub heading: f64,
    /// S0..S5 ambient readings.
    pub front: [u16; FRONT],
}

impl Sample {
    fn from_telemetry(t: &Telemetry) -> Sample {
        let light = t.light.values();
        Sample {
            x: f64::from(t.pose.x_mm) / 1000.0,
            y: f64::from(t.pose.y_mm) / 1000.0,
            heading: f64::from(t.pose.heading_mrad) / 1000.0,
            front: std::array::from_fn(|k| light[k]),
        }
    }

    fn lit(&self) -> bool {
        self.front.iter().any(|&v| v < T1)
    }
}

/// What the training gave.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    pub recording: String,
    pub out: String,
    pub bytes: usize,
    pub reference: Reference,
    /// Telemetry frames used (mode and light).
    pub frames: usize,
    /// Full turns found (turn reference only).
    pub turns: usize,
    pub examples: usize,
    pub trained_on: usize,
    pub held_out: usize,
    /// Held-out errors, degrees (paper, on its training rotation: mean 1.52, max 6.52).
    pub mean_deg: f64,
    pub max_deg: f64,
    /// Errors on the training examples, degrees.
    pub train_mean_deg: f64,
    pub train_max_deg: f64,
}

/// The telemetry frames of a recording (in `Mode::CalibrateLight` unless `any_mode`).
pub fn samples(rec: &Recording, any_mode: bool) -> Vec<Sample> {
    let mut out = Vec::new();
    walk(rec, |item| {
        if let Item::Frame {
            dir: Direction::FromRobot,
            msg: Message::Telemetry(t),
            ..
        } = item
        {
            if any_mode || t.mode == Mode::CalibrateLight {
                out.push(Sample::from_telemetry(t));
            }
        }
    });
    out
}

fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    a - t * ((a + std::f64::consts::PI) / t).floor()
}

/// The front sensors' directions from the robot's profile, radians.
fn sensor_angles() -> [f64; FRONT] {
    let a = robot_firmware::KHEPERA.ir.angle_rad;
    std::array::from_fn(|k| f64::from(a[k]))
}

/// The light's direction from one full turn's samples: the readings' centroid along each
/// sensor's direction, each sensor's mean removed, negated (lower is brighter). Weighted by
/// the heading change, so uneven telemetry spacing does not bias it.
fn turn_direction(turn: &[Sample], angles: &[f64; FRONT]) -> Option<f64> {
    let mut v = (0.0, 0.0);
    let mut u = (0.0, 0.0);
    let mut sum = [0.0; FRONT];
    let mut total = 0.0;
    for pair in turn.windows(2) {
        let (p, s) = (&pair[0], &pair[1]);
        let dh = wrap(s.heading - p.heading).abs();
        for ((&r, &a), m) in s.front.iter().zip(angles).zip(sum.iter_mut()) {
            let r = f64::from(r);
            v.0 += r * dh * (s.heading + a).cos();
            v.1 += r * dh * (s.heading + a).sin();
            *m += r * dh;
        }
        u.0 += dh * s.heading.cos();
        u.1 += dh * s.heading.sin();
        total += dh;
    }
    if total <= 0.0 {
        return None;
    }
    for (&m, &a) in sum.iter().zip(angles) {
        let m = m / total;
        let (sa, ca) = a.sin_cos();
        v.0 -= m * (ca * u.0 - sa * u.1);
        v.1 -= m * (sa * u.0 + ca * u.1);
    }
    let strength = v.0.hypot(v.1);
    (strength.is_finite() && strength > 10.0).then(|| (-v.1).atan2(-v.0))
}

/// The turns of `samples`: index ranges over which the heading turns a full circle.
fn turns(samples: &[Sample]) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let (mut start, mut turned) = (0, 0.0);
    for i in 1..samples.len() {
        turned += wrap(samples[i].heading - samples[i - 1].heading).abs();
        if turned >= std::f64::consts::TAU {
            out.push(start..i + 1);
            start = i;
            turned = 0.0;
        }
    }
    out
}

/// Labelled examples (§5.3) from the samples; the reference used and the number of turns.
pub fn examples(
    samples: &[Sample],
    light: Option<(f64, f64)>,
) -> anyhow::Result<(Vec<Example<FRONT>>, Reference, usize)> {
    let mut labelled: Vec<(Sample, f64)> = Vec::new();
    // The likeliest mistake first, in its own words: a robot calibrated far from any lamp.
    if !samples.iter().any(Sample::lit) {
        bail!(
            "no front light reading below T1 = {T1} in {} frames: no lamp near the robot; set \
             it down about 1 cm from one (in the emulator: station --arena builtin:forage \
             --start 0.1825,0.62,0)",
            samples.len()
        );
    }
    let (reference, n_turns) = match light {
        Some((lx, ly)) => {
            for s in samples.iter().filter(|s| s.lit()) {
                labelled.push((*s, wrap((ly - s.y).atan2(lx - s.x) - s.heading)));
            }
            (Reference::Light, 0)
        }
        None => {
            let angles = sensor_angles();
            let ranges = turns(samples);
            let mut found = 0;
            for r in &ranges {
                let turn = &samples[r.clone()];
                if !turn.iter().any(Sample::lit) {
                    continue;
                }
                let Some(dir) = turn_direction(turn, &angles) else {
                    continue;
                };
                found += 1;
                for s in turn.iter().skip(1).filter(|s| s.lit()) {
                    labelled.push((*s, wrap(dir - s.heading)));
                }
            }
            if found == 0 {
                bail!(
                    "no full turn near a light among {} frames ({} full turns): the robot must \
                     turn on the spot next to the light (mode calibrate-light), or give --light X,Y",
                    samples.len(),
                    ranges.len()
                );
            }
            (Reference::Turns, found)
        }
    };
    let half = std::f64::consts::FRAC_PI_2;
    let out: Vec<Example<FRONT>> = labelled
        .iter()
        .filter(|(_, a)| a.abs() <= half)
        .map(|(s, a)| Example {
            inputs: rescale(s.front.map(f32::from), 50.0, 500.0),
            output: (a + half).to_degrees() as f32,
        })
        .collect();
    Ok((out, reference, n_turns))
}

/// (mean, max) absolute recall error over `set`, degrees.
pub fn errors(som: &LightSom, set: &[Example<FRONT>]) -> (f64, f64) {
    let e: Vec<f64> = set
        .iter()
        .filter_map(|ex| {
            som.recall(&ex.inputs)
                .map(|y| f64::from((y - ex.output).abs()))
        })
        .collect();
    if e.is_empty() {
        return (0.0, 0.0);
    }
    (
        e.iter().sum::<f64>() / e.len() as f64,
        e.iter().copied().fold(0.0, f64::max),
    )
}

/// Splits off every `HOLD_OUT`-th example, trains §5.3's network (60 neurons, 20 epochs,
/// width 10 -> 1, rate 0.6 -> 0.1) on the rest; returns it and the (train, held-out) sets.
pub fn train(
    all: &[Example<FRONT>],
    seed: u32,
) -> (LightSom, Vec<Example<FRONT>>, Vec<Example<FRONT>>) {
    let (mut fit, mut test) = (Vec::new(), Vec::new());
    for (i, ex) in all.iter().enumerate() {
        if i % HOLD_OUT == HOLD_OUT - 1 {
            test.push(*ex);
        } else {
            fit.push(*ex);
        }
    }
    let mut rng = XorShift32::new(seed);
    let mut som = LightSom::random(&mut rng, (50.0, 500.0), (0.0, 180.0));
    som.train(&fit, &Schedule::LIGHT, &mut rng);
    (som, fit, test)
}

/// The JSON form of a trained map, with the figures that describe it.
pub fn encode_json(som: &LightSom, report: Option<&Report>) -> anyhow::Result<Vec<u8>> {
    let (weights, outputs): (Vec<[f32; FRONT]>, Vec<f32>) =
        (0..NEURONS).filter_map(|i| som.neuron(i)).unzip();
    let doc = serde_json::json!({
        "format": FORMAT,
        "version": FILE_VERSION,
        "neurons": NEURONS,
        "inputs": FRONT,
        "weights": weights,
        "outputs": outputs,
        // A network downloaded from the robot comes without the station's figures.
        "examples": report.map(|r| r.examples),
        "held_out_mean_deg": report.map(|r| r.mean_deg),
        "held_out_max_deg": report.map(|r| r.max_deg),
    });
    let mut bytes = Vec::new();
    crate::json_text::write_pretty(&mut bytes, &doc)?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// The binary form (see the module text).
pub fn encode_bin(som: &LightSom) -> Vec<u8> {
    let mut out = Vec::with_capacity(14 + NEURONS * (FRONT + 1) * 2);
    out.extend_from_slice(MAGIC);
    for v in [FILE_VERSION, NEURONS as u16, FRONT as u16] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let centi = |v: f32| ((v * 100.0).round().clamp(0.0, 65535.0) as u16).to_le_bytes();
    for (w, o) in (0..NEURONS).filter_map(|i| som.neuron(i)) {
        for v in w {
            out.extend_from_slice(&centi(v));
        }
        out.extend_from_slice(&centi(o));
    }
    let crc = protocol::crc32c(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// The network as a LightCalibration object (PROTOCOL.md §12), what the robot stores.
pub fn light_object(som: &LightSom) -> anyhow::Result<Vec<u8>> {
    let mut out = vec![0; protocol::object::LIGHT_OBJECT_LEN];
    let n = som
        .encode_object(&mut out)
        .map_err(|e| anyhow::anyhow!("light network: {e}"))?;
    out.truncate(n);
    Ok(out)
}

/// A LightCalibration object's network (e.g. downloaded from the robot).
pub fn from_light_object(bytes: &[u8]) -> anyhow::Result<LightSom> {
    let view = protocol::object::LightView::parse(bytes)
        .map_err(|e| anyhow::anyhow!("light calibration object: {e}"))?;
    let mut som = LightSom::from_neurons([[0.0; FRONT]; NEURONS], [0.0; NEURONS]);
    som.load_object(&view);
    Ok(som)
}

/// Reads the map in the file at `path`; errors name the file, and the line and column of a
/// JSON syntax error (`som.json:3:14: JSON light map: expected value`).
pub fn decode_file(path: &Path) -> anyhow::Result<LightSom> {
    let bytes = crate::input_file::read(path, &LIGHT_MAP_FILE)?;
    decode_named(path, &bytes)
}

/// What a light-map file may be (`input_file`'s rule): a map is 854 bytes, its JSON about
/// 11 KB; a mebibyte leaves room for generous white space.
pub const LIGHT_MAP_FILE: crate::input_file::InputKind = crate::input_file::InputKind {
    what: "light maps",
    max_bytes: 1 << 20,
    pipes: false,
};

/// [`decode`] of `bytes` read from `path`, with [`decode_file`]'s errors.
pub fn decode_named(path: &Path, bytes: &[u8]) -> anyhow::Result<LightSom> {
    let shown = path.display();
    if !bytes.starts_with(MAGIC) {
        if let Err(e) = serde_json::from_slice::<serde::de::IgnoredAny>(bytes) {
            // serde_json puts the position last ("... at line 3 column 14"): put it first.
            let text = e.to_string();
            let what = text.split(" at line ").next().unwrap_or(&text);
            bail!(
                "{shown}:{}:{}: JSON light map: {what}",
                e.line(),
                e.column()
            );
        }
    }
    decode(bytes).map_err(|e| anyhow::anyhow!("{shown}: {e:#}"))
}

/// Reads a map written by [`encode_json`] or [`encode_bin`]; errors say what and where.
pub fn decode(bytes: &[u8]) -> anyhow::Result<LightSom> {
    if bytes.starts_with(MAGIC) {
        decode_bin(bytes)
    } else {
        decode_json(bytes)
    }
}

fn decode_bin(bytes: &[u8]) -> anyhow::Result<LightSom> {
    let want = 10 + NEURONS * (FRONT + 1) * 2 + 4;
    if bytes.len() < want {
        bail!(
            "binary light map: byte {}: the file ends early; a map is {want} bytes",
            bytes.len()
        );
    }
    if bytes.len() > want {
        bail!(
            "binary light map: byte {want}: {} bytes after the map's end",
            bytes.len() - want
        );
    }
    let (body, crc) = bytes.split_at(want - 4);
    let stored = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if protocol::crc32c(body) != stored {
        let computed = protocol::crc32c(body);
        bail!(
            "binary light map: byte {}: CRC mismatch (stored {stored:#010x}, computed \
             {computed:#010x})",
            want - 4
        );
    }
    let u16_at = |i: usize| u16::from_le_bytes([body[i], body[i + 1]]);
    let (version, n, m) = (u16_at(4), u16_at(6), u16_at(8));
    if version != FILE_VERSION || usize::from(n) != NEURONS || usize::from(m) != FRONT {
        bail!(
            "binary light map: version {version}, {n} x {m}; this station reads version 1, 60 x 6"
        );
    }
    let mut weights = [[0.0f32; FRONT]; NEURONS];
    let mut outputs = [0.0f32; NEURONS];
    for (i, (w, o)) in weights.iter_mut().zip(outputs.iter_mut()).enumerate() {
        let base = 10 + i * (FRONT + 1) * 2;
        for (k, v) in w.iter_mut().enumerate() {
            *v = f32::from(u16_at(base + 2 * k)) / 100.0;
        }
        let out = u16_at(base + 2 * FRONT);
        if out > protocol::object::LIGHT_MAX_OUTPUT {
            bail!(
                "binary light map: byte {}: neuron {i}'s output {}.{:02} deg is above 180 deg",
                base + 2 * FRONT,
                out / 100,
                out % 100
            );
        }
        *o = f32::from(out) / 100.0;
    }
    Ok(LightSom::from_neurons(weights, outputs))
}

fn decode_json(bytes: &[u8]) -> anyhow::Result<LightSom> {
    #[derive(serde::Deserialize)]
    struct Doc {
        format: String,
        version: u16,
        weights: Vec<Vec<f32>>,
        outputs: Vec<f32>,
    }
    let doc: Doc = serde_json::from_slice(bytes).context("JSON light map")?;
    if doc.format != FORMAT || doc.version != FILE_VERSION {
        bail!(
            "JSON light map: format {:?} version {}; expected {FORMAT:?} version 1",
            doc.format,
            doc.version
        );
    }
    if doc.weights.len() != NEURONS || doc.outputs.len() != NEURONS {
        bail!(
            "JSON light map: {} weight rows and {} outputs, expected {NEURONS}",
            doc.weights.len(),
            doc.outputs.len()
        );
    }
    let mut weights = [[0.0f32; FRONT]; NEURONS];
    for (i, (row, w)) in doc.weights.iter().zip(weights.iter_mut()).enumerate() {
        if row.len() != FRONT || row.iter().any(|v| !(0.0..=655.35).contains(v)) {
            bail!("JSON light map: weights[{i}] must be {FRONT} numbers in 0..=655.35");
        }
        w.copy_from_slice(row);
    }
    // Outputs are the light's angle + 90 deg; the robot takes nothing else (PROTOCOL.md §12).
    if let Some(i) = doc.outputs.iter().position(|v| !(0.0..=180.0).contains(v)) {
        bail!("JSON light map: outputs[{i}] must be an angle + 90 deg in 0..=180");
    }
    let outputs: [f32; NEURONS] = std::array::from_fn(|i| doc.outputs[i]);
    Ok(LightSom::from_neurons(weights, outputs))
}

pub fn is_json(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}
