//! The summary figures of a build and their definitions (`docs/report.md`).

use std::collections::HashSet;

use serde::Serialize;
use sv_strips::{Contour, StripRecord};

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
        let steel_area_mm2: f64 = strips.iter().map(|s| s.area_mm2).sum();
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
            cut_length_mm: strips.iter().map(strip_cut_length).sum(),
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
    contour_length(&strip.outline) + strip.cuts.iter().map(contour_length).sum::<f64>()
}

/// Pierces of one strip: one per closed cut contour.
pub fn strip_pierces(strip: &StripRecord) -> usize {
    1 + strip.cuts.len()
}

/// Length of a closed contour (mm). A segment with bulge `b` (`tan` of a quarter of its
/// sweep) is an arc of sweep `4 atan b` over the chord `c`: length `c (sweep / 2) /
/// sin(sweep / 2)`.
pub fn contour_length(contour: &Contour) -> f64 {
    let v = &contour.0;
    (0..v.len())
        .map(|i| {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let chord = (b[0] - a[0]).hypot(b[1] - a[1]);
            arc_length(chord, a[2])
        })
        .sum()
}

/// Length of the arc of bulge `bulge` over a chord of length `chord`.
pub fn arc_length(chord: f64, bulge: f64) -> f64 {
    let half = 2.0 * bulge.abs().atan(); // half the sweep
    if half < 1e-12 {
        chord
    } else {
        chord * half / half.sin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn a_circle_of_two_half_arcs_has_its_circumference() {
        // bulge 1: a half circle; two of them over a 20 mm chord make a circle of radius 10
        let circle = Contour(vec![[0.0, 0.0, 1.0], [20.0, 0.0, 1.0]]);
        assert!(close(
            contour_length(&circle),
            20.0 * std::f64::consts::PI,
            1e-12
        ));
        let clockwise = Contour(vec![[0.0, 0.0, -1.0], [20.0, 0.0, -1.0]]);
        assert!(close(
            contour_length(&clockwise),
            20.0 * std::f64::consts::PI,
            1e-12
        ));
    }

    #[test]
    fn straight_contours_and_quarter_arcs() {
        let square = Contour(vec![
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [10.0, 10.0, 0.0],
            [0.0, 10.0, 0.0],
        ]);
        assert_eq!(contour_length(&square), 40.0);
        // a quarter circle of radius 5: chord 5 sqrt 2, bulge tan(pi / 8)
        let b = (std::f64::consts::PI / 8.0).tan();
        let quarter = arc_length(5.0 * 2f64.sqrt(), b);
        assert!(close(quarter, 2.5 * std::f64::consts::PI, 1e-12));
        assert_eq!(arc_length(3.0, 0.0), 3.0);
        assert!(close(arc_length(3.0, 1e-14), 3.0, 1e-12));
    }
}
