//! The one home of the DXF format in Spin-Valence: reading plasma parts from DXF files
//! written by any CAD program ([`read_dxf`]) and writing strips and sheets as DXF
//! ([`Drawing`]). Pure: the reader takes bytes, the writer returns `String`; the caller
//! touches the file system. `docs/dxf.md` has the rules and conventions.
//!
//! The shop layers, read and written alike: [`LAYER_OUTSIDE`] (part outlines),
//! [`LAYER_INSIDE`] (inside cuts), [`LAYER_ETCH`] (etched marks, open polylines),
//! [`LAYER_INFO`] (never cut: nominal tiles, titles, sheet outline, pierce points).
//!
//! ```
//! use sv_dxf::{read_dxf, Drawing, ReadOptions, LAYER_INSIDE, LAYER_OUTSIDE};
//! use sv_geom::Contour;
//! let mut d = Drawing::new();
//! d.contour(LAYER_INSIDE, &Contour::circle(50.0, 25.0, 5.0));
//! d.contour(LAYER_OUTSIDE, &Contour::polygon(&[[0.0, 0.0], [100.0, 0.0], [100.0, 50.0], [0.0, 50.0]]));
//! let text = d.finish();
//! let read = read_dxf(text.as_bytes(), "plate", &ReadOptions::default()).unwrap();
//! assert_eq!(read.parts.len(), 1);
//! assert_eq!(read.parts[0].holes.len(), 1);
//! assert!((read.parts[0].outer.area() - 5000.0).abs() < 1e-9);
//! ```

mod reader;
mod write;

pub use reader::{
    parse_parts, read_dxf, DxfPart, DxfParts, EntityRef, LayerRole, LayerRule, LayerRules, Note,
    ReadOptions, Units, DEFAULT_ARC_TOLERANCE, DEFAULT_JOIN_TOLERANCE,
};
pub use write::Drawing;

/// Layer of the part outlines.
pub const LAYER_OUTSIDE: &str = "OUTSIDE";
/// Layer of the inside cuts.
pub const LAYER_INSIDE: &str = "INSIDE";
/// Layer of etched labels and marks.
pub const LAYER_ETCH: &str = "ETCH";
/// Layer of information that is never cut.
pub const LAYER_INFO: &str = "INFO";

/// Errors of the DXF reader; one line each, naming the file and the place.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DxfError {
    /// A contour that cannot be a part (open, zero size, ...), named by file and entities.
    #[error("part {file} ({entities}): {reason}")]
    BadPart {
        /// the file's name as the reader was given it
        file: String,
        /// the entities, by layer and type (`layer 0: LINE 8A, 8C`)
        entities: String,
        /// what is wrong
        reason: String,
    },
    /// A file that cannot be read (not DXF, unknown units, bad options).
    #[error("{file}: {message}")]
    Dxf {
        /// file name
        file: String,
        /// what is wrong
        message: String,
    },
}
