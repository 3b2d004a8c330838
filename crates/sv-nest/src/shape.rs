//! Collision shapes of sheet parts, made before jagua-rs sees them (it gets a small polygon
//! to take as it is, so its set-up is only the pole surrogate):
//!
//! 1. the outline is grown by half the spacing on its arcs themselves (cavalier_contours);
//! 2. the grown outline is flattened from outside: a convex arc by a polyline of tangents
//!    around it, a concave arc by chords (which lie outside the material), so the polygon
//!    holds the grown outline whatever the chord tolerance;
//! 3. dents are filled, smallest first, while the added area stays within a share of the
//!    part's area (the polygon only grows, so the layout stays valid for the true part);
//! 4. congruent outlines (the same up to a rotation and a translation, as the mirrored
//!    strips of a symmetric surface or the repeated parts of a shop job) share one shape:
//!    [`Congruence`] finds the motion between them.
//!
//! Two shapes that do not overlap keep their parts at least twice the growth apart.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

use cavalier_contours::core::Control;
use cavalier_contours::polyline::{
    PlineCreation, PlineIntersect, PlineOrientation, PlineSource, PlineSourceMut, PlineVertex,
    Polyline,
};

use crate::part::Contour;
pub(crate) use sv_geom::planar::convex_hull;

/// Positions closer than this (mm) are one vertex.
const SAME_POINT: f64 = 1e-9;

/// A rigid motion `p -> R(rotation) p + translation` (radians, mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rigid {
    pub rotation: f64,
    pub translation: [f64; 2],
}

impl Rigid {
    pub const IDENTITY: Self = Self {
        rotation: 0.0,
        translation: [0.0, 0.0],
    };

    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.rotation.sin_cos();
        [
            c * p[0] - s * p[1] + self.translation[0],
            s * p[0] + c * p[1] + self.translation[1],
        ]
    }

    /// `self` after `first`: `p -> self(first(p))`.
    pub fn after(&self, first: &Rigid) -> Rigid {
        Rigid {
            rotation: self.rotation + first.rotation,
            translation: self.apply(first.translation),
        }
    }

    pub fn inverse(&self) -> Rigid {
        let (s, c) = (-self.rotation).sin_cos();
        let [tx, ty] = self.translation;
        Rigid {
            rotation: -self.rotation,
            translation: [-(c * tx - s * ty), -(s * tx + c * ty)],
        }
    }
}

/// The outline of a part as a closed counter-clockwise cavalier polyline without repeated
/// vertices, checked: finite, a positive area, no self-intersection.
pub(crate) fn outline(c: &Contour) -> Result<Polyline<f64>, String> {
    if c.vertices
        .iter()
        .any(|v| !(v.x.is_finite() && v.y.is_finite() && v.bulge.is_finite()))
    {
        return Err("non-finite coordinate".into());
    }
    let mut p = Polyline::with_capacity(c.vertices.len(), true);
    for v in &c.vertices {
        p.add(v.x, v.y, v.bulge);
    }
    let p = p.remove_repeat_pos(SAME_POINT).unwrap_or(p);
    let distinct = p.vertex_count();
    if distinct < 2 || (distinct == 2 && p.iter_vertexes().all(|v| v.bulge.abs() < 1e-12)) {
        return Err("outline has fewer than 3 distinct points (zero size)".into());
    }
    let flat = p
        .extents()
        .is_none_or(|e| (e.max_x - e.min_x).min(e.max_y - e.min_y) <= 1e-9);
    if flat {
        return Err("outline has zero area".into());
    }
    let mut first = None;
    p.visit_self_intersects(&mut |i: PlineIntersect<f64>| {
        let at = match i {
            PlineIntersect::Basic(b) => (b.start_index1, b.start_index2),
            PlineIntersect::Overlapping(o) => {
                if runs_on(&p, o.start_index1, o.start_index2) {
                    return Control::Continue;
                }
                (o.start_index1, o.start_index2)
            }
        };
        first = Some(at);
        Control::Break(())
    });
    if let Some((i, j)) = first {
        return Err(format!(
            "outline is self-intersecting (segments {} and {})",
            i.min(j),
            i.max(j)
        ));
    }
    if p.area().is_nan() || p.area().abs() <= 1e-9 {
        return Err("outline has zero area".into());
    }
    Ok(match p.orientation() {
        PlineOrientation::Clockwise => {
            let mut r = p;
            r.invert_direction_mut();
            r
        }
        _ => p,
    })
}

