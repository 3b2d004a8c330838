//! Hand-written SVG previews of sheets.

use std::fmt::Write;

use crate::part::Part;
use crate::sheets::NestReport;

fn path_of(pts: &[[f64; 2]], h: f64) -> String {
    let mut d = String::new();
    for (i, p) in pts.iter().enumerate() {
        let _ = write!(
            d,
            "{}{:.3},{:.3} ",
            if i == 0 { "M" } else { "L" },
            p[0],
            h - p[1]
        );
    }
    d.push('Z');
    d
}

/// SVG preview of sheet `index` of `report`; `parts` are the parts given to `nest_sheets`
/// (looked up by id). Arcs are flattened with `tolerance`.
pub fn sheet_svg(report: &NestReport, parts: &[Part], index: usize, tolerance: f64) -> String {
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
    for pl in &sheet.placements {
        let Some(part) = parts.iter().find(|p| p.id == pl.strip) else {
            continue;
        };
        let moved = part.transformed(pl.rotation_deg, pl.translation);
        let mut d = path_of(&moved.outer.flatten(tolerance), h);
        for hole in &moved.holes {
            d.push(' ');
            d.push_str(&path_of(&hole.flatten(tolerance), h));
        }
        let _ = writeln!(
            s,
            r##"<path d="{d}" fill="#7aa6d8" fill-rule="evenodd" stroke="#124" stroke-width="0.5"><title>{}</title></path>"##,
            xml_escape(&pl.strip)
        );
    }
    if let Some(o) = report.offcut.as_ref().filter(|o| o.sheet == index) {
        let _ = writeln!(
            s,
            r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#2a2" stroke-dasharray="10,5"/>"##,
            o.x,
            h - o.y - o.height,
            o.width,
            o.height
        );
    }
    s.push_str("</svg>\n");
    s
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
