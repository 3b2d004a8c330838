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
    /// Extra: length and width of the part as cut (mm): its outline's extent along x and y
    /// of the strip's frame ([`crate::StripProfile::size`]).
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
                size_mm: p.size(),
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

    /// Check what the fold check needs to read the file against a frame of `units` units:
    /// the profile parameters ([`ProfileParams::validate`]), every unit index in range and
    /// each strip's `units` the units of its `flat` tiles. The error names the JSON path,
    /// e.g. `strips[1].units[0]: index 999 out of range (the frame has 20 units)` or
    /// `params.thickness = 0: must be a finite length > 0`. Whether every unit is in exactly
    /// one strip is a check of its own ([`crate::fold_check`]'s first row).
    pub fn validate(&self, units: usize) -> Result<(), String> {
        if let Err(crate::StripsError::Parameter { name, value, why }) =
            self.params.profile.validate()
        {
            return Err(format!("params.{name} = {value}: {why}"));
        }
        let in_range = |path: String, u: usize| {
            if u < units {
                Ok(())
            } else {
                Err(format!(
                    "{path}: index {u} out of range (the frame has {units} units)"
                ))
            }
        };
        for (i, strip) in self.strips.iter().enumerate() {
            for (j, &u) in strip.units.iter().enumerate() {
                in_range(format!("strips[{i}].units[{j}]"), u)?;
            }
            for (j, tile) in strip.flat.iter().enumerate() {
                in_range(format!("strips[{i}].flat[{j}].unit"), tile.unit)?;
            }
            for (j, &u) in strip.cut_units.iter().enumerate() {
                in_range(format!("strips[{i}].cut_units[{j}]"), u)?;
            }
            let flat: Vec<usize> = strip.flat.iter().map(|t| t.unit).collect();
            if flat != strip.units {
                return Err(format!(
                    "strips[{i}]: units {:?} but its flat tiles are of units {flat:?}",
                    strip.units
                ));
            }
        }
        Ok(())
    }
}

/// Every unit of a frame of `units` units that is in no strip or in more than one, counted
/// on the strips' flat tiles (what the fold check folds): `(unit, the indices of its
/// strips)`, in unit order.
pub(crate) fn strips_of_units(strips: &[StripRecord], units: usize) -> Vec<(usize, Vec<usize>)> {
    let mut of: Vec<Vec<usize>> = vec![Vec::new(); units];
    for (si, strip) in strips.iter().enumerate() {
        for tile in &strip.flat {
            if let Some(list) = of.get_mut(tile.unit) {
                list.push(si);
            }
        }
    }
    of.into_iter()
        .enumerate()
        .filter(|(_, list)| list.len() != 1)
        .collect()
}
