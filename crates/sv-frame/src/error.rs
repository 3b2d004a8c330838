use thiserror::Error;

/// A quad mesh that cannot carry a frame. Every message names the face, vertex or edge:
/// as [`MeshError::describe`] is told to (a file's reader: 1-based, with its lines), else
/// by their 0-based indices in the mesh (`Display`).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// No faces at all.
    Empty,
    /// A vertex coordinate is NaN or infinite.
    NonFinite {
        /// Vertex index (0-based).
        vertex: usize,
    },
    /// A face refers to a vertex that does not exist.
    IndexOutOfRange {
        /// Face index.
        face: usize,
        /// The bad vertex index (0-based).
        index: usize,
        /// Number of vertices.
        count: usize,
    },
    /// Repeated vertex, zero-length edge or zero area.
    DegenerateFace {
        /// Face index.
        face: usize,
        /// What is degenerate.
        why: Degeneracy,
    },
    /// An edge used by more than two faces, or twice in the same direction.
    NonManifoldEdge {
        /// First vertex.
        v: usize,
        /// Second vertex.
        w: usize,
        /// What is wrong.
        why: String,
        /// The faces that list the edge from `v` to `w`.
        faces: Vec<usize>,
    },
    /// Diagonal distance / mean edge above the tolerance.
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
    TooSmall {
        /// Why.
        why: String,
    },
}

/// What makes a face degenerate (vertex indices 0-based).
#[derive(Debug, Clone, PartialEq)]
pub enum Degeneracy {
    /// The face lists this vertex twice.
    VertexTwice(usize),
    /// The edge between these two vertices has zero length.
    ZeroEdge(usize, usize),
    /// The face has no area.
    ZeroArea,
    /// Anything else, said in words.
    Other(String),
}

impl MeshError {
    /// The message with faces and vertices named by `face` and `vertex` (from a 0-based
    /// index: e.g. `3 (line 23)` for a file's third face).
    pub fn describe(
        &self,
        face: &dyn Fn(usize) -> String,
        vertex: &dyn Fn(usize) -> String,
    ) -> String {
        match self {
            MeshError::Empty => "mesh has no faces".into(),
            MeshError::NonFinite { vertex: v } => {
                format!("vertex {} has a non-finite coordinate", vertex(*v))
            }
            MeshError::IndexOutOfRange { face: f, index, count } => format!(
                "face {} refers to vertex {}, but the mesh has {count} vertices",
                face(*f),
                vertex(*index)
            ),
            MeshError::DegenerateFace { face: f, why } => {
                let why = match why {
                    Degeneracy::VertexTwice(v) => format!("vertex {} is used twice", vertex(*v)),
                    Degeneracy::ZeroEdge(v, w) => {
                        format!("edge ({}, {}) has zero length", vertex(*v), vertex(*w))
                    }
                    Degeneracy::ZeroArea => "zero area".into(),
                    Degeneracy::Other(why) => why.clone(),
                };
                format!("face {} is degenerate: {why}", face(*f))
            }
            MeshError::NonManifoldEdge { v, w, why, faces } => {
                let named: Vec<String> = faces.iter().map(|&f| face(f)).collect();
                format!(
                    "edge ({}, {}) is non-manifold: {why} (faces {})",
                    vertex(*v),
                    vertex(*w),
                    named.join(", ")
                )
            }
            MeshError::NonPlanar {
                face: f,
                distance,
                ratio,
                tolerance,
            } => format!(
                "face {} is not planar: diagonal distance {distance:.3} mm is {ratio:.4} of its mean edge (tolerance {tolerance})",
                face(*f)
            ),
            MeshError::TooSmall { why } => format!("mesh is smaller than a frame: {why}"),
        }
    }
}

impl std::fmt::Display for MeshError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let index = |i: usize| i.to_string();
        f.write_str(&self.describe(&index, &index))
    }
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
    /// The joint solve pulled the hub faces far from planar and still left joints open
    /// (given up: the frame it started from is the better one to cut).
    #[error(
        "closing them left {open} joints outside their limits and pulled the hub mesh far \
         from its goals (planarity {planarity:.4} against {start:.4}, after {iterations} \
         iterations)"
    )]
    PulledOff {
        /// Joints outside their limits when it gave up.
        open: usize,
        /// The hub faces' planarity then (diagonal distance / mean side, largest).
        planarity: f64,
        /// Their planarity where the solve began.
        start: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// The sparse factorisation failed (internal; please report).
    #[error("internal: sparse solve failed: {0}")]
    Linear(String),
}
