//! Errors of the strip stage. Bad input (parameters, frames that cannot be cut) names the
//! parameter or the strip and unit; [`StripsError::Internal`] is a bug.

use thiserror::Error;

/// Why strips or profiles could not be made.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StripsError {
    /// A profile or strip parameter that cannot be cut.
    #[error("parameter {name} = {value}: {why}")]
    Parameter {
        /// Parameter name as in `strips.json` `params`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must satisfy.
        why: String,
    },
    /// The frame file is inconsistent (missing link slots, bad indices, degenerate tiles).
    #[error("frame: {why}")]
    Frame {
        /// What is wrong.
        why: String,
    },
    /// A strip or unit that cannot be unrolled or profiled.
    #[error("strip {strip}, unit {unit}: {why}")]
    Unit {
        /// Strip id (or `"-"` before ids are known).
        strip: String,
        /// Frame unit index.
        unit: usize,
        /// What is wrong.
        why: String,
    },
    /// Two consecutive units of a strip whose facing sides, as cut, overlap too little for
    /// a bridge of the profile's neck width: the strip can end there instead
    /// ([`crate::StripOptions::breaks`]).
    #[error("strip {strip}, unit {}: facing sides overlap too little for a bridge of width {width} to unit {}", units[1], units[0])]
    NoBridge {
        /// Strip id.
        strip: String,
        /// The two units, in strip order.
        units: [usize; 2],
        /// The bridge's width (the profile's neck width, mm).
        width: f64,
    },
    /// More strips than the id scheme `A01`..`Z99` can name.
    #[error("{count} strips, but ids run out after Z99 (2574 strips)")]
    TooManyStrips {
        /// Number of strips needed.
        count: usize,
    },
    /// A contour operation failed where it should not: please report it as a bug.
    #[error("internal error (please report): {why}")]
    Internal {
        /// What failed.
        why: String,
    },
}
