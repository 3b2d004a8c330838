//! The DXF of one profiled strip: outline (`OUTSIDE`), slots (`INSIDE`), labels in the
//! single-stroke font, fold marks and face marks etched (`ETCH`), nominal tiles, pins and
//! title (`INFO`).

use sv_dxf::{Drawing, LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};
use sv_strips::{FlatStrip, Label, StripProfile};

use crate::font::text_strokes;
use crate::ShopConvention;

/// Etched single-stroke text centred on `at` (baseline along `angle`, cap height `h`).
pub(crate) fn strokes(d: &mut Drawing, layer: &str, text: &str, at: [f64; 2], angle: f64, h: f64) {
    for s in text_strokes(text, at, angle, h) {
        d.open_line(layer, &s);
    }
}

/// The DXF text of one profiled strip in the default shop convention ([`ShopConvention`]:
/// etching first, then the slots counter-clockwise, then the outline clockwise).
pub fn strip_dxf(strip: &FlatStrip, profile: &StripProfile) -> String {
    let convention = ShopConvention::default();
    let mut d = Drawing::new();
    for s in etch_strokes(profile) {
        d.open_line(LAYER_ETCH, &s);
    }
    for c in &profile.cuts {
        d.contour(LAYER_INSIDE, &convention.inside(c));
    }
    d.contour(LAYER_OUTSIDE, &convention.outside(&profile.outline));
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
    d.finish()
}

/// What a strip etches (labels, fold marks and face marks), as open polylines in the
/// strip's frame.
pub fn etch_strokes(profile: &StripProfile) -> Vec<Vec<[f64; 2]>> {
    let mut out = label_strokes(&profile.labels);
    out.extend(mark_strokes(profile));
    out
}

/// The strokes of etched labels.
pub(crate) fn label_strokes(labels: &[Label]) -> Vec<Vec<[f64; 2]>> {
    labels
        .iter()
        .flat_map(|l| text_strokes(&l.text, l.at, l.angle, l.height))
        .collect()
}

/// What a strip etches besides its labels (fold marks, face marks): strokes that read the
/// same however the part is turned.
pub(crate) fn mark_strokes(profile: &StripProfile) -> Vec<Vec<[f64; 2]>> {
    let mut out: Vec<Vec<[f64; 2]>> = profile.fold_marks.iter().map(|f| f.to_vec()).collect();
    out.extend(profile.face_marks.iter().flat_map(|m| m.strokes()));
    out
}
