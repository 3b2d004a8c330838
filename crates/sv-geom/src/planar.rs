//! 2D queries on `[x, y]` points (flat patterns and sheets, mm), shared by the design-rule
//! check, the nester's outline validation, the sheet writer and the tests that measure
//! webs and spacings: segment distances and crossings, polygon area, bounds and
//! containment.
//!
//! Side tests are exact (Shewchuk's adaptive orientation predicate from `robust`, as geo
//! uses), so nearly collinear segments apart on one line never read as crossing, and no
//! tolerance decides a topological question.

use robust::{orient2d, Coord};

/// The side of `c` relative to the directed line through `a` and `b`: 1 left, -1 right,
/// 0 exactly on it.
pub fn orientation(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let o = orient2d(
        Coord { x: a[0], y: a[1] },
        Coord { x: b[0], y: b[1] },
        Coord { x: c[0], y: c[1] },
    );
    if o > 0.0 {
        1
    } else if o < 0.0 {
        -1
    } else {
        0
    }
}

/// Distance from `p` to `q`.
pub fn distance(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

/// Distance from `p` to the segment `ab`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    point_segment_distance2(p, a, b).sqrt()
}

/// Squared distance from `p` to the segment `ab` (for inner loops that compare distances:
/// a square root per edge costs more than the rest of the test).
pub fn point_segment_distance2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
    ex * ex + ey * ey
}

/// Whether segments `ab` and `cd` cross properly: the ends of each strictly on both sides
/// of the other's line (exact).
pub fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    orientation(a, b, c) * orientation(a, b, d) < 0
        && orientation(c, d, a) * orientation(c, d, b) < 0
}

/// Whether `p`, exactly on the line of `ab`, lies within the segment's box.
fn within(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether the closed segments `ab` and `cd` touch or cross (exact).
pub fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orientation(a, b, c), orientation(a, b, d));
    let (o3, o4) = (orientation(c, d, a), orientation(c, d, b));
    (o1 * o2 < 0 && o3 * o4 < 0)
        || (o1 == 0 && within(a, b, c))
        || (o2 == 0 && within(a, b, d))
        || (o3 == 0 && within(c, d, a))
        || (o4 == 0 && within(c, d, b))
}

/// Smallest distance between segments `ab` and `cd` (0 when they cross).
pub fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    if segments_cross(a, b, c, d) {
        return 0.0;
    }
    point_segment_distance(a, c, d)
        .min(point_segment_distance(b, c, d))
        .min(point_segment_distance(c, a, b))
        .min(point_segment_distance(d, a, b))
}

/// Signed area of the closed polygon `pts` (positive counter-clockwise).
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

/// The part of the convex polygon `a` inside the convex counter-clockwise polygon `b`
/// (Sutherland-Hodgman: `a` clipped by every side of `b`), counter-clockwise when `a` is;
/// fewer than three points when they do not overlap.
pub fn convex_clip(a: &[[f64; 2]], b: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut poly: Vec<[f64; 2]> = a.to_vec();
    for i in 0..b.len() {
        if poly.is_empty() {
            break;
        }
        let (p, q) = (b[i], b[(i + 1) % b.len()]);
        let side = |x: &[f64; 2]| (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0]);
        let input = std::mem::take(&mut poly);
        for j in 0..input.len() {
            let (c, d) = (input[j], input[(j + 1) % input.len()]);
            let (sc, sd) = (side(&c), side(&d));
            if sc >= 0.0 {
                poly.push(c);
            }
            if (sc >= 0.0) != (sd >= 0.0) {
                let t = sc / (sc - sd);
                poly.push([c[0] + (d[0] - c[0]) * t, c[1] + (d[1] - c[1]) * t]);
            }
        }
    }
    poly
}

/// Axis-aligned bounds `(min, max)` of `pts` (infinite and reversed when empty).
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

/// Whether `p` is inside the closed polygon `poly` (even-odd rule; points on an edge may
/// count either way).
pub fn point_in_polygon(p: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let n = poly.len();
    (0..n).fold(false, |inside, i| {
        inside != ray_crosses(p, poly[i], poly[(i + 1) % n])
    })
}

/// Whether the ray from `p` towards +x crosses the edge `a`-`b`: what
/// [`point_in_polygon`] counts. Only edges that straddle `p`'s height can.
pub fn ray_crosses(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    if !straddles(a, b, p[1]) {
        return false;
    }
    // exact: is p left of the upward edge (right of a downward one)?
    let up = b[1] > a[1];
    let o = orientation(a, b, p);
    (up && o > 0) || (!up && o < 0)
}

/// Whether the edge `a`-`b` straddles the height `y` (one end above it, the other not).
pub fn straddles(a: [f64; 2], b: [f64; 2], y: f64) -> bool {
    (a[1] > y) != (b[1] > y)
}

/// The edges of the closed polygon `poly` that straddle the height `y`: the only ones
/// [`point_in_polygon`] counts for a point there.
pub fn straddling_edges(
    poly: &[[f64; 2]],
    y: f64,
) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
    let n = poly.len();
    (0..n)
        .map(move |i| (poly[i], poly[(i + 1) % n]))
        .filter(move |(a, b)| straddles(*a, *b, y))
}

