//! The closed form of sec. 3.2 and its derivatives.

use serde::{Deserialize, Serialize};
use sv_geom::{cross_matrix, Matrix3, Point3, Real, Vector3};

use crate::UnitError;

/// A rhombic tile in its own frame: centroid at the origin, corner 0 at `(a, 0, 0)`,
/// corner 1 at `(0, b, 0)`, corner 2 at `(-a, 0, 0)`, corner 3 at `(0, -b, 0)`
/// (counter-clockwise seen from `+z`). `a`, `b` are the half-diagonals in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rhombus {
    a: Real,
    b: Real,
}

impl Rhombus {
    /// A rhombus with half-diagonals `a` (along x) and `b` (along y).
    pub fn new(a: Real, b: Real) -> Result<Self, UnitError> {
        if a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0 {
            Ok(Self { a, b })
        } else {
            Err(UnitError::BadRhombus { a, b })
        }
    }
    /// Half-diagonal along x (`|r1|`).
    pub fn a(&self) -> Real {
        self.a
    }
    /// Half-diagonal along y (`|r2|`).
    pub fn b(&self) -> Real {
        self.b
    }
    /// The half-diagonal vectors `r1 .. r4` (corners), counter-clockwise.
    pub fn corners(&self) -> [Vector3; 4] {
        [
            Vector3::new(self.a, 0.0, 0.0),
            Vector3::new(0.0, self.b, 0.0),
            Vector3::new(-self.a, 0.0, 0.0),
            Vector3::new(0.0, -self.b, 0.0),
        ]
    }
    /// Side length `sqrt(a^2 + b^2)`.
    pub fn side(&self) -> Real {
        self.a.hypot(self.b)
    }

    /// This rhombus with its half-diagonals scaled by `[along x, along y]`.
    pub fn scaled(&self, scale: [Real; 2]) -> Result<Self, UnitError> {
        Self::new(self.a * scale[0], self.b * scale[1])
    }
}

/// Which diagonal the rotation axis is orthogonal to (the two cases of the theorem).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AxisCase {
    /// `t . r1 = 0`: `t = sin(phi) r2/|r2| + cos(phi) n` (the paper's case 2).
    #[default]
    OrthogonalToR1,
    /// `t . r2 = 0`: `t = sin(phi) r1/|r1| + cos(phi) n` (the symmetric case).
    OrthogonalToR2,
}

/// The sign of `P` along `d = (R r1 - r2) x (R r2 + r1)`. `d` is continuous in
/// `(theta, phi)` and equals `2 r1 x r2` (the tile normal, `+z`) at `theta = 0`, but it
/// vanishes on the degenerate curve `cos(phi) = (a/b) cot(theta/2)` of a rhombus with
/// half-diagonals `a`, `b` (see docs/geometry.md), where the side is undefined. Near the
/// flat state [`Side::HubPositive`] deploys the hub to the `+z` side of the primary tile and
/// [`Side::HubNegative`] to the `-z` side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// `P = +sqrt(g) d/|d|`.
    #[default]
    HubPositive,
    /// `P = -sqrt(g) d/|d|`.
    HubNegative,
}

impl Side {
    /// `+1` or `-1`.
    pub fn sign(self) -> Real {
        match self {
            Side::HubPositive => 1.0,
            Side::HubNegative => -1.0,
        }
    }
    /// The other side.
    pub fn flipped(self) -> Self {
        match self {
            Side::HubPositive => Side::HubNegative,
            Side::HubNegative => Side::HubPositive,
        }
    }
}

/// One point of the configuration space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Deployment {
    /// Rotation angle about the axis `t` (rad). `0` is the flat state.
    pub theta: Real,
    /// Tilt of the axis away from the tile normal (rad), in `[-pi/2, pi/2]`.
    pub phi: Real,
    /// Which diagonal the axis is orthogonal to.
    pub case: AxisCase,
    /// Which side of the primary tile the hub goes to.
    pub side: Side,
}

