//! The one closed 2D contour of the workspace: straight segments and circular arcs, stored
//! as DXF-style bulge vertices, with the operations every stage needs (flatten, area,
//! length, containment, rigid and conformal maps, offsets), most of them computed by
//! [`cavalier_contours`] on the arcs themselves.
//!
//! ```text
//!        bulge b = tan(sweep / 4)         b > 0: counter-clockwise arc
//!    v[i] ●────────────────● v[i+1]       b = 0: straight segment
//!          ╲     sweep    ╱               b = 1: half circle
//!            ╲    ╭─╮   ╱
//!              ╲  │c│ ╱   radius = chord (1 + b²) / (4 |b|)
//! ```
//!
//! Conventions: lengths in mm, y up, angles in radians counter-clockwise from +x. A contour
//! is closed (the last vertex joins the first) and may run either way; `signed_area` tells
//! which (positive counter-clockwise).
//!
//! ```
//! use sv_geom::Contour;
//! let disc = Contour::circle(0.0, 0.0, 10.0);
//! assert!((disc.area() - std::f64::consts::PI * 100.0).abs() < 1e-9);
//! assert!((disc.length() - 20.0 * std::f64::consts::PI).abs() < 1e-9);
//! assert!(disc.contains([3.0, 4.0]) && !disc.contains([8.0, 8.0]));
//! let grown = disc.offset(2.0);
//! assert!((grown[0].area() - std::f64::consts::PI * 144.0).abs() < 1e-6);
//! ```

use cavalier_contours::core::math::Vector2 as CVector2;
use cavalier_contours::polyline::{
    seg_arc_radius_and_center, seg_closest_point, seg_length, seg_midpoint, PlineCreation,
    PlineSource, PlineVertex, Polyline,
};
use serde::{Deserialize, Serialize};

/// Bulges below this in magnitude are straight segments (a sagitta of 1e-12 of the chord).
pub const BULGE_EPS: f64 = 1e-12;

/// A contour vertex: the start of a segment running to the next vertex. `bulge` is
/// `tan(sweep / 4)` of that segment (0 straight, > 0 counter-clockwise arc, 1 a half
/// circle). Written `[x, y, bulge]` in files (`strips.json`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "[f64; 3]", into = "[f64; 3]")]
pub struct Vertex {
    /// x (mm)
    pub x: f64,
    /// y (mm)
    pub y: f64,
    /// bulge of the segment leaving this vertex
    pub bulge: f64,
}

impl Vertex {
    /// A vertex with its bulge.
    pub const fn new(x: f64, y: f64, bulge: f64) -> Self {
        Self { x, y, bulge }
    }

    /// A vertex followed by a straight segment.
    pub const fn line(x: f64, y: f64) -> Self {
        Self { x, y, bulge: 0.0 }
    }

    /// The position `[x, y]`.
    pub const fn point(&self) -> [f64; 2] {
        [self.x, self.y]
    }

    fn pline(self) -> PlineVertex<f64> {
        PlineVertex::new(self.x, self.y, self.bulge)
    }
}

impl From<[f64; 3]> for Vertex {
    fn from(v: [f64; 3]) -> Self {
        Self::new(v[0], v[1], v[2])
    }
}

impl From<Vertex> for [f64; 3] {
    fn from(v: Vertex) -> Self {
        [v.x, v.y, v.bulge]
    }
}

/// One segment of a contour: from `start` to `end`, straight or a circular arc of bulge
/// `bulge`. All the arc maths of the workspace lives here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First point.
    pub start: [f64; 2],
    /// Last point.
    pub end: [f64; 2],
    /// `tan(sweep / 4)`, 0 for a straight segment.
    pub bulge: f64,
}

impl Segment {
    /// Whether the segment is an arc (bulge above [`BULGE_EPS`] and a chord above zero).
    pub fn is_arc(&self) -> bool {
        self.bulge.abs() > BULGE_EPS && self.chord() > BULGE_EPS
    }

    /// Length of the chord from start to end.
    pub fn chord(&self) -> f64 {
        (self.end[0] - self.start[0]).hypot(self.end[1] - self.start[1])
    }

