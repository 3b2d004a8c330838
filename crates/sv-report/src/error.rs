//! Errors of the report: inputs that do not belong together.

/// The frame, the strips and the nest disagree (files from different builds, or a bug
/// upstream). Every message names the strip, unit or sheet.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReportError {
    /// A strip lists a unit the frame does not have.
    #[error("strip {strip}: unit {unit} is not in the frame ({units} units)")]
    UnknownUnit {
        /// Strip id.
        strip: String,
        /// The unit index it lists.
        unit: usize,
        /// Units in the frame.
        units: usize,
    },
    /// A link names a unit the frame does not have.
    #[error("link {link}: unit {unit} is not in the frame ({units} units)")]
    UnknownLinkUnit {
        /// Link index.
        link: usize,
        /// The unit index it names.
        unit: usize,
        /// Units in the frame.
        units: usize,
    },
    /// A sheet places a part that is not a strip.
    #[error("sheet {sheet}: part {part} is not a strip of strips.json")]
    UnknownPart {
        /// Sheet number (1-based).
        sheet: usize,
        /// The part id.
        part: String,
    },
    /// A strip is placed twice.
    #[error("strip {strip} is placed twice (sheets {first} and {second})")]
    PlacedTwice {
        /// Strip id.
        strip: String,
        /// First sheet (1-based).
        first: usize,
        /// Second sheet (1-based).
        second: usize,
    },
    /// A face index of the mesh is out of range.
    #[error("mesh face {face}: vertex {vertex} is not in the mesh ({vertices} vertices)")]
    BadFace {
        /// Face index.
        face: usize,
        /// The vertex index.
        vertex: usize,
        /// Vertices in the mesh.
        vertices: usize,
    },
}
