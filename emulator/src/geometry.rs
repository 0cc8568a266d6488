//! Plane geometry for the simulated world: segments, rays, circles, polygons.
//!
//! Layer: pure maths under the emulator's world, physics and sensor models and the arena
//! importers; no I/O, no allocation in the per-step queries (ray casts, collision tests).
//! Frame: x right, y up, metres. Points are nalgebra `Point2<f64>`, directions `Vector2<f64>`.
//!
//! Invariants: a [`SegmentSet`] is immutable once built; it keeps its walls as one flat `Vec`
//! of segments (bounding boxes computed when queried) and, past [`INDEX_THRESHOLD`] segments, a
//! uniform bucket grid, so a ray visits only the cells it crosses (a 32x32 micromouse maze or
//! the CiberRato 2005 lab has hundreds to ~1000 edges; 8 IR sensors at 12.5 Hz at 10,000x real
//! time is a million rays per second). Queries with non-finite input return "no hit" / `false`
//! rather than panicking; nothing here can fail otherwise.
//!
//! Conventions (the tests pin each one): touching counts — a ray through a segment's endpoint
//! hits it, a circle whose edge exactly reaches a wall collides; a ray starting on a wall hits it
//! at distance 0; a ray parallel to a segment hits it only when collinear, at its nearer end.

pub use nalgebra::{Point2, Vector2};

/// A point in the map frame, metres.
pub type Point = Point2<f64>;
/// A direction or displacement in the map frame.
pub type Vector = Vector2<f64>;

/// Segment count from which a [`SegmentSet`] builds its bucket grid; a small set is scanned flat
/// with bounding-box rejection. Measured by `tests/arena_raycast_speed.rs` (release, 8 rays per
/// pose): Micro-Rato'99's 24 segments flat ~7e6 rays/s; CiberRato 2005's 162 indexed 4.5e6 vs
/// 1.5e6 flat; a 32x32 maze's 1792 indexed 4.6e6 vs 2e5 flat.
pub const INDEX_THRESHOLD: usize = 48;

/// The z component of the 3-D cross product: > 0 when `b` is anticlockwise of `a`.
#[inline]
pub fn cross(a: Vector, b: Vector) -> f64 {
    a.x * b.y - a.y * b.x
}

/// An axis-aligned bounding box (closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower-left corner.
    pub min: Point,
    /// Upper-right corner.
    pub max: Point,
}

impl Aabb {
    /// The box spanning two corners given in any order.
    pub fn from_corners(a: Point, b: Point) -> Self {
        Aabb {
            min: Point::new(a.x.min(b.x), a.y.min(b.y)),
            max: Point::new(a.x.max(b.x), a.y.max(b.y)),
        }
    }

    /// The box around `points`, or `None` when there are none.
    pub fn around(points: impl IntoIterator<Item = Point>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = it.next()?;
        let mut b = Aabb::from_corners(first, first);
        for p in it {
            b.min = Point::new(b.min.x.min(p.x), b.min.y.min(p.y));
            b.max = Point::new(b.max.x.max(p.x), b.max.y.max(p.y));
        }
        Some(b)
    }

