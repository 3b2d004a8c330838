//! One unit as a function of its face's four vertices and its primary plate's pose: the
//! primary plate and the hub plate as cut in the world, and how far each of its four legs
//! is from its length as cut, with their derivatives.
//!
//! The hub is the spun best-fit rhombus of the face ([`Hub::fit`]) and the cut of its tile
//! ([`UnitLayout`]) depends on the rhombus' half-diagonals. The primary plate is placed by
//! its own pose `(Q, t)` (tile frame to world), a free rigid motion: the legs are
//! residuals of the solve, not a chart. (The chart of `sv_unit::Linkage::pose` is not
//! smooth where the tile is nearly symmetric and `phi` near 0: there the cut linkage's two
//! branches meet, and a projection onto them can jump from one to the other.)

use sv_geom::{Matrix3, Point2, Point3, Real, Rotation3, Vector3};
use sv_unit::{CutWidths, Linkage, Rhombus, UnitLayout};

use crate::Hub;

/// Inputs of one unit: the 12 coordinates of its face's vertices (vertex-major), then the
/// primary plate's rotation increment (3, an arc in mm at the length scale), its
/// translation increment (3, mm), the hub's spin (an arc in mm at the length scale), the
/// tile's two half-diagonals (each scaled by `1 + input / length scale`) and the hub's lift
/// off its face along the face's normal (mm).
pub(crate) const INPUTS: usize = 22;

/// How a unit sits on its face: the hub's spin in the face (rad) and the scales of its
/// tile's half-diagonals against the face's best-fit rhombus (the cut, the hub plate with
/// it): the face places the unit, its tile need not be the face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Shape {
    pub spin: Real,
    pub scale: [Real; 2],
    /// The hub plate's lift off its face, along the face's normal (mm): where hubs lap, one
    /// lies on the other.
    pub lift: Real,
}

/// Points of one unit: the primary plate's corners (the tile), then the hub plate's.
pub(crate) const POINTS: usize = 8;

/// How a unit is built from its inputs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Model {
    pub spin: Real,
    pub expansion: Real,
    pub cut: Option<CutWidths>,
    /// Length of the arc per radian of the rotation inputs.
    pub scale: Real,
}

/// The primary plate's pose: tile-frame point `r` at `q r + t` in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PlatePose {
    pub q: Matrix3,
    pub t: Vector3,
}

impl PlatePose {
    /// This pose turned by the rotation vector `omega` (rad) about its own origin, then
    /// moved by `shift`.
    pub fn moved(&self, omega: &Vector3, shift: &Vector3) -> Self {
        Self {
            q: Rotation3::new(*omega).into_inner() * self.q,
            t: self.t + shift,
        }
    }
}

/// A unit's points and leg errors, and with [`Model::points`]' `derivatives` theirs.
#[derive(Clone, Debug)]
pub(crate) struct UnitPoints {
    pub points: [Point3; POINTS],
    /// Per leg: its pin-to-pin distance minus its length as cut (mm).
    pub legs: [Real; 4],
    /// `d[p][i]`: derivative of point `p` along input `i`.
    pub d: Option<Box<[[Vector3; INPUTS]; POINTS]>>,
    /// `dl[j][i]`: derivative of leg `j`'s error along input `i`.
    pub dl: Option<Box<[[Real; INPUTS]; 4]>>,
}

impl UnitPoints {
    pub fn primary(&self) -> [Point3; 4] {
        std::array::from_fn(|i| self.points[i])
    }
    pub fn hub_plate(&self) -> [Point3; 4] {
        std::array::from_fn(|i| self.points[4 + i])
    }
}

/// A unit's failure: the input is off the unit's domain.
#[derive(Clone, Debug)]
pub(crate) enum UnitFailure {
    NoHub,
    Cut(String),
}

