//! The DXF of a nested sheet, written by the same writer as the strips ([`crate::strip_dxf`]).
//!
//! Per placed part, in placement order: its inside contours (`INSIDE`), then its outside
//! contour (`OUTSIDE`), each a closed LWPOLYLINE with bulges moved by the placement (arcs
//! stay arcs, nothing is offset: the CAM applies the kerf), each followed by its suggested
//! pierce point (a `POINT` on `INFO`) in scrap; then the part's etching (`ETCH`: marks moved
//! with the part, labels moved and turned to read upright) and its label (`TEXT` on
//! `INFO`). The sheet outline, the sheet title and the reusable offcut
//! are on `INFO` too.

use sv_dxf::{Drawing, LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};
use sv_geom::planar::{bbox, point_in_polygon, polygon_area};
use sv_geom::Contour;
use sv_nest::{ById, NestReport, Part, PartPlacement};
use sv_strips::{FlatStrip, Label, StripProfile};

use crate::strip::{label_strokes, mark_strokes};

/// Chord tolerance (mm) for the pierce-point search.
const FLATTEN: f64 = 0.05;

/// One part as drawn on a sheet: the contours given to the nester and what it etches, in
/// the part's own drawing frame (the frame the placements of `nest.json` map).
#[derive(Clone, Debug, PartialEq)]
pub struct SheetPart {
    /// The cut contours (`part.id` is the `strip` of the placements).
    pub part: Part,
    /// Etched open polylines moved with the part as they are (fold marks, face marks; a
    /// DXF part read by `spinvalence nest` has all its etching here).
    pub etch: Vec<Vec<[f64; 2]>>,
    /// Etched labels, moved with the part and turned to read upright on the sheet
    /// ([`Label::placed`]).
    pub labels: Vec<Label>,
}

impl SheetPart {
    /// A part without etching (a DXF part read by `spinvalence nest`).
    pub fn plain(part: Part) -> Self {
        Self {
            part,
            etch: Vec::new(),
            labels: Vec::new(),
        }
    }

    /// What this part etches where `placement` puts it on a sheet, as open polylines.
    fn etch_on_sheet(&self, placement: &PartPlacement) -> Vec<Vec<[f64; 2]>> {
        let rotation = placement.rotation_deg.to_radians();
        let (s, c) = rotation.sin_cos();
        let t = placement.translation;
        let mut out: Vec<Vec<[f64; 2]>> = self
            .etch
            .iter()
            .map(|l| {
                l.iter()
                    .map(|p| [c * p[0] - s * p[1] + t[0], s * p[0] + c * p[1] + t[1]])
                    .collect()
            })
            .collect();
        let labels: Vec<Label> = self.labels.iter().map(|l| l.placed(rotation, t)).collect();
        out.extend(label_strokes(&labels));
        out
    }
}

/// The nesting part of a profiled strip: outline, slots as holes, labels, fold marks and
/// face marks as etching, in the strip's frame (the coordinates of `strips/ID.dxf` and
/// `strips.json`).
pub fn strip_sheet_part(strip: &FlatStrip, profile: &StripProfile) -> SheetPart {
    SheetPart {
        part: Part {
            id: strip.id.clone(),
            outer: profile.outline.clone(),
            holes: profile.cuts.clone(),
        },
        etch: mark_strokes(profile),
        labels: profile.labels.clone(),
    }
}

/// `sheet-01_3000x1500mm_t3mm` (without extension): sheet number, stock size and, when
/// known, the material thickness, so that the file says what to load on the table.
pub fn sheet_file_stem(index: usize, width: f64, height: f64, thickness: Option<f64>) -> String {
    let mm = |x: f64| {
        let s = format!("{x:.1}");
        s.trim_end_matches(".0").to_string()
    };
    let mut stem = format!("sheet-{:02}_{}x{}mm", index + 1, mm(width), mm(height));
    if let Some(t) = thickness {
        stem.push_str(&format!("_t{}mm", mm(t)));
    }
    stem
}

/// Which way cut contours run (the CAM follows the direction written).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CutDirection {
    /// Outside contours clockwise, inside contours counter-clockwise: the usual plasma
    /// convention (with a right-hand swirl the good edge of the part is on the right).
    #[default]
    OutsideClockwise,
    /// Outside contours counter-clockwise, inside contours clockwise.
    OutsideCounterClockwise,
}