/// Whether segments `i` and `j` of the closed polyline `p`, which cavalier's tolerance
/// calls overlapping, are neighbours where the one runs on from the other in the same
/// direction: a curve drawn as thousands of short lines turns so little at each vertex
/// that its neighbours look collinear, which is no fold. A real fold runs back.
fn runs_on(p: &Polyline<f64>, i: usize, j: usize) -> bool {
    let n = p.vertex_count();
    let (a, b) = if (i + 1) % n == j {
        (i, j)
    } else if (j + 1) % n == i {
        (j, i)
    } else {
        return false;
    };
    let segment = |k: usize| {
        let (v, w) = (p.at(k), p.at((k + 1) % n));
        sv_geom::Segment {
            start: [v.x, v.y],
            end: [w.x, w.y],
            bulge: v.bulge,
        }
    };
    let (_, into) = segment(a).tangent_angles();
    let (out, _) = segment(b).tangent_angles();
    (out - into).cos() > 0.0
}

/// A checked outline with what the construction orders parts by.
pub(crate) struct Outline {
    pub pline: Polyline<f64>,
    /// area (arcs exact)
    pub area: f64,
    /// area x diameter of the vertices: the construction places large parts first. The
    /// outline's own area, not its convex hull's: the hull of a bowed strip counts the lens
    /// under the bow, which put the most bowed strips first and together on one sheet
    pub key: f64,
    /// bounding box (arcs exact): lower left, upper right
    pub bounds: ([f64; 2], [f64; 2]),
}

impl Outline {
    pub fn new(pline: Polyline<f64>) -> Self {
        // arcs count: a disc is two vertices and two half circles
        let diameter = sv_geom::planar::diameter(&flatten_outside(&pline, 0.5, 0.0));
        let bounds = pline.extents().map_or(([0.0; 2], [0.0; 2]), |e| {
            ([e.min_x, e.min_y], [e.max_x, e.max_y])
        });
        Self {
            area: pline.area(),
            key: pline.area().abs() * diameter,
            bounds,
            pline,
        }
    }
}

/// The outline grown by `d` >= 0 (a counter-clockwise polyline; the outer one when the
/// growth closes a bay into a hole, which the shape then covers).
pub(crate) fn grown(p: &Polyline<f64>, d: f64) -> Polyline<f64> {
    if d <= 0.0 {
        return p.clone();
    }
    // cavalier offsets to the left of the direction of travel: outward is negative for a
    // counter-clockwise polyline
    p.parallel_offset(-d)
        .into_iter()
        .filter(|q| q.area() > 0.0)
        .max_by(|a, b| a.area().total_cmp(&b.area()))
        .unwrap_or_else(|| p.clone())
}

