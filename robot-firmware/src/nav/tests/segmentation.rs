//! Segmentation (seed 004 §6, Fig. 6) on hand-made grids, checked square by square, and the
//! connectivity graph.

extern crate std;

use std::collections::BTreeSet;
use std::vec;
use std::vec::Vec;

use super::reference;
use super::util::{lattice, parse, tuples, Seg};
use crate::nav::{segment, IdStore, PackedIds, SegmentError, Square};

#[test]
fn fig6_takes_the_largest_free_square_at_each_uncovered_cell_in_row_major_order() {
    let g = parse(&["..#.", "....", "....", "#..."]);
    let seg = Seg::new(&g).expect("fits");
    // Hand computation of Fig. 6's rule:
    // (0,0): 2 fits, 3 would take the obstacle at (2,0)      -> A (0,0,2)
    // (1,0) in A; (2,0) obstacle; (3,0): 2 runs off the map  -> B (3,0,1)
    // row 1: (0,1), (1,1) in A; (2,1): 2 fits, 3 runs off    -> C (2,1,2)
    // row 2: (0,2): 2 would take the obstacle (0,3)           -> D (0,2,1)
    //        (1,2): 2 would take (2,2), already in C          -> E (1,2,1)
    // row 3: (0,3) obstacle; (1,3), (2,3), (3,3) at the edge  -> F, G, H of side 1
    assert_eq!(
        tuples(&seg.squares),
        [
            (0, 0, 2),
            (3, 0, 1),
            (2, 1, 2),
            (0, 2, 1),
            (1, 2, 1),
            (1, 3, 1),
            (2, 3, 1),
            (3, 3, 1)
        ]
    );
    #[rustfmt::skip]
    let expected_map = [
        0, 0, u32::MAX, 1,
        0, 0, 2, 2,
        3, 4, 2, 2,
        u32::MAX, 5, 6, 7,
    ];
    assert_eq!(seg.map, expected_map);
}

#[test]
fn a_cell_in_an_earlier_square_cannot_join_a_new_one() {
    let g = parse(&["##...", ".....", ".....", "....."]);
    let seg = Seg::new(&g).expect("fits");
    // (2,0) grows to side 3 (cols 2-4, rows 0-2). At (0,1) the free 3 x 3 square (cols 0-2,
    // rows 1-3) would reuse (2,1) and (2,2), already in that square, so it stops at side 2.
    assert_eq!(
        tuples(&seg.squares),
        [
            (2, 0, 3),
            (0, 1, 2),
            (0, 3, 1),
            (1, 3, 1),
            (2, 3, 1),
            (3, 3, 1),
            (4, 3, 1)
        ]
    );
}

#[test]
fn unknown_cells_are_segmented_exactly_like_obstacles() {
    let known = parse(&["..#..", ".#...", ".....", "...#."]);
    let unknown = parse(&["..?..", ".?...", ".....", "...?."]);
    let (a, b) = (
        Seg::new(&known).expect("fits"),
        Seg::new(&unknown).expect("fits"),
    );
    assert_eq!(a.squares, b.squares);
    assert_eq!(a.map, b.map);
    assert!(b
        .squares
        .iter()
        .all(|s| !s.contains(2, 0) && !s.contains(1, 1) && !s.contains(3, 3)));
}

#[test]
fn an_all_free_grid_is_one_square_and_a_blocked_grid_has_none() {
    let free = parse(&["...", "...", "..."]);
    assert_eq!(tuples(&Seg::new(&free).expect("fits").squares), [(0, 0, 3)]);
    // A non-square free grid: the largest square, then the rest of the rows.
    let wide = parse(&["....", "....", "...."]);
    assert_eq!(
        tuples(&Seg::new(&wide).expect("fits").squares),
        [(0, 0, 3), (3, 0, 1), (3, 1, 1), (3, 2, 1)]
    );
    let blocked = parse(&["#?", "?#"]);
    assert!(Seg::new(&blocked).expect("fits").squares.is_empty());
}

#[test]
fn segmentation_matches_the_letter_of_fig6_on_generated_grids() {
    let mut rng = super::util::Rng(4);
    for round in 0..200 {
        let (w, h) = (1 + rng.below(20) as usize, 1 + rng.below(20) as usize);
        let density = rng.below(70);
        let rows: Vec<std::string::String> = (0..h)
            .map(|_| {
                (0..w)
                    .map(|_| match rng.below(100) {
                        d if d < density => '#',
                        d if d < density + 5 => '?',
                        _ => '.',
                    })
                    .collect()
            })
            .collect();
        let refs: Vec<&str> = rows.iter().map(|r| r.as_str()).collect();
        let g = parse(&refs);
        let seg = Seg::new(&g).expect("fits");
        assert_eq!(seg.squares, reference::fig6(&g), "round {round}: {rows:?}");
    }
}

#[test]
fn a_map_of_the_wrong_length_is_an_error() {
    let g = parse(&["...", "..."]);
    let mut map = [0u32; 5];
    let mut squares = [Square::EMPTY; 6];
    assert_eq!(
        segment(&g, &mut map[..], &mut squares[..]).err(),
        Some(SegmentError::MapSizeMismatch {
            expected: 6,
            got: 5
        })
    );
}

#[test]
fn running_out_of_squares_or_id_width_is_too_many_regions() {
    let g = parse(&[".#.#.", "#.#.#"]);
    let mut map = [0u32; 10];
    let mut squares = [Square::EMPTY; 4];
    assert_eq!(
        segment(&g, &mut map[..], &mut squares[..]).err(),
        Some(SegmentError::TooManyRegions { capacity: 4 })
    );
    // A 2-bit packed map holds ids 0 ..= 2 only (3 marks "none").
    let mut bytes = [0u8; 8];
    let mut packed = PackedIds::<2, _>::new(10, &mut bytes[..]).expect("enough bytes");
    let mut squares = [Square::EMPTY; 10];
    assert_eq!(
        segment(&g, &mut packed, &mut squares[..]).err(),
        Some(SegmentError::TooManyRegions { capacity: 3 })
    );
}

