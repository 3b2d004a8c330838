//! Part geometry: closed contours with bulges (DXF convention), flattening, validation and
//! rigid transforms that keep arcs as arcs.

use serde::{Deserialize, Serialize};

use crate::NestError;

/// Default chord tolerance (mm) used to flatten arcs for collision detection.
///
/// The flattened outline is grown by this amount before nesting, so a coarser tolerance is
/// still safe (never closer than the spacing) but wastes a little sheet.
pub const DEFAULT_FLATTEN_TOLERANCE: f64 = 0.05;

/// A contour vertex. `bulge` is the DXF bulge of the segment from this vertex to the next one
/// (`tan(angle / 4)`, positive = counter-clockwise arc, 0 = straight line).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Vertex {
    /// x (mm)
    pub x: f64,
    /// y (mm)
    pub y: f64,
    /// bulge of the segment leaving this vertex
    #[serde(default)]
    pub bulge: f64,
}

impl Vertex {
    /// A vertex followed by a straight segment.
    pub fn line(x: f64, y: f64) -> Self {
        Self { x, y, bulge: 0.0 }
    }
}

/// A closed contour: the last vertex connects back to the first.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Contour {
    /// vertices in order (either orientation)
    pub vertices: Vec<Vertex>,
}

impl Contour {
    /// A polygonal contour from points.
    pub fn polygon(points: &[[f64; 2]]) -> Self {
        Self {
            vertices: points.iter().map(|p| Vertex::line(p[0], p[1])).collect(),
        }
    }

    /// A circle as two half-circle bulge segments.
    pub fn circle(cx: f64, cy: f64, r: f64) -> Self {
        Self {
            vertices: vec![
                Vertex {
                    x: cx + r,
                    y: cy,
                    bulge: 1.0,
                },
                Vertex {
                    x: cx - r,
                    y: cy,
                    bulge: 1.0,
                },
            ],
        }
    }

    /// Polyline approximation: every arc is replaced by chords deviating at most `tolerance`
    /// from the true arc (chords lie on the concave side of the arc).
    pub fn flatten(&self, tolerance: f64) -> Vec<[f64; 2]> {
        let n = self.vertices.len();
        let mut out = Vec::with_capacity(n * 2);
        for i in 0..n {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % n];
            out.push([a.x, a.y]);
            if a.bulge.abs() > 1e-12 {
                arc_points(a, b, tolerance, &mut out);
            }
        }
        out
    }

    /// The same contour after rotating by `rotation_deg` about the origin then translating.
    /// Bulges are invariant under proper rigid motions, so arcs stay arcs.
    pub fn transformed(&self, rotation_deg: f64, translation: [f64; 2]) -> Self {
        let (s, c) = rotation_deg.to_radians().sin_cos();
        Self {
            vertices: self
                .vertices
                .iter()
                .map(|v| Vertex {
                    x: c * v.x - s * v.y + translation[0],
                    y: s * v.x + c * v.y + translation[1],
                    bulge: v.bulge,
                })
                .collect(),
        }
    }
}

/// Pushes the interior points of the arc from `a` to `b` (bulge of `a`).
fn arc_points(a: Vertex, b: Vertex, tolerance: f64, out: &mut Vec<[f64; 2]>) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let chord = (dx * dx + dy * dy).sqrt();
    if chord < 1e-12 {
        return;
    }
    let theta = 4.0 * a.bulge.atan();
    let r = chord / (2.0 * (theta / 2.0).sin().abs());
    // centre: midpoint + normal * d, d signed
    let d = r * (theta / 2.0).cos() * theta.signum();
    let (mx, my) = ((a.x + b.x) / 2.0, (a.y + b.y) / 2.0);
    let (nx, ny) = (-dy / chord, dx / chord);
    let (cx, cy) = (mx + nx * d, my + ny * d);
    let tol = tolerance.clamp(1e-6, r);
    let max_step = 2.0 * (1.0 - tol / r).clamp(-1.0, 1.0).acos();
    let steps = ((theta.abs() / max_step.max(1e-3)).ceil() as usize).clamp(1, 4096);
    let a0 = (a.y - cy).atan2(a.x - cx);
    for k in 1..steps {
        let ang = a0 + theta * k as f64 / steps as f64;
        out.push([cx + r * ang.cos(), cy + r * ang.sin()]);
    }
}

/// A part to nest: an outer contour, inner cut-outs and an identifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Part {
    /// identifier reported back in placements (`strip` in `nest.json`)
    pub id: String,
    /// outside contour
    pub outer: Contour,
    /// inside contours (holes); kept for output, ignored for nesting
    #[serde(default)]
    pub holes: Vec<Contour>,
}