/// The counter-clockwise polyline `p` as a polygon that holds it: straight segments as they
/// are, concave arcs by chords within `tolerance` of the arc, convex arcs by tangent
/// polylines around them within `tolerance`, or by fewer tangents (a quarter turn each at
/// most) when those add less than `tiny_area` (mm²) outside the arc: the small rounds of a
/// grown corner become sharp corners.
pub(crate) fn flatten_outside(p: &Polyline<f64>, tolerance: f64, tiny_area: f64) -> Vec<[f64; 2]> {
    let n = p.vertex_count();
    let mut out = Vec::with_capacity(2 * n);
    for i in 0..n {
        let a = p.at(i);
        let b = p.at((i + 1) % n);
        out.push([a.x, a.y]);
        if a.bulge.abs() < 1e-12 {
            continue;
        }
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let chord = dx.hypot(dy);
        if chord < SAME_POINT {
            continue;
        }
        let theta = 4.0 * a.bulge.atan();
        let r = chord / (2.0 * (theta / 2.0).sin().abs());
        let d = r * (theta / 2.0).cos() * theta.signum();
        let (cx, cy) = (
            a.x + dx / 2.0 - dy / chord * d,
            a.y + dy / 2.0 + dx / chord * d,
        );
        let a0 = (a.y - cy).atan2(a.x - cx);
        let tol = tolerance.clamp(1e-6, r);
        if theta > 0.0 {
            // convex: corners of tangents at r / cos(step / 2), each within `tol` of the arc,
            // or fewer (a quarter turn each at most) when they add less than `tiny_area`
            let max_step = 2.0 * (r / (r + tol)).acos();
            let mut k = ((theta / max_step).ceil() as usize).clamp(1, 4096);
            let excess =
                |k: usize| r * r * (k as f64 * (theta / (2.0 * k as f64)).tan() - theta / 2.0);
            let fewest = ((theta / std::f64::consts::FRAC_PI_2 - 1e-9).ceil() as usize).max(1);
            if let Some(few) = (fewest..k).find(|&j| excess(j) <= tiny_area) {
                k = few;
            }
            let step = theta / k as f64;
            let rr = r / (step / 2.0).cos();
            for j in 0..k {
                let ang = a0 + step * (j as f64 + 0.5);
                out.push([cx + rr * ang.cos(), cy + rr * ang.sin()]);
            }
        } else {
            // concave: chords lie outside the material
            let max_step = 2.0 * (1.0 - tol / r).clamp(-1.0, 1.0).acos();
            let k = ((theta.abs() / max_step.max(1e-3)).ceil() as usize).clamp(1, 4096);
            for j in 1..k {
                let ang = a0 + theta * j as f64 / k as f64;
                out.push([cx + r * ang.cos(), cy + r * ang.sin()]);
            }
        }
    }
    crate::part::dedup_points(&mut out);
    out
}

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Whether `p` lies in the closed triangle `abc` (counter-clockwise or not).
fn in_triangle(p: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (d1, d2, d3) = (cross(a, b, p), cross(b, c, p), cross(c, a, p));
    let neg = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let pos = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(neg && pos)
}

/// One way to simplify the polygon by adding a small area, smallest first (ties: lowest
/// vertex): drop a dent vertex, or replace a short edge between two convex corners by one
/// corner where its neighbouring edges meet.
#[derive(PartialEq)]
struct Step {
    area: f64,
    /// the dent vertex, or the first corner of the edge
    vertex: usize,
    corner: bool,
    /// versions of the vertices involved when the step was found
    versions: (u32, u32),
}

impl Eq for Step {}

impl Ord for Step {
    fn cmp(&self, o: &Self) -> Ordering {
        o.area
            .total_cmp(&self.area)
            .then_with(|| o.vertex.cmp(&self.vertex))
            .then_with(|| o.corner.cmp(&self.corner))
    }
}

impl PartialOrd for Step {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// A uniform grid of vertex indices over the polygon's bounding box, for "is any vertex in
/// this triangle" queries. A vertex that moves is filed again where it went (its old entry
/// stays and is harmless: queries test the current position).
struct Grid {
    lo: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(pts: &[[f64; 2]]) -> Self {
        let (lo, hi) = crate::part::bbox(pts);
        let side = ((hi[0] - lo[0]) * (hi[1] - lo[1]) / pts.len().max(1) as f64)
            .sqrt()
            .max((hi[0] - lo[0]).max(hi[1] - lo[1]) / 1024.0)
            .max(1e-9);
        let nx = (((hi[0] - lo[0]) / side) as usize + 1).min(1024);
        let ny = (((hi[1] - lo[1]) / side) as usize + 1).min(1024);
        let mut g = Self {
            lo,
            cell: side,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, p) in pts.iter().enumerate() {
            g.file(i, *p);
        }
        g
    }

