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

impl FrameFile {
    /// Whether its joints were closed (`links[].joint` recorded): bridges and welds are
    /// then the frame's, and the parts as cut are measured on them.
    pub fn joints_closed(&self) -> bool {
        self.links.iter().any(|l| l.joint.is_some())
    }

    /// The label of each unit as people and clients name it: its `id` (`"A03-02"`), or its
    /// index (`"7"`) where the id is blank.
    pub fn unit_labels(&self) -> Vec<String> {
        self.units
            .iter()
            .enumerate()
            .map(|(i, u)| {
                let id = u.id.trim();
                if id.is_empty() {
                    i.to_string()
                } else {
                    id.to_string()
                }
            })
            .collect()
    }

    /// Where the frame breaks "each face of the hub mesh is one unit" (model.md 1) or gives
    /// two units one label, in face order, then label order; empty when it holds. The one
    /// place both `spinvalence check` and the streamer ask it. `units[].face` out of range is
    /// the reader's error (`frame.json: units[3].face: index ...`) and is skipped here.
    pub fn unit_problems(&self) -> Vec<UnitProblem> {
        if self.units.is_empty() {
            return vec![UnitProblem::NoUnits];
        }
        let labels = self.unit_labels();
        let mut on_face: Vec<Vec<usize>> = vec![Vec::new(); self.mesh.faces.len()];
        for (i, u) in self.units.iter().enumerate() {
            if let Some(units) = on_face.get_mut(u.face) {
                units.push(i);
            }
        }
        let mut problems = Vec::new();
        for (face, units) in on_face.iter().enumerate() {
            match units.len() {
                0 => problems.push(UnitProblem::FaceWithoutUnit { face }),
                1 => {}
                _ => problems.push(UnitProblem::FaceWithUnits {
                    face,
                    units: units.iter().map(|&u| labels[u].clone()).collect(),
                }),
            }
        }
        let mut first: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        for (i, label) in labels.iter().enumerate() {
            if let Some(&j) = first.get(label.as_str()) {
                problems.push(UnitProblem::DuplicateLabel {
                    label: label.clone(),
                    units: [j, i],
                });
            } else {
                first.insert(label, i);
            }
        }
        problems
    }
}

/// A break of "each face is one unit, each unit its own label" ([`FrameFile::unit_problems`]).
/// Faces and units are numbered as in the file (0-based indices into `mesh.faces` and
/// `units`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnitProblem {
    /// `units` is empty.
    NoUnits,
    /// A face of the hub mesh that no unit stands on.
    FaceWithoutUnit {
        /// Index into `mesh.faces`.
        face: usize,
    },
    /// A face that more than one unit stands on (a unit written twice).
    FaceWithUnits {
        /// Index into `mesh.faces`.
        face: usize,
        /// Their labels ([`FrameFile::unit_labels`]), in file order.
        units: Vec<String>,
    },
    /// Two units with one label.
    DuplicateLabel {
        /// The label.
        label: String,
        /// The first unit with it and this one (indices into `units`).
        units: [usize; 2],
    },
}

impl std::fmt::Display for UnitProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            UnitProblem::NoUnits => write!(f, "the frame has no units"),
            UnitProblem::FaceWithoutUnit { face } => write!(f, "face {face} has no unit"),
            UnitProblem::FaceWithUnits { face, units } => {
                // a few ids, not thousands: the message stays one short line
                let named = match units.len() {
                    n if n <= 4 => units.join(", "),
                    n => format!("{}, ... and {} more", units[..3].join(", "), n - 3),
                };
                write!(f, "face {face} has {} units ({named})", units.len())
            }
            UnitProblem::DuplicateLabel { label, units } => write!(
                f,
                "duplicate unit id {label:?} (units[{}] and units[{}])",
                units[0], units[1]
            ),
        }
    }
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
    /// Sheet thickness (mm; extra field, with `links[].joint`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
    /// What the joints must reach (extra field, with `links[].joint`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_limits: Option<JointLimits>,
    /// One hub lap for every link, held by the joint solve (extra field, `[frame] overlap`
    /// constant or a length; absent where the laps are free).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hub_lap: Option<LapGoal>,
    /// The two hub plates of every lap were pulled together to touch somewhere, within the
    /// weld gap limit (extra field, `[frame] laps_touch`; absent where they were not).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub hub_laps_touch: bool,
}

/// One hub lap for every link, so that one gauge block checks every hub joint on site:
/// `length` within `tolerance` either way (mm, on the hub plates as cut).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LapGoal {
    /// The one lap.
    pub length: f64,
    /// How far a lap may be from it, either way.
    pub tolerance: f64,
}

/// What the joints between primary plates must reach, measured on the plates as cut
/// (`params.joint_limits`; docs/geometry.md, "Closing the joints").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointLimits {
    /// Largest distance between the facing sides at a bridge (mm): the bridge's stretch.
    pub bridge_gap: f64,
    /// Largest in-plane bend of a bridge (rad).
    pub bend: f64,
    /// Largest twist of a bridge (rad).
    pub twist: f64,
    /// Largest gap between the plates at a weld (mm, thickness included).
    pub weld_gap: f64,
    /// Deepest a plate may reach into another (mm, thickness included).
    pub collision: f64,
}

