//! Rigid least-squares fit of one point set onto another (Kabsch).

use crate::{Isometry3, Matrix3, Point3, Real, UnitQuaternion, Vector3};

/// The proper rigid motion `m` (rotation and translation, no scale, no mirror) that puts
/// `from[i]` nearest `to[i]` in least squares, and the largest residual `|m from[i] - to[i]|`.
/// `None` for fewer than 3 pairs, sets of different lengths, or a failed decomposition.
/// Planar sets (a flat part onto its folded pose) fit too: of the rotation and the mirror
/// that fit them equally, the rotation is returned.
pub fn rigid_fit(from: &[Point3], to: &[Point3]) -> Option<(Isometry3, Real)> {
    if from.len() < 3 || from.len() != to.len() {
        return None;
    }
    let n = from.len() as Real;
    let cf = from.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let ct = to.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let mut h = Matrix3::zeros();
    for (a, b) in from.iter().zip(to) {
        h += (a.coords - cf) * (b.coords - ct).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    let rotation =
        UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(r));
    let motion = Isometry3::from_parts((ct - rotation * cf).into(), rotation);
    let residual = from
        .iter()
        .zip(to)
        .map(|(a, b)| (motion * a - b).norm())
        .fold(0.0, Real::max);
    residual.is_finite().then_some((motion, residual))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_the_motion_of_a_flat_square() {
        let flat = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(300.0, 0.0, 0.0),
            Point3::new(300.0, 300.0, 0.0),
            Point3::new(0.0, 300.0, 0.0),
        ];
        let m = Isometry3::new(
            Vector3::new(10.0, -4.0, 900.0),
            Vector3::new(0.3, -1.1, 0.7),
        );
        let moved = flat.map(|p| m * p);
        let (fit, res) = rigid_fit(&flat, &moved).unwrap();
        assert!(res < 1e-9, "{res}");
        assert!((fit.rotation.angle_to(&m.rotation)) < 1e-12);
        // a proper rotation even for a flat set: flat +z goes to the moved normal
        assert!((fit.rotation * Vector3::z() - m.rotation * Vector3::z()).norm() < 1e-12);
        assert!(rigid_fit(&flat[..2], &moved[..2]).is_none());
    }
}