    /// The smallest box holding both.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: Point::new(self.min.x.min(o.min.x), self.min.y.min(o.min.y)),
            max: Point::new(self.max.x.max(o.max.x), self.max.y.max(o.max.y)),
        }
    }

    /// This box grown by `r` on every side.
    pub fn expanded(&self, r: f64) -> Aabb {
        Aabb {
            min: Point::new(self.min.x - r, self.min.y - r),
            max: Point::new(self.max.x + r, self.max.y + r),
        }
    }

    /// Width (x extent).
    pub fn width(&self) -> f64 {
        self.max.x - self.min.x
    }

    /// Height (y extent).
    pub fn height(&self) -> f64 {
        self.max.y - self.min.y
    }

    /// True when the closed boxes share at least one point.
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
    }

    /// True when `p` lies in the closed box.
    pub fn contains(&self, p: Point) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }

    /// Distance from `p` to the closed box (0 inside).
    pub fn distance_to_point(&self, p: Point) -> f64 {
        let dx = (self.min.x - p.x).max(0.0).max(p.x - self.max.x);
        let dy = (self.min.y - p.y).max(0.0).max(p.y - self.max.y);
        dx.hypot(dy)
    }

    /// The parameter interval `[t0, t1]` over which `o + t d` lies in the box (slab method),
    /// or `None` when the line misses it.
    pub fn ray_interval(&self, o: Point, d: Vector) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for (oa, da, lo, hi) in [
            (o.x, d.x, self.min.x, self.max.x),
            (o.y, d.y, self.min.y, self.max.y),
        ] {
            if da == 0.0 {
                if oa < lo || oa > hi {
                    return None;
                }
            } else {
                let (a, b) = ((lo - oa) / da, (hi - oa) / da);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

/// A closed line segment from `a` to `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First end.
    pub a: Point,
    /// Second end.
    pub b: Point,
}

impl Segment {
    /// The segment from `a` to `b`.
    pub fn new(a: Point, b: Point) -> Self {
        Segment { a, b }
    }

    /// `b - a`.
    pub fn direction(&self) -> Vector {
        self.b - self.a
    }

    /// Length in metres.
    pub fn length(&self) -> f64 {
        self.direction().norm()
    }

    /// Bounding box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_corners(self.a, self.b)
    }

    /// The point of the segment closest to `p`.
    pub fn closest_point(&self, p: Point) -> Point {
        let e = self.direction();
        let len2 = e.norm_squared();
        if len2 == 0.0 {
            return self.a;
        }
        // Clamp the projection so the answer stays on the segment, not the infinite line.
        let u = ((p - self.a).dot(&e) / len2).clamp(0.0, 1.0);
        self.a + e * u
    }

    /// Euclidean distance from `p` to the segment.
    pub fn distance_to_point(&self, p: Point) -> f64 {
        (p - self.closest_point(p)).norm()
    }

    /// Distance `t >= 0` along the ray `o + t d` to its first point on this segment.
    pub fn ray_hit(&self, o: Point, d: Vector) -> Option<f64> {
        let e = self.direction();
        let ao = self.a - o;
        let denom = cross(d, e);
        if denom == 0.0 {
            // Parallel: only a collinear segment is hit, at its nearest point ahead of the ray.
            if cross(ao, d) != 0.0 || d.norm_squared() == 0.0 {
                return None;
            }
            let dd = d.norm_squared();
            let (ta, tb) = (ao.dot(&d) / dd, (self.b - o).dot(&d) / dd);
            let (lo, hi) = (ta.min(tb), ta.max(tb));
            return if hi < 0.0 { None } else { Some(lo.max(0.0)) };
        }
        let t = cross(ao, e) / denom;
        let u = cross(ao, d) / denom;
        (t >= 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
    }

    /// True when the two closed segments share a point (crossing, touching or overlapping).
    pub fn intersects(&self, o: &Segment) -> bool {
        if !self.aabb().overlaps(&o.aabb()) {
            return false;
        }
        let d1 = cross(self.direction(), o.a - self.a);
        let d2 = cross(self.direction(), o.b - self.a);
        let d3 = cross(o.direction(), self.a - o.a);
        let d4 = cross(o.direction(), self.b - o.a);
        if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
            && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
        {
            return true;
        }
        // Touching or collinear: some endpoint lies on the other segment (boxes overlap, so an
        // endpoint with zero orientation is on it).
        let (sb, ob) = (self.aabb(), o.aabb());
        (d1 == 0.0 && sb.contains(o.a))
            || (d2 == 0.0 && sb.contains(o.b))
            || (d3 == 0.0 && ob.contains(self.a))
            || (d4 == 0.0 && ob.contains(self.b))
    }
}

/// The edges of a closed polygon, last corner back to the first.
pub fn polygon_edges(corners: &[Point]) -> impl Iterator<Item = Segment> + '_ {
    let n = corners.len();
    (0..n).map(move |i| Segment::new(corners[i], corners[(i + 1) % n]))
}

