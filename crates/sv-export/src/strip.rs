//! The DXF of one profiled strip: outline (`OUTSIDE`), slots (`INSIDE`), labels and fold
//! marks etched in the single-stroke font (`ETCH`), nominal tiles, pins and title (`INFO`).

use sv_dxf::{Drawing, LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};
use sv_strips::{FlatStrip, StripProfile};

use crate::font::text_strokes;

/// Etched single-stroke text centred on `at` (baseline along `angle`, cap height `h`).
pub(crate) fn strokes(d: &mut Drawing, layer: &str, text: &str, at: [f64; 2], angle: f64, h: f64) {
    for s in text_strokes(text, at, angle, h) {
        d.open_line(layer, &s);
    }
}

/// The DXF text of one profiled strip.
pub fn strip_dxf(strip: &FlatStrip, profile: &StripProfile) -> String {
    let mut d = Drawing::new();
    d.contour(LAYER_OUTSIDE, &profile.outline);
    for c in &profile.cuts {
        d.contour(LAYER_INSIDE, c);
    }
    for s in etch_strokes(profile) {
        d.open_line(LAYER_ETCH, &s);
    }
    for t in &profile.tiles {
        d.polygon(LAYER_INFO, t);
    }
    for pin in &strip.pins {
        let (x, y, r) = (pin.point.x, pin.point.y, 3.0);
        d.open_line(LAYER_INFO, &[[x - r, y], [x + r, y]]);
        d.open_line(LAYER_INFO, &[[x, y - r], [x, y + r]]);
    }
    let title = format!("{} {:.0}X{:.0}", strip.id, strip.size[0], strip.size[1]);
    strokes(
        &mut d,
        LAYER_INFO,
        &title,
        [strip.size[0] / 2.0, -30.0],
        0.0,
        15.0,
    );
    let (ext_min, ext_max) = extents(profile);
    d.finish(ext_min, ext_max)
}

/// What a strip etches (labels and fold marks), as open polylines in the strip's frame.
pub fn etch_strokes(profile: &StripProfile) -> Vec<Vec<[f64; 2]>> {
    let mut out: Vec<Vec<[f64; 2]>> = profile
        .labels
        .iter()
        .flat_map(|l| text_strokes(&l.text, l.at, l.angle, l.height))
        .collect();
    out.extend(profile.fold_marks.iter().map(|f| f.to_vec()));
    out
}

fn extents(p: &StripProfile) -> ([f64; 2], [f64; 2]) {
    let mut a = [f64::MAX, f64::MAX];
    let mut b = [f64::MIN, f64::MIN];
    for v in &p.outline.vertices {
        a = [a[0].min(v.x), a[1].min(v.y)];
        b = [b[0].max(v.x), b[1].max(v.y)];
    }
    if a[0] > b[0] {
        return ([0.0, 0.0], [0.0, 0.0]);
    }
    // arcs may bulge past their vertices by at most the fillet; leave room for the title
    ([a[0] - 10.0, a[1] - 50.0], [b[0] + 10.0, b[1] + 10.0])
}