#[test]
fn packed_u16_and_u32_maps_give_the_same_regions() {
    let g = parse(&["..#...", "......", ".?....", "....#."]);
    let wide = Seg::new(&g).expect("fits");
    let mut narrow = vec![0u16; g.len()];
    let mut squares = vec![Square::EMPTY; g.len()];
    let r16 = segment(&g, &mut narrow[..], &mut squares[..]).expect("fits");
    assert_eq!(r16.squares(), &wide.squares[..]);
    let mut bytes = vec![0u8; crate::nav::packed_bytes(5, g.len())];
    let mut packed = PackedIds::<5, _>::new(g.len(), &mut bytes[..]).expect("enough bytes");
    let mut squares = vec![Square::EMPTY; g.len()];
    let rp = segment(&g, &mut packed, &mut squares[..]).expect("fits");
    for i in 0..g.len() {
        let none = |v: u32, n: u32| if v == n { u32::MAX } else { v };
        let p = rp.map().get(i);
        assert_eq!(none(p, 31), wide.map[i], "cell {i}");
    }
}

#[test]
fn neighbours_are_squares_sharing_an_edge_and_corner_contact_does_not_count() {
    let g = parse(&["..#.", "....", "....", "#..."]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut edges = BTreeSet::new();
    regions.for_each_edge(|a, b| {
        assert!(edges.insert((a, b)), "edge ({a}, {b}) reported twice");
    });
    // A(0) B(1) C(2) D(3) E(4) F(5) G(6) H(7) from the Fig. 6 test above; D (0,2) and F (1,3)
    // touch only at a corner.
    let expected: BTreeSet<(u32, u32)> = [
        (0, 2),
        (0, 3),
        (0, 4),
        (1, 2),
        (2, 4),
        (2, 6),
        (2, 7),
        (3, 4),
        (4, 5),
        (5, 6),
        (6, 7),
    ]
    .into_iter()
    .collect();
    assert_eq!(edges, expected);
    assert!(!edges.contains(&(3, 5)));
    let mut of_c: Vec<u32> = regions.neighbours(2).collect();
    of_c.sort_unstable();
    assert_eq!(of_c, [0, 1, 4, 6, 7]);
}

#[test]
fn neighbour_walk_matches_the_quadratic_pairwise_check_on_generated_grids() {
    let mut rng = super::util::Rng(40);
    for _ in 0..100 {
        let (w, h) = (1 + rng.below(30) as usize, 1 + rng.below(30) as usize);
        let cells: Vec<crate::nav::Cell> = (0..w * h)
            .map(|_| {
                if rng.below(100) < 25 {
                    crate::nav::Cell::Obstacle
                } else {
                    crate::nav::Cell::Free
                }
            })
            .collect();
        let g = super::util::from_cells(w, h, &cells);
        let seg = Seg::new(&g).expect("fits");
        let mut walk = BTreeSet::new();
        seg.regions(&g).for_each_edge(|a, b| {
            walk.insert((a, b));
        });
        assert_eq!(walk, reference::edges(&seg.squares));
    }
}

#[test]
fn no_grid_up_to_16_cells_has_more_squares_than_max_regions_and_the_bound_is_reached() {
    use crate::nav::{grid_bytes, max_regions, Cell, Geometry, Grid};
    // Every free/obstacle pattern of every size up to 16 cells (unknown segments as an
    // obstacle, so two states cover all grids).
    for (w, h) in [
        (1, 1),
        (2, 2),
        (3, 3),
        (2, 5),
        (5, 2),
        (3, 4),
        (4, 3),
        (4, 4),
        (2, 8),
    ] {
        let cells = w * h;
        let mut most = 0;
        for bits in 0u32..(1 << cells) {
            let mut g = Grid::new(
                w as u16,
                h as u16,
                Geometry::SEED_004,
                vec![0; grid_bytes(w, h)],
            )
            .expect("valid size");
            for i in 0..cells {
                let c = if bits >> i & 1 == 1 {
                    Cell::Free
                } else {
                    Cell::Obstacle
                };
                g.set(i % w, i / w, c).expect("inside");
            }
            let n = Seg::new(&g)
                .expect("one square per cell fits")
                .squares
                .len();
            assert!(
                n <= max_regions(w, h),
                "{w} x {h} pattern {bits:#x}: {n} squares"
            );
            most = most.max(n);
        }
        assert_eq!(most, max_regions(w, h), "{w} x {h}: the bound is tight");
    }
}

#[test]
fn the_64_by_64_worst_case_is_3072_squares_not_the_checkerboards_2048() {
    use crate::nav::{max_regions, Cell};
    assert_eq!(max_regions(64, 64), 3072);
    for (w, h) in [(64, 64), (63, 64), (17, 17), (28, 28), (1, 64)] {
        let n = Seg::new(&lattice(w, h)).expect("fits").squares.len();
        assert_eq!(n, max_regions(w, h), "{w} x {h}");
    }
    let mut board = lattice(64, 64);
    for y in 0..64 {
        for x in 0..64 {
            let c = if (x + y) % 2 == 0 {
                Cell::Free
            } else {
                Cell::Obstacle
            };
            board.set(x, y, c).expect("inside");
        }
    }
    assert_eq!(Seg::new(&board).expect("fits").squares.len(), 2048);
}
