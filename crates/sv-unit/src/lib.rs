//! One Spin-Valence unit: the closed-form kinematics of paper sec. 3.2 (the zero-width limit)
//! and the unit as cut ([`UnitLayout`]: where the slots run and the legs are pinned;
//! [`Linkage`]: its deployment on four rigid legs).
//!
//! The closed form:
//!
//! A unit is a rhombic primary tile with half-diagonals `r1 = (a, 0, 0)` and
//! `r2 = (0, b, 0)` in its own frame (centroid at the origin, normal `+z`), and a hub
//! congruent to it, placed by the isometry `s = R r + P`. Four legs join hub corner `s_i`
//! to primary corner `r_{i+1}`; their lengths equal the sides `|r_i - r_{i+1}|` for every
//! deployment this crate returns: that is the kirigami constraint, solved exactly.
//!
//! The configuration space has two parameters (theorem, sec. 3.2): the rotation angle
//! `theta` and the tilt `phi` of the rotation axis `t`, which is orthogonal to one of the
//! two diagonals ([`AxisCase`]). The translation then follows in closed form (eq. 8-11):
//! `P = ±sqrt(2 (R r1).r2) d/|d|` with `d = (R r1 - r2) x (R r2 + r1)` and
//! `2 (R r1).r2 = 2 sin(theta) cos(phi) a b`, which must be `>= 0` (the feasible domain).
//! The sign ([`Side`]) chooses which side of the sheet the hub goes to.
//!
//! ```
//! use sv_unit::{deploy, AxisCase, Deployment, Rhombus, Side};
//! let tile = Rhombus::new(100.0, 100.0).unwrap();
//! let d = deploy(&tile, &Deployment::new(45f64.to_radians(), 0.0)).unwrap();
//! // every leg is as long as the side it replaces
//! for i in 0..4 {
//!     let leg = (d.hub[i] - d.primary[(i + 1) % 4]).norm();
//!     let side = (d.primary[i] - d.primary[(i + 1) % 4]).norm();
//!     assert!((leg - side).abs() < 1e-9 * side);
//! }
//! // the frame depth is sqrt(2 sin(theta) a b)
//! let depth = (2.0 * 45f64.to_radians().sin() * 100.0 * 100.0).sqrt();
//! assert!((d.translation.norm() - depth).abs() < 1e-9);
//! ```

mod cut;
mod error;
mod kinematics;
mod linkage;

pub use cut::{inset, inset_sides, leg_outline, CutError, CutWidths, Pins, UnitLayout};
pub use error::UnitError;
pub use kinematics::{
    axis, deploy, depth_squared, inverse, primary_in_hub_frame, rotation, AxisCase, CornerJacobian,
    Deployed, Deployment, Inverse, Rhombus, Side,
};
pub use linkage::{Linkage, LEG_TOLERANCE};
