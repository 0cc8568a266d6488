//! PROTOCOL.md §12's object examples checked against the encoders and decoders, the errors a
//! decoder reports (what and at which byte), and untrusted bytes that never panic.
//! (`robot-firmware/tests/transfers.rs` checks the same examples against the nav code.)
#![allow(clippy::unwrap_used, clippy::panic)]

use proptest::prelude::*;
use protocol::object::*;
use protocol::{crc32c, ObjectKind, PointMm};

fn p(x_mm: i32, y_mm: i32) -> PointMm {
    PointMm { x_mm, y_mm }
}

/// The example map: 6 x 4, drawn top row first as `##.?..`, `......`, `...#..`, `...#..`.
fn map_example() -> Vec<u8> {
    let rows = ["...#..", "...#..", "......", "##.?.."]; // y = 0 first
    let mut cells = vec![0u8; 6];
    for (y, row) in rows.iter().enumerate() {
        for (x, ch) in row.chars().enumerate() {
            let code = match ch {
                '.' => 1,
                '#' => 2,
                _ => 0,
            };
            let i = y * 6 + x;
            cells[i / 4] |= code << (2 * (i % 4));
        }
    }
    let header = MapHeader {
        width: 6,
        height: 4,
        cell_mm: 300,
        origin: p(-900, 0),
        start: Some(p(-750, 150)),
        goal: Some(p(750, 150)),
    };
    let mut out = vec![0; 64];
    let n = encode_map(&header, &cells, &mut out).unwrap();
    out.truncate(n);
    out
}

fn regions_example(map_id: u32) -> Vec<u8> {
    let sq = |x, y, size| SquareRec { x, y, size };
    let squares = [
        sq(0, 0, 3),
        sq(4, 0, 2),
        sq(3, 2, 1),
        sq(4, 2, 2),
        sq(2, 3, 1),
    ];
    let mut out = vec![0; 64];
    let n = encode_regions(6, 4, map_id, squares, &mut out).unwrap();
    out.truncate(n);
    out
}

fn plan_example(map_id: u32) -> Vec<u8> {
    let nav = NavPlan {
        start: [128, 128],
        goal: [1408, 128],
        regions: 4,
        cost: 2035,
    };
    let waypoints = [
        p(-750, 150),
        p(-450, 450),
        p(150, 750),
        p(600, 900),
        p(600, 300),
        p(750, 150),
    ];
    let meta = PlanMeta {
        smoothed: false,
        map_id,
    };
    let mut out = vec![0; 128];
    let n = encode_plan(meta, &nav, [0, 2, 3, 1], waypoints, &mut out).unwrap();
    out.truncate(n);
    out
}

/// The example light network: neuron `i`'s weight `k` is 50.00 + 7.00 k + 0.50 i (a rescaled
/// reading), its output 3.00 i deg (the angle + 90 deg).
fn light_example() -> Vec<u8> {
    let neurons = (0..LIGHT_NEURONS as u16).map(|i| {
        let w = core::array::from_fn(|k| 5000 + 700 * k as u16 + 50 * i);
        (w, 300 * i)
    });
    let mut out = vec![0; LIGHT_OBJECT_LEN];
    assert_eq!(encode_light(neurons, &mut out), Ok(LIGHT_OBJECT_LEN));
    out
}

fn documented(doc: &str, name: &str) -> Vec<u8> {
    let start = doc
        .find(&format!("\nobject `{name}`\n"))
        .unwrap_or_else(|| panic!("PROTOCOL.md lacks object `{name}`"));
    let mut bytes = Vec::new();
    for line in doc[start + 1..].lines().skip(1) {
        let t = line.trim();
        if t.is_empty() && bytes.is_empty() {
            continue;
        }
        let Some((off, hex)) = t.split_once(": ") else {
            break;
        };
        if usize::from_str_radix(off, 16) != Ok(bytes.len()) {
            break;
        }
        bytes.extend(
            hex.split_whitespace()
                .map(|h| u8::from_str_radix(h, 16).unwrap()),
        );
    }
    bytes
}

