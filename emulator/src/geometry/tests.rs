use super::*;

fn p(x: f64, y: f64) -> Point {
    Point::new(x, y)
}

fn seg(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
    Segment::new(p(ax, ay), p(bx, by))
}

#[test]
fn ray_hits_a_perpendicular_wall_at_its_distance() {
    let t = seg(2.0, -1.0, 2.0, 1.0).ray_hit(p(0.0, 0.0), Vector::new(1.0, 0.0));
    assert_eq!(t, Some(2.0));
}

#[test]
fn ray_through_an_endpoint_counts_as_a_hit() {
    let s = seg(2.0, 0.0, 2.0, 1.0);
    assert_eq!(s.ray_hit(p(0.0, 0.0), Vector::new(1.0, 0.0)), Some(2.0));
    assert_eq!(s.ray_hit(p(0.0, 1.0), Vector::new(1.0, 0.0)), Some(2.0));
    assert_eq!(s.ray_hit(p(0.0, 1.0 + 1e-12), Vector::new(1.0, 0.0)), None);
}

#[test]
fn ray_parallel_to_a_segment_misses_unless_collinear() {
    let s = seg(1.0, 1.0, 3.0, 1.0);
    assert_eq!(s.ray_hit(p(0.0, 0.0), Vector::new(1.0, 0.0)), None);
    assert_eq!(s.ray_hit(p(0.0, 1.0), Vector::new(1.0, 0.0)), Some(1.0));
    assert_eq!(s.ray_hit(p(2.0, 1.0), Vector::new(1.0, 0.0)), Some(0.0));
    assert_eq!(s.ray_hit(p(4.0, 1.0), Vector::new(1.0, 0.0)), None);
    assert_eq!(s.ray_hit(p(4.0, 1.0), Vector::new(-1.0, 0.0)), Some(1.0));
}

#[test]
fn ray_pointing_away_or_starting_on_the_wall() {
    let s = seg(2.0, -1.0, 2.0, 1.0);
    assert_eq!(s.ray_hit(p(0.0, 0.0), Vector::new(-1.0, 0.0)), None);
    assert_eq!(s.ray_hit(p(2.0, 0.5), Vector::new(1.0, 0.0)), Some(0.0));
}

#[test]
fn segment_set_returns_the_nearest_of_several_hits_within_range() {
    let set = SegmentSet::new(vec![seg(5.0, -1.0, 5.0, 1.0), seg(3.0, -1.0, 3.0, 1.0)]);
    let hit = set.ray_cast(p(0.0, 0.0), Vector::new(1.0, 0.0), f64::INFINITY);
    assert_eq!(
        hit,
        Some(RayHit {
            distance: 3.0,
            segment: 1
        })
    );
    assert_eq!(set.ray_cast(p(0.0, 0.0), Vector::new(1.0, 0.0), 2.9), None);
    assert!(set
        .ray_cast(p(0.0, 0.0), Vector::new(1.0, 0.0), 3.0)
        .is_some());
    assert_eq!(
        set.ray_cast(p(f64::NAN, 0.0), Vector::new(1.0, 0.0), 9.0),
        None
    );
}

#[test]
fn circle_touching_a_wall_collides_and_one_just_apart_does_not() {
    let set = SegmentSet::new(vec![seg(0.0, 0.0, 4.0, 0.0)]);
    assert!(set.circle_collides(p(2.0, 0.5), 0.5));
    assert!(!set.circle_collides(p(2.0, 0.5 + 1e-9), 0.5));
    // Beyond the end the distance is to the endpoint, not the infinite line.
    assert!(!set.circle_collides(p(4.4, 0.4), 0.5));
    assert!(set.circle_collides(p(4.3, 0.4), 0.5));
    let mut out = Vec::new();
    set.contacts(p(2.0, 0.25), 0.5, &mut out);
    assert_eq!(out.len(), 1);
    assert!((out[0].distance - 0.25).abs() < 1e-12 && out[0].point == p(2.0, 0.0));
}

#[test]
fn point_to_segment_distance_uses_the_ends_beyond_the_segment() {
    let s = seg(0.0, 0.0, 2.0, 0.0);
    assert_eq!(s.distance_to_point(p(1.0, 3.0)), 3.0);
    assert_eq!(s.distance_to_point(p(5.0, 4.0)), 5.0);
    assert_eq!(seg(1.0, 1.0, 1.0, 1.0).distance_to_point(p(4.0, 5.0)), 5.0);
}

