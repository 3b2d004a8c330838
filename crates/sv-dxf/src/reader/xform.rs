//! 2D affine maps from an entity's own coordinates (its OCS, inside nested blocks) to the
//! drawing's world coordinates in millimetres.

/// `p -> M p + t` with `M = [[a, b], [c, d]]` (row-major).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Affine {
    m: [f64; 4],
    t: [f64; 2],
}

impl Affine {
    pub(crate) const IDENTITY: Affine = Affine {
        m: [1.0, 0.0, 0.0, 1.0],
        t: [0.0, 0.0],
    };

    pub(crate) fn scale(sx: f64, sy: f64) -> Self {
        Self {
            m: [sx, 0.0, 0.0, sy],
            t: [0.0, 0.0],
        }
    }

    pub(crate) fn rotation(radians: f64) -> Self {
        let (s, c) = radians.sin_cos();
        Self {
            m: [c, -s, s, c],
            t: [0.0, 0.0],
        }
    }

    pub(crate) fn translation(x: f64, y: f64) -> Self {
        Self {
            m: [1.0, 0.0, 0.0, 1.0],
            t: [x, y],
        }
    }

    /// `self` after `other`: `p -> self(other(p))`.
    pub(crate) fn then(&self, other: &Affine) -> Affine {
        let [a, b, c, d] = self.m;
        let [e, f, g, h] = other.m;
        Affine {
            m: [a * e + b * g, a * f + b * h, c * e + d * g, c * f + d * h],
            t: self.apply(other.t),
        }
    }

    pub(crate) fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let [a, b, c, d] = self.m;
        [
            a * p[0] + b * p[1] + self.t[0],
            c * p[0] + d * p[1] + self.t[1],
        ]
    }

    /// The linear part applied to a vector.
    pub(crate) fn apply_vector(&self, v: [f64; 2]) -> [f64; 2] {
        let [a, b, c, d] = self.m;
        [a * v[0] + b * v[1], c * v[0] + d * v[1]]
    }

    pub(crate) fn det(&self) -> f64 {
        self.m[0] * self.m[3] - self.m[1] * self.m[2]
    }

    /// Whether the map reverses orientation (a mirror).
    pub(crate) fn mirrors(&self) -> bool {
        self.det() < 0.0
    }

    /// Whether the map is a similarity (circles stay circles), to 1e-9 relative.
    pub(crate) fn is_conformal(&self) -> bool {
        let [a, b, c, d] = self.m;
        let s = a.hypot(c).max(b.hypot(d)).max(f64::MIN_POSITIVE);
        let tol = 1e-9 * s;
        ((a - d).abs() <= tol && (b + c).abs() <= tol)
            || ((a + d).abs() <= tol && (b - c).abs() <= tol)
    }
}

/// The map from an entity's object coordinate system (extrusion direction `n`) to the
/// coordinates of its block, when its plane is parallel to XY: the identity for (0, 0, 1),
/// a mirror in x for (0, 0, -1) (the arbitrary-axis algorithm of the DXF reference gives
/// the OCS x axis (-1, 0, 0) there). `None` for a tilted plane.
pub(crate) fn ocs(n: [f64; 3]) -> Option<Affine> {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return Some(Affine::IDENTITY);
    }
    let (x, y, z) = (n[0] / len, n[1] / len, n[2] / len);
    if x.abs() > 1e-9 || y.abs() > 1e-9 {
        return None;
    }
    Some(if z > 0.0 {
        Affine::IDENTITY
    } else {
        Affine::scale(-1.0, 1.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn composition_and_conformality() {
        let r = Affine::rotation(std::f64::consts::FRAC_PI_2);
        let t = Affine::translation(10.0, 0.0);
        // rotate, then translate
        let p = t.then(&r).apply([1.0, 0.0]);
        assert!((p[0] - 10.0).abs() < 1e-12 && (p[1] - 1.0).abs() < 1e-12);
        assert!(r.is_conformal() && !r.mirrors());
        let m = Affine::scale(-2.0, 2.0).then(&r);
        assert!(m.is_conformal() && m.mirrors() && (m.det() + 4.0).abs() < 1e-12);
        assert!(!Affine::scale(1.0, 2.0).is_conformal());
        assert_eq!(
            ocs([0.0, 0.0, -1.0]).unwrap().apply([3.0, 4.0]),
            [-3.0, 4.0]
        );
        assert!(ocs([0.0, 0.6, 0.8]).is_none());
    }
}
