//! 2D segment queries on `[x, y]` points (flat patterns and sheets, mm), shared by the
//! design-rule check, the nester's outline validation and the tests that measure webs and
//! spacings.

/// Distance from a line (mm) within which a point counts as on it in the side tests below:
/// far below anything a cutter resolves, far above the rounding of the test. Without it two
/// nearly collinear segments apart on one line (two straight runs of slots of one unit, say)
/// can read as crossing, since their side tests are rounding noise.
pub const ON_LINE: f64 = 1e-6;

/// Twice the signed area of the triangle `abc` (> 0 counter-clockwise).
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Side of `r` relative to the line through `p` and `q`: -1, 0 (within [`ON_LINE`]) or 1.
fn side(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> f64 {
    let o = orient(p, q, r);
    if o.abs() <= ON_LINE * (q[0] - p[0]).hypot(q[1] - p[1]) {
        0.0
    } else {
        o.signum()
    }
}

/// Distance from `p` to the segment `ab`.
pub fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// Whether segments `ab` and `cd` cross properly: the ends of each strictly on both sides
/// of the other's line (more than [`ON_LINE`] away).
pub fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0
}

/// Whether the closed segments `ab` and `cd` touch (within [`ON_LINE`]) or cross.
pub fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    segments_cross(a, b, c, d) || segment_distance(a, b, c, d) <= ON_LINE
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

#[cfg(test)]
mod tests {
    use super::*;

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
