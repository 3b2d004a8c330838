//! A tiny single-stroke font (0-9, A-Z, '-') for etched labels: many CAM systems drop DXF
//! TEXT, and a plasma or marker follows one stroke. Glyphs live on a 4 x 6 grid (cap height
//! 6, advance 5); each stroke is a polyline, each point two digits `x y`.

const GLYPHS: &[(char, &str)] = &[
    ('0', "0040460600|0046"),
    ('1', "152620|1030"),
    ('2', "05163645440040"),
    ('3', "064624344341301001"),
    ('4', "30360242"),
    ('5', "4606033342413000"),
    ('6', "46160501103041423303"),
    ('7', "064610"),
    ('8', "13040516364544331302011030414233"),
    ('9', "00304145361605041343"),
    ('A', "002640|1333"),
    ('B', "00063645443303|3342413000"),
    ('C', "4130100105163645"),
    ('D', "00063645413000"),
    ('E', "40000646|0333"),
    ('F', "000646|0333"),
    ('G', "45361605011030414323"),
    ('H', "0006|4046|0343"),
    ('I', "1030|2026|1636"),
    ('J', "0110304146"),
    ('K', "0006|4602|1340"),
    ('L', "060040"),
    ('M', "0006234640"),
    ('N', "00064046"),
    ('O', "103041453616050110"),
    ('P', "00063645443303"),
    ('Q', "103041453616050110|2240"),
    ('R', "00063645443303|2340"),
    ('S', "453616050413334241301001"),
    ('T', "0646|2620"),
    ('U', "060110304146"),
    ('V', "062046"),
    ('W', "0610233046"),
    ('X', "0046|0640"),
    ('Y', "0623|4623|2320"),
    ('Z', "06464000"),
    ('-', "1333"),
];

/// Cap height of the glyph grid.
const CAP: f64 = 6.0;
/// Advance per character on the glyph grid.
const ADVANCE: f64 = 5.0;

/// True when the font has a glyph for `c` (space is blank).
pub fn has_glyph(c: char) -> bool {
    c == ' ' || GLYPHS.iter().any(|g| g.0 == c.to_ascii_uppercase())
}

/// Width of `text` at cap height `height` (mm).
pub fn text_width(text: &str, height: f64) -> f64 {
    let n = text.chars().count() as f64;
    ((n * ADVANCE - 1.0).max(0.0)) * height / CAP
}

/// The strokes of `text` (uppercased; unknown characters are skipped) with cap height
/// `height`, centred at `at`, baseline along `angle` (rad).
pub fn text_strokes(text: &str, at: [f64; 2], angle: f64, height: f64) -> Vec<Vec<[f64; 2]>> {
    let k = height / CAP;
    let (s, c) = angle.sin_cos();
    let (x0, y0) = (-text_width(text, height) / 2.0, -height / 2.0);
    let place = |x: f64, y: f64| [at[0] + c * x - s * y, at[1] + s * x + c * y];
    let mut out = Vec::new();
    for (i, ch) in text.chars().enumerate() {
        let Some((_, code)) = GLYPHS.iter().find(|g| g.0 == ch.to_ascii_uppercase()) else {
            continue;
        };
        let ox = x0 + i as f64 * ADVANCE * k;
        for stroke in code.split('|') {
            let d: Vec<f64> = stroke
                .bytes()
                .map(|b| f64::from(b.wrapping_sub(b'0')))
                .collect();
            out.push(
                d.chunks(2)
                    .map(|p| place(ox + p[0] * k, y0 + p[1] * k))
                    .collect(),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_glyph_is_well_formed() {
        for (c, code) in GLYPHS {
            for stroke in code.split('|') {
                assert!(stroke.len() >= 4 && stroke.len() % 2 == 0, "{c}: {stroke}");
                for (i, b) in stroke.bytes().enumerate() {
                    let max = if i % 2 == 0 { b'4' } else { b'6' };
                    assert!((b'0'..=max).contains(&b), "{c}: {stroke}");
                }
            }
        }
        for c in ('0'..='9').chain('A'..='Z').chain(['-']) {
            assert!(has_glyph(c), "{c}");
        }
    }

    #[test]
    fn text_is_centred_and_sized() {
        let s = text_strokes("A03-07", [100.0, 50.0], 0.0, 12.0);
        let pts: Vec<[f64; 2]> = s.into_iter().flatten().collect();
        let (minx, maxx) = pts
            .iter()
            .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p[0]), a.1.max(p[0])));
        let (miny, maxy) = pts
            .iter()
            .fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p[1]), a.1.max(p[1])));
        assert!((maxy - miny - 12.0).abs() < 1e-9);
        assert!(((minx + maxx) / 2.0 - 100.0).abs() < 1e-9);
        assert!((maxx - minx - text_width("A03-07", 12.0)).abs() < 1e-9);
    }
}
