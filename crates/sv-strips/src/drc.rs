//! Design-rule check of cut profiles.

use cavalier_contours::polyline::{PlineContainsResult, PlineSource, Polyline};
use serde::{Deserialize, Serialize};
use sv_geom::planar::segment_distance;

use sv_geom::{Contour, Segment};

use crate::params::MIN_INSIDE_RADIUS;
use crate::{FlatStrip, ProfileParams, StripProfile};

/// Chord tolerance used to flatten arcs for distance measurements (mm). 0.005 mm is far
/// below what a plasma resolves, so a measured web is exact to the cutter.
pub const DRC_ARC_TOLERANCE: f64 = 0.005;

/// A design rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DrcRule {
    /// A contour is not closed or crosses itself.
    ClosedSimple,
    /// A cut is not strictly inside the outline.
    CutInside,
    /// Material between two contours narrower than max(1.5 t, 3 mm).
    MinWeb,
    /// A slot narrower than max(1.5 t, 3 mm) somewhere.
    SlotWidth,
    /// An inside corner of the material without a radius >= 1 mm.
    InsideRadius,
    /// A slot without two full-round ends of diameter >= max(kerf + 0.5, t).
    SlotEnd,
    /// No room for the pierce and lead-in inside a cut.
    LeadIn,
}

/// One violation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// Strip id.
    pub strip: String,
    /// Frame unit, when the violation belongs to one.
    pub unit: Option<usize>,
    /// The rule.
    pub rule: DrcRule,
    /// Measured value (mm; 0 when not a length).
    pub value: f64,
    /// The limit it violates (mm).
    pub limit: f64,
    /// Where (strip frame, mm).
    pub at: [f64; 2],
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = self.unit.map(|u| format!(" unit {u}")).unwrap_or_default();
        write!(
            f,
            "strip {}{unit}: {:?} {:.3} (limit {:.3}) at ({:.1}, {:.1})",
            self.strip, self.rule, self.value, self.limit, self.at[0], self.at[1]
        )
    }
}

fn bounds(p: &[[f64; 2]]) -> [f64; 4] {
    p.iter()
        .fold([f64::MAX, f64::MAX, f64::MIN, f64::MIN], |b, q| {
            [
                b[0].min(q[0]),
                b[1].min(q[1]),
                b[2].max(q[0]),
                b[3].max(q[1]),
            ]
        })
}

/// Smallest distance between two closed sampled contours within `reach` of each other
/// (returns `reach` when they are farther apart), with the closest point on `a`.
fn distance(a: &[[f64; 2]], b: &[[f64; 2]], reach: f64) -> (f64, [f64; 2]) {
    // a segment within reach of the other contour's bounding box, on both sides: a cut
    // against a whole strip outline only meets the outline segments around its own unit
    let near = |bx: &[f64; 4], p: [f64; 2], q: [f64; 2]| {
        p[0].min(q[0]) <= bx[2] + reach
            && p[0].max(q[0]) >= bx[0] - reach
            && p[1].min(q[1]) <= bx[3] + reach
            && p[1].max(q[1]) >= bx[1] - reach
    };
    let (ba, bb) = (bounds(a), bounds(b));
    let (na, nb) = (a.len(), b.len());
    let b_near: Vec<([f64; 2], [f64; 2])> = (0..nb)
        .map(|j| (b[j], b[(j + 1) % nb]))
        .filter(|&(p, q)| near(&ba, p, q))
        .collect();
    let mut best = (reach, [0.0, 0.0]);
    for i in 0..na {
        let (p, q) = (a[i], a[(i + 1) % na]);
        if !near(&bb, p, q) {
            continue;
        }
        // two segments whose boxes are farther apart than `reach` are farther apart
        let pq = [
            p[0].min(q[0]),
            p[1].min(q[1]),
            p[0].max(q[0]),
            p[1].max(q[1]),
        ];
        for &(r, s) in &b_near {
            if !near(&pq, r, s) {
                continue;
            }
            let d = segment_distance(p, q, r, s);
            if d < best.0 {
                best = (d, p);
            }
        }
    }
    best
}