    fn file(&mut self, i: usize, p: [f64; 2]) {
        let (cx, cy) = self.at(p);
        self.cells[cy * self.nx + cx].push(i as u32);
    }

    fn at(&self, p: [f64; 2]) -> (usize, usize) {
        let f = |v: f64, lo: f64, n: usize| (((v - lo) / self.cell).max(0.0) as usize).min(n - 1);
        (f(p[0], self.lo[0], self.nx), f(p[1], self.lo[1], self.ny))
    }

    /// Whether a live vertex other than those in `skip` lies in the closed triangle `tri`
    /// (a vertex on a corner's position counts: dropping would pinch the polygon there).
    fn any_in(&self, tri: [[f64; 2]; 3], skip: &[usize], pts: &[[f64; 2]], alive: &[bool]) -> bool {
        let lo = [
            tri[0][0].min(tri[1][0]).min(tri[2][0]),
            tri[0][1].min(tri[1][1]).min(tri[2][1]),
        ];
        let hi = [
            tri[0][0].max(tri[1][0]).max(tri[2][0]),
            tri[0][1].max(tri[1][1]).max(tri[2][1]),
        ];
        let (x0, y0) = self.at(lo);
        let (x1, y1) = self.at(hi);
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                for &k in &self.cells[cy * self.nx + cx] {
                    let k = k as usize;
                    if !alive[k] || skip.contains(&k) {
                        continue;
                    }
                    let p = pts[k];
                    if p[0] >= lo[0]
                        && p[0] <= hi[0]
                        && p[1] >= lo[1]
                        && p[1] <= hi[1]
                        && in_triangle(p, tri[0], tri[1], tri[2])
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// Simplifies the counter-clockwise simple polygon `pts` by adding area only, smallest
/// additions first, while they add up to at most `budget` (mm²): a dent vertex (a
/// clockwise turn, or none) is dropped, or the edge between two convex corners is replaced
/// by one corner where the neighbouring edges meet (inside the bounding box), when no other
/// vertex lies in the triangle added. The result holds `pts` and keeps at least 4 vertices;
/// it is simple in all but rare cases of an edge passing a replaced corner, which the
/// caller checks ([`is_simple`]).
pub(crate) fn simplify_outside(pts: &[[f64; 2]], budget: f64) -> Vec<[f64; 2]> {
    let n = pts.len();
    if n <= 4 {
        return pts.to_vec();
    }
    let (blo, bhi) = crate::part::bbox(pts);
    let mut pts = pts.to_vec();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let mut version = vec![0u32; n];
    let mut grid = Grid::new(&pts);
    let mut heap = BinaryHeap::new();
    // the steps starting at vertex i: drop i (a dent), or merge the edge i -> next(i)
    let steps = |i: usize, pts: &[[f64; 2]], prev: &[usize], next: &[usize], version: &[u32]| {
        let mut out = Vec::with_capacity(2);
        let (u, w) = (prev[i], next[i]);
        let c = cross(pts[u], pts[i], pts[w]);
        if c <= 0.0 {
            out.push(Step {
                area: -0.5 * c,
                vertex: i,
                corner: false,
                versions: (version[i], version[i]),
            });
        }
        let (v0, v1, v2, v3) = (u, i, w, next[w]);
        if c > 0.0 && cross(pts[v1], pts[v2], pts[v3]) > 0.0 {
            if let Some(x) = corner_point(pts[v0], pts[v1], pts[v2], pts[v3]) {
                if x[0] >= blo[0] && x[0] <= bhi[0] && x[1] >= blo[1] && x[1] <= bhi[1] {
                    out.push(Step {
                        area: 0.5 * cross(pts[v1], x, pts[v2]).abs(),
                        vertex: i,
                        corner: true,
                        versions: (version[v1], version[v2]),
                    });
                }
            }
        }
        out
    };
    for i in 0..n {
        heap.extend(steps(i, &pts, &prev, &next, &version));
    }
    let mut used = 0.0;
    let mut count = n;
    while let Some(st) = heap.pop() {
        if count <= 4 || used + st.area > budget {
            break;
        }
        let i = st.vertex;
        let (u, w) = (prev[i], next[i]);
        if !alive[i] || st.versions != (version[i], if st.corner { version[w] } else { version[i] })
        {
            continue;
        }
        if st.corner {
            let x = match corner_point(pts[u], pts[i], pts[w], pts[next[w]]) {
                Some(x) => x,
                None => continue,
            };
            if grid.any_in([pts[i], x, pts[w]], &[u, i, w, next[w]], &pts, &alive) {
                continue;
            }
            // i moves to x, w goes
            let ww = next[w];
            alive[w] = false;
            next[i] = ww;
            prev[ww] = i;
            pts[i] = x;
            grid.file(i, x);
        } else {
            if grid.any_in([pts[u], pts[i], pts[w]], &[u, i, w], &pts, &alive) {
                continue;
            }
            alive[i] = false;
            next[u] = w;
            prev[w] = u;
        }
        used += st.area;
        count -= 1;
        // every step that involves a vertex next to the change is found again
        let around = if st.corner {
            [prev[u], u, i, next[i]]
        } else {
            [prev[u], u, w, next[w]]
        };
        for k in around {
            version[k] += 1;
        }
        for k in [prev[around[0]], around[0], around[1], around[2], around[3]] {
            heap.extend(steps(k, &pts, &prev, &next, &version));
        }
    }
    let start = (0..n).find(|&i| alive[i]).expect("four vertices stay");
    let mut out = Vec::with_capacity(count);
    let mut i = start;
    loop {
        out.push(pts[i]);
        i = next[i];
        if i == start {
            break;
        }
    }
    out
}

/// Where the line through `v0 v1` continued beyond `v1` meets the line through `v3 v2`
/// continued beyond `v2`, if they meet on that side.
fn corner_point(v0: [f64; 2], v1: [f64; 2], v2: [f64; 2], v3: [f64; 2]) -> Option<[f64; 2]> {
    let d1 = [v1[0] - v0[0], v1[1] - v0[1]];
    let d2 = [v2[0] - v3[0], v2[1] - v3[1]];
    let den = d1[0] * d2[1] - d1[1] * d2[0];
    if den.abs() < 1e-12 {
        return None;
    }
    let e = [v2[0] - v1[0], v2[1] - v1[1]];
    let s = (e[0] * d2[1] - e[1] * d2[0]) / den;
    let t = (e[0] * d1[1] - e[1] * d1[0]) / den;
    (s > 0.0 && t > 0.0).then(|| [v1[0] + s * d1[0], v1[1] + s * d1[1]])
}

/// Whether two closed polygons' edges are free of crossings and touching between
/// non-adjacent edges of one polygon (a sweep over x; `O(n log n)` for the usual shapes).
pub(crate) fn is_simple(pts: &[[f64; 2]]) -> bool {
    let n = pts.len();
    if n < 3 {
        return false;
    }
    let mut order: Vec<usize> = (0..n).collect();
    let xmin = |i: usize| pts[i][0].min(pts[(i + 1) % n][0]);
    let xmax = |i: usize| pts[i][0].max(pts[(i + 1) % n][0]);
    order.sort_by(|&a, &b| xmin(a).total_cmp(&xmin(b)));
    let mut active: Vec<usize> = Vec::new();
    for &i in &order {
        let x = xmin(i);
        active.retain(|&j| xmax(j) >= x);
        for &j in &active {
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                continue;
            }
            if crate::part::segments_intersect(pts[i], pts[(i + 1) % n], pts[j], pts[(j + 1) % n]) {
                return false;
            }
        }
        active.push(i);
    }
    true
}

/// What congruence is tested on: the outline's vertices (counter-clockwise) and, per
/// vertex, the length and bulge of the segment leaving it.
pub(crate) struct Signature {
    vertices: Vec<PlineVertex<f64>>,
    lengths: Vec<f64>,
    /// `(vertex count, area in 0.01 mm², perimeter in 0.01 mm)`: congruent outlines agree
    /// (up to a rounding boundary, which only costs a missed share)
    pub key: (usize, i64, i64),
}

impl Signature {
    pub fn new(p: &Polyline<f64>) -> Self {
        let vertices: Vec<PlineVertex<f64>> = p.iter_vertexes().collect();
        let n = vertices.len();
        let lengths: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                (b.x - a.x).hypot(b.y - a.y)
            })
            .collect();
        let perimeter = p.path_length();
        Self {
            key: (
                n,
                (p.area() * 100.0).round() as i64,
                (perimeter * 100.0).round() as i64,
            ),
            vertices,
            lengths,
        }
    }

