//! The deployment of the unit as cut: hub and primary plate joined by four rigid legs,
//! each pinned at its two neck centres ([`crate::UnitLayout::pins`]).
//!
//! A pose `(R, P)` places the hub plate's points `x` (flat frame) at `R x + P` in the primary
//! plate's frame, as in the closed form (`s = R r + P`). Leg `j` holds when
//! `|R h_j + P - p_j| = |h_j - p_j|`: four equations on six unknowns, a two-parameter family
//! as in the paper. We chart it with the paper's own parameters: the closed-form pose of the
//! tile's rhombus at `(theta, phi)` is moved to the nearest pose (least rotation and
//! translation, Gauss-Newton with minimum-norm steps) at which all four legs of the cut
//! hold. With zero widths the closed form already holds and nothing moves: the closed form
//! is the limit of this model, not a different one.

use sv_geom::{Matrix3, Point2, Point3, Real, Vector3};

use crate::kinematics::{deploy, CornerJacobian, Deployment, Rhombus};
use crate::{Pins, UnitError};

type Matrix4x6 = nalgebra::SMatrix<Real, 4, 6>;

/// Four rigid legs between the pins of one unit, in the flat unit's frame (z = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Linkage {
    /// Leg `j`'s pin on the hub plate.
    pub hub: [Vector3; 4],
    /// Leg `j`'s pin on the primary plate.
    pub rim: [Vector3; 4],
    /// Pin-to-pin length of leg `j` (mm), as cut.
    pub length: [Real; 4],
}

/// Largest leg error (mm) a projected pose may keep: the 1e-6 mm of `spinvalence check`.
/// The projection aims a million times lower and accepts this where rounding stalls it.
pub const LEG_TOLERANCE: Real = 1e-6;

/// Steps of the continuation from the zero-width legs to the legs as cut.
const CONTINUATION: usize = 2;

impl Linkage {
    /// The legs of a cut.
    pub fn new(pins: &Pins) -> Self {
        let v = |p: &Point2| Vector3::new(p.x, p.y, 0.0);
        let hub = pins.hub.each_ref().map(v);
        let rim = pins.rim.each_ref().map(v);
        Self {
            hub,
            rim,
            length: std::array::from_fn(|j| (hub[j] - rim[j]).norm()),
        }
    }

    /// The paper's zero-width legs: hub corner `j` to primary corner `j + 1`.
    pub fn zero_width(rhombus: &Rhombus) -> Self {
        let c = rhombus.corners();
        let hub = c;
        let rim = std::array::from_fn(|j| c[(j + 1) % 4]);
        Self {
            hub,
            rim,
            length: std::array::from_fn(|j| (hub[j] - rim[j]).norm()),
        }
    }

    /// Signed leg errors `|R h_j + P - p_j| - length_j` (mm) at a pose.
    pub fn leg_errors(&self, rotation: &Matrix3, translation: &Vector3) -> [Real; 4] {
        std::array::from_fn(|j| {
            (rotation * self.hub[j] + translation - self.rim[j]).norm() - self.length[j]
        })
    }

    /// The pose nearest `(rotation, translation)` at which every leg holds (to
    /// [`LEG_TOLERANCE`]). Errors when the legs cannot reach (the start is too far from the
    /// family, or the legs are in a singular position).
    pub fn project(
        &self,
        rotation: &Matrix3,
        translation: &Vector3,
    ) -> Result<(Matrix3, Vector3), UnitError> {
        self.project_within(rotation, translation, Real::INFINITY)
    }

    /// [`Linkage::project`] for a pose whose legs already nearly hold: no step is longer
    /// than `reach` times the leg errors, so that where the legs are nearly singular the pose
    /// settles nearby instead of jumping to another part of the family.
    pub fn settle(
        &self,
        rotation: &Matrix3,
        translation: &Vector3,
    ) -> Result<(Matrix3, Vector3), UnitError> {
        self.project_within(rotation, translation, 4.0)
    }