/// Distance from `p` to the boundary of the closed polygon `poly`.
pub fn boundary_distance(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| point_segment_distance(p, poly[i], poly[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

/// `(a - o) x (b - o)`: positive when `o, a, b` turn left.
fn turn(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Convex hull of `pts` (Andrew's monotone chain): counter-clockwise from the lowest-x
/// point, no collinear or repeated points (points closer than 1e-12 are one).
pub fn convex_hull(pts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p = pts.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-12);
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(p.len() + 1);
    // the lower chain left to right, then the upper one back
    for chain in [p.clone(), p.into_iter().rev().collect()] {
        let start = hull.len();
        for q in chain {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        // its last point is the other chain's first
        hull.pop();
    }
    hull
}

/// The largest distance between two of `pts` (0 for fewer than two): rotating calipers on
/// the convex hull, so `n log n` for any number of points.
pub fn diameter(pts: &[[f64; 2]]) -> f64 {
    let h = convex_hull(pts);
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    match h.len() {
        0 | 1 => return 0.0,
        2 => return dist(h[0], h[1]),
        _ => {}
    }
    let n = h.len();
    let mut best = 0.0_f64;
    let mut j = 1;
    for i in 0..n {
        let (a, b) = (h[i], h[(i + 1) % n]);
        // the vertex farthest from the edge's line
        while turn(a, b, h[(j + 1) % n]) > turn(a, b, h[j]) {
            j = (j + 1) % n;
        }
        best = best.max(dist(a, h[j])).max(dist(b, h[j]));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Points on a circle (every one on the hull), on a small grid with repeats, or
    /// anywhere in a long flat box; 1 to 60 of them.
    fn point_sets() -> impl Strategy<Value = Vec<[f64; 2]>> {
        let on_circle = (0.0..std::f64::consts::TAU).prop_map(|a: f64| [a.cos(), a.sin()]);
        let on_grid = (0..5i32, 0..5i32).prop_map(|(x, y)| [f64::from(x), f64::from(y)]);
        let anywhere = (-50.0..50.0f64, 0.0..3.0f64).prop_map(|(x, y)| [x, y]);
        prop_oneof![
            prop::collection::vec(on_circle, 1..60),
            prop::collection::vec(on_grid, 1..60),
            prop::collection::vec(anywhere, 1..60),
        ]
    }

    proptest! {
        #[test]
        fn hull_and_diameter_are_those_of_every_point(pts in point_sets()) {
            let h = convex_hull(&pts);
            // every point inside or on the hull, which turns left at every vertex
            for k in 0..h.len() {
                let (a, b) = (h[k], h[(k + 1) % h.len()]);
                if h.len() >= 3 {
                    prop_assert!(turn(a, b, h[(k + 2) % h.len()]) > 0.0, "{h:?}");
                    for &p in &pts {
                        prop_assert!(turn(a, b, p) >= -1e-9, "{p:?} outside {h:?}");
                    }
                }
            }
            let mut every = 0.0_f64;
            for a in &pts {
                for b in &pts {
                    every = every.max((a[0] - b[0]).hypot(a[1] - b[1]));
                }
            }
            prop_assert!((diameter(&pts) - every).abs() <= 1e-12 * every.max(1.0), "{pts:?}");
        }
    }

    #[test]
    fn collinear_segments_apart_are_measured_not_crossed() {
        // Two straight slot runs of one pavilion unit (strip A26 with sheet-filling pieces):
        // the short run lies on the line of the long one, 14.5 mm beyond its end. Their side
        // tests have opposite signs in both directions; an exact-sign test read that as a
        // crossing (web 0 in the design-rule check).
        let (a, b) = (
            [392.3843959010201, 29.074226677924667],
            [382.5390969686966, 27.322059633789113],
        );
        let (c, d) = (
            [656.520533939849, 76.08251351799211],
            [406.6600793528891, 31.614868891921194],
        );
        let d_ab = segment_distance(a, b, c, d);
        assert!((d_ab - 14.5).abs() < 0.1, "{d_ab}");
        assert_eq!(d_ab, segment_distance(c, d, a, b));
        assert!(!segments_intersect(a, b, c, d));
        assert!(!segments_intersect(c, d, a, b));
    }

    #[test]
    fn crossing_touching_parallel_and_apart() {
        // a real crossing is 0, parallel segments are their offset apart
        assert_eq!(
            segment_distance([0.0, 0.0], [10.0, 10.0], [0.0, 10.0], [10.0, 0.0]),
            0.0
        );
        assert!(segments_cross(
            [0.0, 0.0],
            [10.0, 10.0],
            [0.0, 10.0],
            [10.0, 0.0]
        ));
        let d = segment_distance([0.0, 0.0], [10.0, 0.0], [2.0, 3.0], [8.0, 3.0]);
        assert!((d - 3.0).abs() < 1e-12);
        // collinear and overlapping: touching, distance 0, but no proper crossing
        assert_eq!(
            segment_distance([0.0, 0.0], [10.0, 0.0], [5.0, 0.0], [15.0, 0.0]),
            0.0
        );
        assert!(!segments_cross(
            [0.0, 0.0],
            [10.0, 0.0],
            [5.0, 0.0],
            [15.0, 0.0]
        ));
        assert!(segments_intersect(
            [0.0, 0.0],
            [10.0, 0.0],
            [5.0, 0.0],
            [15.0, 0.0]
        ));
        // a T: one end on the other segment
        assert!(segments_intersect(
            [0.0, 0.0],
            [10.0, 0.0],
            [5.0, 0.0],
            [5.0, 5.0]
        ));
        // apart
        assert!(!segments_intersect(
            [0.0, 0.0],
            [10.0, 0.0],
            [5.0, 1.0],
            [5.0, 5.0]
        ));
        assert!((point_segment_distance([5.0, 4.0], [0.0, 0.0], [10.0, 0.0]) - 4.0).abs() < 1e-12);
        assert!((point_segment_distance([13.0, 4.0], [0.0, 0.0], [10.0, 0.0]) - 5.0).abs() < 1e-12);
    }
}
