//! From a quad mesh of hubs to a deployed Spin-Valence frame.
//!
//! - [`QuadMesh`]: the secondary (hub) mesh, validated ([`QuadMesh::validate`]).
//! - [`Hub`]: per face, the best-fit rhombus spun by the spin angle (model.md sec. 2).
//! - [`Link`]: per interior edge, the two units and which sides/corners face each other.
//! - [`solve`]: the primary-surface solve (sparse Levenberg-Marquardt on the gaps).
//! - [`FrameFile`]: `frame.json` v1 as plain serde data; [`check_frame`] re-verifies it.
//!
//! ```
//! use sv_frame::{solve, QuadMesh, SolveOptions};
//! let mesh = QuadMesh::grid(4, 3, 300.0);
//! let solved = solve(&mesh, &SolveOptions::default(), &mut |_| {}).unwrap();
//! assert!(solved.report.gap_max < 1e-6 * 300.0);
//! let file = solved.to_frame_file(&mesh);
//! assert!(sv_frame::check_frame(&file, &Default::default()).ok());
//! ```

mod check;
mod error;
mod file;
mod hub;
mod joint;
mod mesh;
pub mod plates;
mod solve;
mod unit;

pub use check::{
    check_frame, CheckOptions, CheckReport, CheckRow, Worst, GOAL_CONICAL_DEG, GOAL_PLANARITY,
};
pub use error::{Degeneracy, FrameError, MeshError};
pub use file::{
    FrameFile, FrameParams, JointKind, JointLimits, JointMeasure, JointRecord, LapGoal, LegPins,
    LinkRecord, MeshData, SolveSummary, UnitProblem, UnitRecord, FRAME_FORMAT, FRAME_VERSION,
};
pub use hub::{hubs_from_mesh, Hub};
pub use joint::{
    close_joints, Anchor, JointFigures, JointOptions, JointReport, PieceLength, Surface,
};
pub use mesh::{normal_cone, normal_cone_residual, Link, MeshChecks, QuadMesh};
pub use solve::{
    evaluate, solve, Evaluation, GapObjective, Joints, Progress, SidePolicy, SolveOptions,
    SolveReport, Solved, DEFAULT_SPIN_ANGLE, STALL_WINDOW,
};
pub use unit::{FrameUnits, UnitPose};