/// Signed area (positive when the corners run anticlockwise).
pub fn polygon_signed_area(corners: &[Point]) -> f64 {
    polygon_edges(corners)
        .map(|s| cross(s.a.coords, s.b.coords))
        .sum::<f64>()
        / 2.0
}

/// Even-odd point-in-polygon test; a point exactly on an edge may go either way, so callers
/// that care about the boundary also check the distance to the edges.
pub fn point_in_polygon(p: Point, corners: &[Point]) -> bool {
    let mut inside = false;
    for s in polygon_edges(corners) {
        // Half-open rule on y so a vertex shared by two edges is counted once.
        if (s.a.y > p.y) != (s.b.y > p.y) {
            let x = s.a.x + (p.y - s.a.y) * (s.b.x - s.a.x) / (s.b.y - s.a.y);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The first pair of edges (indices into [`polygon_edges`]) that cross or overlap other than at
/// the corner adjacent edges share, or `None` for a simple polygon.
pub fn polygon_self_crossing(corners: &[Point]) -> Option<(usize, usize)> {
    let edges: Vec<Segment> = polygon_edges(corners).collect();
    let n = edges.len();
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if adjacent {
                // Neighbours meet at one corner; they are bad only when one folds back onto the
                // other (collinear and pointing back).
                let (e1, e2) = if j == i + 1 {
                    (edges[i], edges[j])
                } else {
                    (edges[j], edges[i])
                };
                let (u, v) = (e1.direction(), e2.direction());
                if cross(u, v) == 0.0 && u.dot(&v) < 0.0 {
                    return Some((i, j));
                }
            } else if edges[i].intersects(&edges[j]) {
                return Some((i, j));
            }
        }
    }
    None
}

/// The nearest hit of a ray cast into a [`SegmentSet`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the ray, in multiples of the direction's length (metres for a unit one).
    pub distance: f64,
    /// Index of the segment hit, into [`SegmentSet::segments`].
    pub segment: usize,
}

/// The wall point nearest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Index of the segment, into [`SegmentSet::segments`].
    pub segment: usize,
    /// Distance from the query point, metres.
    pub distance: f64,
    /// The closest point on that segment.
    pub point: Point,
}

/// Walls for queries: a flat list of segments and, when large, a
/// uniform bucket grid over them.
#[derive(Clone, Debug, Default)]
pub struct SegmentSet {
    // Bounding boxes are recomputed from the segments when queried (a few min/max): storing
    // them doubled a large world's memory (32 bytes a segment) for no measurable speed.
    segments: Vec<Segment>,
    index: Option<BucketGrid>,
}