    fn project_within(
        &self,
        rotation: &Matrix3,
        translation: &Vector3,
        reach: Real,
    ) -> Result<(Matrix3, Vector3), UnitError> {
        let size = self
            .length
            .iter()
            .fold(0.0, |a: Real, l| a.max(*l))
            .max(1.0);
        let (mut r, mut p) = (*rotation, *translation);
        let worst_at = |r: &Matrix3, p: &Vector3| {
            self.leg_errors(r, p)
                .iter()
                .fold(0.0, |a: Real, e| a.max(e.abs()))
        };
        let merit =
            |r: &Matrix3, p: &Vector3| self.leg_errors(r, p).iter().map(|e| e * e).sum::<Real>();
        // the merit of the pose kept, carried over from the step that reached it
        let mut now = merit(&r, &p);
        // a settling pose creeps where the legs are nearly singular: more, shorter steps,
        // to a tenth of the tolerance. A projection converges in a few steps where the
        // legs are far from singular and creeps near it (spins far from 45 degrees: with
        // 60 steps the legs stayed 2-7e-6 mm off at 78-80 degrees)
        let (iterations, aim) = if reach.is_finite() {
            (4000, 0.1 * LEG_TOLERANCE)
        } else {
            (600, 1e-6 * LEG_TOLERANCE)
        };
        for it in 0..iterations {
            let mut c = nalgebra::Vector4::zeros();
            let mut jac = Matrix4x6::zeros();
            for j in 0..4 {
                let rh = r * self.hub[j];
                let v = rh + p - self.rim[j];
                let l = self.length[j].max(1e-12);
                // (|v|^2 - l^2) / 2l: the leg error to first order, smooth everywhere
                c[j] = (v.norm_squared() - l * l) / (2.0 * l);
                // d/d(omega): (rh x v) / l; the step's rotation is measured as the arc
                // (mm) it moves a point at the unit's size, so both halves weigh alike
                let dw = rh.cross(&v) / (l * size);
                let dp = v / l;
                for k in 0..3 {
                    jac[(j, k)] = dw[k];
                    jac[(j, 3 + k)] = dp[k];
                }
            }
            let worst = c.amax();
            if worst <= aim {
                return Ok((r, p));
            }
            // minimum-norm step, regularised: where the tile is symmetric (phi = 0, the two
            // axis cases meet) one combination of the legs is stationary to first order,
            // and holds by symmetry. The regulariser grows until the step lowers the leg
            // errors (Levenberg).
            let jjt = jac * jac.transpose();
            let trace = jjt.trace().max(1e-300);
            let mut mu = 1e-12 * trace;
            let mut moved = false;
            while mu < trace {
                let mut damped = jjt;
                for k in 0..4 {
                    damped[(k, k)] += mu;
                }
                let Some(chol) = damped.cholesky() else {
                    mu *= 10.0;
                    continue;
                };
                let mut step = -(jac.transpose() * chol.solve(&c));
                // a settling pose creeps: its reach doubles every 100 iterations
                let cap = reach * (1u64 << (it / 100).min(20)) as Real * c.norm() + 1e-12 * size;
                if step.norm() > cap {
                    step *= cap / step.norm();
                }
                let omega = Vector3::new(step[0], step[1], step[2]) / size;
                let rn = nalgebra::Rotation3::new(omega).into_inner() * r;
                let pn = p + Vector3::new(step[3], step[4], step[5]);
                let then = merit(&rn, &pn);
                if then < now {
                    r = rn;
                    p = pn;
                    now = then;
                    moved = true;
                    break;
                }
                mu *= 10.0;
            }
            if !moved {
                break;
            }
        }
        let err = worst_at(&r, &p);
        if err <= LEG_TOLERANCE {
            Ok((r, p))
        } else {
            Err(UnitError::LegsUnreachable { error: err })
        }
    }

    /// The pose of the unit as cut at the chart point `deployment` of the tile `rhombus`:
    /// the closed-form pose, carried onto these legs by moving the pins from the tile's
    /// corners (where the closed form holds) to their places in [`CONTINUATION`] steps,
    /// projecting at each.
    pub fn pose(
        &self,
        rhombus: &Rhombus,
        deployment: &Deployment,
    ) -> Result<(Matrix3, Vector3), UnitError> {
        let d = deploy(rhombus, deployment)?;
        let zero = Linkage::zero_width(rhombus);
        let (mut r, mut p) = (d.rotation, d.translation);
        for step in 1..=CONTINUATION {
            let k = step as Real / CONTINUATION as Real;
            let between = Linkage::between(&zero, self, k);
            (r, p) = between.project(&r, &p)?;
        }
        Ok((r, p))
    }

    /// The legs with every pin `k` of the way from `a`'s to `b`'s.
    fn between(a: &Linkage, b: &Linkage, k: Real) -> Linkage {
        let hub: [Vector3; 4] = std::array::from_fn(|j| a.hub[j] * (1.0 - k) + b.hub[j] * k);
        let rim: [Vector3; 4] = std::array::from_fn(|j| a.rim[j] * (1.0 - k) + b.rim[j] * k);
        Linkage {
            hub,
            rim,
            length: std::array::from_fn(|j| (hub[j] - rim[j]).norm()),
        }
    }

