//! Nesting of plasma-cut parts on the jagua-rs collision engine.
//!
//! * [`nest_strip`]: strip packing (fixed height, minimise length) for benchmark instances.
//! * [`nest_sheets`]: bin packing of [`Part`]s onto rectangular stock sheets with spacing and
//!   margin, producing [`NestReport`] (`nest.json`).
//!
//! The nester takes [`Part`]s (outlines and holes as `sv_geom::Contour`s, arcs kept) and
//! returns placements; reading and drawing them is the format crates' work (`sv-dxf`,
//! `sv-export`). The library never prints; long runs report through a caller-supplied
//! progress callback.

mod engine;
pub mod part;
mod prepare;
mod shape;
pub mod sheets;
pub mod strip;

pub use part::{ById, Contour, Part, Vertex, DEFAULT_FLATTEN_TOLERANCE};
pub use sheets::{
    lower_bounds, margin_leaves_room, nest_sheets, sheet_work_budget, LeftOut, LowerBounds,
    NestOptions, NestReport, Offcut, PartPlacement, RotationMode, SearchReport, SheetReport,
    SheetSpec, StockSheet,
};
pub use strip::{
    nest_strip, strip_work_budget, Progress, StripInstance, StripOptions, StripPlacement,
    StripResult,
};

/// Errors of the nesting crate. Part errors name the part.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NestError {
    /// A part outline is unusable (open, self-intersecting, zero size, non-finite).
    #[error("part {part}: {reason}")]
    BadPart {
        /// part id
        part: String,
        /// what is wrong
        reason: String,
    },
    /// Invalid options.
    #[error("invalid options: {0}")]
    Options(String),
    /// Invalid benchmark instance.
    #[error("instance: {0}")]
    Instance(String),
    /// I/O failure.
    #[error("{path}: {message}")]
    Io {
        /// path
        path: String,
        /// error text
        message: String,
    },
}
