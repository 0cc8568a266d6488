//! The stored connectivity graph ([`Adjacency`]) against the implicit one.

extern crate std;

use std::collections::BTreeSet;
use std::vec;
use std::vec::Vec;

use super::util::{parse, Seg};
use crate::nav::{Adjacency, Edge, GraphError, RegionGraph, Regions};

fn edges_of<G: RegionGraph>(g: &G) -> BTreeSet<(u32, u32, u32)> {
    let mut out = BTreeSet::new();
    for a in 0..g.region_count() as u32 {
        g.for_each_neighbour(a, |b, cost| {
            out.insert((a, b, cost));
        });
    }
    out
}

#[test]
fn the_stored_graph_has_the_same_edges_and_costs_as_the_border_walk() {
    let g = parse(&["..#.", "....", "....", "#..."]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let directed = Adjacency::edge_count(&regions);
    assert_eq!(directed, 22, "11 undirected edges, see the Fig. 6 test");
    let mut offsets = vec![0u32; regions.len() + 1];
    let mut edges = vec![Edge::default(); directed];
    let adj = Adjacency::build(regions, &mut offsets, &mut edges).expect("sized");
    assert_eq!(edges_of(&adj), edges_of(&regions));
    // A (0,0,2) centre (1, 1) cells to C (2,1,2) centre (3, 2): sqrt(5) cells, rounded up.
    assert!(adj.edges(0).contains(&Edge { to: 2, cost: 573 }));
    assert_eq!(adj.edges(99), &[]);
}

#[test]
fn storage_too_small_for_the_graph_is_an_error() {
    let g = parse(&["..#.", "....", "....", "#..."]);
    let seg = Seg::new(&g).expect("fits");
    let regions = seg.regions(&g);
    let mut offsets = vec![0u32; regions.len()];
    let mut edges = vec![Edge::default(); 22];
    assert_eq!(
        Adjacency::build(regions, &mut offsets, &mut edges).err(),
        Some(GraphError::OffsetsTooSmall { needed: 9 })
    );
    let mut offsets = vec![0u32; regions.len() + 1];
    let mut edges = vec![Edge::default(); 21];
    assert_eq!(
        Adjacency::build(regions, &mut offsets, &mut edges).err(),
        Some(GraphError::EdgesTooSmall { needed: 22 })
    );
}

#[test]
fn views_are_rebuilt_from_stored_parts_only_when_the_sizes_fit() {
    let g = parse(&["...", ".#.", "..."]);
    let seg = Seg::new(&g).expect("fits");
    assert!(Regions::from_segmented(&g, &seg.map[..], &seg.squares[..]).is_some());
    assert!(Regions::from_segmented(&g, &seg.map[..8], &seg.squares[..]).is_none());
    let regions = seg.regions(&g);
    let mut offsets = vec![0u32; regions.len() + 1];
    let mut edges = vec![Edge::default(); Adjacency::edge_count(&regions)];
    Adjacency::build(regions, &mut offsets, &mut edges).expect("sized");
    let stored: Vec<Edge> = edges.clone();
    let again = Adjacency::from_built(regions, &offsets, &stored).expect("sizes fit");
    assert_eq!(edges_of(&again), edges_of(&regions));
    assert!(Adjacency::from_built(regions, &offsets, &stored[1..]).is_none());
    assert!(Adjacency::from_built(regions, &offsets[1..], &stored).is_none());
}