    /// Signed sweep angle (rad, counter-clockwise positive; 0 when straight).
    pub fn sweep(&self) -> f64 {
        4.0 * self.bulge.atan()
    }

    /// Radius and centre of an arc; `None` for a straight segment.
    pub fn arc(&self) -> Option<(f64, [f64; 2])> {
        self.is_arc().then(|| {
            let (r, c) = seg_arc_radius_and_center(self.v1(), self.v2());
            (r, [c.x, c.y])
        })
    }

    /// Length along the segment (arcs at their true length).
    pub fn length(&self) -> f64 {
        if self.is_arc() {
            seg_length(self.v1(), self.v2())
        } else {
            self.chord()
        }
    }

    /// The point of the segment nearest `p` (on the arc for an arc).
    pub fn closest_point(&self, p: [f64; 2]) -> [f64; 2] {
        let q = seg_closest_point(self.v1(), self.v2(), CVector2::new(p[0], p[1]), BULGE_EPS);
        [q.x, q.y]
    }

    /// The point halfway along the segment (on the arc for an arc).
    pub fn midpoint(&self) -> [f64; 2] {
        if self.is_arc() {
            let m = seg_midpoint(self.v1(), self.v2());
            [m.x, m.y]
        } else {
            [
                0.5 * (self.start[0] + self.end[0]),
                0.5 * (self.start[1] + self.end[1]),
            ]
        }
    }

    /// Direction (rad) of travel at the start and at the end of the segment.
    pub fn tangent_angles(&self) -> (f64, f64) {
        let chord = (self.end[1] - self.start[1]).atan2(self.end[0] - self.start[0]);
        let half = 2.0 * self.bulge.atan(); // half the sweep
        (chord - half, chord + half)
    }

    /// The same segment run the other way.
    pub fn reversed(&self) -> Self {
        Self {
            start: self.end,
            end: self.start,
            bulge: -self.bulge,
        }
    }

    /// Pushes the interior points of an arc replaced by chords deviating at most
    /// `tolerance` from it (chords on the concave side; nothing for a straight segment).
    /// The tolerance is clamped to `[1e-6, radius]` and an arc gets at most 4096 chords.
    pub fn flatten_into(&self, tolerance: f64, out: &mut Vec<[f64; 2]>) {
        if !self.is_arc() {
            return;
        }
        let [ax, ay] = self.start;
        let (dx, dy) = (self.end[0] - ax, self.end[1] - ay);
        let chord = (dx * dx + dy * dy).sqrt();
        let theta = self.sweep();
        let r = chord / (2.0 * (theta / 2.0).sin().abs());
        // centre: midpoint + normal * d, d signed
        let d = r * (theta / 2.0).cos() * theta.signum();
        let (mx, my) = ((ax + self.end[0]) / 2.0, (ay + self.end[1]) / 2.0);
        let (nx, ny) = (-dy / chord, dx / chord);
        let (cx, cy) = (mx + nx * d, my + ny * d);
        let tol = tolerance.clamp(1e-6, r);
        let max_step = 2.0 * (1.0 - tol / r).clamp(-1.0, 1.0).acos();
        let steps = ((theta.abs() / max_step.max(1e-3)).ceil() as usize).clamp(1, 4096);
        let a0 = (ay - cy).atan2(ax - cx);
        for k in 1..steps {
            let ang = a0 + theta * k as f64 / steps as f64;
            out.push([cx + r * ang.cos(), cy + r * ang.sin()]);
        }
    }

    fn v1(&self) -> PlineVertex<f64> {
        PlineVertex::new(self.start[0], self.start[1], self.bulge)
    }

    fn v2(&self) -> PlineVertex<f64> {
        PlineVertex::new(self.end[0], self.end[1], 0.0)
    }
}

/// A closed contour: straight segments and arcs through `vertices` (the last vertex joins
/// the first). Written as `[[x, y, bulge], ...]` in files.
///
/// Cavalier's algorithms run on it directly (it is a [`PlineSource`]), so an area, a
/// containment test or an offset never flattens the arcs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Contour {
    /// The vertices in order (either orientation).
    pub vertices: Vec<Vertex>,
}

