//! A scripted station for the robot's serial port: handshake, commands with retries, uploads
//! and downloads with the protocol's `Sender` and `Receiver`, an optional lossy line; and the
//! host side of planning (the nav code over `Vec` storage, as the station runs it).
#![allow(dead_code, clippy::unwrap_used, clippy::panic)]

use std::collections::VecDeque;

use protocol::object::PlanView;
use protocol::transfer::{Outcome, Receiver, Sender};
use protocol::*;
use robot_firmware::nav::{
    find_path, grid_bytes, segment, Adjacency, Cell, Edge, Geometry, Grid, GridPoint,
    SearchScratch, Square,
};
use robot_firmware::scripted::ScriptedHal;
use robot_firmware::transfer::{
    encode_map_object, encode_plan_object, encode_regions_object, MAP_OBJECT_MAX,
};
use robot_firmware::AnyRobot;
use robot_firmware::RobotOptions;

/// Seed 004 §5's grid of the Micro-Rato'99 arena at 0.3 m (as `emulator/tests/arena_formats.rs`
/// rasterises wallsMicRato99.xml); the first line is the top row (y = 16), `G` the goal cell.
pub const MICRO_RATO_99: &str = "\
#################
................#
................#
................#
......######.##.#
......######.##.#
......##.....##.#
......##.....##.#
...##.##..G.....#
...##.##.....##.#
...##.##.....##.#
...##.##.....##.#
...##.######.##.#
...##.######.##.#
...##...........#
...##...........#
...##...........#
";

/// A grid from a picture whose first line is the top row; returns it and the `G` cell.
pub fn picture(art: &str) -> (Grid<Vec<u8>>, Option<(u16, u16)>) {
    let rows: Vec<&str> = art.lines().collect();
    let (w, h) = (rows[0].len(), rows.len());
    let mut g = Grid::new(
        w as u16,
        h as u16,
        Geometry::SEED_004,
        vec![0; grid_bytes(w, h)],
    )
    .unwrap();
    let mut goal = None;
    for (line, row) in rows.iter().enumerate() {
        let y = h - 1 - line;
        for (x, ch) in row.chars().enumerate() {
            let cell = match ch {
                '#' => Cell::Obstacle,
                '?' => Cell::Unknown,
                'G' => {
                    goal = Some((x as u16, y as u16));
                    Cell::Free
                }
                _ => Cell::Free,
            };
            g.set(x, y, cell).unwrap();
        }
    }
    (g, goal)
}

pub fn mm(x_mm: i32, y_mm: i32) -> PointMm {
    PointMm { x_mm, y_mm }
}

/// The Micro-Rato'99 map as a Map object, start at cell (1, 1), goal at the beacon cell.
pub fn micro_rato_map() -> (Grid<Vec<u8>>, Vec<u8>, PointMm, PointMm) {
    let (grid, g) = picture(MICRO_RATO_99);
    let (gx, gy) = g.unwrap();
    let geo = grid.geometry();
    let (sx, sy) = geo.cell_centre_mm(1, 1);
    let (gx, gy) = geo.cell_centre_mm(gx, gy);
    let (start, goal) = (mm(sx, sy), mm(gx, gy));
    let mut buf = vec![0; 2048];
    let n = encode_map_object(&grid, Some(start), Some(goal), &mut buf).unwrap();
    buf.truncate(n);
    (grid, buf, start, goal)
}

/// The station's side: segmentation, a stored adjacency with the h cache, A*, all in `Vec`s
/// (another code path than the robot's fixed arrays and implicit graph). Returns the Plan and
/// Regions objects.
pub fn host_plan(
    grid: &Grid<Vec<u8>>,
    map_id: u32,
    from: PointMm,
    to: PointMm,
) -> (Vec<u8>, Vec<u8>) {
    let mut map = vec![0u32; grid.len()];
    let mut squares = vec![Square::EMPTY; grid.len()];
    let regions = segment(grid, &mut map[..], &mut squares[..]).unwrap();
    let n = regions.len();
    let mut offsets = vec![0u32; n + 1];
    let mut edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
    let graph = Adjacency::build(regions, &mut offsets, &mut edges).unwrap();
    let (mut f, mut h) = (vec![0u32; n], vec![0u32; n]);
    let (mut parent, mut heap, mut pos) = (vec![0u32; n], vec![0u32; n], vec![0u32; n]);
    let mut scratch = SearchScratch::new(&mut f, &mut parent[..], &mut heap[..], &mut pos[..])
        .with_h_cache(&mut h);
    let mut path = vec![0u32; n];
    let geo = grid.geometry();
    let (start, goal) = (
        geo.to_grid(from.x_mm, from.y_mm),
        geo.to_grid(to.x_mm, to.y_mm),
    );
    let plan = find_path(&graph, start, goal, &mut scratch, &mut path[..]).unwrap();
    let mut plan_obj = vec![0; 8192];
    let k = encode_plan_object(&regions, &plan, &path[..], map_id, &mut plan_obj).unwrap();
    plan_obj.truncate(k);
    // The embedded nav block is `Plan::encode` itself, and the waypoints are its centres.
    let mut nav = vec![0; plan.encoded_len()];
    plan.encode(&path[..], &mut nav).unwrap();
    let view = PlanView::parse(&plan_obj).unwrap();
    assert_eq!(view.nav_block(), &nav[..]);
    let centres: Vec<PointMm> = plan
        .waypoints(&regions, &path[..])
        .map(|p: GridPoint| {
            let (x, y) = geo.to_mm(p);
            mm(x, y)
        })
        .collect();
    assert_eq!(view.waypoints().collect::<Vec<_>>(), centres);
    let mut reg_obj = vec![0; 8192];
    let k = encode_regions_object(&regions, map_id, &mut reg_obj).unwrap();
    reg_obj.truncate(k);
    (plan_obj, reg_obj)
}

