//! Pictures of the nested sheets, drawn from the strips' own contours (`strips.json`) moved
//! by their placements (`nest.json`): what the plasma cutter will cut, arcs as SVG arcs.

use std::fmt::Write;

use sv_export::svg_path_data;
use sv_nest::{ById, SheetReport};
use sv_strips::StripRecord;

use crate::plot::escape;
use crate::ReportInput;

/// One sheet (`index`, 0-based) as an inline `<svg>` in mm: the stock, the margin, every
/// placed strip with its slots and its id, the offcut. The root carries `data-sheet`
/// (1-based) and `data-parts` (placed strips) for tests.
pub fn sheet_svg(
    input: &ReportInput<'_>,
    strips: &ById<'_, StripRecord>,
    sheet: &SheetReport,
    index: usize,
) -> String {
    let (w, h) = (sheet.width, sheet.height);
    let margin = input.nest.map_or(0.0, |n| n.report.sheet.margin);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg class="sheet" viewBox="-10 -10 {} {}" role="img" data-sheet="{}" data-parts="{}" xmlns="http://www.w3.org/2000/svg"><title>sheet {}</title><g transform="translate(0 {h}) scale(1 -1)"><rect class="stock" x="0" y="0" width="{w}" height="{h}"/>"#,
        w + 20.0,
        h + 20.0,
        index + 1,
        sheet.placements.len(),
        index + 1
    );
    if margin > 0.0 && 2.0 * margin < w.min(h) {
        let _ = write!(
            s,
            r#"<rect class="margin" x="{margin}" y="{margin}" width="{}" height="{}"/>"#,
            w - 2.0 * margin,
            h - 2.0 * margin
        );
    }
    let mut labels = String::new();
    for (k, p) in sheet.placements.iter().enumerate() {
        let Some(strip) = strips.get(&p.strip) else {
            continue;
        };
        let mut d = svg_path_data(&strip.outline, 1);
        for cut in &strip.cuts {
            d.push_str(&svg_path_data(cut, 1));
        }
        let _ = write!(
            s,
            r#"<g transform="translate({:.2} {:.2}) rotate({:.4})"><path class="part" fill="{}" d="{d}"><title>{}</title></path></g>"#,
            p.translation[0],
            p.translation[1],
            p.rotation_deg,
            part_colour(k),
            escape(&strip.id)
        );
        let c = placed_centre(strip, p.rotation_deg, p.translation);
        let _ = write!(
            labels,
            r#"<text x="{:.1}" y="{:.1}">{}</text>"#,
            c[0],
            h - c[1],
            escape(&strip.id)
        );
    }
    if let Some(o) = input
        .nest
        .and_then(|n| n.report.offcut.as_ref())
        .filter(|o| o.sheet == index)
    {
        let _ = write!(
            s,
            r#"<rect class="offcut" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"><title>offcut {:.0} x {:.0} mm</title></rect>"#,
            o.x, o.y, o.width, o.height, o.width, o.height
        );
    }
    s.push_str("</g>");
    s.push_str(&labels);
    s.push_str("</svg>");
    s
}

fn part_colour(k: usize) -> String {
    format!("hsl({:.0}, 45%, 72%)", (k as f64 * 137.508) % 360.0)
}

/// The centre of a strip's outline vertices after `p = R(rotation) p + t`.
fn placed_centre(strip: &StripRecord, rotation_deg: f64, t: [f64; 2]) -> [f64; 2] {
    let n = strip.outline.vertices.len().max(1) as f64;
    let (x, y) = strip
        .outline
        .vertices
        .iter()
        .fold((0.0, 0.0), |(x, y), p| (x + p.x / n, y + p.y / n));
    let (sin, cos) = rotation_deg.to_radians().sin_cos();
    [cos * x - sin * y + t[0], sin * x + cos * y + t[1]]
}