impl Deployment {
    /// `(theta, phi)` with the default case ([`AxisCase::OrthogonalToR1`]) and side.
    pub fn new(theta: Real, phi: Real) -> Self {
        Self {
            theta,
            phi,
            case: AxisCase::default(),
            side: Side::default(),
        }
    }
    /// The same deployment with another axis case.
    pub fn with_case(mut self, case: AxisCase) -> Self {
        self.case = case;
        self
    }
    /// The same deployment with another side.
    pub fn with_side(mut self, side: Side) -> Self {
        self.side = side;
        self
    }
}

/// A deployed unit in the primary tile's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Deployed {
    /// `R`: rotation by `theta` about the axis.
    pub rotation: Matrix3,
    /// `P`: from the primary centroid to the hub centroid.
    pub translation: Vector3,
    /// The unit rotation axis `t`.
    pub axis: Vector3,
    /// Primary corners `r_i`.
    pub primary: [Point3; 4],
    /// Hub corners `s_i = R r_i + P`.
    pub hub: [Point3; 4],
}

/// `2 (R r1).r2 = 2 sin(theta) cos(phi) a b = |P|^2`, the squared frame depth. It is the
/// same in both axis cases; the deployment is feasible exactly where it is `>= 0`.
pub fn depth_squared(rhombus: &Rhombus, theta: Real, phi: Real) -> Real {
    2.0 * theta.sin() * phi.cos() * rhombus.a * rhombus.b
}

/// The unit rotation axis `t` for a case and tilt, and its derivative with respect to `phi`.
pub fn axis(case: AxisCase, phi: Real) -> (Vector3, Vector3) {
    let (s, c) = phi.sin_cos();
    match case {
        AxisCase::OrthogonalToR1 => (Vector3::new(0.0, s, c), Vector3::new(0.0, c, -s)),
        AxisCase::OrthogonalToR2 => (Vector3::new(s, 0.0, c), Vector3::new(c, 0.0, -s)),
    }
}

/// Rodrigues' rotation (eq. 9) by `theta` about the unit axis `t`.
pub fn rotation(t: &Vector3, theta: Real) -> Matrix3 {
    let k = cross_matrix(t);
    Matrix3::identity() + k * theta.sin() + k * k * (1.0 - theta.cos())
}

/// Internal: `R`, `P` and (optionally) their partial derivatives.
struct Closed {
    r: Matrix3,
    p: Vector3,
    t: Vector3,
    /// `(dR/dtheta, dR/dphi, dP/dtheta, dP/dphi)`
    derivs: Option<(Matrix3, Matrix3, Vector3, Vector3)>,
}

fn closed_form(
    rh: &Rhombus,
    dep: &Deployment,
    with_derivatives: bool,
) -> Result<Closed, UnitError> {
    let (theta, phi) = (dep.theta, dep.phi);
    let bad = UnitError::Infeasible { theta, phi };
    if !theta.is_finite() || !phi.is_finite() {
        return Err(bad);
    }
    let g = depth_squared(rh, theta, phi);
    let scale = rh.a * rh.b;
    if g < -1e-12 * scale {
        return Err(bad);
    }
    let g = g.max(0.0);
    let (t, t_phi) = axis(dep.case, phi);
    let (st, ct) = theta.sin_cos();
    let k = cross_matrix(&t);
    let k2 = k * k;
    let r = Matrix3::identity() + k * st + k2 * (1.0 - ct);
    let [r1, r2, _, _] = rh.corners();
    let u = r * r1 - r2;
    let v = r * r2 + r1;
    let d = u.cross(&v);
    let dn = d.norm();
    if dn <= 1e-10 * scale {
        return Err(UnitError::Degenerate { theta, phi });
    }
    let dh = d / dn;
    let m = g.sqrt();
    let sigma = dep.side.sign();
    let p = dh * (sigma * m);
    let derivs = if with_derivatives {
        if g <= 1e-14 * scale {
            return Err(UnitError::OnBoundary { theta, phi });
        }
        let kp = cross_matrix(&t_phi);
        let r_th = k * ct + k2 * st;
        let r_ph = kp * st + (kp * k + k * kp) * (1.0 - ct);
        let dd = |rx: &Matrix3| (rx * r1).cross(&v) + u.cross(&(rx * r2));
        let dhat = |ddx: Vector3| (ddx - dh * dh.dot(&ddx)) / dn;
        let ab2 = 2.0 * rh.a * rh.b;
        let (sp, cp) = phi.sin_cos();
        let g_th = ab2 * ct * cp;
        let g_ph = -ab2 * st * sp;
        let p_th = (dh * (g_th / (2.0 * m)) + dhat(dd(&r_th)) * m) * sigma;
        let p_ph = (dh * (g_ph / (2.0 * m)) + dhat(dd(&r_ph)) * m) * sigma;
        Some((r_th, r_ph, p_th, p_ph))
    } else {
        None
    };
    Ok(Closed { r, p, t, derivs })
}

