//! The primary-surface solve. (being written)

use serde::{Deserialize, Serialize};
use sv_geom::Real;
use sv_unit::{AxisCase, Deployment};

use crate::{FrameError, FrameFile, Hub, Link, QuadMesh};

/// Default spin angle: 45 degrees, for a square grid.
pub const DEFAULT_SPIN_ANGLE: Real = std::f64::consts::FRAC_PI_4;

/// Which side of each hub its primary tile goes to (model.md, "Which side").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SidePolicy {
    /// Per unit, hubs on the concave side of the mesh (shorter distances there); flat
    /// regions keep the mesh orientation.
    #[default]
    Auto,
    /// Every hub on the side its face normal points to (the mesh orientation).
    Normal,
    /// Every hub on the side opposite to its face normal.
    Opposite,
}

/// Options of [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// Spin angle alpha (rad), in (0, pi/2).
    pub spin_angle: Real,
    /// Expansion factor e >= 1 of the primary tiles, about their centroids.
    pub expansion: Real,
    /// Side choice.
    pub side: SidePolicy,
    /// Axis case for every unit.
    pub axis_case: AxisCase,
    /// Largest number of Levenberg-Marquardt iterations.
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost is below this.
    pub tolerance: Real,
    /// Planarity tolerance for the input mesh (diagonal distance / mean edge).
    pub planarity_tolerance: Real,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            spin_angle: DEFAULT_SPIN_ANGLE,
            expansion: 1.0,
            side: SidePolicy::Auto,
            axis_case: AxisCase::OrthogonalToR1,
            max_iterations: 100,
            tolerance: 1e-10,
            planarity_tolerance: crate::MeshChecks::DEFAULT_PLANARITY_TOLERANCE,
        }
    }
}

/// Progress of a running solve, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Iteration number.
    pub iteration: usize,
    /// Largest iteration number.
    pub max_iterations: usize,
    /// Current sum of gaps (mm).
    pub gap_sum: Real,
}

/// What a solve reached.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveReport {
    /// Sum of gaps at the start (theta = alpha, phi = 0).
    pub gap_sum_start: Real,
    /// Sum of gaps at the end (the paper's objective).
    pub gap_sum: Real,
    /// Largest gap at the end.
    pub gap_max: Real,
    /// Iterations used.
    pub iterations: usize,
}

/// Gaps and overlaps of a set of deployments.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// Per link: closest distance of the facing expanded primary sides (mm).
    pub gaps: Vec<Real>,
    /// Per link: hub overlap (mm).
    pub overlaps: Vec<Real>,
}

/// A solved frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Solved {
    /// Hubs, one per face.
    pub hubs: Vec<Hub>,
    /// Interior edges.
    pub links: Vec<Link>,
    /// One deployment per unit.
    pub deployments: Vec<Deployment>,
    /// Gaps and overlaps at the end.
    pub evaluation: Evaluation,
    /// Figures.
    pub report: SolveReport,
    /// Options used.
    pub options: SolveOptions,
}

/// Solve the primary surface of a quad mesh of hubs.
pub fn solve(
    _mesh: &QuadMesh,
    _options: &SolveOptions,
    _progress: &mut dyn FnMut(Progress),
) -> Result<Solved, FrameError> {
    unimplemented!("being written")
}

/// Gaps and overlaps of given deployments.
pub fn evaluate(
    _hubs: &[Hub],
    _links: &[Link],
    _deployments: &[Deployment],
    _expansion: Real,
) -> Result<Evaluation, FrameError> {
    unimplemented!("being written")
}

impl Solved {
    /// The frame file for this solve.
    pub fn to_frame_file(&self, _mesh: &QuadMesh) -> FrameFile {
        unimplemented!("being written")
    }
}
