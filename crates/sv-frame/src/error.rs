use thiserror::Error;

/// A quad mesh that cannot carry a frame. Every message names the face, vertex or edge.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// No faces at all.
    #[error("mesh has no faces")]
    Empty,
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// Vertex index (0-based).
        vertex: usize,
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but the mesh has {count} vertices")]
    IndexOutOfRange {
        /// Face index.
        face: usize,
        /// The bad vertex index (0-based).
        index: usize,
        /// Number of vertices.
        count: usize,
    },
    /// Repeated vertex, zero-length edge or zero area.
    #[error("face {face} is degenerate: {why}")]
    DegenerateFace {
        /// Face index.
        face: usize,
        /// What is degenerate.
        why: String,
    },
    /// An edge used by more than two faces, or twice in the same direction.
    #[error("edge ({v}, {w}) is non-manifold: {why}")]
    NonManifoldEdge {
        /// First vertex.
        v: usize,
        /// Second vertex.
        w: usize,
        /// What is wrong.
        why: String,
    },
    /// Diagonal distance / mean edge above the tolerance.
    #[error("face {face} is not planar: diagonal distance {distance:.3} mm is {ratio:.4} of its mean edge (tolerance {tolerance})")]
    NonPlanar {
        /// Face index.
        face: usize,
        /// Distance between the diagonals (mm).
        distance: f64,
        /// Distance / mean edge.
        ratio: f64,
        /// Allowed ratio.
        tolerance: f64,
    },
    /// Fewer faces or links than a frame needs.
    #[error("mesh is smaller than a frame: {why}")]
    TooSmall {
        /// Why.
        why: String,
    },
}

/// Errors of the frame stage.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FrameError {
    /// Bad mesh.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A parameter out of range.
    #[error("invalid parameter {name} = {value}: {why}")]
    Parameter {
        /// Parameter name as the user spells it.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        why: &'static str,
    },
    /// A unit's tile is too small for its cut.
    #[error("unit {unit}: its tile cannot carry the cut: {why}")]
    Cut {
        /// Unit (face) index.
        unit: usize,
        /// What the cut needs.
        why: String,
    },
    /// A unit failed to deploy (should not happen inside the solver's bounds).
    #[error("unit {unit} (face {face}): {cause}")]
    Unit {
        /// Unit index.
        unit: usize,
        /// Face index.
        face: usize,
        /// Cause (in the message; not a `source`, so chains print it once).
        cause: sv_unit::UnitError,
    },
    /// The sparse factorisation failed (internal; please report).
    #[error("internal: sparse solve failed: {0}")]
    Linear(String),
}