/// Deploy a unit: `(theta, phi, case, side) -> (R, P)` and the corner positions, in the
/// primary tile's frame. Errors outside the feasible domain and at the degenerate points
/// where `P` is not unique.
pub fn deploy(rhombus: &Rhombus, deployment: &Deployment) -> Result<Deployed, UnitError> {
    let c = closed_form(rhombus, deployment, false)?;
    let rs = rhombus.corners();
    let primary = rs.map(Point3::from);
    let hub = rs.map(|ri| Point3::from(c.r * ri + c.p));
    Ok(Deployed {
        rotation: c.r,
        translation: c.p,
        axis: c.t,
        primary,
        hub,
    })
}

/// Corners of the (expanded) primary tile in the *hub's* frame, with their derivatives.
#[derive(Clone, Debug, PartialEq)]
pub struct CornerJacobian {
    /// Corner `i` of the primary tile scaled by the expansion about its centroid.
    pub corners: [Point3; 4],
    /// `d corner_i / d theta`.
    pub d_theta: [Vector3; 4],
    /// `d corner_i / d phi`.
    pub d_phi: [Vector3; 4],
}

/// The primary tile seen from the hub: the hub's frame has its origin at the hub centroid,
/// `x` toward hub corner 0, `y` toward hub corner 1, so the hub corners are the rhombus
/// corners there. The primary corners are `R^T (e r_i - P)` (`e` = expansion about the
/// primary centroid), and this returns their exact partial derivatives with respect to
/// `theta` and `phi`, which are unbounded (an error) on the domain boundary.
pub fn primary_in_hub_frame(
    rhombus: &Rhombus,
    deployment: &Deployment,
    expansion: Real,
) -> Result<CornerJacobian, UnitError> {
    let c = closed_form(rhombus, deployment, true)?;
    let (r_th, r_ph, p_th, p_ph) = c.derivs.expect("requested derivatives");
    let rt = c.r.transpose();
    let rs = rhombus.corners();
    let mut out = CornerJacobian {
        corners: [Point3::origin(); 4],
        d_theta: [Vector3::zeros(); 4],
        d_phi: [Vector3::zeros(); 4],
    };
    for (i, ri) in rs.iter().enumerate() {
        let w = ri * expansion - c.p;
        out.corners[i] = Point3::from(rt * w);
        out.d_theta[i] = r_th.transpose() * w - rt * p_th;
        out.d_phi[i] = r_ph.transpose() * w - rt * p_ph;
    }
    Ok(out)
}

/// Result of [`inverse`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inverse {
    /// The recovered deployment.
    pub deployment: Deployment,
    /// Largest distance (mm) between the given hub corners and the hub the recovered
    /// deployment produces from the given primary tile: 0 for an exact unit.
    pub residual: Real,
}