#[test]
fn segments_cross_touch_overlap_or_stay_apart() {
    assert!(seg(0.0, 0.0, 2.0, 2.0).intersects(&seg(0.0, 2.0, 2.0, 0.0)));
    assert!(seg(0.0, 0.0, 1.0, 0.0).intersects(&seg(1.0, 0.0, 1.0, 5.0)));
    assert!(seg(0.0, 0.0, 2.0, 0.0).intersects(&seg(1.0, 0.0, 3.0, 0.0)));
    assert!(!seg(0.0, 0.0, 1.0, 0.0).intersects(&seg(2.0, 0.0, 3.0, 0.0)));
    assert!(!seg(0.0, 0.0, 1.0, 0.0).intersects(&seg(0.0, 1.0, 1.0, 1.0)));
    assert!(!seg(0.0, 0.0, 1.0, 1.0).intersects(&seg(2.0, 0.0, 1.5, 1.0)));
}

#[test]
fn point_in_a_concave_polygon() {
    // An L like the CiberRato 2005 lab's corner walls.
    let l = [
        p(0.0, 0.0),
        p(2.0, 0.0),
        p(2.0, 1.0),
        p(1.0, 1.0),
        p(1.0, 2.0),
        p(0.0, 2.0),
    ];
    assert!(point_in_polygon(p(0.5, 1.5), &l));
    assert!(point_in_polygon(p(1.5, 0.5), &l));
    assert!(!point_in_polygon(p(1.5, 1.5), &l));
    assert!(!point_in_polygon(p(-0.5, 0.5), &l));
    assert_eq!(polygon_signed_area(&l), 3.0);
    assert_eq!(polygon_self_crossing(&l), None);
    let bow = [p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 1.0)];
    assert_eq!(polygon_self_crossing(&bow), Some((0, 2)));
    let fold = [p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0)];
    assert!(polygon_self_crossing(&fold).is_some());
}

#[test]
fn line_of_sight_is_blocked_only_by_walls_strictly_between() {
    let set = SegmentSet::new(vec![seg(1.0, -1.0, 1.0, 1.0)]);
    assert!(set.blocks(p(0.0, 0.0), p(2.0, 0.0)));
    assert!(!set.blocks(p(0.0, 0.0), p(1.0, 0.0)));
    assert!(!set.blocks(p(0.0, 2.0), p(2.0, 2.0)));
}

// Small deterministic generator so the index is checked against the flat scan on many
// random walls without a dependency.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn bucket_grid_gives_the_same_hits_as_a_flat_scan() {
    let mut r = Lcg(7);
    let mut segs = Vec::new();
    for i in 0..400 {
        let (x, y) = (r.next() * 10.0, r.next() * 5.0);
        // Mix axis-aligned walls (the common case, and grid-edge ties) with random ones.
        segs.push(match i % 3 {
            0 => seg(x.round(), y, x.round(), y + r.next()),
            1 => seg(x, y.round(), x + r.next(), y.round()),
            _ => seg(x, y, x + r.next() - 0.5, y + r.next() - 0.5),
        });
    }
    let indexed = SegmentSet::new(segs.clone());
    assert!(indexed.is_indexed());
    for k in 0..3000 {
        let o = p(r.next() * 12.0 - 1.0, r.next() * 7.0 - 1.0);
        let a = r.next() * std::f64::consts::TAU;
        let d = Vector::new(a.cos(), a.sin());
        let max = if k % 2 == 0 {
            f64::INFINITY
        } else {
            r.next() * 3.0
        };
        let want = indexed
            .ray_scan(0..segs.len(), o, d, max, None)
            .map(|h| h.distance);
        let got = indexed.ray_cast(o, d, max).map(|h| h.distance);
        assert_eq!(got, want, "ray {k} from {o:?} dir {d:?}");
        let radius = r.next() * 0.3;
        let brute = segs.iter().any(|s| s.distance_to_point(o) <= radius);
        assert_eq!(indexed.circle_collides(o, radius), brute);
    }
    // Zero and denormal directions end (the walk is bounded) instead of spinning.
    let o = p(5.0, 2.5);
    assert_eq!(
        indexed.ray_cast(o, Vector::new(0.0, 0.0), f64::INFINITY),
        None
    );
    for d in [
        Vector::new(1e-300, 0.0),
        Vector::new(5e-324, 1e-310),
        Vector::new(0.0, -1e-320),
    ] {
        let _ = indexed.ray_cast(o, d, f64::INFINITY);
    }
}