/// Uniform grid of buckets; each bucket lists the segments whose (slightly grown) bounding box
/// overlaps the cell, in compressed-row form (`starts[c]..starts[c+1]` into `items`).
#[derive(Clone, Debug)]
struct BucketGrid {
    origin: Point,
    cell: f64,
    nx: usize,
    ny: usize,
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl BucketGrid {
    // Largest side in buckets: keeps the grid's memory small whatever the arena's aspect.
    const MAX_SIDE: usize = 256;

    fn build(segments: &[Segment]) -> Option<BucketGrid> {
        let boxes = || segments.iter().map(Segment::aabb);
        let all = boxes().reduce(|a, b| a.union(&b))?;
        let (w, h) = (all.width(), all.height());
        if !(w.is_finite() && h.is_finite()) {
            return None;
        }
        // About one bucket per segment; never thinner than 1/MAX_SIDE of the longer side.
        let longest = w.max(h).max(1e-9);
        let cell = ((w * h) / segments.len() as f64)
            .sqrt()
            .max(longest / Self::MAX_SIDE as f64);
        // A margin of half a cell keeps segments on the outer edge strictly inside the grid.
        let origin = Point::new(all.min.x - cell / 2.0, all.min.y - cell / 2.0);
        let nx = ((w / cell).ceil() as usize + 1).clamp(1, Self::MAX_SIDE + 1);
        let ny = ((h / cell).ceil() as usize + 1).clamp(1, Self::MAX_SIDE + 1);
        let mut grid = BucketGrid {
            origin,
            cell,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        // Two passes (count, fill) so the buckets are one flat array. Boxes grow by a hair so a
        // segment lying exactly on a bucket edge is listed on both sides of it.
        let eps = cell * 1e-9;
        for b in boxes() {
            let (x0, x1, y0, y1) = grid.span(&b.expanded(eps));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    grid.starts[y * nx + x + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut fill: Vec<u32> = grid.starts[..nx * ny].to_vec();
        grid.items = vec![0; grid.starts[nx * ny] as usize];
        for (i, b) in boxes().enumerate() {
            let (x0, x1, y0, y1) = grid.span(&b.expanded(eps));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let slot = &mut fill[y * nx + x];
                    grid.items[*slot as usize] = i as u32;
                    *slot += 1;
                }
            }
        }
        Some(grid)
    }

    fn bounds(&self) -> Aabb {
        Aabb {
            min: self.origin,
            max: Point::new(
                self.origin.x + self.nx as f64 * self.cell,
                self.origin.y + self.ny as f64 * self.cell,
            ),
        }
    }

    fn col(&self, x: f64) -> usize {
        // Float-to-int casts saturate (NaN -> 0), so this clamps rather than panics.
        (((x - self.origin.x) / self.cell).floor().max(0.0) as usize).min(self.nx - 1)
    }

    fn row(&self, y: f64) -> usize {
        (((y - self.origin.y) / self.cell).floor().max(0.0) as usize).min(self.ny - 1)
    }

    /// Inclusive bucket ranges (x0, x1, y0, y1) a box overlaps.
    fn span(&self, b: &Aabb) -> (usize, usize, usize, usize) {
        (
            self.col(b.min.x),
            self.col(b.max.x),
            self.row(b.min.y),
            self.row(b.max.y),
        )
    }

    fn bucket(&self, x: usize, y: usize) -> &[u32] {
        let c = y * self.nx + x;
        &self.items[self.starts[c] as usize..self.starts[c + 1] as usize]
    }
}

impl SegmentSet {
    /// Builds the set; the bucket grid is made when there are [`INDEX_THRESHOLD`] or more.
    pub fn new(segments: Vec<Segment>) -> Self {
        let index = if segments.len() >= INDEX_THRESHOLD {
            BucketGrid::build(&segments)
        } else {
            None
        };
        SegmentSet { segments, index }
    }

    /// Builds the set without the bucket grid, whatever its size (benchmarks, tests).
    pub fn unindexed(segments: Vec<Segment>) -> Self {
        SegmentSet {
            segments,
            index: None,
        }
    }

    /// The segments, in the order given to [`SegmentSet::new`].
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Number of segments.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// True when there are no segments.
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// True when queries go through the bucket grid.
    pub fn is_indexed(&self) -> bool {
        self.index.is_some()
    }

    /// The nearest segment hit by the ray `o + t d`, `0 <= t <= max_t`. `d` should be a unit
    /// vector so that distances are metres; `max_t` may be infinite.
    pub fn ray_cast(&self, o: Point, d: Vector, max_t: f64) -> Option<RayHit> {
        if !(o.x.is_finite() && o.y.is_finite() && d.x.is_finite() && d.y.is_finite())
            || (d.x == 0.0 && d.y == 0.0)
            || max_t.is_nan()
        {
            return None;
        }
        match &self.index {
            Some(grid) => self.ray_indexed(grid, o, d, max_t),
            None => self.ray_scan(0..self.segments.len(), o, d, max_t, None),
        }
    }

    /// True when a wall crosses the open segment from `a` to `b` (line of sight blocked);
    /// a wall that only touches `b` itself does not block.
    pub fn blocks(&self, a: Point, b: Point) -> bool {
        let v = b - a;
        let len = v.norm();
        if len == 0.0 {
            return false;
        }
        self.ray_cast(a, v / len, len)
            .is_some_and(|h| h.distance < len)
    }

    /// True when a disc of `radius` at `c` touches or overlaps any segment.
    pub fn circle_collides(&self, c: Point, radius: f64) -> bool {
        let mut hit = false;
        self.visit_near(c, radius, |i| {
            hit = hit || self.segments[i].distance_to_point(c) <= radius;
        });
        hit
    }

    /// Every segment within `radius` of `c` (touching included), nearest first, into `out`
    /// (cleared first; reuse it across steps to avoid allocating).
    pub fn contacts(&self, c: Point, radius: f64, out: &mut Vec<Nearest>) {
        out.clear();
        self.visit_near(c, radius, |i| {
            let point = self.segments[i].closest_point(c);
            let distance = (c - point).norm();
            if distance <= radius {
                out.push(Nearest {
                    segment: i,
                    distance,
                    point,
                });
            }
        });
        // A segment spanning several buckets is visited once per bucket.
        out.sort_by(|a, b| {
            a.distance
                .total_cmp(&b.distance)
                .then(a.segment.cmp(&b.segment))
        });
        out.dedup_by_key(|n| n.segment);
        out.sort_by(|a, b| a.distance.total_cmp(&b.distance));
    }

    /// The segment nearest to `p` within `max_distance` (may be infinite).
    pub fn nearest(&self, p: Point, max_distance: f64) -> Option<Nearest> {
        let mut best: Option<Nearest> = None;
        let mut consider = |i: usize| {
            let point = self.segments[i].closest_point(p);
            let distance = (p - point).norm();
            if distance <= max_distance && best.is_none_or(|b| distance < b.distance) {
                best = Some(Nearest {
                    segment: i,
                    distance,
                    point,
                });
            }
        };
        if max_distance.is_finite() {
            self.visit_near(p, max_distance, consider);
        } else {
            (0..self.segments.len()).for_each(&mut consider);
        }
        best
    }

    /// The ids of every segment whose box comes within `r` of `c`, ascending, each once, into
    /// `out` (cleared first; reuse it). A superset of the segments within `r` of `c`: several
    /// rays from near `c` that reach no farther than `r` test only these
    /// ([`SegmentSet::ray_cast_among`]) instead of walking the grid (or every segment) each.
    pub fn near_ids(&self, c: Point, r: f64, out: &mut Vec<u32>) {
        out.clear();
        self.visit_near(c, r, |i| out.push(i as u32));
        if self.index.is_some() {
            // A segment spanning several buckets is visited once per bucket.
            out.sort_unstable();
            out.dedup();
        }
    }

    /// [`SegmentSet::ray_cast`] among the segments `ids` only (from [`SegmentSet::near_ids`]
    /// for a disc that holds the whole ray): the same distance, as every segment the ray can
    /// hit is among them.
    pub fn ray_cast_among(&self, ids: &[u32], o: Point, d: Vector, max_t: f64) -> Option<RayHit> {
        if !(o.x.is_finite() && o.y.is_finite() && d.x.is_finite() && d.y.is_finite())
            || (d.x == 0.0 && d.y == 0.0)
            || max_t.is_nan()
        {
            return None;
        }
        self.ray_scan(ids.iter().map(|&i| i as usize), o, d, max_t, None)
    }

    /// Calls `f` with every segment whose box comes within `r` of `c` (possibly repeated).
    fn visit_near(&self, c: Point, r: f64, mut f: impl FnMut(usize)) {
        if !(c.x.is_finite() && c.y.is_finite() && r >= 0.0 && r.is_finite()) {
            return;
        }
        let q = Aabb::from_corners(c, c).expanded(r);
        match &self.index {
            Some(g) if g.bounds().overlaps(&q) => {
                let (x0, x1, y0, y1) = g.span(&q);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        for &i in g.bucket(x, y) {
                            if self.segments[i as usize].aabb().overlaps(&q) {
                                f(i as usize);
                            }
                        }
                    }
                }
            }
            Some(_) => {}
            None => (0..self.segments.len())
                .filter(|&i| self.segments[i].aabb().overlaps(&q))
                .for_each(f),
        }
    }