/// Recover `(theta, phi, case, side)` from a hub and its primary tile (any placement in
/// space, corners in matching order). Fails when the pair is not congruent, not rhombic,
/// or its rotation axis is orthogonal to neither diagonal (`tolerance` is in mm).
pub fn inverse(
    hub: &[Point3; 4],
    primary: &[Point3; 4],
    tolerance: Real,
) -> Result<Inverse, UnitError> {
    let not = |m: String| UnitError::NotAUnit(m);
    let cp = Point3::from((primary.iter().fold(Vector3::zeros(), |a, p| a + p.coords)) / 4.0);
    let h1 = (primary[0] - primary[2]) / 2.0;
    let h2 = (primary[1] - primary[3]) / 2.0;
    let (a, b) = (h1.norm(), h2.norm());
    let rh = Rhombus::new(a, b).map_err(|e| not(e.to_string()))?;
    let ex = h1 / a;
    let n = h1.cross(&h2);
    if n.norm() <= 1e-12 * a * b {
        return Err(not("primary tile is degenerate".into()));
    }
    let ez = n.normalize();
    let ey = ez.cross(&ex);
    let frame = Matrix3::from_columns(&[ex, ey, ez]);
    let to_local = |p: &Point3| frame.transpose() * (p - cp);
    // r_i and s_i in the primary frame
    let r: [Vector3; 4] = primary.map(|p| to_local(&p));
    let s: [Vector3; 4] = hub.map(|p| to_local(&p));
    let sc = (s[0] + s[1] + s[2] + s[3]) / 4.0;
    // Kabsch: R minimising sum |R r_i - (s_i - sc)|^2
    let mut h = Matrix3::zeros();
    for i in 0..4 {
        h += (s[i] - sc) * r[i].transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut dmat = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        dmat[(2, 2)] = -1.0;
    }
    let rot = u * dmat * vt;
    // axis and angle, theta in [0, pi]
    let cos_t = ((rot.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let theta = cos_t.acos();
    let w = Vector3::new(
        rot[(2, 1)] - rot[(1, 2)],
        rot[(0, 2)] - rot[(2, 0)],
        rot[(1, 0)] - rot[(0, 1)],
    );
    let mut t = if w.norm() > 1e-12 {
        w.normalize()
    } else {
        Vector3::z()
    };
    if t.z < 0.0 {
        // (t, theta) and (-t, -theta) are the same rotation; the domain wants cos(phi) >= 0
        t = -t;
    }
    let theta = if t.dot(&w) < 0.0 { -theta } else { theta };
    let case = if t.x.abs() <= t.y.abs() {
        AxisCase::OrthogonalToR1
    } else {
        AxisCase::OrthogonalToR2
    };
    let phi = match case {
        AxisCase::OrthogonalToR1 => t.y.atan2(t.z),
        AxisCase::OrthogonalToR2 => t.x.atan2(t.z),
    };
    let mut best: Option<Inverse> = None;
    for side in [Side::HubPositive, Side::HubNegative] {
        let dep = Deployment {
            theta,
            phi,
            case,
            side,
        };
        let Ok(d) = deploy(&rh, &dep) else { continue };
        let residual = (0..4)
            .map(|i| (d.hub[i].coords - s[i]).norm())
            .fold(0.0, Real::max);
        if best.is_none_or(|b| residual < b.residual) {
            best = Some(Inverse {
                deployment: dep,
                residual,
            });
        }
    }
    let best =
        best.ok_or_else(|| not(format!("theta = {theta:.6}, phi = {phi:.6} is infeasible")))?;
    if best.residual > tolerance {
        return Err(not(format!(
            "hub misses the closed-form deployment by {:.3e} mm (tolerance {tolerance:.1e})",
            best.residual
        )));
    }
    Ok(best)
}

#[cfg(test)]
mod tests;
