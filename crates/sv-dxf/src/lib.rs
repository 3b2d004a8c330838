//! The one home of the DXF format in Spin-Valence: reading plasma parts from DXF files
//! ([`parse_parts`]) and writing strips and sheets as DXF ([`Drawing`]). Pure: readers take
//! text, writers return `String`; the caller touches the file system.
//!
//! The shop layers, read and written alike: [`LAYER_OUTSIDE`] (part outlines),
//! [`LAYER_INSIDE`] (inside cuts), [`LAYER_ETCH`] (etched marks, open polylines),
//! [`LAYER_INFO`] (never cut: nominal tiles, titles, sheet outline, pierce points).
//!
//! ```
//! use sv_dxf::{parse_parts, Drawing, LAYER_INSIDE, LAYER_OUTSIDE};
//! use sv_geom::Contour;
//! let mut d = Drawing::new();
//! d.contour(LAYER_INSIDE, &Contour::circle(50.0, 25.0, 5.0));
//! d.contour(LAYER_OUTSIDE, &Contour::polygon(&[[0.0, 0.0], [100.0, 0.0], [100.0, 50.0], [0.0, 50.0]]));
//! let text = d.finish([-10.0, -10.0], [110.0, 60.0]);
//! let read = parse_parts(&text, "plate").unwrap();
//! assert_eq!(read.parts.len(), 1);
//! assert_eq!(read.parts[0].holes.len(), 1);
//! ```

mod read;
mod write;

pub use read::{parse_parts, DxfPart, DxfParts, DEFAULT_CHAIN_TOLERANCE};
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
    /// A contour that cannot be a part (open, zero size, ...), named by file and place.
    #[error("part {part}: {reason}")]
    BadPart {
        /// file name and where in it
        part: String,
        /// what is wrong
        reason: String,
    },
    /// Unreadable or invalid DXF.
    #[error("{file}: {message}")]
    Dxf {
        /// file name
        file: String,
        /// what is wrong (with line number when known)
        message: String,
    },
}
