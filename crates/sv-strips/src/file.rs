//! `strips.json` version 1 as plain serde data.

use serde::{Deserialize, Serialize};

use crate::{
    Contour, FaceMark, FlatStrip, HubFace, Label, ProfileParams, SplitRule, StripOptions,
    StripProfile,
};

/// The `format` tag of a strips file.
pub const STRIPS_FORMAT: &str = "spin-valence/strips";

/// The whole strips file: `{"format", "version", "length_unit", "params", "strips"}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StripsFile {
    /// Always [`STRIPS_FORMAT`].
    pub format: String,
    /// Always 1.
    pub version: u32,
    /// Always `"mm"`.
    pub length_unit: String,
    /// The profile parameters and the derived limits.
    pub params: StripsParams,
    /// One record per strip.
    pub strips: Vec<StripRecord>,
}

/// `params`: the profile parameters plus the derived limits.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StripsParams {
    /// Profile parameters (`thickness`, `kerf`, `leg_width`, ...), flattened.
    #[serde(flatten)]
    pub profile: ProfileParams,
    /// Minimum web and slot width max(1.5 t, 3 mm).
    pub min_web: f64,
    /// Expansion factor of the frame the tiles were unrolled from.
    pub expansion: f64,
    /// Longest allowed flat pattern (mm).
    pub max_length: f64,
    /// Extra: how chains longer than `max_length` were cut (`fill` or `balanced`).
    #[serde(default)]
    pub split: SplitRule,
}

/// One strip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StripRecord {
    /// Strip id, e.g. `A03`.
    pub id: String,
    /// Frame unit indices in strip order.
    pub units: Vec<usize>,
    /// Flat expanded primary tile of each unit.
    pub flat: Vec<FlatTile>,
    /// Part outline `[x, y, bulge]`, counter-clockwise.
    pub outline: Contour,
    /// Cuts `[[x, y, bulge], ...]`, clockwise.
    pub cuts: Vec<Contour>,
    /// Net part area (mm^2).
    pub area_mm2: f64,
    /// Extra: length and width of the strip's bounding rectangle (mm).
    pub size_mm: [f64; 2],
    /// Extra: frame unit of each cut.
    pub cut_units: Vec<usize>,
    /// Extra: the joints between consecutive units.
    pub pins: Vec<PinRecord>,
    /// Extra: etched labels.
    pub labels: Vec<Label>,
    /// Extra: etched fold marks.
    pub fold_marks: Vec<[[f64; 2]; 2]>,
    /// Extra: per unit, the etched mark of the face its hub comes out of.
    #[serde(default)]
    pub face_marks: Vec<FaceMark>,
}

/// A flat tile: `primary` corners in frame order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlatTile {
    /// Frame unit index.
    pub unit: usize,
    /// Corners `[x, y]` (mm), frame order.
    pub primary: [[f64; 2]; 4],
    /// Extra: the face of the part the unit's hub comes out of: `etched` (`+z`, the face
    /// seen in the DXF) or `back`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hub_face: Option<HubFace>,
}

/// A joint between consecutive units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PinRecord {
    /// The two frame units.
    pub units: [usize; 2],
    /// Their facing sides.
    pub sides: [usize; 2],
    /// Pin position in the strip frame (mm).
    pub at: [f64; 2],
    /// Bending angle the joint takes up (rad).
    pub bend: f64,
    /// Twisting angle the joint takes up (rad).
    pub twist: f64,
    /// 3D gap between the pin points (mm).
    pub gap: f64,
}

impl StripsFile {
    /// Assemble the file from unrolled strips and their profiles (same order).
    pub fn new(
        strips: &[FlatStrip],
        profiles: &[StripProfile],
        params: &ProfileParams,
        expansion: f64,
        options: &StripOptions,
    ) -> Self {
        let records = strips
            .iter()
            .zip(profiles)
            .map(|(s, p)| StripRecord {
                id: s.id.clone(),
                units: s.units.clone(),
                flat: s
                    .units
                    .iter()
                    .zip(&s.tiles)
                    .zip(&s.hub_faces)
                    .map(|((&unit, t), &face)| FlatTile {
                        unit,
                        primary: t.map(|q| [q.x, q.y]),
                        hub_face: Some(face),
                    })
                    .collect(),
                outline: p.outline.clone(),
                cuts: p.cuts.clone(),
                area_mm2: p.area,
                size_mm: s.size,
                cut_units: p.cut_units.clone(),
                pins: s
                    .pins
                    .iter()
                    .map(|pin| PinRecord {
                        units: pin.units,
                        sides: pin.sides,
                        at: [pin.point.x, pin.point.y],
                        bend: pin.bend,
                        twist: pin.twist,
                        gap: pin.gap,
                    })
                    .collect(),
                labels: p.labels.clone(),
                fold_marks: p.fold_marks.clone(),
                face_marks: p.face_marks.clone(),
            })
            .collect();
        Self {
            format: STRIPS_FORMAT.into(),
            version: 1,
            length_unit: "mm".into(),
            params: StripsParams {
                profile: params.clone(),
                min_web: params.min_web(),
                expansion,
                max_length: options.max_length,
                split: options.split,
            },
            strips: records,
        }
    }
}