/// Sharp right turns (material-concave corners, material on the left) and clockwise arcs
/// below `min_radius`; returns (radius, position) of the worst one. Also counts the
/// half-circle (or larger) arcs of diameter >= `end_diameter`.
fn corners(c: &Contour, min_radius: f64, end_diameter: f64) -> (Option<(f64, [f64; 2])>, usize) {
    let segments: Vec<Segment> = c.segments().collect();
    let n = segments.len();
    let mut worst: Option<(f64, [f64; 2])> = None;
    let mut ends = 0;
    for (i, s) in segments.iter().enumerate() {
        if s.bulge.abs() > 1e-9 {
            if let Some((radius, _)) = s.arc() {
                if s.bulge < 0.0 && radius < min_radius - 1e-9 && worst.is_none_or(|w| radius < w.0)
                {
                    worst = Some((radius, s.start));
                }
                if s.sweep().abs() >= std::f64::consts::PI - 1e-6
                    && 2.0 * radius >= end_diameter - 1e-9
                {
                    ends += 1;
                }
            }
        }
        // turn at the start of segment i
        let tin = segments[(i + n - 1) % n].tangent_angles().1;
        let tout = s.tangent_angles().0;
        let turn = (tout - tin + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        if turn < -1e-6 && worst.is_none_or(|w| w.0 > 0.0) {
            worst = Some((0.0, s.start));
        }
    }
    (worst, ends)
}

/// Check every contour of a profiled strip: closed and simple, cuts inside the outline,
/// webs and slot widths >= max(1.5 t, 3 mm), inside radii >= 1 mm, slot ends full rounds of
/// diameter >= max(kerf + 0.5, t), room for a lead-in inside every cut.
pub fn check_profile(
    strip: &FlatStrip,
    profile: &StripProfile,
    params: &ProfileParams,
) -> Vec<Violation> {
    let web = params.min_web();
    let mut out = Vec::new();
    let v = |unit, rule, value, limit, at| Violation {
        strip: strip.id.clone(),
        unit,
        rule,
        value,
        limit,
        at,
    };
    let outline = profile.outline.to_pline();
    let first = |c: &Contour| c.vertices.first().map_or([0.0, 0.0], |v| v.point());
    let simple =
        |p: &Polyline<f64>| p.is_closed() && p.vertex_count() >= 2 && !p.scan_for_self_intersect();
    if !simple(&outline) {
        out.push(v(
            None,
            DrcRule::ClosedSimple,
            0.0,
            0.0,
            first(&profile.outline),
        ));
    }
    if let (Some((r, at)), _) = corners(&profile.outline, MIN_INSIDE_RADIUS, 0.0) {
        out.push(v(None, DrcRule::InsideRadius, r, MIN_INSIDE_RADIUS, at));
    }
    let flat_outline = profile.outline.flatten(DRC_ARC_TOLERANCE);
    let flat_cuts: Vec<Vec<[f64; 2]>> = profile
        .cuts
        .iter()
        .map(|c| c.flatten(DRC_ARC_TOLERANCE))
        .collect();
    let boxes: Vec<[f64; 4]> = flat_cuts.iter().map(|c| bounds(c)).collect();
    for (ci, cut) in profile.cuts.iter().enumerate() {
        let unit = profile.cut_units.get(ci).copied();
        let pl = cut.to_pline();
        let at = first(cut);
        if !simple(&pl) {
            out.push(v(unit, DrcRule::ClosedSimple, 0.0, 0.0, at));
            continue;
        }
        match pl.contains(&outline) {
            PlineContainsResult::Pline1InsidePline2 => {}
            _ => out.push(v(unit, DrcRule::CutInside, 0.0, 0.0, at)),
        }
        let (worst, ends) = corners(cut, MIN_INSIDE_RADIUS, params.min_slot_end_diameter());
        if let Some((r, at)) = worst {
            out.push(v(unit, DrcRule::InsideRadius, r, MIN_INSIDE_RADIUS, at));
        }
        if ends < 2 {
            out.push(v(
                unit,
                DrcRule::SlotEnd,
                ends as f64,
                params.min_slot_end_diameter(),
                at,
            ));
        }
        // holes run clockwise: their inside is to the right (negative offset)
        let waist = pl.parallel_offset(-(web / 2.0 - 1e-3));
        if waist.len() != 1 {
            out.push(v(unit, DrcRule::SlotWidth, 0.0, web, at));
        }
        if pl.parallel_offset(-(params.lead_in_room / 2.0)).is_empty() {
            out.push(v(unit, DrcRule::LeadIn, 0.0, params.lead_in_room, at));
        }
        let (d, at) = distance(&flat_cuts[ci], &flat_outline, web);
        if d < web - 1e-6 {
            out.push(v(unit, DrcRule::MinWeb, d, web, at));
        }
        for cj in (ci + 1)..flat_cuts.len() {
            let (a, b) = (boxes[ci], boxes[cj]);
            if a[0] > b[2] + web || b[0] > a[2] + web || a[1] > b[3] + web || b[1] > a[3] + web {
                continue;
            }
            let (d, at) = distance(&flat_cuts[ci], &flat_cuts[cj], web);
            if d < web - 1e-6 {
                out.push(v(unit, DrcRule::MinWeb, d, web, at));
            }
        }
    }
    out
}