impl CutDirection {
    /// Whether outside contours run counter-clockwise.
    pub fn outside_ccw(self) -> bool {
        self == CutDirection::OutsideCounterClockwise
    }
}

/// Where the etching goes in the file (a CAM that follows file order etches in it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EtchOrder {
    /// All etching before the first cut, so nothing is etched on a part already cut free.
    #[default]
    BeforeCuts,
    /// All etching after the last cut.
    AfterCuts,
}

/// The shop conventions of a sheet or strip DXF (`docs/dxf.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShopConvention {
    /// Which way contours run.
    pub direction: CutDirection,
    /// Where the etching goes.
    pub etch: EtchOrder,
}

impl ShopConvention {
    /// An outline in this convention (same first vertex).
    pub fn outside(&self, c: &Contour) -> Contour {
        c.oriented(self.direction.outside_ccw())
    }

    /// A hole in this convention (same first vertex).
    pub fn inside(&self, c: &Contour) -> Contour {
        c.oriented(!self.direction.outside_ccw())
    }
}

/// What the sheet title says besides the sheet number and size.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SheetCaption {
    /// Material thickness (mm), when known.
    pub thickness: Option<f64>,
    /// Who wrote the file (`spinvalence 0.1.0`).
    pub generator: String,
}

/// A placed part in sheet coordinates with its flattened contours (for pierce points).
struct Placed {
    part: Part,
    outer: Vec<[f64; 2]>,
    holes: Vec<Vec<[f64; 2]>>,
    lo: [f64; 2],
    hi: [f64; 2],
}

impl Placed {
    fn new(part: Part) -> Self {
        let outer = part.outer.flatten(FLATTEN);
        let holes = part.holes.iter().map(|h| h.flatten(FLATTEN)).collect();
        let (lo, hi) = bbox(&outer);
        Self {
            part,
            outer,
            holes,
            lo,
            hi,
        }
    }

    /// Squared distance from `p` to this part's box (0 inside it): no point of the part
    /// is nearer.
    fn box_distance2(&self, p: [f64; 2]) -> f64 {
        let dx = (self.lo[0] - p[0]).max(p[0] - self.hi[0]).max(0.0);
        let dy = (self.lo[1] - p[1]).max(p[1] - self.hi[1]).max(0.0);
        dx * dx + dy * dy
    }

    /// Whether `p` is on this part's material (inside the outline, outside every hole),
    /// or within `clear` of its outline.
    fn covers(&self, p: [f64; 2], clear: f64) -> bool {
        if p[0] < self.lo[0] - clear
            || p[1] < self.lo[1] - clear
            || p[0] > self.hi[0] + clear
            || p[1] > self.hi[1] + clear
        {
            return false;
        }
        if clear > 0.0 && boundary_distance_fast(p, &self.outer) < clear {
            return true;
        }
        point_in_polygon(p, &self.outer) && !self.holes.iter().any(|h| point_in_polygon(p, h))
    }
}

