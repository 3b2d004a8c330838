//! Re-verification of a frame file against the invariants of model.md. (being written)

use crate::FrameFile;

/// Tolerances of [`check_frame`].
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Relative tolerance on leg length vs side length.
    pub leg_tolerance: f64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self { leg_tolerance: 1e-9 }
    }
}

/// One row of the check table.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckRow {
    /// What was checked.
    pub name: String,
    /// Worst value found.
    pub worst: f64,
    /// Allowed limit.
    pub limit: f64,
    /// Where the worst value is (unit id, link, face).
    pub at: String,
    /// Passed?
    pub ok: bool,
}

/// The check table.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CheckReport {
    /// Rows.
    pub rows: Vec<CheckRow>,
}

impl CheckReport {
    /// All rows passed.
    pub fn ok(&self) -> bool {
        self.rows.iter().all(|r| r.ok)
    }
}

/// Re-verify every invariant of model.md on a frame file.
pub fn check_frame(_frame: &FrameFile, _options: &CheckOptions) -> CheckReport {
    unimplemented!("being written")
}