impl Part {
    /// A part without holes.
    pub fn new(id: impl Into<String>, outer: Contour) -> Self {
        Self {
            id: id.into(),
            outer,
            holes: Vec::new(),
        }
    }

    /// The part moved by a placement: rotate about the origin of its own coordinates, then
    /// translate. Holes follow the outer contour.
    pub fn transformed(&self, rotation_deg: f64, translation: [f64; 2]) -> Self {
        Self {
            id: self.id.clone(),
            outer: self.outer.transformed(rotation_deg, translation),
            holes: self
                .holes
                .iter()
                .map(|h| h.transformed(rotation_deg, translation))
                .collect(),
        }
    }

    /// Flattens and validates the outer contour: finite, at least three distinct points,
    /// positive area, no self-intersection. Returns a counter-clockwise polygon.
    pub fn validated_outline(&self, tolerance: f64) -> Result<Vec<[f64; 2]>, NestError> {
        let bad = |reason: &str| NestError::BadPart {
            part: self.id.clone(),
            reason: reason.to_string(),
        };
        if self
            .outer
            .vertices
            .iter()
            .any(|v| !(v.x.is_finite() && v.y.is_finite() && v.bulge.is_finite()))
        {
            return Err(bad("non-finite coordinate"));
        }
        let mut pts = self.outer.flatten(tolerance);
        dedup_points(&mut pts);
        if pts.len() < 3 {
            return Err(bad("outline has fewer than 3 distinct points (zero size)"));
        }
        if let Some((i, j)) = self_intersection(&pts) {
            return Err(bad(&format!(
                "outline is self-intersecting (segments {i} and {j})"
            )));
        }
        let area = polygon_area(&pts);
        let (lo, hi) = bbox(&pts);
        let size = (hi[0] - lo[0]).min(hi[1] - lo[1]);
        if area.abs() <= 1e-9 || size <= 1e-9 {
            return Err(bad("outline has zero area"));
        }
        if area < 0.0 {
            pts.reverse();
        }
        Ok(pts)
    }
}

/// Removes consecutive duplicates (and a closing duplicate).
pub(crate) fn dedup_points(pts: &mut Vec<[f64; 2]>) {
    pts.dedup_by(|a, b| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
    while pts.len() > 1 {
        let (f, l) = (pts[0], pts[pts.len() - 1]);
        if (f[0] - l[0]).abs() < 1e-9 && (f[1] - l[1]).abs() < 1e-9 {
            pts.pop();
        } else {
            break;
        }
    }
}

/// Signed area (positive = counter-clockwise).
pub fn polygon_area(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Axis-aligned bounds `(min, max)`.
pub fn bbox(pts: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Whether `p` is strictly inside the closed polygon `poly` (even-odd rule).
pub fn point_in_polygon(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance from `p` to the segment `ab`.
pub use sv_geom::planar::point_segment_distance as segment_distance;
/// Whether closed segments `ab` and `cd` touch or cross (nearly collinear edges apart on one
/// line do not).
pub use sv_geom::planar::segments_intersect;

/// Distance from `p` to the boundary of the closed polygon `poly`.
pub fn boundary_distance(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| segment_distance(p, poly[i], poly[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

/// First pair of non-adjacent edges of the closed polygon that touch, if any.
pub fn self_intersection(pts: &[[f64; 2]]) -> Option<(usize, usize)> {
    let n = pts.len();
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        for j in i + 1..n {
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (c, d) = (pts[j], pts[(j + 1) % n]);
            if segments_intersect(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_flattening_stays_within_tolerance() {
        let c = Contour::circle(0.0, 0.0, 10.0);
        let pts = c.flatten(0.01);
        assert!(pts.len() > 20);
        for p in &pts {
            let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
            assert!((r - 10.0).abs() < 1e-9);
        }
        let a = polygon_area(&pts);
        assert!(
            (a - std::f64::consts::PI * 100.0).abs() < 0.01 * 2.0 * std::f64::consts::PI * 10.0
        );
    }

    #[test]
    fn bowtie_is_rejected() {
        let p = Part::new(
            "bow",
            Contour::polygon(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]),
        );
        let err = p.validated_outline(0.1).unwrap_err().to_string();
        assert!(
            err.contains("bow") && err.contains("self-intersecting"),
            "{err}"
        );
    }

    #[test]
    fn transform_keeps_bulges() {
        let c = Contour::circle(5.0, 0.0, 1.0).transformed(90.0, [1.0, 2.0]);
        assert!((c.vertices[0].x - 1.0).abs() < 1e-12 && (c.vertices[0].y - 8.0).abs() < 1e-12);
        assert_eq!(c.vertices[0].bulge, 1.0);
    }
}