    /// The primary plate's corners (the tile scaled by `expansion`) in the hub's frame at
    /// the chart point `deployment`, with their derivatives along the chart (forward
    /// differences of the projected pose, step 1e-6 rad).
    pub fn primary_in_hub_frame(
        &self,
        rhombus: &Rhombus,
        deployment: &Deployment,
        expansion: Real,
    ) -> Result<CornerJacobian, UnitError> {
        let corners = |d: &Deployment| -> Result<[Point3; 4], UnitError> {
            let (r, p) = self.pose(rhombus, d)?;
            let rt = r.transpose();
            Ok(rhombus
                .corners()
                .map(|c| Point3::from(rt * (c * expansion - p))))
        };
        let h = 1e-6;
        let at = |dt: Real, dp: Real| {
            let mut d = *deployment;
            d.theta += dt;
            d.phi += dp;
            corners(&d)
        };
        let c0 = corners(deployment)?;
        let (tp, pp) = (at(h, 0.0)?, at(0.0, h)?);
        Ok(CornerJacobian {
            corners: c0,
            d_theta: std::array::from_fn(|i| (tp[i] - c0[i]) / h),
            d_phi: std::array::from_fn(|i| (pp[i] - c0[i]) / h),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CutWidths, UnitLayout};
    use sv_geom::Point2;

    fn tile(r: &Rhombus, e: Real) -> [Point2; 4] {
        r.corners().map(|c| Point2::new(c.x * e, c.y * e))
    }

    const DEFAULT: CutWidths = CutWidths::STEEL_3MM;

    #[test]
    fn every_leg_of_the_cut_holds_exactly_over_the_chart() {
        // a square (symmetric: the two axis cases meet at phi = 0) and a skewed rhombus,
        // over the solver's whole box
        for (a, b) in [(212.0, 212.0), (225.0, 195.0)] {
            let r = Rhombus::new(a, b).unwrap();
            let l = Linkage::new(&UnitLayout::new(&tile(&r, 1.0), &DEFAULT).unwrap().pins());
            for ti in 0..8 {
                let theta = 0.05 + 0.2 * ti as Real;
                for pi in 0..9 {
                    let phi = -1.0 + 0.25 * pi as Real;
                    let (rot, p) = l.pose(&r, &Deployment::new(theta, phi)).unwrap();
                    assert!((rot.determinant() - 1.0).abs() < 1e-12);
                    for e in l.leg_errors(&rot, &p) {
                        assert!(
                            e.abs() < 1e-6,
                            "{a}x{b} theta {theta} phi {phi}: leg off {e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_unit_as_cut_tends_to_the_closed_form_as_legs_and_slots_vanish() {
        let r = Rhombus::new(212.0, 200.0).unwrap();
        let dep = Deployment::new(0.75, 0.12);
        let closed = deploy(&r, &dep).unwrap();
        let mut last = Real::INFINITY;
        for k in [1.0, 0.1, 0.01, 0.001] {
            let pins = UnitLayout::new(&tile(&r, 1.0), &DEFAULT.scaled(k))
                .unwrap()
                .pins();
            let (rot, p) = Linkage::new(&pins).pose(&r, &dep).unwrap();
            let off = (0..4)
                .map(|i| {
                    let c = r.corners()[i];
                    (rot * c + p - closed.hub[i].coords).norm()
                })
                .fold(0.0, Real::max);
            assert!(off < last, "k = {k}: {off} mm not below {last}");
            last = off;
        }
        assert!(last < 0.1, "hub still {last} mm off the closed form");
        // and the zero-width legs leave the closed form where it is
        let z = Linkage::zero_width(&r);
        let (rot, p) = z.pose(&r, &dep).unwrap();
        assert!((p - closed.translation).norm() < 1e-9);
        assert!((rot - closed.rotation).norm() < 1e-12);
    }

    #[test]
    fn the_chart_derivatives_match_the_closed_form_in_the_zero_width_limit() {
        let r = Rhombus::new(212.0, 200.0).unwrap();
        let dep = Deployment::new(0.75, 0.12);
        let exact = crate::primary_in_hub_frame(&r, &dep, 1.0).unwrap();
        let fd = Linkage::zero_width(&r)
            .primary_in_hub_frame(&r, &dep, 1.0)
            .unwrap();
        for i in 0..4 {
            assert!((exact.corners[i] - fd.corners[i]).norm() < 1e-9);
            assert!((exact.d_theta[i] - fd.d_theta[i]).norm() < 1e-3);
            assert!((exact.d_phi[i] - fd.d_phi[i]).norm() < 1e-3);
        }
    }
}
