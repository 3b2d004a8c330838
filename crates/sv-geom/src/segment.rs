//! Closest points of two 3D segments.

use crate::{Point3, Real};

/// Result of [`segment_closest`]: the closest points are `p0 + s (p1 - p0)` and
/// `q0 + t (q1 - q0)`, with `s, t` in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmentClosest {
    /// Parameter on the first segment.
    pub s: Real,
    /// Parameter on the second segment.
    pub t: Real,
    /// Distance between the two closest points (mm).
    pub distance: Real,
}

/// Closest points between segments `p0 p1` and `q0 q1` (Ericson, Real-Time Collision
/// Detection, sec. 5.1.9). Degenerate (zero-length) segments are handled as points;
/// parallel segments return one of the closest pairs.
pub fn segment_closest(p0: &Point3, p1: &Point3, q0: &Point3, q1: &Point3) -> SegmentClosest {
    const TINY: Real = 1e-24;
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t) = if a <= TINY && e <= TINY {
        (0.0, 0.0)
    } else if a <= TINY {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= TINY {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s = if denom > TINY * a.max(e) {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let cp = p0 + d1 * s;
    let cq = q0 + d2 * t;
    SegmentClosest {
        s,
        t,
        distance: (cp - cq).norm(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pt() -> impl Strategy<Value = Point3> {
        (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
    }

    proptest! {
        /// The returned distance is never beaten by a dense sample of point pairs.
        #[test]
        fn closest_is_no_worse_than_samples(p0 in pt(), p1 in pt(), q0 in pt(), q1 in pt()) {
            let c = segment_closest(&p0, &p1, &q0, &q1);
            prop_assert!((0.0..=1.0).contains(&c.s) && (0.0..=1.0).contains(&c.t));
            let got = ((p0 + (p1 - p0) * c.s) - (q0 + (q1 - q0) * c.t)).norm();
            prop_assert!((got - c.distance).abs() < 1e-9);
            for i in 0..=20 {
                for j in 0..=20 {
                    let a = p0 + (p1 - p0) * (i as f64 / 20.0);
                    let b = q0 + (q1 - q0) * (j as f64 / 20.0);
                    prop_assert!(c.distance <= (a - b).norm() + 1e-9);
                }
            }
        }
    }

    #[test]
    fn collinear_overlapping_segments_touch() {
        let c = segment_closest(
            &Point3::new(0.0, 0.0, 0.0),
            &Point3::new(2.0, 0.0, 0.0),
            &Point3::new(3.0, 0.0, 0.0),
            &Point3::new(1.0, 0.0, 0.0),
        );
        assert!(c.distance < 1e-12);
    }
}