impl Contour {
    /// A contour through `vertices`.
    pub fn new(vertices: Vec<Vertex>) -> Self {
        Self { vertices }
    }

    /// A polygon through `points` (straight segments).
    pub fn polygon(points: &[[f64; 2]]) -> Self {
        Self::new(points.iter().map(|p| Vertex::line(p[0], p[1])).collect())
    }

    /// A circle as two counter-clockwise half circles, starting at `(cx + r, cy)`.
    pub fn circle(cx: f64, cy: f64, r: f64) -> Self {
        Self::new(vec![
            Vertex::new(cx + r, cy, 1.0),
            Vertex::new(cx - r, cy, 1.0),
        ])
    }

    /// The contour of a cavalier polyline (closed or not: the result is closed).
    pub fn from_pline(p: &Polyline<f64>) -> Self {
        Self::new(
            p.iter_vertexes()
                .map(|v| Vertex::new(v.x, v.y, v.bulge))
                .collect(),
        )
    }

    /// A closed cavalier polyline of this contour.
    pub fn to_pline(&self) -> Polyline<f64> {
        Polyline::create_from(self)
    }

    /// The segments in order, the last one closing the contour.
    pub fn segments(&self) -> impl ExactSizeIterator<Item = Segment> + '_ {
        let n = self.vertices.len();
        (0..n).map(move |i| {
            let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
            Segment {
                start: a.point(),
                end: b.point(),
                bulge: a.bulge,
            }
        })
    }

    /// Polyline approximation: every vertex, and every arc replaced by chords deviating at
    /// most `tolerance` from it (see [`Segment::flatten_into`]).
    pub fn flatten(&self, tolerance: f64) -> Vec<[f64; 2]> {
        let mut out = Vec::with_capacity(self.vertices.len() * 2);
        for s in self.segments() {
            out.push(s.start);
            s.flatten_into(tolerance, &mut out);
        }
        out
    }

    /// Signed area (mm^2, positive counter-clockwise), arcs exact.
    pub fn signed_area(&self) -> f64 {
        if self.vertices.len() < 2 {
            return 0.0;
        }
        PlineSource::area(self)
    }

    /// Enclosed area (mm^2), arcs exact.
    pub fn area(&self) -> f64 {
        self.signed_area().abs()
    }

    /// Whether the contour runs counter-clockwise (positive area).
    pub fn is_ccw(&self) -> bool {
        self.signed_area() > 0.0
    }

    /// Length of the contour (mm), arcs at their true length.
    pub fn length(&self) -> f64 {
        self.segments().map(|s| s.length()).sum()
    }

    /// Whether `p` is inside (a non-zero winding number; arcs exact). Points on the
    /// contour may count either way.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        self.vertices.len() >= 2 && self.winding_number(CVector2::new(p[0], p[1])) != 0
    }

    /// Exact bounds `(min, max)` of the contour, arcs included; `None` when empty.
    pub fn bounds(&self) -> Option<([f64; 2], [f64; 2])> {
        if self.vertices.len() < 2 {
            return self.vertices.first().map(|v| (v.point(), v.point()));
        }
        self.extents()
            .map(|b| ([b.min_x, b.min_y], [b.max_x, b.max_y]))
    }

    /// Whether any two segments cross or touch other than at their shared vertex
    /// (cavalier's self-intersection scan, arcs exact).
    pub fn self_intersects(&self) -> bool {
        self.vertices.len() >= 2 && self.scan_for_self_intersect()
    }

    /// The same contour run the other way, from the same first vertex.
    pub fn reversed(&self) -> Self {
        let n = self.vertices.len();
        let vertices = (0..n)
            .map(|k| {
                // vertex k of the result is vertex -k of this one; its segment runs back
                // along the segment that ended at it
                let i = (n - k) % n;
                let prev = (i + n - 1) % n;
                Vertex::new(
                    self.vertices[i].x,
                    self.vertices[i].y,
                    -self.vertices[prev].bulge,
                )
            })
            .collect();
        Self { vertices }
    }

    /// This contour running counter-clockwise (`ccw`) or clockwise: reversed when needed.
    pub fn oriented(&self, ccw: bool) -> Self {
        if self.is_ccw() == ccw {
            self.clone()
        } else {
            self.reversed()
        }
    }

    /// The contour mapped by a conformal map `f` (a similarity: rotation, uniform scale,
    /// translation, and a mirror when `mirrors`): arcs stay arcs, bulges keep their value
    /// and change sign under a mirror.
    pub fn mapped(&self, f: impl Fn([f64; 2]) -> [f64; 2], mirrors: bool) -> Self {
        let sign = if mirrors { -1.0 } else { 1.0 };
        Self::new(
            self.vertices
                .iter()
                .map(|v| {
                    let [x, y] = f(v.point());
                    Vertex::new(x, y, sign * v.bulge)
                })
                .collect(),
        )
    }

    /// The same contour after rotating by `rotation_deg` about the origin then translating.
    /// Bulges are invariant under proper rigid motions, so arcs stay arcs.
    pub fn transformed(&self, rotation_deg: f64, translation: [f64; 2]) -> Self {
        let (s, c) = rotation_deg.to_radians().sin_cos();
        self.mapped(
            |[x, y]| {
                [
                    c * x - s * y + translation[0],
                    s * x + c * y + translation[1],
                ]
            },
            false,
        )
    }

    /// The region grown by `distance` (mm; negative shrinks it), whichever way the contour
    /// runs: cavalier's parallel offset on the arcs (convex corners become arcs). Returns
    /// the contours of the result in this contour's orientation: one when growing, none or
    /// several when shrinking past a waist.
    pub fn offset(&self, distance: f64) -> Vec<Contour> {
        if self.vertices.len() < 2 {
            return Vec::new();
        }
        // cavalier offsets to the left of the direction of travel for a positive distance,
        // which is inside a counter-clockwise contour
        let sign = if self.is_ccw() { -1.0 } else { 1.0 };
        self.parallel_offset(sign * distance)
            .iter()
            .map(Contour::from_pline)
            .collect()
    }
}

