//! The SVG preview of a nested sheet (`DIR/sheets/*.svg`): the stock, every placed part
//! with its holes (arcs as SVG arcs), its id, and the offcut dashed. 1:1 in mm, y up.

use std::fmt::Write;

use sv_nest::{ById, NestReport};

use crate::SheetPart;

use crate::svg::{escape, path_data};

/// SVG preview of sheet `index` of `report`; `parts` are the parts given to `nest_sheets`
/// (by id).
pub fn sheet_svg(report: &NestReport, parts: &ById<'_, SheetPart>, index: usize) -> String {
    let sheet = &report.sheets[index];
    let (w, h) = (sheet.width, sheet.height);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w} {h}" width="{}mm" height="{}mm">"#,
        w, h
    );
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{w}" height="{h}" fill="#eee" stroke="#000" stroke-width="2"/>"##
    );
    // model coordinates (y up) inside a flipped group
    let _ = writeln!(s, r#"<g transform="translate(0 {h}) scale(1 -1)">"#);
    for pl in &sheet.placements {
        let Some(sp) = parts.get(&pl.strip) else {
            continue;
        };
        let moved = sp.part.transformed(pl.rotation_deg, pl.translation);
        let mut d = path_data(&moved.outer, 3);
        for hole in &moved.holes {
            d.push_str(&path_data(hole, 3));
        }
        let _ = writeln!(
            s,
            r##"<path d="{d}" fill="#7aa6d8" fill-rule="evenodd" stroke="#124" stroke-width="0.5"><title>{}</title></path>"##,
            escape(&pl.strip)
        );
    }
    if let Some(o) = report.offcut.as_ref().filter(|o| o.sheet == index) {
        let _ = writeln!(
            s,
            r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#2a2" stroke-dasharray="10,5"/>"##,
            o.x, o.y, o.width, o.height
        );
    }
    s.push_str("</g>\n</svg>\n");
    s
}