#[test]
fn protocol_md_object_examples_match_the_encoders_and_decode_back() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md"))
        .expect("PROTOCOL.md beside the crate");
    let map = map_example();
    let id = crc32c(&map);
    assert_eq!(id, 0xb2be_3c7e, "the id PROTOCOL.md states");
    let regions = regions_example(id);
    let plan = plan_example(id);
    assert_eq!(documented(&doc, "map"), map);
    assert_eq!(documented(&doc, "regions"), regions);
    assert_eq!(documented(&doc, "plan"), plan);

    let ObjectView::Map(m) = parse(&map).unwrap() else {
        panic!("not a map")
    };
    assert_eq!(m.header.goal, Some(p(750, 150)));
    assert_eq!(
        (m.cell(3, 0), m.cell(3, 3), m.cell(0, 3)),
        (Some(2), Some(0), Some(2))
    );
    let ObjectView::Regions(r) = parse(&regions).unwrap() else {
        panic!("not regions")
    };
    assert_eq!(
        r.square(3),
        Some(SquareRec {
            x: 4,
            y: 2,
            size: 2
        })
    );
    assert_eq!(r.squares().count(), 5);
    let ObjectView::Plan(v) = parse(&plan).unwrap() else {
        panic!("not a plan")
    };
    assert_eq!((v.meta.map_id, v.nav.cost), (id, 2035));
    assert_eq!((v.region(1), v.region(4)), (Some(2), None));
    assert_eq!(v.waypoint(3), Some(p(600, 900)));
    assert_eq!(v.nav_block().len(), 24 + 16);
    assert_eq!(crc32c(&plan), 0x7692_f253);

    // The light network is shown only as far as its second neuron; its id pins the rest.
    let light = light_example();
    let shown = documented(&doc, "light");
    assert_eq!(shown.len(), 32);
    assert_eq!(shown, light[..32]);
    let id = crc32c(&light);
    assert!(
        doc.contains(&format!("id `{id:#010x}`")),
        "PROTOCOL.md must state the light example's id {id:#010x}"
    );
    let ObjectView::LightCalibration(l) = parse(&light).unwrap() else {
        panic!("not a light calibration")
    };
    assert_eq!(
        l.neuron(59),
        Some(([7950, 8650, 9350, 10050, 10750, 11450], 17700))
    );
}

fn err(bytes: &[u8]) -> ObjectError {
    parse(bytes).expect_err("malformed")
}

#[test]
fn a_decoder_names_what_is_wrong_and_at_which_byte() {
    let map = map_example();
    let at = |bytes: &[u8]| {
        let e = err(bytes);
        (e.offset, e.problem)
    };
    let mut b = map.clone();
    b[0] = 2;
    assert_eq!(at(&b), (0, Problem::UnsupportedVersion { version: 2 }));
    b = map.clone();
    b[1] = 7;
    assert_eq!(at(&b), (1, Problem::UnknownKind { kind: 7 }));
    b = map.clone();
    b[2] |= 0x80;
    assert_eq!(at(&b), (2, Problem::ReservedNotZero));
    b = map.clone();
    b[2] = 0x01; // goal absent but its coordinates are not zero
    assert_eq!(at(&b), (28, Problem::AbsentPointNotZero));
    b = map.clone();
    b[4] = 0;
    assert_eq!(
        at(&b),
        (
            4,
            Problem::BadSize {
                width: 0,
                height: 4
            }
        )
    );
    b = map.clone();
    b[40] |= 0b1100_0000;
    assert_eq!(at(&b), (40, Problem::ReservedCellCode { cell: 19 }));
    assert_eq!(at(&map[..40]), (40, Problem::Truncated { needed: 42 }));
    b = map.clone();
    b.push(0);
    assert_eq!(at(&b), (42, Problem::TrailingBytes { extra: 1 }));
    assert_eq!(at(&[]), (0, Problem::Truncated { needed: 1 }));
    let e = MapView::parse(&plan_example(1)).unwrap_err();
    assert_eq!(
        e,
        ObjectError {
            offset: 1,
            problem: Problem::WrongKind {
                found: ObjectKind::Plan
            }
        }
    );
    assert_eq!(e.to_string(), "byte 1: expected another object, found Plan");

    let plan = plan_example(1);
    let mut b = plan.clone();
    b[48] = 0; // the waypoint count, at 32 + 4 L with L = 4

    assert_eq!(at(&b), (48, Problem::NoWaypoints));
    let mut b = plan.clone();
    b[24] = 200; // 200 regions: the bytes cannot hold them
    assert_eq!(at(&b).0, 24);
    let regions = regions_example(1);
    let mut b = regions.clone();
    b[12 + 6 * 3 + 4] = 9; // square 3 grows past the map
    assert_eq!(at(&b), (30, Problem::BadSquare { index: 3 }));
}

