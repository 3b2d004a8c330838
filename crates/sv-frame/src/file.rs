//! `frame.json` version 2 (docs/frame-format.md), as plain serde data. Version 2 is version
//! 1 (model.md) measured on the units as cut: `hub_overlap` is the overlap of the hub plates
//! as cut, and the units deploy on their legs as cut (`params.cut`, per unit `pins`). Extra
//! fields are welcome and kept optional so that files from other tools still read.

use serde::{Deserialize, Serialize};
use sv_unit::{AxisCase, Side};

/// The `format` tag of a frame file.
pub const FRAME_FORMAT: &str = "spin-valence/frame";
/// The `version` this build writes and reads.
pub const FRAME_VERSION: u32 = 2;

/// The whole frame file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameFile {
    /// Always [`FRAME_FORMAT`].
    pub format: String,
    /// Always [`FRAME_VERSION`].
    pub version: u32,
    /// Always `"mm"`.
    pub length_unit: String,
    /// Design parameters.
    pub params: FrameParams,
    /// The hub (secondary) mesh.
    pub mesh: MeshData,
    /// One record per unit (face).
    pub units: Vec<UnitRecord>,
    /// One record per interior edge.
    pub links: Vec<LinkRecord>,
    /// What the solve reached (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solve: Option<SolveSummary>,
}

/// Design parameters (`params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameParams {
    /// Spin angle alpha (rad).
    pub spin_angle: f64,
    /// Expansion factor e >= 1 of the tiles (the whole cut is made on the expanded tile).
    pub expansion: f64,
    /// Where the cut goes in every unit (mm); absent for the paper's zero-width unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cut: Option<sv_unit::CutWidths>,
}

/// `mesh`: vertices (mm) and quad faces.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshData {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Quad faces, counter-clockwise seen from the hub normal side.
    pub faces: Vec<[usize; 4]>,
}

/// One unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnitRecord {
    /// Label etched on the part.
    pub id: String,
    /// Index into `mesh.faces`.
    pub face: usize,
    /// Strip label.
    pub strip: String,
    /// Rotation angle (rad).
    pub theta: f64,
    /// Axis tilt (rad).
    pub phi: f64,
    /// Hub corners `s_i` (model size).
    pub hub: [[f64; 3]; 4],
    /// Primary corners `r_i` (model size), `s_i = R r_i + P`.
    pub primary: [[f64; 3]; 4],
    /// Which diagonal the rotation axis is orthogonal to (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_case: Option<AxisCase>,
    /// Which side of the primary tile the hub is on (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side: Option<Side>,
    /// Frame depth `|P|` (mm, extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// The hub plate as cut (inside the inner slots), corners in hub corner order (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hub_plate: Option<[[f64; 3]; 4]>,
    /// The legs' pins in the deployed pose.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pins: Option<LegPins>,
}

/// Where the four legs of a unit are pinned, deployed (mm): leg `j` is a rigid bar from
/// `hub[j]` (its neck on the hub plate) to `rim[j]` (its neck on the primary plate).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LegPins {
    /// Pins on the hub plate.
    pub hub: [[f64; 3]; 4],
    /// Pins on the primary plate.
    pub rim: [[f64; 3]; 4],
    /// Pin-to-pin length of each leg as cut (flat).
    pub length: [f64; 4],
}

/// One link (interior edge).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinkRecord {
    /// The two unit indices.
    pub units: [usize; 2],
    /// The shared mesh edge, as `units[0]`'s face lists it.
    pub edge: [usize; 2],
    /// Closest distance between the facing sides of the expanded primary tiles (mm).
    pub primary_gap: f64,
    /// How far the two facing corners of the hub plates as cut pass each other along the
    /// line between the hub centres (mm); negative when they do not reach each other.
    pub hub_overlap: f64,
    /// Side / corner index `k` facing this link in each unit (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slots: Option<[usize; 2]>,
}

/// Solver figures (extra field `solve`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolveSummary {
    /// Sum of gaps at the start (mm), the paper's objective.
    pub gap_sum_start: f64,
    /// Sum of gaps at the end (mm).
    pub gap_sum: f64,
    /// Largest gap (mm).
    pub gap_max: f64,
    /// Solver iterations.
    pub iterations: usize,
    /// Largest planarity residual of the mesh (diagonal distance / mean edge).
    pub planarity_max: f64,
    /// Largest conical (angle balance) residual at interior valence-4 vertices (rad).
    pub conical_max: f64,
}
