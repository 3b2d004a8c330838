//! Small 2D helpers: convex polygon intersection area, convex hull, minimum-area rectangle.

use sv_geom::{Point2, Vector2};

/// z component of the 2D cross product.
pub(crate) fn cross(a: &Vector2, b: &Vector2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Area of the intersection of two convex counter-clockwise polygons
/// ([`sv_geom::planar::convex_clip`]).
pub fn convex_intersection_area(a: &[Point2], b: &[Point2]) -> f64 {
    let flat = |p: &[Point2]| p.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>();
    let poly = sv_geom::planar::convex_clip(&flat(a), &flat(b));
    if poly.len() < 3 {
        0.0
    } else {
        sv_geom::planar::polygon_area(&poly).max(0.0)
    }
}

/// [`sv_geom::planar::convex_hull`] of points as nalgebra points.
pub(crate) fn convex_hull(points: &[Point2]) -> Vec<Point2> {
    let flat: Vec<[f64; 2]> = points.iter().map(|q| [q.x, q.y]).collect();
    sv_geom::planar::convex_hull(&flat)
        .into_iter()
        .map(|q| Point2::new(q[0], q[1]))
        .collect()
}

/// The minimum-area enclosing rectangle of a point set, as (angle of its longer side,
/// longer side, shorter side). Rotating calipers over the hull edges.
pub(crate) fn min_area_rect(points: &[Point2]) -> (f64, f64, f64) {
    let h = convex_hull(points);
    if h.len() < 2 {
        return (0.0, 0.0, 0.0);
    }
    let mut best = (0.0, f64::INFINITY, 0.0, f64::INFINITY);
    for i in 0..h.len() {
        let e = h[(i + 1) % h.len()] - h[i];
        if e.norm() < 1e-12 {
            continue;
        }
        let u = e.normalize();
        let v = Vector2::new(-u.y, u.x);
        let (mut u0, mut u1, mut v0, mut v1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for q in &h {
            let (a, b) = (q.coords.dot(&u), q.coords.dot(&v));
            u0 = u0.min(a);
            u1 = u1.max(a);
            v0 = v0.min(b);
            v1 = v1.max(b);
        }
        let (w, hh) = (u1 - u0, v1 - v0);
        if w * hh < best.3 {
            let angle = u.y.atan2(u.x);
            best = if w >= hh {
                (angle, w, hh, w * hh)
            } else {
                (angle + std::f64::consts::FRAC_PI_2, hh, w, w * hh)
            };
        }
    }
    (best.0, best.1, best.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(x: f64, y: f64, s: f64) -> Vec<Point2> {
        vec![
            Point2::new(x, y),
            Point2::new(x + s, y),
            Point2::new(x + s, y + s),
            Point2::new(x, y + s),
        ]
    }

    #[test]
    fn intersection_area_of_squares() {
        assert!(
            (convex_intersection_area(&sq(0.0, 0.0, 2.0), &sq(1.0, 1.0, 2.0)) - 1.0).abs() < 1e-12
        );
        assert_eq!(
            convex_intersection_area(&sq(0.0, 0.0, 1.0), &sq(1.0, 0.0, 1.0)),
            0.0
        );
        assert_eq!(
            convex_intersection_area(&sq(0.0, 0.0, 1.0), &sq(3.0, 0.0, 1.0)),
            0.0
        );
    }

    #[test]
    fn rectangle_of_a_rotated_bar() {
        let a = 0.3f64;
        let (c, s) = (a.cos(), a.sin());
        let pts: Vec<Point2> = [(0.0, 0.0), (10.0, 0.0), (10.0, 2.0), (0.0, 2.0)]
            .iter()
            .map(|&(x, y)| Point2::new(c * x - s * y, s * x + c * y))
            .collect();
        let (ang, long, short) = min_area_rect(&pts);
        assert!((long - 10.0).abs() < 1e-9 && (short - 2.0).abs() < 1e-9);
        assert!((ang - a).sin().abs() < 1e-9);
    }
}