    /// The motion `m` with `other ≈ m(self)` (every vertex within `tol` mm, every bulge
    /// within 1e-6), if the two outlines are congruent.
    pub fn motion_to(&self, other: &Signature, tol: f64) -> Option<Rigid> {
        let n = self.vertices.len();
        if n != other.vertices.len() || n == 0 {
            return None;
        }
        let (a0, a1) = (self.vertices[0], self.vertices[1 % n]);
        for k in 0..n {
            if (self.lengths[0] - other.lengths[k]).abs() > tol
                || (self.vertices[0].bulge - other.vertices[k].bulge).abs() > 1e-6
            {
                continue;
            }
            let (b0, b1) = (other.vertices[k], other.vertices[(k + 1) % n]);
            let rotation = (b1.y - b0.y).atan2(b1.x - b0.x) - (a1.y - a0.y).atan2(a1.x - a0.x);
            let r = Rigid {
                rotation,
                translation: [0.0, 0.0],
            };
            let moved = r.apply([a0.x, a0.y]);
            let m = Rigid {
                rotation,
                translation: [b0.x - moved[0], b0.y - moved[1]],
            };
            let fits = (0..n).all(|i| {
                let (a, b) = (self.vertices[i], other.vertices[(i + k) % n]);
                let p = m.apply([a.x, a.y]);
                (p[0] - b.x).hypot(p[1] - b.y) <= tol && (a.bulge - b.bulge).abs() <= 1e-6
            });
            if fits {
                return Some(m);
            }
        }
        None
    }
}

/// Groups of congruent outlines: each outline is either a representative (the first of its
/// kind) or the image of one under a motion.
pub(crate) struct Congruence {
    tol: f64,
    reps: HashMap<(usize, i64, i64), Vec<usize>>,
}

impl Congruence {
    pub fn new(tol: f64) -> Self {
        Self {
            tol,
            reps: HashMap::new(),
        }
    }

