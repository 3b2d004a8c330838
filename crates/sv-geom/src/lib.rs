//! Geometry core of Spin-Valence: the nalgebra aliases every other crate uses, named
//! tolerances, a few small 3D queries (closest points of two segments, planarity), exact 2D
//! predicates for flat patterns and sheets ([`planar`]) and the one arc contour of the
//! workspace ([`Contour`]: flatten, area, length, containment, maps, offsets); and the
//! escaping of outside text quoted in one-line messages ([`text`]).
//!
//! Conventions: lengths in millimetres, right-handed, Z up, angles in radians.
//!
//! ```
//! use sv_geom::{Point3, segment_closest};
//! let c = segment_closest(
//!     &Point3::new(0.0, 0.0, 0.0), &Point3::new(1.0, 0.0, 0.0),
//!     &Point3::new(0.5, -1.0, 2.0), &Point3::new(0.5, 1.0, 2.0),
//! );
//! assert!((c.distance - 2.0).abs() < 1e-12);
//! assert!((c.s - 0.5).abs() < 1e-12 && (c.t - 0.5).abs() < 1e-12);
//! ```

mod contour;
pub mod planar;
mod rigid;
mod segment;
pub mod sparse;
pub mod text;

pub use contour::{Contour, Segment, Vertex, BULGE_EPS};
pub use rigid::rigid_fit;
pub use segment::{segment_closest, SegmentClosest};

/// The scalar type of all geometry.
pub type Real = f64;
/// A point in model space (mm).
pub type Point3 = nalgebra::Point3<Real>;
/// A displacement or direction in model space.
pub type Vector3 = nalgebra::Vector3<Real>;
/// A 2D point (flat patterns, mm).
pub type Point2 = nalgebra::Point2<Real>;
/// A 2D vector.
pub type Vector2 = nalgebra::Vector2<Real>;
/// A 3x3 matrix (rotations are stored column-major, acting on column vectors).
pub type Matrix3 = nalgebra::Matrix3<Real>;
/// A unit vector.
pub type UnitVector3 = nalgebra::Unit<Vector3>;
/// A rotation matrix with its exponential map (`Rotation3::new(axis_angle)`).
pub type Rotation3 = nalgebra::Rotation3<Real>;
/// A rotation as a unit quaternion (written `[x, y, z, w]` in files).
pub type UnitQuaternion = nalgebra::UnitQuaternion<Real>;
/// A proper rigid motion.
pub type Isometry3 = nalgebra::Isometry3<Real>;

/// Lengths below this (mm) are treated as zero when normalising directions.
/// Choose it far below any manufacturing tolerance: 1e-9 mm is a nanometre-scale zero.
pub const EPS_LENGTH: Real = 1e-9;

/// The skew-symmetric matrix `[v]x` with `[v]x w = v x w`.
pub fn cross_matrix(v: &Vector3) -> Matrix3 {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Centroid of a set of points; `None` for an empty slice.
pub fn centroid(points: &[Point3]) -> Option<Point3> {
    if points.is_empty() {
        return None;
    }
    let sum = points
        .iter()
        .fold(Vector3::zeros(), |acc, p| acc + p.coords);
    Some(Point3::from(sum / points.len() as Real))
}

/// True when every coordinate is finite (not NaN, not infinite).
pub fn is_finite_point(p: &Point3) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}

/// Planarity of a quad: distance between its two diagonals (closest distance of the
/// segments `q0 q2` and `q1 q3`). Zero exactly for a planar convex quad.
pub fn quad_diagonal_distance(q: &[Point3; 4]) -> Real {
    segment_closest(&q[0], &q[2], &q[1], &q[3]).distance
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_matrix_matches_cross_product() {
        let v = Vector3::new(1.0, -2.0, 3.5);
        let w = Vector3::new(-0.5, 4.0, 2.0);
        assert!((cross_matrix(&v) * w - v.cross(&w)).norm() < 1e-12);
    }

    #[test]
    fn twisted_quad_has_diagonal_distance() {
        let flat = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        assert!(quad_diagonal_distance(&flat) < 1e-12);
        let mut twisted = flat;
        twisted[1].z = 0.2;
        // common perpendicular of (t, t, 0) and (1, 0, 0.2) + u (-1, 1, -0.2)
        let expected = 0.2 / 4.08f64.sqrt();
        assert!((quad_diagonal_distance(&twisted) - expected).abs() < 1e-12);
    }
}