impl PlineSource for Contour {
    type Num = f64;
    type OutputPolyline = Polyline<f64>;

    fn get_userdata_count(&self) -> usize {
        0
    }

    fn get_userdata_values(&self) -> impl Iterator<Item = u64> + '_ {
        std::iter::empty()
    }

    fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    fn is_closed(&self) -> bool {
        true
    }

    fn get(&self, index: usize) -> Option<PlineVertex<f64>> {
        self.vertices.get(index).map(|v| v.pline())
    }

    fn at(&self, index: usize) -> PlineVertex<f64> {
        self.vertices[index].pline()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    fn near(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// A 100 x 50 plate with a half-round right end (radius 25).
    fn plate() -> Contour {
        Contour::new(vec![
            Vertex::line(0.0, 0.0),
            Vertex::new(100.0, 0.0, 1.0),
            Vertex::line(100.0, 50.0),
            Vertex::line(0.0, 50.0),
        ])
    }

    #[test]
    fn area_length_and_bounds_are_exact_on_arcs() {
        let p = plate();
        let area = 100.0 * 50.0 + PI * 25.0 * 25.0 / 2.0;
        assert!(near(p.signed_area(), area, 1e-9));
        assert!(near(p.length(), 100.0 + 100.0 + 50.0 + PI * 25.0, 1e-9));
        let (lo, hi) = p.bounds().unwrap();
        assert!(near(lo[0], 0.0, 1e-12) && near(hi[0], 125.0, 1e-9) && near(hi[1], 50.0, 1e-12));
        // the flattened polygon is inside the arc, within the tolerance
        let flat = p.flatten(0.01);
        let poly = crate::planar::polygon_area(&flat);
        assert!(
            poly < area && area - poly < 0.01 * p.length(),
            "{poly} {area}"
        );
        for q in &flat[2..flat.len() - 2] {
            let r = (q[0] - 100.0).hypot(q[1] - 25.0);
            assert!(q[0] < 100.0 + 1e-9 || near(r, 25.0, 1e-9));
        }
    }

    #[test]
    fn segment_arc_maths() {
        // a quarter circle of radius 5 about the origin, counter-clockwise
        let s = Segment {
            start: [5.0, 0.0],
            end: [0.0, 5.0],
            bulge: (PI / 8.0).tan(),
        };
        let (r, c) = s.arc().unwrap();
        assert!(near(r, 5.0, 1e-12) && near(c[0], 0.0, 1e-12) && near(c[1], 0.0, 1e-12));
        assert!(near(s.sweep(), FRAC_PI_2, 1e-12));
        assert!(near(s.length(), 2.5 * PI, 1e-12));
        let (t0, t1) = s.tangent_angles();
        assert!(near(t0, FRAC_PI_2, 1e-12) && near(t1, PI, 1e-12));
        let m = s.midpoint();
        assert!(
            near(m[0], 5.0 * FRAC_PI_4.cos(), 1e-12) && near(m[1], 5.0 * FRAC_PI_4.sin(), 1e-12)
        );
        let back = s.reversed();
        assert!(near(back.length(), s.length(), 1e-12) && back.arc().unwrap().1 == c);
        let line = Segment {
            start: [0.0, 0.0],
            end: [3.0, 4.0],
            bulge: 0.0,
        };
        assert!(line.arc().is_none() && line.length() == 5.0);
    }

    #[test]
    fn reversing_keeps_the_start_and_the_shape() {
        let p = plate();
        let r = p.reversed();
        assert_eq!(r.vertices[0].point(), p.vertices[0].point());
        assert!(near(r.signed_area(), -p.signed_area(), 1e-9));
        assert!(near(r.length(), p.length(), 1e-9));
        assert_eq!(r.reversed(), p);
        assert!(!p.oriented(false).is_ccw() && p.oriented(true) == p);
    }

    #[test]
    fn containment_and_maps() {
        let p = plate();
        assert!(p.contains([120.0, 25.0]) && !p.contains([124.0, 45.0]));
        assert!(p.reversed().contains([120.0, 25.0]));
        // turned a quarter and moved: arcs stay arcs
        let t = p.transformed(90.0, [10.0, 0.0]);
        assert!(near(t.area(), p.area(), 1e-9));
        assert!(t.contains([10.0 - 25.0, 120.0]));
        // mirrored in x: the area changes sign, the shape is the mirror image
        let m = p.mapped(|[x, y]| [-x, y], true);
        assert!(near(m.signed_area(), -p.signed_area(), 1e-9));
        assert!(m.contains([-120.0, 25.0]) && !m.contains([120.0, 25.0]));
        // scaled by 2
        let s = p.mapped(|[x, y]| [2.0 * x, 2.0 * y], false);
        assert!(near(s.area(), 4.0 * p.area(), 1e-6));
    }

    #[test]
    fn offsets_grow_and_shrink_either_way_round() {
        let sq = Contour::polygon(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]);
        for c in [sq.clone(), sq.reversed()] {
            let g = c.offset(1.0);
            assert_eq!(g.len(), 1);
            assert!(
                near(g[0].area(), 100.0 + 40.0 + PI, 1e-6),
                "{}",
                g[0].area()
            );
            let s = c.offset(-1.0);
            assert_eq!(s.len(), 1);
            assert!(near(s[0].area(), 64.0, 1e-6));
            assert!(c.offset(-6.0).is_empty());
        }
        assert!(!plate().self_intersects());
        let bow = Contour::polygon(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]);
        assert!(bow.self_intersects());
    }

    #[test]
    fn files_hold_vertices_as_triples() {
        let c = Contour::circle(0.0, 0.0, 1.0);
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(json, "[[1.0,0.0,1.0],[-1.0,0.0,1.0]]");
        let back: Contour = serde_json::from_str(&json).unwrap();
        assert_eq!(back, c);
    }
}