/// What the station received, owned.
#[derive(Clone, Debug, PartialEq)]
pub enum In {
    Ack(u16, AckInfo),
    Nack(u16, NackReason),
    Begin(TransferBegin),
    /// A `TransferData` chunk: tag, offset, data.
    Chunk(u8, u32, Vec<u8>),
    TAck(TransferAck),
}

/// A scripted station on the robot's serial port; `drop` loses frames both ways.
pub struct Station {
    pub robot: AnyRobot,
    pub hal: ScriptedHal,
    pub dec: FrameDecoder,
    pub seq: u16,
    pub rng: u32,
    pub drop: f64,
    pub inbox: VecDeque<In>,
    pub events: Vec<Event>,
    pub telemetry: Option<Telemetry>,
    pub last_tx_ms: u64,
    /// Frames the lossy line ate, both ways.
    pub lost: usize,
    /// The last upload's tag.
    pub tag: u8,
}

impl Station {
    pub fn new(profile: &'static robot_firmware::Profile) -> Self {
        let robot = AnyRobot::new(RobotOptions {
            profile,
            seed: 1,
            start: robot_firmware::odometry::Pose::new(0.5, 0.5, 0.0),
            emulated: false,
            firmware_version: "test",
        });
        let hal = ScriptedHal {
            encoders: profile.has(caps::ENCODERS).then_some([0, 0]),
            compass: Some(0.0),
            ..ScriptedHal::default()
        };
        let mut s = Station {
            robot,
            hal,
            dec: FrameDecoder::new(),
            seq: 0,
            rng: 0x1234_5678,
            drop: 0.0,
            inbox: VecDeque::new(),
            events: Vec::new(),
            telemetry: None,
            last_tx_ms: 0,
            lost: 0,
            tag: 0,
        };
        s.handshake(7);
        s
    }

    /// A handshake with session nonce `session` (a new session when it differs from the
    /// last one).
    pub fn handshake(&mut self, session: u32) {
        self.send(&Message::Hello(Hello {
            fingerprint: FINGERPRINT,
            protocol: PROTOCOL_VERSION,
            session,
            station: "test",
        }));
        self.run(5);
        assert!(self.robot.link().connected());
    }

    pub fn now_ms(&self) -> u32 {
        (self.hal.now_us / 1000) as u32
    }

    pub fn lost(&mut self) -> bool {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 17;
        self.rng ^= self.rng << 5;
        let lost = f64::from(self.rng) / f64::from(u32::MAX) < self.drop;
        self.lost += usize::from(lost);
        lost
    }

    pub fn send_seq(&mut self, seq: u16, msg: &Message<'_>) {
        self.last_tx_ms = self.hal.now_us / 1000;
        if self.lost() {
            return;
        }
        let mut buf = [0u8; MAX_FRAME];
        let n = encode(seq, msg, &mut buf).unwrap();
        assert_eq!(
            self.hal.push_rx(&buf[..n]),
            n,
            "robot's receive buffer overflowed"
        );
    }

    pub fn send(&mut self, msg: &Message<'_>) -> u16 {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        self.send_seq(seq, msg);
        seq
    }