/// Distance from `p` to the boundary of the closed polygon `poly`.
fn boundary_distance_fast(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| sv_geom::planar::point_segment_distance2(p, poly[i], poly[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// The point inside the closed polygon `poly` farthest from its boundary, and that
/// distance. Candidates: from every edge's midpoint, halfway along the inward normal to the
/// boundary across (for a thin slot that is its centre line, which a grid would miss),
/// then a local grid refinement around the best. About `n²` work for `n` vertices.
fn deepest_point(poly: &[[f64; 2]]) -> ([f64; 2], f64) {
    let (lo, hi) = bbox(poly);
    let reach = (hi[0] - lo[0]).min(hi[1] - lo[1]);
    let ccw = polygon_area(poly) > 0.0;
    let mut best = ([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0], -1.0);
    let n = poly.len();
    let consider = |p: [f64; 2], best: &mut ([f64; 2], f64)| {
        // the squared distance to the boundary, given up as soon as it is no better; then
        // whether the point is inside (most candidates fail the first test early)
        let floor = if best.1 > 0.0 {
            best.1 * best.1
        } else {
            best.1
        };
        let mut d2 = f64::INFINITY;
        for i in 0..n {
            d2 = d2.min(sv_geom::planar::point_segment_distance2(
                p,
                poly[i],
                poly[(i + 1) % n],
            ));
            if d2 <= floor {
                return;
            }
        }
        if point_in_polygon(p, poly) {
            *best = (p, d2.sqrt());
        }
    };
    consider(best.0, &mut best);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        if len < 1e-9 {
            continue;
        }
        // inward normal: left of the edge for a counter-clockwise polygon
        let s = if ccw { 1.0 } else { -1.0 };
        let nrm = [-s * dy / len, s * dx / len];
        let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        // the nearest other edge along the normal
        let mut across = f64::INFINITY;
        for j in 0..n {
            if j == i {
                continue;
            }
            let (c, d) = (poly[j], poly[(j + 1) % n]);
            let (ex, ey) = (d[0] - c[0], d[1] - c[1]);
            let den = nrm[0] * ey - nrm[1] * ex;
            if den.abs() < 1e-12 {
                continue;
            }
            let (wx, wy) = (c[0] - mid[0], c[1] - mid[1]);
            let t = (wx * ey - wy * ex) / den;
            let u = (wx * nrm[1] - wy * nrm[0]) / den;
            if t > 1e-9 && (0.0..=1.0).contains(&u) {
                across = across.min(t);
            }
        }
        if across.is_finite() {
            let t = across / 2.0;
            consider([mid[0] + t * nrm[0], mid[1] + t * nrm[1]], &mut best);
        }
    }
    // refine: shrinking grids around the best point, until a grid gains less than 1 %
    let mut half = (best.1.max(reach / 64.0)).max(1e-3);
    const N: usize = 6;
    for _ in 0..4 {
        let before = best.1;
        let c = best.0;
        for i in 0..=N {
            for j in 0..=N {
                let p = [
                    c[0] - half + 2.0 * half * i as f64 / N as f64,
                    c[1] - half + 2.0 * half * j as f64 / N as f64,
                ];
                consider(p, &mut best);
            }
        }
        half /= 3.0;
        if before > 0.0 && best.1 < 1.01 * before {
            break;
        }
    }
    best
}

/// A pierce point in scrap for the outside contour of `parts[k]`: `offset` outside the
/// outline (half the spacing: midway to any neighbour), at the middle of the longest
/// straight edge where that is clear of every part and inside the sheet, else the clearest
/// candidate.
fn outside_pierce(parts: &[Placed], k: usize, offset: f64, sheet: [f64; 2]) -> [f64; 2] {
    let me = &parts[k];
    let ccw = polygon_area(&me.outer) > 0.0;
    let v = &me.part.outer.vertices;
    let n = v.len();
    // candidate edges: straight ones first, longest first; then every flattened edge
    let mut edges: Vec<([f64; 2], [f64; 2], bool)> = (0..n)
        .map(|i| {
            let (a, b) = (v[i], v[(i + 1) % n]);
            ([a.x, a.y], [b.x, b.y], a.bulge == 0.0)
        })
        .collect();
    let m = me.outer.len();
    edges.extend((0..m).map(|i| (me.outer[i], me.outer[(i + 1) % m], true)));
    // longest first (the sort is stable), each length computed once
    let mut edges: Vec<(f64, [f64; 2], [f64; 2])> = edges
        .into_iter()
        .filter(|e| e.2)
        .map(|(a, b, _)| ((b[0] - a[0]).hypot(b[1] - a[1]), a, b))
        .filter(|e| e.0 > 1e-6)
        .collect();
    edges.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut best = ([me.lo[0] - offset, me.lo[1] - offset], f64::NEG_INFINITY);
    for (_, a, b) in edges {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        // outward normal of a counter-clockwise outline is the edge direction turned right
        let s = if ccw { 1.0 } else { -1.0 };
        let nrm = [s * dy / len, -s * dx / len];
        let p = [
            (a[0] + b[0]) / 2.0 + offset * nrm[0],
            (a[1] + b[1]) / 2.0 + offset * nrm[1],
        ];
        if p[0] < 0.0 || p[1] < 0.0 || p[0] > sheet[0] || p[1] > sheet[1] {
            continue;
        }
        if point_in_polygon(p, &me.outer) {
            continue;
        }
        // clearance: distance to the nearest material of any part (own outline included);
        // a part whose box is farther than the nearest so far cannot be nearer
        let mut clear = f64::INFINITY;
        for q in parts {
            if q.box_distance2(p) >= clear * clear {
                continue;
            }
            clear = clear.min(if q.covers(p, 0.0) {
                0.0
            } else {
                boundary_distance_fast(p, &q.outer)
            });
        }
        if clear >= 0.9 * offset {
            return p;
        }
        if clear > best.1 {
            best = (p, clear);
        }
    }
    best.0
}

/// The DXF text of sheet `index` of `report` in `convention`. `parts` holds every nested
/// part (looked up by id). An outline's pierce point sits half the spacing outside it
/// (midway to the nearest neighbour); a hole's at the point of the hole farthest from its
/// edge.
pub fn sheet_dxf(
    report: &NestReport,
    index: usize,
    parts: &ById<'_, SheetPart>,
    caption: &SheetCaption,
    convention: &ShopConvention,
) -> Result<String, String> {
    let sheet = report.sheets.get(index).ok_or_else(|| {
        format!(
            "sheet {} of {}: no such sheet",
            index + 1,
            report.sheets.len()
        )
    })?;
    let (w, h) = (sheet.width, sheet.height);
    let mut placed = Vec::with_capacity(sheet.placements.len());
    let mut etch = Vec::with_capacity(sheet.placements.len());
    for pl in &sheet.placements {
        let sp = parts.get(&pl.strip).ok_or_else(|| {
            format!(
                "sheet {}: part {:?} is not among the parts",
                index + 1,
                pl.strip
            )
        })?;
        placed.push(Placed::new(
            sp.part.transformed(pl.rotation_deg, pl.translation),
        ));
        etch.push(sp.etch_on_sheet(pl));
    }
    let offset = (report.sheet.spacing / 2.0).max(0.5);
    let mut d = Drawing::new();
    d.polygon(LAYER_INFO, &[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]);
    let etch_all = |d: &mut Drawing| {
        for lines in &etch {
            for l in lines {
                d.open_line(LAYER_ETCH, l);
            }
        }
    };
    if convention.etch == EtchOrder::BeforeCuts {
        etch_all(&mut d);
    }
    for (k, p) in placed.iter().enumerate() {
        for (hole, flat) in p.part.holes.iter().zip(&p.holes) {
            d.contour(LAYER_INSIDE, &convention.inside(hole));
            d.point(LAYER_INFO, deepest_point(flat).0);
        }
        d.contour(LAYER_OUTSIDE, &convention.outside(&p.part.outer));
        d.point(LAYER_INFO, outside_pierce(&placed, k, offset, [w, h]));
        // the label inside the part's box: a third of its smaller side, narrower for a
        // long id on a small part
        let label = &p.part.id;
        let chars = label.chars().count().max(1) as f64;
        let size = (p.hi[1] - p.lo[1]).min(p.hi[0] - p.lo[0]);
        let th = (size / 3.0)
            .min(0.8 * (p.hi[0] - p.lo[0]) / chars)
            .clamp(1.0, 40.0);
        let at = [
            (p.lo[0] + p.hi[0]) / 2.0 - 0.3 * th * chars,
            (p.lo[1] + p.hi[1]) / 2.0 - th / 2.0,
        ];
        d.text(LAYER_INFO, label, at, th);
    }
    if convention.etch == EtchOrder::AfterCuts {
        etch_all(&mut d);
    }
    if let Some(o) = report.offcut.as_ref().filter(|o| o.sheet == index) {
        let (x0, y0, x1, y1) = (o.x, o.y, o.x + o.width, o.y + o.height);
        d.polygon(LAYER_INFO, &[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]);
        d.text(
            LAYER_INFO,
            &format!("OFFCUT {:.0} x {:.0} mm", o.width, o.height),
            [x0 + 20.0, y1 - 60.0],
            30.0,
        );
    }
    let mut title = format!(
        "SHEET {} OF {}  {:.0} x {:.0} mm",
        index + 1,
        report.sheets.len(),
        w,
        h
    );
    if let Some(t) = caption.thickness {
        title.push_str(&format!("  t = {t} mm"));
    }
    title.push_str(&format!(
        "  {} parts  {:.1} % used  spacing {} mm  margin {} mm",
        sheet.placements.len(),
        100.0 * sheet.utilisation,
        report.sheet.spacing,
        report.sheet.margin
    ));
    if !caption.generator.is_empty() {
        title.push_str(&format!("  {}", caption.generator));
    }
    d.text(LAYER_INFO, &title, [0.0, -60.0], 30.0);
    Ok(d.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::font::text_strokes;

    #[test]
    fn labels_turned_upside_down_by_the_nest_are_turned_back_marks_are_not() {
        let label = Label {
            text: "A01-02".into(),
            at: [100.0, 40.0],
            angle: 0.1,
            height: 20.0,
        };
        let mark = vec![[90.0, 10.0], [110.0, 12.0]];
        let part = SheetPart {
            part: Part {
                id: "A01".into(),
                outer: Contour::polygon(&[[0.0, 0.0], [200.0, 0.0], [200.0, 80.0]]),
                holes: Vec::new(),
            },
            etch: vec![mark],
            labels: vec![label.clone()],
        };
        let placement = |rotation_deg: f64| PartPlacement {
            strip: "A01".into(),
            translation: [500.0, 300.0],
            rotation_deg,
        };
        // a half turn: the mark turns with the part, the label reads along 0.1 rad again
        // about its centre moved with the part
        let etch = part.etch_on_sheet(&placement(180.0));
        let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9;
        assert!(close(etch[0][0], [410.0, 290.0]) && close(etch[0][1], [390.0, 288.0]));
        let want = text_strokes("A01-02", [400.0, 260.0], 0.1, 20.0);
        assert_eq!(etch.len(), 1 + want.len());
        for (got, want) in etch[1..].iter().zip(&want) {
            assert!(got.iter().zip(want).all(|(&a, &b)| close(a, b)), "{got:?}");
        }
        // unturned: the label as the strip etches it, moved
        let etch = part.etch_on_sheet(&placement(0.0));
        let want = text_strokes("A01-02", [600.0, 340.0], 0.1, 20.0);
        for (got, want) in etch[1..].iter().zip(&want) {
            assert!(got.iter().zip(want).all(|(&a, &b)| close(a, b)), "{got:?}");
        }
    }

    #[test]
    fn file_stem_names_sheet_size_and_thickness() {
        assert_eq!(
            sheet_file_stem(0, 3000.0, 1500.0, Some(3.0)),
            "sheet-01_3000x1500mm_t3mm"
        );
        assert_eq!(
            sheet_file_stem(11, 2500.0, 1250.5, Some(2.5)),
            "sheet-12_2500x1250.5mm_t2.5mm"
        );
        assert_eq!(
            sheet_file_stem(1, 3000.0, 1500.0, None),
            "sheet-02_3000x1500mm"
        );
    }

    #[test]
    fn deepest_point_of_a_slot_is_on_its_axis() {
        let slot = [[0.0, 0.0], [40.0, 0.0], [40.0, 4.0], [0.0, 4.0]];
        let (p, d) = deepest_point(&slot);
        assert!(
            (p[1] - 2.0).abs() < 0.05 && (d - 2.0).abs() < 0.05,
            "{p:?} {d}"
        );
        // an L: the deepest point is inside the L, not at the bbox centre (outside it)
        let l = [
            [0.0, 0.0],
            [50.0, 0.0],
            [50.0, 10.0],
            [10.0, 10.0],
            [10.0, 50.0],
            [0.0, 50.0],
        ];
        let (p, d) = deepest_point(&l);
        assert!(point_in_polygon(p, &l) && d > 4.9, "{p:?} {d}");
        // a thin L-shaped slot as the strips have (4.5 mm wide, 300 mm arms, clockwise):
        // the point is on a centre line, not at the (outside) middle of the bounding box
        let slot = [
            [0.0, 0.0],
            [0.0, 300.0],
            [4.5, 300.0],
            [4.5, 4.5],
            [300.0, 4.5],
            [300.0, 0.0],
        ];
        let (p, d) = deepest_point(&slot);
        assert!(point_in_polygon(p, &slot) && d > 2.2, "{p:?} {d}");
    }
}
