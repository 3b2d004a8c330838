//! SVG drawing of one strip for the fabricator: part with its cuts, etched labels, fold
//! marks and face marks, nominal tiles and pins, a scale bar, and a title with the strip id
//! and size.
//! Drawn 1:1 in mm (`width`/`height` in mm), y up as in the DXF.

use std::fmt::Write;

use sv_geom::Contour;
use sv_strips::{FlatStrip, HubFace, ProfileParams, StripProfile};

use crate::font::text_strokes;

/// SVG path data of a closed contour in its own (y up) coordinates, `decimals` digits
/// after the point (one more for arc radii): `M x y`, then `L x y` per straight segment and
/// `A r r 0 large ccw x y` per arc (SVG's sweep flag 1 is counter-clockwise in y-up
/// coordinates), closed by `Z`. Arcs stay arcs.
pub fn path_data(contour: &Contour, decimals: usize) -> String {
    let mut d = String::new();
    let n = contour.vertices.len();
    let p = decimals;
    for (i, s) in contour.segments().enumerate() {
        if i == 0 {
            let _ = write!(d, "M{:.p$} {:.p$}", s.start[0], s.start[1]);
        }
        let [x, y] = s.end;
        match s.arc() {
            Some((r, _)) => {
                let large = u8::from(s.sweep().abs() > std::f64::consts::PI);
                let ccw = u8::from(s.bulge > 0.0);
                let q = p + 1;
                let _ = write!(d, "A{r:.q$} {r:.q$} 0 {large} {ccw} {x:.p$} {y:.p$}");
            }
            // the last straight segment is drawn by Z
            None if i + 1 < n => {
                let _ = write!(d, "L{x:.p$} {y:.p$}");
            }
            None => {}
        }
    }
    if n > 0 {
        d.push('Z');
    }
    d
}