    /// Steps the robot `ms` milliseconds, keeping the link alive, collecting what it sent.
    pub fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            if self.hal.now_us / 1000 >= self.last_tx_ms + 200 {
                self.send(&Message::Heartbeat(Heartbeat { time_ms: 0 }));
            }
            self.robot.step(&mut self.hal);
            self.drain();
            self.hal.now_us += 1000;
        }
    }

    pub fn drain(&mut self) {
        let mut buf = [0u8; 4096];
        let n = self.hal.take_tx(&mut buf);
        let mut input = &buf[..n];
        loop {
            let (m, rest) = match self.dec.feed(input) {
                Feed::NeedMore => break,
                Feed::Error { error, .. } => panic!("robot sent a bad frame: {error}"),
                Feed::Frame { frame, rest } => (frame.message, rest),
            };
            input = rest;
            let item = match m {
                Message::Ack(a) => In::Ack(a.cmd_seq, a.info),
                Message::Nack(n) => In::Nack(n.cmd_seq, n.reason),
                Message::TransferBegin(b) => In::Begin(b),
                Message::TransferData(c) => In::Chunk(c.tag, c.offset, c.data.to_vec()),
                Message::TransferAck(a) => In::TAck(a),
                Message::Event(e) => {
                    self.events.push(e);
                    continue;
                }
                Message::Telemetry(t) => {
                    self.telemetry = Some(t);
                    continue;
                }
                _ => continue,
            };
            if !self.lost() {
                self.inbox.push_back(item);
            }
        }
    }

    /// Sends a command, retrying as a station does (same seq, 200 ms, 5 sends).
    pub fn command(&mut self, c: Command) -> Result<AckInfo, NackReason> {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        for _ in 0..timing::COMMAND_ATTEMPTS {
            self.send_seq(seq, &Message::Command(c));
            for _ in 0..timing::COMMAND_RETRY_MS {
                self.run(1);
                let found = self.inbox.iter().position(|i| match i {
                    In::Ack(s, _) | In::Nack(s, _) => *s == seq,
                    _ => false,
                });
                match found.and_then(|k| self.inbox.remove(k)) {
                    Some(In::Ack(_, info)) => return Ok(info),
                    Some(In::Nack(_, reason)) => return Err(reason),
                    _ => {}
                }
            }
        }
        panic!("{c:?} was never answered");
    }

    /// Uploads `bytes` with `sender`; returns its outcome and the chunk bytes it sent.
    pub fn upload(&mut self, mut sender: Sender, bytes: &[u8]) -> (Outcome, usize) {
        let mut sent = 0;
        for _ in 0..60_000 {
            let now = self.now_ms();
            sender.poll(now, bytes, |m| {
                if let Message::TransferData(c) = m {
                    sent += c.data.len();
                }
                self.send(m);
                true
            });
            self.run(1);
            while let Some(k) = self.inbox.iter().position(|i| matches!(i, In::TAck(_))) {
                if let Some(In::TAck(a)) = self.inbox.remove(k) {
                    sender.on_ack(&a, self.now_ms());
                }
            }
            if let Some(outcome) = sender.outcome() {
                return (outcome, sent);
            }
        }
        panic!("the upload never ended");
    }

    pub fn upload_object(&mut self, object: ObjectKind, bytes: &[u8]) -> Outcome {
        // A new transfer gets the tag after the last one's (PROTOCOL.md §8): a reused tag's
        // eager chunk, its Begin lost, would be answered the last transfer's `Complete`.
        self.tag = protocol::transfer::next_tag(self.tag);
        self.upload(Sender::for_object(object, bytes, self.tag).unwrap(), bytes)
            .0
    }

    /// Downloads an object; returns the Ack's info and the verified bytes.
    pub fn download(&mut self, object: ObjectKind) -> Result<(AckInfo, Vec<u8>), NackReason> {
        let info = self.command(Command::Download { object })?;
        let AckInfo::Object { len, .. } = info else {
            panic!("Download answered {info:?}");
        };
        let mut rx = Receiver::new();
        let mut staging = vec![0u8; len as usize];
        let mut got = None;
        for _ in 0..60_000 {
            self.run(1);
            while let Some(item) = self.inbox.pop_front() {
                let ack = match item {
                    In::Begin(b) => rx.on_begin(&b, staging.len(), false),
                    In::Chunk(tag, offset, data) => {
                        let c = TransferData {
                            tag,
                            offset,
                            data: &data,
                        };
                        rx.on_chunk(&c, &mut staging, |v| {
                            got = Some(v.bytes.to_vec());
                            true
                        })
                    }
                    _ => continue,
                };
                self.send(&Message::TransferAck(ack));
            }
            let robot_done = self.robot.objects().download_progress().is_none();
            if robot_done {
                if let Some(bytes) = got.take() {
                    return Ok((info, bytes));
                }
                panic!(
                    "download ended with {:?}",
                    self.robot.objects().last_download()
                );
            }
        }
        panic!("the download never ended");
    }

    pub fn plan_event_id(&self) -> u32 {
        let e = self
            .events
            .iter()
            .rev()
            .find(|e| e.code == EventCode::PlanInstalled);
        e.unwrap().value as u32
    }

    pub fn map_bytes(&self) -> Vec<u8> {
        let mut out = vec![0; MAP_OBJECT_MAX];
        let n = self.robot.objects().map_object(&mut out).unwrap();
        out.truncate(n);
        out
    }
}