    /// The representative `r` among the earlier outlines and the motion `m` with
    /// `outline ≈ m(outline r)`, or `None` when `index` starts a kind of its own.
    pub fn classify(&mut self, index: usize, sigs: &[Signature]) -> Option<(usize, Rigid)> {
        let s = &sigs[index];
        let list = self.reps.entry(s.key).or_default();
        for &r in list.iter() {
            if let Some(m) = sigs[r].motion_to(s, self.tol) {
                return Some((r, m));
            }
        }
        list.push(index);
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part::{point_in_polygon, polygon_area, Vertex};

    /// An L with unequal arms (its mirror image is not a turned copy).
    fn l_shape() -> Contour {
        Contour::polygon(&[
            [0.0, 0.0],
            [100.0, 0.0],
            [100.0, 30.0],
            [30.0, 30.0],
            [30.0, 60.0],
            [0.0, 60.0],
        ])
    }

    #[test]
    fn grown_flattened_outline_holds_every_point_within_the_growth() {
        // a rounded rectangle with a round notch: convex and concave arcs
        let b = (std::f64::consts::FRAC_PI_2 / 4.0).tan();
        let v = |x: f64, y: f64, bulge: f64| Vertex { x, y, bulge };
        let c = Contour {
            vertices: vec![
                v(10.0, 0.0, 0.0),
                v(190.0, 0.0, b),
                v(200.0, 10.0, 0.0),
                v(200.0, 80.0, b),
                v(190.0, 90.0, 0.0),
                v(120.0, 90.0, -1.0),
                v(80.0, 90.0, 0.0),
                v(10.0, 90.0, b),
                v(0.0, 80.0, 0.0),
                v(0.0, 10.0, b),
            ],
        };
        let p = outline(&c).unwrap();
        let g = grown(&p, 3.0);
        let poly = flatten_outside(&g, 0.05, 0.5);
        assert!(is_simple(&poly));
        let filled = simplify_outside(&poly, 0.001 * polygon_area(&poly));
        assert!(is_simple(&filled) && filled.len() < poly.len());
        assert!(polygon_area(&filled) <= polygon_area(&poly) * 1.001 + 1e-9);
        // every point of the part grown by 3 mm (sampled finely on its boundary, pushed
        // out along the normal) is inside both polygons
        let fine = c.flatten(0.001);
        let m = fine.len();
        for i in 0..m {
            let (a, b2) = (fine[i], fine[(i + 1) % m]);
            let (dx, dy) = (b2[0] - a[0], b2[1] - a[1]);
            let l = dx.hypot(dy);
            if l < 1e-9 {
                continue;
            }
            let q = [a[0] + dy / l * 2.999, a[1] - dx / l * 2.999];
            let inside_part = point_in_polygon(q, &fine);
            assert!(
                inside_part || point_in_polygon(q, &poly),
                "{q:?} outside the flattened shape"
            );
            assert!(inside_part || point_in_polygon(q, &filled), "{q:?} lost");
        }
        // and the growth is close: area of the grown outline within 0.2 %
        let exact = g.area();
        assert!(polygon_area(&poly) >= exact && polygon_area(&poly) < exact * 1.002);
    }

    #[test]
    fn bad_outlines_are_named() {
        let bow = Contour::polygon(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]);
        assert!(outline(&bow).unwrap_err().contains("self-intersecting"));
        let flat = Contour::polygon(&[[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]]);
        assert!(outline(&flat).unwrap_err().contains("zero"));
        let nan = Contour::polygon(&[[0.0, 0.0], [f64::NAN, 0.0], [20.0, 5.0]]);
        assert!(outline(&nan).unwrap_err().contains("non-finite"));
        // a circle (two half circles) is fine, and comes out counter-clockwise
        let mut circle = Contour::circle(0.0, 0.0, 5.0);
        for v in &mut circle.vertices {
            v.bulge = -v.bulge;
        }
        let p = outline(&circle).unwrap();
        assert!((p.area() - 25.0 * std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn congruent_outlines_are_found_with_their_motion() {
        let a = outline(&l_shape()).unwrap();
        let m = Rigid {
            rotation: 2.0,
            translation: [500.0, -70.0],
        };
        // the same L turned and moved, listed from another vertex
        let mut pts: Vec<[f64; 2]> = l_shape()
            .vertices
            .iter()
            .map(|v| m.apply([v.x, v.y]))
            .collect();
        pts.rotate_left(2);
        let b = outline(&Contour::polygon(&pts)).unwrap();
        // its mirror image is not congruent (a plate is not turned over)
        let mirrored: Vec<[f64; 2]> = l_shape()
            .vertices
            .iter()
            .rev()
            .map(|v| [-v.x, v.y])
            .collect();
        let c = outline(&Contour::polygon(&mirrored)).unwrap();
        let sigs = [Signature::new(&a), Signature::new(&b), Signature::new(&c)];
        let mut groups = Congruence::new(1e-4);
        assert!(groups.classify(0, &sigs).is_none());
        let (rep, found) = groups.classify(1, &sigs).expect("congruent");
        assert_eq!(rep, 0);
        for v in l_shape().vertices {
            let (p, q) = (found.apply([v.x, v.y]), m.apply([v.x, v.y]));
            assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        }
        assert!(groups.classify(2, &sigs).is_none());
        // motions compose and invert
        let back = found.inverse().after(&found);
        let p = back.apply([3.0, 4.0]);
        assert!((p[0] - 3.0).abs() < 1e-9 && (p[1] - 4.0).abs() < 1e-9);
    }
}