#[test]
fn encoders_refuse_short_buffers_and_inconsistent_counts() {
    let mut small = [0u8; 10];
    let nav = NavPlan {
        regions: 2,
        ..NavPlan::default()
    };
    let meta = PlanMeta::default();
    let e = encode_plan(meta, &nav, [1], [p(0, 0)], &mut [0u8; 128]).unwrap_err();
    assert_eq!(e.problem, Problem::CountMismatch);
    let e = encode_plan(meta, &NavPlan::default(), [], [p(0, 0)], &mut small).unwrap_err();
    assert_eq!(e.problem, Problem::OutputTooSmall { needed: 44 });
    let e = encode_plan(meta, &NavPlan::default(), [], [], &mut [0u8; 64]).unwrap_err();
    assert_eq!(e.problem, Problem::NoWaypoints);
    let big = [SquareRec {
        x: 0,
        y: 0,
        size: 5,
    }];
    let e = encode_regions(4, 4, 0, big, &mut [0u8; 64]).unwrap_err();
    assert_eq!(e.problem, Problem::BadSquare { index: 0 });
    let h = MapHeader {
        width: 3,
        height: 3,
        cell_mm: 0,
        origin: p(0, 0),
        start: None,
        goal: None,
    };
    assert_eq!(
        encode_map(&h, &[0; 3], &mut [0u8; 64]).unwrap_err().problem,
        Problem::BadCellSize { cell_mm: 0 }
    );
}

/// What `parse` accepts is a valid object: it re-encodes to exactly the bytes it came from
/// (encodings are canonical, PROTOCOL.md §12). Err: the re-encoding.
fn reencodes_to_itself(bytes: &[u8]) -> Result<(), Vec<u8>> {
    let Ok(view) = parse(bytes) else {
        return Ok(());
    };
    let mut out = vec![0; bytes.len()];
    let n = match view {
        ObjectView::Map(m) => encode_map(&m.header, m.cells(), &mut out),
        ObjectView::Regions(r) => {
            let h = r.header;
            encode_regions(
                h.width,
                h.height,
                h.map_id,
                r.squares().collect::<Vec<_>>(),
                &mut out,
            )
        }
        ObjectView::Plan(v) => {
            let regions: Vec<u32> = (0..v.nav.regions).map(|i| v.region(i).unwrap()).collect();
            encode_plan(
                v.meta,
                &v.nav,
                regions,
                v.waypoints().collect::<Vec<_>>(),
                &mut out,
            )
        }
        ObjectView::LightCalibration(l) => encode_light(l.neurons().collect::<Vec<_>>(), &mut out),
    };
    match n {
        Ok(n) if out[..n] == *bytes => Ok(()),
        Ok(n) => Err(out[..n].to_vec()),
        Err(_) => Err(Vec::new()),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Any bytes: a decoder answers, never panics; what it accepts re-encodes to itself.
    #[test]
    fn untrusted_bytes_never_panic_and_accepted_ones_are_canonical(
        kind in 0u8..5,
        body in proptest::collection::vec(any::<u8>(), 0..200),
    ) {
        let mut bytes = vec![1, kind];
        bytes.extend(body);
        prop_assert_eq!(reencodes_to_itself(&bytes), Ok(()));
    }

    /// Valid objects with one byte changed or cut short: an error or another valid object
    /// (one that re-encodes to itself), never a panic.
    #[test]
    fn damaged_objects_are_refused_or_valid(which in 0usize..4, pos in any::<usize>(), val in any::<u8>(), cut in any::<bool>()) {
        let map = map_example();
        let mut b = [map.clone(), regions_example(5), plan_example(5), light_example()][which].clone();
        let i = pos % b.len();
        if cut {
            b.truncate(i);
        } else {
            b[i] = val;
        }
        prop_assert_eq!(reencodes_to_itself(&b), Ok(()));
    }
}