/// The cut of a hub's tile scaled by `e`: its legs and hub plate (hub frame), and the
/// tile's rhombus.
fn cut_of(
    hub: &Hub,
    cut: Option<&CutWidths>,
    e: Real,
    scale: [Real; 2],
) -> Result<(Linkage, [Point3; 4], Rhombus), UnitFailure> {
    let rhombus = hub
        .rhombus
        .scaled(scale)
        .map_err(|e| UnitFailure::Cut(e.to_string()))?;
    match cut {
        Some(w) => {
            let tile = rhombus.corners().map(|c| Point2::new(c.x * e, c.y * e));
            let layout = UnitLayout::new(&tile, w).map_err(|e| UnitFailure::Cut(e.0))?;
            Ok((
                Linkage::new(&layout.pins()),
                layout.hub.map(|p| Point3::new(p.x, p.y, 0.0)),
                rhombus,
            ))
        }
        None => {
            let scaled = Rhombus::new(rhombus.a() * e, rhombus.b() * e)
                .map_err(|e| UnitFailure::Cut(e.to_string()))?;
            Ok((
                Linkage::zero_width(&scaled),
                scaled.corners().map(Point3::from),
                rhombus,
            ))
        }
    }
}

/// What a unit's face, spin and tile scales make of it: its hub (on the face), the legs and
/// hub plate of its cut (hub frame) and its tile's rhombus. Its pose and its hub's lift only
/// place it.
struct Made {
    hub: Hub,
    legs: Linkage,
    hub_plate: [Point3; 4],
    rhombus: Rhombus,
}

impl Model {
    /// The unit on `quad` with `shape`'s spin and scales (a hub fit and a cut).
    fn make(&self, quad: &[Point3; 4], shape: Shape) -> Result<Made, UnitFailure> {
        let hub = Hub::fit(quad, shape.spin).ok_or(UnitFailure::NoHub)?;
        let (legs, hub_plate, rhombus) =
            cut_of(&hub, self.cut.as_ref(), self.expansion, shape.scale)?;
        Ok(Made {
            hub,
            legs,
            hub_plate,
            rhombus,
        })
    }

    /// The unit's points and leg errors, `made` with its primary plate at `pose` and its
    /// hub lifted by `lift`.
    fn place(&self, made: &Made, pose: &PlatePose, lift: Real) -> ([Point3; POINTS], [Real; 4]) {
        let mut hub = made.hub;
        hub.centre += hub.normal() * lift;
        let e = self.expansion;
        let mut points = [Point3::origin(); POINTS];
        for (i, c) in made.rhombus.corners().iter().enumerate() {
            points[i] = Point3::from(pose.q * (c * e) + pose.t);
            points[4 + i] = hub.to_world(&made.hub_plate[i]);
        }
        let mut errors = [0.0; 4];
        for j in 0..4 {
            let h = hub.to_world(&Point3::from(made.legs.hub[j]));
            let r = Point3::from(pose.q * made.legs.rim[j] + pose.t);
            errors[j] = (h - r).norm() - made.legs.length[j];
        }
        (points, errors)
    }

    /// The unit's points and leg errors at `quad` with its primary plate at `pose`.
    fn eval(
        &self,
        quad: &[Point3; 4],
        pose: &PlatePose,
        shape: Shape,
    ) -> Result<([Point3; POINTS], [Real; 4]), UnitFailure> {
        Ok(self.place(&self.make(quad, shape)?, pose, shape.lift))
    }