fn polyline(points: &[[f64; 2]]) -> String {
    points
        .iter()
        .map(|p| format!("{:.3},{:.3}", p[0], p[1]))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A "nice" scale bar length (mm) about a fifth of `span`: 1, 2 or 5 times a power of ten.
fn bar_length(span: f64) -> f64 {
    let target = (span / 5.0).max(10.0);
    let p = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .iter()
        .map(|m| m * p)
        .find(|&l| l <= target)
        .unwrap_or(p)
}

/// The SVG text of one profiled strip.
pub fn strip_svg(strip: &FlatStrip, profile: &StripProfile, params: &ProfileParams) -> String {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for t in &profile.tiles {
        for p in t {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
    }
    if x0 > x1 {
        (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
    }
    let margin = 30.0;
    let title_h = 70.0;
    let bar_h = 60.0;
    let (w, h) = (
        x1 - x0 + 2.0 * margin,
        y1 - y0 + 2.0 * margin + title_h + bar_h,
    );
    // model (y up) to drawing: x' = x - x0 + margin, y' = (y1 + margin + title_h) - y
    let mut s = String::with_capacity(64 * 1024);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.1}mm" height="{h:.1}mm" viewBox="0 0 {w:.3} {h:.3}">"#
    );
    let _ = writeln!(
        s,
        r#"<rect x="0" y="0" width="{w:.3}" height="{h:.3}" fill="white"/>"#
    );
    let units = strip.units.len();
    let _ = writeln!(
        s,
        r#"<text x="{margin}" y="28" font-family="sans-serif" font-size="20" font-weight="bold">Strip {} — {:.0} × {:.0} mm — {units} units</text>"#,
        strip.id, strip.size[0], strip.size[1]
    );
    let _ = writeln!(
        s,
        r##"<text x="{margin}" y="52" font-family="sans-serif" font-size="12">t = {} mm · kerf {} mm (nominal contours, CAM compensates) · net area {:.3} m² · <tspan fill="black">cut</tspan> · <tspan fill="#2a7">etch</tspan> · <tspan fill="#d22">fold</tspan> · <tspan fill="#999">tile / pin (info)</tspan> · seen from the etched face: <tspan fill="#2a7">⊙ hub out of the etched face (towards you), ⊗ out of the back</tspan></text>"##,
        params.thickness,
        params.kerf,
        profile.area / 1e6
    );
    let _ = writeln!(
        s,
        r#"<g transform="translate({:.3},{:.3}) scale(1,-1)">"#,
        margin - x0,
        y1 + margin + title_h
    );
    // info: nominal tiles and pins
    for t in &profile.tiles {
        let _ = writeln!(
            s,
            r##"<polygon points="{}" fill="none" stroke="#999" stroke-width="0.6" stroke-dasharray="6 4"/>"##,
            polyline(t)
        );
    }
    // the part: outline and cuts in one even-odd path
    let mut d = path_data(&profile.outline, 3);
    for c in &profile.cuts {
        d.push_str(&path_data(c, 3));
    }
    let _ = writeln!(
        s,
        r##"<path d="{d}" fill="#dfe5ec" fill-rule="evenodd" stroke="black" stroke-width="0.8"/>"##
    );
    for pin in &strip.pins {
        let (x, y) = (pin.point.x, pin.point.y);
        let _ = writeln!(
            s,
            r##"<path d="M{:.3},{y:.3}H{:.3}M{x:.3},{:.3}V{:.3}" stroke="#999" stroke-width="0.6"/>"##,
            x - 4.0,
            x + 4.0,
            y - 4.0,
            y + 4.0
        );
    }
    for f in &profile.fold_marks {
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#d22" stroke-width="1.2"/>"##,
            polyline(f)
        );
    }
    for l in &profile.labels {
        // the strokes are what gets etched; the title names them on hover and for search
        let _ = writeln!(
            s,
            r#"<g class="label" data-label="{0}"><title>{0}</title>"#,
            escape(&l.text)
        );
        for st in text_strokes(&l.text, l.at, l.angle, l.height) {
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="#2a7" stroke-width="1.2" stroke-linecap="round" stroke-linejoin="round"/>"##,
                polyline(&st)
            );
        }
        s.push_str("</g>\n");
    }
    for (m, &u) in profile.face_marks.iter().zip(&strip.units) {
        let why = match m.face {
            HubFace::Etched => "out of the etched face, towards you",
            HubFace::Back => "out of the back, away from you",
        };
        let _ = writeln!(
            s,
            r#"<g class="face-mark" data-unit="{u}" data-face="{}"><title>hub comes {why}</title>"#,
            m.face.name()
        );
        for st in m.strokes() {
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="#2a7" stroke-width="1.2" stroke-linecap="round" stroke-linejoin="round"/>"##,
                polyline(&st)
            );
        }
        s.push_str("</g>\n");
    }
    s.push_str("</g>\n");
    // scale bar
    let len = bar_length(x1 - x0);
    let (bx, by) = (margin, h - 30.0);
    let _ = writeln!(
        s,
        r#"<g stroke="black" stroke-width="1"><rect x="{bx:.3}" y="{:.3}" width="{:.3}" height="6" fill="black"/><rect x="{:.3}" y="{:.3}" width="{:.3}" height="6" fill="white"/></g>"#,
        by - 6.0,
        len / 2.0,
        bx + len / 2.0,
        by - 6.0,
        len / 2.0
    );
    let _ = writeln!(
        s,
        r#"<text x="{bx:.3}" y="{:.3}" font-family="sans-serif" font-size="12">0</text><text x="{:.3}" y="{:.3}" font-family="sans-serif" font-size="12" text-anchor="end">{len:.0} mm</text>"#,
        by + 14.0,
        bx + len,
        by + 14.0
    );
    s.push_str("</svg>\n");
    s
}

/// Text for an SVG attribute or element.
pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_data_of_straight_and_arc_segments() {
        let square = Contour::polygon(&[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]);
        assert_eq!(
            path_data(&square, 1),
            "M0.0 0.0L10.0 0.0L10.0 10.0L0.0 10.0Z"
        );
        // a circle of radius 10 as two counter-clockwise half arcs
        let circle = Contour::new(vec![[0.0, 0.0, 1.0].into(), [20.0, 0.0, 1.0].into()]);
        assert_eq!(
            path_data(&circle, 1),
            "M0.0 0.0A10.00 10.00 0 0 1 20.0 0.0A10.00 10.00 0 0 1 0.0 0.0Z"
        );
        // more than a half circle, clockwise
        let big = Contour::new(vec![[0.0, 0.0, -2.0].into(), [10.0, 0.0, 0.0].into()]);
        assert!(path_data(&big, 1).starts_with("M0.0 0.0A6.25 6.25 0 1 0 10.0 0.0"));
    }

    #[test]
    fn scale_bars_are_round_numbers() {
        assert_eq!(bar_length(1800.0), 200.0);
        assert_eq!(bar_length(3000.0), 500.0);
        assert_eq!(bar_length(20.0), 10.0);
    }
}
