//! Measures of two plates that meet: how far one passes through the other, and the fold,
//! bend and twist of a hinge between them. The solve aims at them and the fold check
//! measures them, on the same definitions.

use sv_geom::{segment_closest, Point3, Real, Vector3};

/// Unit normal of a convex quad plate, `(q2 - q0) x (q3 - q1)`; `None` when degenerate.
pub fn plate_normal(q: &[Point3; 4]) -> Option<Vector3> {
    (q[2] - q[0]).cross(&(q[3] - q[1])).try_normalize(1e-12)
}

/// The point of plate `a` (a convex quad on its mid-plane, `thickness` thick) nearest `x`.
pub fn nearest_on_plate(a: &[Point3; 4], thickness: Real, x: &Point3) -> Point3 {
    let Some(n) = plate_normal(a) else {
        return a[0];
    };
    let h = n.dot(&(x - a[0]));
    let flat = x - n * h;
    // inside the outline, or the nearest point of its nearest side
    let inside = (0..4).all(|i| n.cross(&(a[(i + 1) % 4] - a[i])).dot(&(flat - a[i])) >= 0.0);
    let on = if inside {
        flat
    } else {
        (0..4)
            .map(|i| {
                let c = segment_closest(&a[i], &a[(i + 1) % 4], &flat, &flat);
                a[i] + (a[(i + 1) % 4] - a[i]) * c.s
            })
            .min_by(|p, q| (p - flat).norm().total_cmp(&(q - flat).norm()))
            .unwrap_or(flat)
    };
    on + n * h.clamp(-thickness / 2.0, thickness / 2.0)
}

/// From plate `a`'s edge at `w` (a point of its side on its mid-plane) to plate `b`: the
/// shortest move that brings the point within one thickness of `b`'s mid-plane, over `b`'s
/// outline. Zero where the two plates touch there, edge to edge (in one plane) or edge on
/// face (one lying on the other), or pass into each other.
pub fn edge_to_plate(_a: &[Point3; 4], w: &Point3, b: &[Point3; 4], thickness: Real) -> Vector3 {
    nearest_on_plate(b, 2.0 * thickness, w) - w
}

/// Points at which [`reach_into`] measures a segment.
pub const REACH_SAMPLES: usize = 17;

/// How far each of [`REACH_SAMPLES`] points of the segment `p q` (from `p` to `q`) reaches
/// into plate `a` (see [`reach_into`]).
pub fn reach_profile(
    a: &[Point3; 4],
    p: &Point3,
    q: &Point3,
    thickness: Real,
) -> [Real; REACH_SAMPLES] {
    let Some(n) = plate_normal(a) else {
        return [0.0; REACH_SAMPLES];
    };
    let inward: [Vector3; 4] =
        std::array::from_fn(|i| n.cross(&(a[(i + 1) % 4] - a[i])).normalize());
    std::array::from_fn(|s| {
        let x = p + (q - p) * (s as Real / (REACH_SAMPLES - 1) as Real);
        let depth = (0..4)
            .map(|i| inward[i].dot(&(x - a[i])))
            .fold(Real::INFINITY, Real::min);
        let clear = thickness - n.dot(&(x - a[0])).abs();
        depth.min(clear).max(0.0)
    })
}

/// How far the segment `p q` reaches into plate `a` (a convex quad of thickness
/// `thickness` on its mid-plane): the largest, over points of the segment, of how deep the
/// point lies inside `a`'s outline (seen along `a`'s normal) while closer to `a`'s
/// mid-plane than `thickness` (mm, 0 when it stays clear). A segment whose plate touches
/// `a` edge to edge, or passes above or below it, reaches 0; it is continuous in every
/// point, so the solve can push it to 0. Measured at [`REACH_SAMPLES`] points.
pub fn reach_into(a: &[Point3; 4], p: &Point3, q: &Point3, thickness: Real) -> Real {
    reach_profile(a, p, q, thickness)
        .into_iter()
        .fold(0.0, Real::max)
}