impl JointLimits {
    /// These limits times `k` (the angles and lengths alike).
    pub fn within(&self, k: f64) -> Self {
        Self {
            bridge_gap: k * self.bridge_gap,
            bend: k * self.bend,
            twist: k * self.twist,
            weld_gap: k * self.weld_gap,
            collision: k * self.collision,
        }
    }

    /// The joint is within these limits.
    pub fn holds(&self, j: &JointRecord) -> bool {
        match j.kind {
            JointKind::Bridge => self.bridge_holds(j) && j.collision <= self.collision,
            JointKind::Weld => j.gap <= self.weld_gap && j.collision <= self.collision,
        }
    }

    /// How far the joint is from its limits: the largest of its figures (for its kind, the
    /// plates into each other included) as a multiple of its limit; at most 1 when it holds.
    pub fn excess(&self, j: &JointRecord) -> f64 {
        self.worst(j).0
    }

    /// The measure of `j` furthest beyond (or nearest to) its limit, and its value as a
    /// multiple of that limit (bridges: gap, bend, twist; welds: gap; both: collision; the
    /// first of a tie).
    pub fn worst(&self, j: &JointRecord) -> (f64, JointMeasure) {
        let over = |v: f64, limit: f64| v.abs() / limit.max(1e-9);
        let measures = match j.kind {
            JointKind::Bridge => vec![
                (over(j.gap, self.bridge_gap), JointMeasure::Gap),
                (over(j.bend, self.bend), JointMeasure::Bend),
                (over(j.twist, self.twist), JointMeasure::Twist),
            ],
            JointKind::Weld => vec![(over(j.gap, self.weld_gap), JointMeasure::Gap)],
        };
        measures
            .into_iter()
            .chain([(over(j.collision, self.collision), JointMeasure::Collision)])
            .fold(
                (0.0, JointMeasure::Gap),
                |a, b| if b.0 > a.0 { b } else { a },
            )
    }

    /// The joint, taken as a bridge, is within these limits.
    pub fn bridge_holds(&self, j: &JointRecord) -> bool {
        j.gap <= self.bridge_gap && j.bend.abs() <= self.bend && j.twist.abs() <= self.twist
    }
}

/// A measure of a joint that [`JointLimits`] bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointMeasure {
    /// How far apart (a bridge's fold line, a weld's plates).
    Gap,
    /// A bridge bent in its plane.
    Bend,
    /// A bridge twisted.
    Twist,
    /// One plate into the other.
    Collision,
}

impl Default for JointLimits {
    /// Bridges within 0.5 mm, bent at most 3 degrees in their plane and twisted at most 7
    /// (a 7.5 x 3.75 mm web of 2.5 mm sheet at 5 % strain, docs/geometry.md); welds within
    /// 1.5 mm (a butt or fillet weld bridges that in 3 mm sheet without a filler); plates
    /// into each other by at most 0.1 mm.
    fn default() -> Self {
        Self {
            bridge_gap: 0.5,
            bend: 3f64.to_radians(),
            twist: 7f64.to_radians(),
            weld_gap: 1.5,
            collision: 0.1,
        }
    }
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
    /// This unit's spin angle (rad) where it is not `params.spin_angle`: the joint solve
    /// turns each hub in its face to close the joints (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin: Option<f64>,
    /// The tile's half-diagonals as a multiple of the face's best-fit rhombus `[along the
    /// hub's x, along its y]`, where the joint solve stretched it (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tile_scale: Option<[f64; 2]>,
    /// How far the hub sits off its face's best-fit rhombus along the face's normal (mm),
    /// where the joint solve lifted it so that lapping hubs lie one on the other (extra
    /// field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hub_lift: Option<f64>,
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
    /// How the two primary plates meet, on frames whose joints were closed (extra field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<JointRecord>,
}

/// How the primary plates of a link meet (`links[].joint`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// The two units are one piece of steel: a bridge spans the joint slot between their
    /// plates (consecutive units of a strip) and folds about the joint line.
    Bridge,
    /// The plates of two strips, welded on site where they touch.
    Weld,
}

/// A joint between two primary plates, measured on the plates as cut (extra field
/// `links[].joint`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointRecord {
    /// Bridge or weld.
    pub kind: JointKind,
    /// Where the joint is on each unit's facing side (0 at its corner `k`, 1 at `k + 1`):
    /// the bridge's middle, or the weld point.
    pub along: [f64; 2],
    /// Gap between the two plates there (mm): at a bridge between the facing sides (the
    /// fold line, so 0 when the bridge folds without stretching); at a weld between the
    /// plates, thickness included (0 when they touch, edge to edge or edge on face).
    pub gap: f64,
    /// In-plane bend of the joint (rad): the turn of the second side in the first plate's
    /// plane.
    pub bend: f64,
    /// Twist of the joint (rad): the turn of the second side out of the first plate's plane.
    pub twist: f64,
    /// How far one plate reaches into the other (mm, thickness included; 0 when clear).
    pub collision: f64,
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
