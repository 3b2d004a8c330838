//! Errors of the secondary-surface stage.

use thiserror::Error;

/// What went wrong while reading a target or building the hub mesh. Messages are one
/// line and name the triangle, vertex or face involved.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SurfaceError {
    /// The target mesh is unusable (user input); the message says where.
    #[error("invalid target: {0}")]
    InvalidTarget(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// No built-in target has this name.
    #[error("unknown built-in target `{name}` (known: flat, vault, dome, saddle, pavilion)")]
    UnknownBuiltin {
        /// The name asked for.
        name: String,
    },
    /// The target is too small for even a 2 x 2 grid at the requested unit size.
    #[error("target too small: {0}")]
    TooSmall(String),
    /// The target is valid but the automatic layout cannot mesh it; a designer's layout
    /// (`--layout`) can.
    #[error("no automatic layout: {0}")]
    NeedsLayout(String),
    /// A designer's layout (coarse quad mesh) that cannot be used on the target.
    #[error("invalid layout: {0}")]
    InvalidLayout(String),
    /// The optimisation produced a collapsed edge or a flipped face and could not recover.
    #[error("optimisation failed: {0}")]
    Folded(String),
    /// An internal failure (please report it).
    #[error("internal error: {0}")]
    Internal(String),
}

impl From<sv_geom::sparse::SparseError> for SurfaceError {
    fn from(e: sv_geom::sparse::SparseError) -> Self {
        SurfaceError::Internal(e.0)
    }
}
