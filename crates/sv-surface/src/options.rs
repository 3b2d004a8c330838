//! Options of the secondary-surface stage.

use serde::{Deserialize, Serialize};
use sv_geom::Real;

use crate::SurfaceError;

/// Parameters of [`crate::build_secondary`]. All weights multiply dimensionless residuals
/// (lengths are divided by the mean edge), so they compare directly.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SecondaryOptions {
    /// Requested unit (face) side in mm. Default [`SecondaryOptions::DEFAULT_UNIT_SIZE`].
    pub unit_size: Real,
    /// Weight of face planarity (`n_f . (v_j - v_i) = 0`, `|n_f| = 1`). Default 1.
    pub planarity_weight: Real,
    /// Weight of the cone-axis constraints at interior valence-4 vertices. Default 1.
    pub conical_weight: Real,
    /// Weight of point-to-tangent-plane closeness to the target. Default 1.
    pub closeness_weight: Real,
    /// Weight of boundary vertices lying on the boundary curve. Default 2.
    pub boundary_weight: Real,
    /// Initial weight of fairness (second differences along grid polylines); it is
    /// halved every 10 iterations down to a tenth. Default 0.1.
    pub fairness_weight: Real,
    /// Weight of equal edges and equal diagonals within each face (constant). Default 0.2.
    pub edge_weight: Real,
    /// Tikhonov regulariser toward the current iterate. Default 1e-4.
    pub regulariser: Real,
    /// Largest vertex move per iteration, as a fraction of the mean edge. Default 0.1.
    /// While the steps ask for moves of more than half a mean edge (a layout being undone)
    /// and are taken whole with the merit falling, the cap grows, up to ten times this.
    pub max_step: Real,
    /// Iteration limit. Default 100.
    pub max_iterations: usize,
    /// Continuation target: the planarity and conical weights grow (by 2^(1/8) per
    /// iteration, up to 100 times) while planarity max (diagonal distance / mean edge) is
    /// above this or the conical residual above `conical_tolerance_deg`. Default 0.001
    /// (half the goal of issue 3, a margin for the final measurement).
    pub planarity_tolerance: Real,
    /// Conical residual target in degrees (see `planarity_tolerance`). Default 0.25.
    pub conical_tolerance_deg: Real,
    /// Closeness goal: max distance to the target / mean edge. While a vertex is farther,
    /// the planarity and conical weights shrink again (the goals conflict there: the mesh
    /// stays on the target and the report names the faces that are not planar); the run
    /// stops once the hard goals hold, every vertex is within 0.6 of this and 95 % of the
    /// faces are nearly square. Default 0.05.
    pub closeness_tolerance: Real,
}

impl SecondaryOptions {
    /// Default unit side (mm).
    pub const DEFAULT_UNIT_SIZE: Real = 300.0;

    /// Reject impossible values with a one-line message.
    pub fn check(&self) -> Result<(), SurfaceError> {
        let bad = |s: String| Err(SurfaceError::InvalidParameter(s));
        if !(self.unit_size.is_finite() && self.unit_size > 0.0) {
            return bad(format!(
                "unit size must be a positive length in mm, got {}",
                self.unit_size
            ));
        }
        for (name, w) in [
            ("planarity_weight", self.planarity_weight),
            ("conical_weight", self.conical_weight),
            ("closeness_weight", self.closeness_weight),
            ("boundary_weight", self.boundary_weight),
            ("fairness_weight", self.fairness_weight),
            ("edge_weight", self.edge_weight),
            ("regulariser", self.regulariser),
            ("planarity_tolerance", self.planarity_tolerance),
            ("conical_tolerance_deg", self.conical_tolerance_deg),
            ("closeness_tolerance", self.closeness_tolerance),
        ] {
            if !(w.is_finite() && w >= 0.0) {
                return bad(format!("{name} must be finite and >= 0, got {w}"));
            }
        }
        if !(self.max_step.is_finite() && self.max_step > 0.0) {
            return bad(format!("max_step must be > 0, got {}", self.max_step));
        }
        if self.regulariser <= 0.0 {
            return bad("regulariser must be > 0".into());
        }
        Ok(())
    }
}

impl Default for SecondaryOptions {
    fn default() -> Self {
        Self {
            unit_size: Self::DEFAULT_UNIT_SIZE,
            planarity_weight: 1.0,
            conical_weight: 1.0,
            closeness_weight: 1.0,
            boundary_weight: 2.0,
            fairness_weight: 0.1,
            edge_weight: 0.2,
            regulariser: 1e-4,
            max_step: 0.1,
            max_iterations: 100,
            planarity_tolerance: 0.001,
            conical_tolerance_deg: 0.25,
            closeness_tolerance: 0.05,
        }
    }
}
