//! Hubs: the best-fit rhombus of each face, spun by the spin angle (model.md sec. 2).

use sv_geom::{Matrix3, Point3, Real, Vector3};
use sv_unit::Rhombus;

use crate::{FrameError, QuadMesh};

/// The hub of one unit, in its face plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hub {
    /// Face centroid (projected into the best-fit plane).
    pub centre: Point3,
    /// Columns: `x` toward hub corner 0, `y` toward hub corner 1, `z` the face normal
    /// `(v0 - v2) x (v1 - v3)` normalised. A proper rotation (world from hub frame).
    pub frame: Matrix3,
    /// Half-diagonals of the fitted rhombus (`a` along `x`, `b` along `y`).
    pub rhombus: Rhombus,
}

impl Hub {
    /// Best-fit rhombus of a planar-ish quad, spun by `spin_angle` (rad) about its normal.
    /// The diagonals `v0 - v2`, `v1 - v3` are made orthogonal symmetrically (each turned
    /// by half their deviation from a right angle); `a`, `b` are the projections of the
    /// diagonals on those directions, which minimises the corner distance.
    pub fn fit(quad: &[Point3; 4], spin_angle: Real) -> Option<Self> {
        let d1 = quad[0] - quad[2];
        let d2 = quad[1] - quad[3];
        let n = d1.cross(&d2);
        if n.norm() <= 1e-12 * d1.norm() * d2.norm() {
            return None;
        }
        let n = n.normalize();
        let centre = Point3::from(quad.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0);
        // project the diagonals into the plane, then symmetrise to an orthogonal pair
        let p1 = (d1 - n * n.dot(&d1)).normalize();
        let p2 = (d2 - n * n.dot(&d2)).normalize();
        let u1 = (p1 - n.cross(&p2)).normalize();
        let u2 = n.cross(&u1);
        let a = d1.dot(&u1) / 2.0;
        let b = d2.dot(&u2) / 2.0;
        let rhombus = Rhombus::new(a, b).ok()?;
        let (s, c) = spin_angle.sin_cos();
        let x = u1 * c + u2 * s;
        let y = n.cross(&x);
        Some(Self {
            centre,
            frame: Matrix3::from_columns(&[x, y, n]),
            rhombus,
        })
    }

    /// Hub corner `i` in world coordinates.
    pub fn corner(&self, i: usize) -> Point3 {
        let r = self.rhombus.corners()[i % 4];
        self.centre + self.frame * r
    }

    /// All four corners.
    pub fn corners(&self) -> [Point3; 4] {
        std::array::from_fn(|i| self.corner(i))
    }

    /// Map a point from the hub frame to the world.
    pub fn to_world(&self, local: &Point3) -> Point3 {
        self.centre + self.frame * local.coords
    }

    /// The face normal (`z` of the hub frame).
    pub fn normal(&self) -> Vector3 {
        self.frame.column(2).into()
    }
}

/// The hub of every face. The mesh must be valid ([`QuadMesh::validate`]).
pub fn hubs_from_mesh(mesh: &QuadMesh, spin_angle: Real) -> Result<Vec<Hub>, FrameError> {
    (0..mesh.faces.len())
        .map(|f| {
            Hub::fit(&mesh.face_points(f), spin_angle).ok_or_else(|| {
                FrameError::Mesh(crate::MeshError::DegenerateFace {
                    face: f,
                    why: crate::Degeneracy::Other(
                        "no best-fit rhombus (diagonals parallel or reversed)".into(),
                    ),
                })
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_face_gives_its_own_corners_spun() {
        let q = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(2.0, 2.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
        ];
        let h = Hub::fit(&q, 0.0).unwrap();
        for i in 0..4 {
            assert!((h.corner(i) - q[i]).norm() < 1e-12);
        }
        let h = Hub::fit(&q, std::f64::consts::FRAC_PI_4).unwrap();
        // spun by 45 degrees: corner 0 points across edge 0 (toward its midpoint)
        let c0 = h.corner(0);
        assert!((c0 - Point3::new(1.0, 1.0 - 2f64.sqrt(), 0.0)).norm() < 1e-12);
        assert!((h.frame.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn skewed_quad_gets_orthogonal_diagonals() {
        let q = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(3.0, 0.2, 0.0),
            Point3::new(3.3, 2.8, 0.0),
            Point3::new(0.1, 3.1, 0.0),
        ];
        let h = Hub::fit(&q, 0.3).unwrap();
        let c = h.corners();
        assert!((c[0] - c[2]).dot(&(c[1] - c[3])).abs() < 1e-9);
        // a rhombus: all sides equal
        let s: Vec<f64> = (0..4).map(|i| (c[i] - c[(i + 1) % 4]).norm()).collect();
        assert!(s.iter().all(|x| (x - s[0]).abs() < 1e-9));
    }
}
