use thiserror::Error;

/// Why a unit cannot be deployed or recovered.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum UnitError {
    /// Half-diagonals must be finite and positive.
    #[error("rhombus half-diagonals must be finite and > 0 (got a = {a}, b = {b})")]
    BadRhombus {
        /// Half-diagonal along r1.
        a: f64,
        /// Half-diagonal along r2.
        b: f64,
    },
    /// `2 sin(theta) cos(phi) |r1||r2| < 0`, or a parameter is not finite.
    #[error("infeasible deployment theta = {theta:.6} rad, phi = {phi:.6} rad: need 2 sin(theta) cos(phi) |r1||r2| >= 0")]
    Infeasible {
        /// Rotation angle.
        theta: f64,
        /// Axis tilt.
        phi: f64,
    },
    /// The two linear constraints on `P` coincide (e.g. a square at theta = 90 degrees):
    /// `P` is not unique there.
    #[error("degenerate deployment theta = {theta:.6} rad, phi = {phi:.6} rad: the translation is not unique")]
    Degenerate {
        /// Rotation angle.
        theta: f64,
        /// Axis tilt.
        phi: f64,
    },
    /// Derivatives are unbounded on the edge of the domain (P ~ sqrt(theta)).
    #[error(
        "derivatives are unbounded at the domain boundary (theta = {theta:.6}, phi = {phi:.6})"
    )]
    OnBoundary {
        /// Rotation angle.
        theta: f64,
        /// Axis tilt.
        phi: f64,
    },
    /// The hub and primary tile given to [`crate::inverse`] are not a valid pair.
    #[error("hub and primary tile are not a deployed rhombic unit: {0}")]
    NotAUnit(String),
    /// The four legs of a cut are in a singular position (their constraints dependent).
    #[error("the legs as cut are in a singular position: the hub's pose is not determined")]
    LegsSingular,
    /// No pose near the requested one holds every leg of the cut.
    #[error("the legs as cut cannot reach this pose: a leg stays {error:.3e} mm off its length")]
    LegsUnreachable {
        /// Largest leg error left (mm).
        error: f64,
    },
}