    /// The unit's points and leg errors; with `derivatives`, their derivatives along its
    /// [`INPUTS`] too (central differences: each evaluation is a hub fit and a cut, no
    /// solve).
    pub fn points(
        &self,
        quad: &[Point3; 4],
        pose: &PlatePose,
        shape: Shape,
        derivatives: bool,
    ) -> Result<UnitPoints, UnitFailure> {
        let made = self.make(quad, shape)?;
        let (points, legs) = self.place(&made, pose, shape.lift);
        if !derivatives {
            return Ok(UnitPoints {
                points,
                legs,
                d: None,
                dl: None,
            });
        }
        let mut d = Box::new([[Vector3::zeros(); INPUTS]; POINTS]);
        let mut dl = Box::new([[0.0; INPUTS]; 4]);
        let h = 1e-4;
        for i in 0..INPUTS {
            let at = |s: Real| {
                let mut q = *quad;
                let mut p = *pose;
                let mut a = shape;
                let step = s * h;
                // the pose and the lift only place the unit: no new hub fit and cut
                if (12..18).contains(&i) || i == 21 {
                    if i == 21 {
                        a.lift += step;
                    } else if i < 15 {
                        let mut w = Vector3::zeros();
                        w[i - 12] = step / self.scale;
                        p = pose.moved(&w, &Vector3::zeros());
                    } else {
                        let mut v = Vector3::zeros();
                        v[i - 15] = step;
                        p = pose.moved(&Vector3::zeros(), &v);
                    }
                    return Ok(self.place(&made, &p, a.lift));
                }
                if i == 18 {
                    a.spin += step / self.scale;
                } else if i >= 19 {
                    a.scale[i - 19] += step / self.scale;
                } else {
                    q[i / 3][i % 3] += step;
                }
                self.eval(&q, &p, a)
            };
            let ((pp, lp), (pm, lm)) = (at(1.0)?, at(-1.0)?);
            for k in 0..POINTS {
                d[k][i] = (pp[k] - pm[k]) / (2.0 * h);
            }
            for j in 0..4 {
                dl[j][i] = (lp[j] - lm[j]) / (2.0 * h);
            }
        }
        Ok(UnitPoints {
            points,
            legs,
            d: Some(d),
            dl: Some(dl),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_unit::{CutWidths, Deployment};

    #[test]
    fn a_pose_from_the_linkage_has_its_legs_and_moving_it_breaks_them() {
        let model = Model {
            spin: std::f64::consts::FRAC_PI_4,
            expansion: 1.0,
            cut: Some(CutWidths::STEEL_3MM),
            scale: 300.0,
        };
        let quad = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(300.0, 10.0, 5.0),
            Point3::new(305.0, 290.0, 12.0),
            Point3::new(-8.0, 296.0, 4.0),
        ];
        let hub = Hub::fit(&quad, model.spin).unwrap();
        let (legs, _, rhombus) = cut_of(&hub, model.cut.as_ref(), 1.0, [1.0, 1.0]).unwrap();
        let (r, p) = legs.pose(&rhombus, &Deployment::new(0.8, 0.1)).unwrap();
        // hub-frame pose (hub x at R x + P in the tile frame) to the plate's world pose
        let q = hub.frame * r.transpose();
        let pose = PlatePose {
            q,
            t: hub.centre.coords - q * p,
        };
        let shape = Shape {
            spin: model.spin,
            scale: [1.0, 1.0],
            lift: 0.0,
        };
        let u = model.points(&quad, &pose, shape, true).unwrap();
        assert!(u.legs.iter().all(|e| e.abs() < 1e-6), "{:?}", u.legs);
        // a 0.01 mm shift along x changes the legs by their x direction cosines
        let moved = model
            .points(
                &quad,
                &pose.moved(&Vector3::zeros(), &Vector3::new(0.01, 0.0, 0.0)),
                shape,
                false,
            )
            .unwrap();
        let dl = u.dl.as_ref().unwrap();
        for j in 0..4 {
            let rate = (moved.legs[j] - u.legs[j]) / 0.01;
            assert!((rate - dl[j][15]).abs() < 1e-3, "{rate} vs {}", dl[j][15]);
            assert!(dl[j][15].abs() > 1e-3);
        }
        // a hub lifted 2 mm off its face: its plate moves 2 mm along the face's normal, the
        // primary plate stays, and the legs change as their derivative along the lift says
        let lifted = model
            .points(&quad, &pose, Shape { lift: 2.0, ..shape }, false)
            .unwrap();
        for i in 0..4 {
            let d = lifted.points[4 + i] - u.points[4 + i];
            assert!((d - hub.normal() * 2.0).norm() < 1e-9, "{d}");
            assert!((lifted.points[i] - u.points[i]).norm() < 1e-12);
        }
        for j in 0..4 {
            let rate = (lifted.legs[j] - u.legs[j]) / 2.0;
            assert!((rate - dl[j][21]).abs() < 0.05, "{rate} vs {}", dl[j][21]);
        }
    }
}