    /// Scans the given segment ids, rejecting by bounding box against the ray's own box first.
    fn ray_scan(
        &self,
        ids: impl Iterator<Item = usize>,
        o: Point,
        d: Vector,
        max_t: f64,
        mut best: Option<RayHit>,
    ) -> Option<RayHit> {
        let reach = |oa: f64, da: f64| {
            let end = if da == 0.0 { oa } else { oa + da * max_t };
            (oa.min(end), oa.max(end))
        };
        let ((x0, x1), (y0, y1)) = (reach(o.x, d.x), reach(o.y, d.y));
        let ray_box = Aabb {
            min: Point::new(x0, y0),
            max: Point::new(x1, y1),
        };
        for i in ids {
            if !self.segments[i].aabb().overlaps(&ray_box) {
                continue;
            }
            if let Some(t) = self.segments[i].ray_hit(o, d) {
                if t <= max_t && best.is_none_or(|b| t < b.distance) {
                    best = Some(RayHit {
                        distance: t,
                        segment: i,
                    });
                }
            }
        }
        best
    }

    /// Amanatides-Woo traversal of the bucket grid, stopping at the first bucket whose exit lies
    /// beyond the best hit so far (every hit point lies in a bucket listing its segment).
    fn ray_indexed(&self, g: &BucketGrid, o: Point, d: Vector, max_t: f64) -> Option<RayHit> {
        let (t_in, t_out) = g.bounds().ray_interval(o, d)?;
        let t0 = t_in.max(0.0);
        if t_out < t0 || t0 > max_t {
            return None;
        }
        let p = o + d * t0;
        let (mut ix, mut iy) = (g.col(p.x) as isize, g.row(p.y) as isize);
        let axis = |oa: f64, da: f64, i: isize, lo: f64| -> (isize, f64, f64) {
            if da > 0.0 {
                (1, (lo + (i + 1) as f64 * g.cell - oa) / da, g.cell / da)
            } else if da < 0.0 {
                (-1, (lo + i as f64 * g.cell - oa) / da, -g.cell / da)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (sx, mut tx, dtx) = axis(o.x, d.x, ix, g.origin.x);
        let (sy, mut ty, dty) = axis(o.y, d.y, iy, g.origin.y);
        let mut best: Option<RayHit> = None;
        // A straight ray crosses at most nx + ny buckets; the bound also ends the walk when a
        // denormal direction makes both step lengths infinite.
        for _ in 0..g.nx + g.ny + 1 {
            let ids = g
                .bucket(ix as usize, iy as usize)
                .iter()
                .map(|&i| i as usize);
            best = self.ray_scan(ids, o, d, max_t, best);
            let exit = tx.min(ty);
            if best.is_some_and(|b| b.distance <= exit) || exit > max_t || exit > t_out {
                return best;
            }
            if tx < ty {
                ix += sx;
                tx += dtx;
            } else {
                iy += sy;
                ty += dty;
            }
            if ix < 0 || iy < 0 || ix >= g.nx as isize || iy >= g.ny as isize {
                return best;
            }
        }
        best
    }
}

/// A solid disc: another robot's round body, as sensors and the physics see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    /// Centre, metres.
    pub centre: Point,
    /// Radius, metres.
    pub radius: f64,
}

impl Disc {
    /// Distance `t >= 0` along the ray `o + t d` (`d` a unit vector) to the disc's edge; 0 when
    /// `o` is inside it (the same convention as a ray starting on a wall).
    pub fn ray_hit(&self, o: Point, d: Vector) -> Option<f64> {
        let oc = o - self.centre;
        let c = oc.norm_squared() - self.radius * self.radius;
        if !(c.is_finite() && d.x.is_finite() && d.y.is_finite()) {
            return None;
        }
        if c <= 0.0 {
            return Some(0.0);
        }
        let b = oc.dot(&d);
        if b > 0.0 {
            return None; // outside and heading away
        }
        let disc = b * b - c;
        (disc >= 0.0).then(|| -b - disc.sqrt())
    }

    /// True when the disc touches or crosses the segment from `a` to `b` (a line of sight).
    pub fn blocks(&self, a: Point, b: Point) -> bool {
        Segment::new(a, b).distance_to_point(self.centre) <= self.radius
    }

    /// Distance between the edges of two discs (negative when they overlap).
    pub fn gap(&self, o: &Disc) -> f64 {
        (self.centre - o.centre).norm() - self.radius - o.radius
    }
}

#[cfg(test)]
mod tests;
