//! The summary figures of a build and their definitions (`docs/report.md`).

use std::collections::HashSet;

use serde::Serialize;
use sv_strips::{HubFace, StripRecord};

use crate::ReportInput;

/// Density of mild steel (kg/m^3) used for the weight.
pub const STEEL_DENSITY: f64 = 7850.0;

/// The figures of the summary table. Lengths in mm, areas in mm^2, mass in kg.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Units of the frame (`frame.json` `units`).
    pub units: usize,
    /// Strips, i.e. parts to cut (`strips.json` `strips`).
    pub strips: usize,
    /// Sheets used by the nesting (`nest.json` `sheets`); `None` without nesting.
    pub sheets: Option<usize>,
    /// Net steel area of all parts: outline area minus the slots, arcs exact
    /// (sum of `strips.json` `area_mm2`).
    pub steel_area_mm2: f64,
    /// Sheet thickness (mm, `strips.json` `params.thickness`).
    pub thickness_mm: f64,
    /// `steel_area_mm2 * thickness_mm * 1e-9 m^3/mm^3 * STEEL_DENSITY`.
    pub steel_mass_kg: f64,
    /// Total length of every cut contour, outlines and slots, arcs at their true length.
    pub cut_length_mm: f64,
    /// Closed cut contours: one pierce each (outlines + slots).
    pub pierces: usize,
    /// Hub welds: one per link, where the hubs of two neighbouring units overlap.
    pub hub_welds: usize,
    /// Primary welds: one per link whose two primary tiles are not joined by a neck of
    /// their strip (they belong to different strips, so they meet on site).
    pub primary_welds: usize,
    /// `hub_welds + primary_welds`.
    pub welds: usize,
}

impl Summary {
    /// The figures of `input` (validated or not: unknown units just do not count).
    pub fn of(input: &ReportInput<'_>) -> Self {
        let strips = &input.strips.strips;
        let thickness = input.strips.params.profile.thickness;
        // folded from +0, not summed (from -0): a build without strips shows 0, not -0
        let steel_area_mm2 = strips.iter().map(|s| s.area_mm2).fold(0.0, |a, x| a + x);
        let necks: HashSet<[usize; 2]> = strips
            .iter()
            .flat_map(|s| &s.pins)
            .map(|p| sorted(p.units))
            .collect();
        let hub_welds = input.frame.links.len();
        let primary_welds = input
            .frame
            .links
            .iter()
            .filter(|l| !necks.contains(&sorted(l.units)))
            .count();
        Self {
            units: input.frame.units.len(),
            strips: strips.len(),
            sheets: input.nest.map(|n| n.report.sheets.len()),
            steel_area_mm2,
            thickness_mm: thickness,
            steel_mass_kg: steel_area_mm2 * thickness * 1e-9 * STEEL_DENSITY,
            cut_length_mm: strips.iter().map(strip_cut_length).fold(0.0, |a, x| a + x),
            pierces: strips.iter().map(strip_pierces).sum(),
            hub_welds,
            primary_welds,
            welds: hub_welds + primary_welds,
        }
    }
}

fn sorted([a, b]: [usize; 2]) -> [usize; 2] {
    [a.min(b), a.max(b)]
}

/// Cut length of one strip (mm): its outline and all its slots.
pub fn strip_cut_length(strip: &StripRecord) -> f64 {
    strip.outline.length() + strip.cuts.iter().map(|c| c.length()).sum::<f64>()
}

/// Pierces of one strip: one per closed cut contour.
pub fn strip_pierces(strip: &StripRecord) -> usize {
    1 + strip.cuts.len()
}

/// The face of a strip its hubs come out of (`strips.json` `flat[].hub_face`): `etched` or
/// `back` when all its units agree, else `mixed` with the units of each face by `label`
/// (`mixed: etched A01-01 A01-02; back A01-03`); empty when the file does not say.
pub fn strip_hub_face(strip: &StripRecord, label: impl Fn(usize) -> String) -> String {
    let faces: Vec<Option<HubFace>> = strip.flat.iter().map(|t| t.hub_face).collect();
    match faces.first() {
        None | Some(None) => return String::new(),
        Some(&Some(first)) if faces.iter().all(|&f| f == Some(first)) => {
            return first.name().to_string()
        }
        _ => {}
    }
    let units = |face: HubFace| -> String {
        strip
            .flat
            .iter()
            .filter(|t| t.hub_face == Some(face))
            .map(|t| label(t.unit))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut parts: Vec<String> = [HubFace::Etched, HubFace::Back]
        .into_iter()
        .map(|f| (f, units(f)))
        .filter(|(_, u)| !u.is_empty())
        .map(|(f, u)| format!("{} {u}", f.name()))
        .collect();
    let unknown = strip.flat.iter().filter(|t| t.hub_face.is_none()).count();
    if unknown > 0 {
        parts.push(format!("{unknown} unknown"));
    }
    format!("mixed: {}", parts.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_strips::{Contour, FlatTile};

    fn strip(faces: &[Option<HubFace>]) -> StripRecord {
        StripRecord {
            id: "A01".into(),
            units: (0..faces.len()).collect(),
            flat: faces
                .iter()
                .enumerate()
                .map(|(unit, &hub_face)| FlatTile {
                    unit,
                    primary: [[0.0; 2]; 4],
                    hub_face,
                })
                .collect(),
            outline: Contour::polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]),
            cuts: Vec::new(),
            area_mm2: 0.0,
            size_mm: [1.0, 1.0],
            cut_units: Vec::new(),
            pins: Vec::new(),
            labels: Vec::new(),
            fold_marks: Vec::new(),
            face_marks: Vec::new(),
        }
    }

    #[test]
    fn a_strip_names_its_hub_face_or_which_units_have_which() {
        let label = |u: usize| format!("A01-{:02}", u + 1);
        let (e, b) = (Some(HubFace::Etched), Some(HubFace::Back));
        assert_eq!(strip_hub_face(&strip(&[e, e, e]), label), "etched");
        assert_eq!(strip_hub_face(&strip(&[b, b]), label), "back");
        assert_eq!(
            strip_hub_face(&strip(&[e, b, e]), label),
            "mixed: etched A01-01 A01-03; back A01-02"
        );
        assert_eq!(
            strip_hub_face(&strip(&[b, None]), label),
            "mixed: back A01-01; 1 unknown"
        );
        // a strips.json that does not say
        assert_eq!(strip_hub_face(&strip(&[None, None]), label), "");
        assert_eq!(strip_hub_face(&strip(&[]), label), "");
    }
}