/// The turn of a hinge from plate `a`'s side `k` to plate `b`'s side `m` (the two facing
/// sides run opposite ways): `(bend, twist)` in radians. `bend` is the turn of `b`'s side in
/// `a`'s plane (about `a`'s normal), `twist` its turn out of it (about the line across the
/// joint); a pure fold about the joint line has both zero.
pub fn hinge_turn(a: &[Point3; 4], k: usize, b: &[Point3; 4], m: usize) -> (Real, Real) {
    let Some(n) = plate_normal(a) else {
        return (Real::NAN, Real::NAN);
    };
    let e = (a[(k + 1) % 4] - a[k]).normalize();
    let across = n.cross(&e);
    let g = (b[m] - b[(m + 1) % 4]).normalize();
    let bend = across.dot(&g).atan2(e.dot(&g));
    let twist = n.dot(&g).clamp(-1.0, 1.0).asin();
    (bend, twist)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: Real, x0: Real) -> [Point3; 4] {
        [
            Point3::new(x0, 0.0, z),
            Point3::new(x0 + 1.0, 0.0, z),
            Point3::new(x0 + 1.0, 1.0, z),
            Point3::new(x0, 1.0, z),
        ]
    }

    #[test]
    fn a_side_reaches_into_a_plate_only_inside_its_outline_and_its_thickness() {
        let a = square(0.0, 0.0);
        let t = 0.05;
        // across a's plate, 0.02 above its mid-plane: reaches to the middle, 0.5 deep
        let (p, q) = (Point3::new(-0.5, 0.5, 0.02), Point3::new(1.5, 0.5, 0.02));
        assert!(
            (reach_into(&a, &p, &q, t) - 0.03).abs() < 1e-12,
            "capped by the thickness"
        );
        let (p, q) = (Point3::new(-0.5, 0.5, 0.0), Point3::new(0.2, 0.5, 0.0));
        assert!((reach_into(&a, &p, &q, 1.0) - 0.2).abs() < 1e-2);
        // above the plate by more than the thickness, or outside its outline: clear
        assert_eq!(
            reach_into(
                &a,
                &Point3::new(-0.5, 0.5, 0.2),
                &Point3::new(1.5, 0.5, 0.2),
                t
            ),
            0.0
        );
        assert_eq!(
            reach_into(
                &a,
                &Point3::new(1.0, 0.0, 0.0),
                &Point3::new(1.0, 1.0, 0.0),
                t
            ),
            0.0
        );
    }

    #[test]
    fn an_edge_touching_a_plate_edge_to_edge_or_on_its_face_has_no_gap() {
        let t = 0.1;
        let a = square(0.0, 0.0);
        // b beside a, edge to edge: a's edge at (1, 0.5) touches b's edge
        let b = square(0.0, 1.0);
        assert!(edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() < 1e-12);
        // b a bit away: the gap is the distance between the edges
        let b = square(0.0, 1.3);
        assert!((edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() - 0.3).abs() < 1e-12);
        // b lying on a's face, under a's edge: the edge rests on it
        let b = square(-t, 0.5);
        assert!(edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() < 1e-12);
        // ... and 0.2 lower: a gap of 0.2
        let b = square(-t - 0.2, 0.5);
        assert!((edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() - 0.2).abs() < 1e-12);
    }

    #[test]
    fn a_fold_about_the_joint_has_no_bend_and_no_twist() {
        let a = square(0.0, 0.0);
        // b shares a's side 1 (x = 1) and is folded up about it by 30 degrees
        let (s, c) = 30f64.to_radians().sin_cos();
        let b = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0 + c, 0.0, s),
            Point3::new(1.0 + c, 1.0, s),
            Point3::new(1.0, 1.0, 0.0),
        ];
        let (bend, twist) = hinge_turn(&a, 1, &b, 3);
        assert!(bend.abs() < 1e-12 && twist.abs() < 1e-12, "{bend} {twist}");
        // b turned in a's plane by 2 degrees about the joint's middle: a bend of 2 degrees
        let (s2, c2) = 2f64.to_radians().sin_cos();
        let mid = Point3::new(1.0, 0.5, 0.0);
        let turn = |v: Vector3| Vector3::new(c2 * v.x - s2 * v.y, s2 * v.x + c2 * v.y, v.z);
        let bent = b.map(|p| mid + turn(p - mid));
        let (bend, twist) = hinge_turn(&a, 1, &bent, 3);
        assert!((bend.to_degrees().abs() - 2.0).abs() < 1e-9 && twist.abs() < 1e-12);
    }
}
