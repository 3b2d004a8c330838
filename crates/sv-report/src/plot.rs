//! Inline SVG plots drawn here, no charting library: histograms and top views coloured by
//! value, with axes, ticks, units and a colour bar.

use std::fmt::Write;

/// The colour map of every value plot (viridis, 9 stops, low to high): readable in grey and
/// by colour-blind readers. The 3D view uses the same stops.
pub const COLOUR_MAP: [&str; 9] = [
    "#440154", "#472d7b", "#3b528b", "#2c728e", "#21918c", "#28ae80", "#5ec962", "#addc30",
    "#fde725",
];

fn rgb(hex: &str) -> [f64; 3] {
    let v = u32::from_str_radix(hex.trim_start_matches('#'), 16).unwrap_or(0);
    [
        (v >> 16) as f64,
        ((v >> 8) & 0xff) as f64,
        (v & 0xff) as f64,
    ]
}

/// The colour of `t` in `[0, 1]` on [`COLOUR_MAP`] (clamped), as `#rrggbb`.
pub fn colour(t: f64) -> String {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (COLOUR_MAP.len() - 1) as f64;
    let i = (x.floor() as usize).min(COLOUR_MAP.len() - 2);
    let f = x - i as f64;
    let (a, b) = (rgb(COLOUR_MAP[i]), rgb(COLOUR_MAP[i + 1]));
    let c: Vec<u8> = (0..3)
        .map(|k| (a[k] + f * (b[k] - a[k])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Escape text for HTML and SVG content and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// A value axis: the range, round ticks within it, and the power of ten the tick labels
/// are scaled by (so that `2.5e-5` reads `2.5` on an axis marked `x 10^-5`).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Lower end.
    pub min: f64,
    /// Upper end.
    pub max: f64,
    /// Tick values, inside `[min, max]`.
    pub ticks: Vec<f64>,
    /// Tick labels are `value / 10^exponent`.
    pub exponent: i32,
    decimals: usize,
}

impl Axis {
    /// An axis over `[lo, hi]` with about `count` round ticks (1, 2 or 5 times a power of
    /// ten apart), widened to the ticks around it. A degenerate range is widened.
    pub fn new(lo: f64, hi: f64, count: usize) -> Self {
        let (mut lo, mut hi) = if lo.is_finite() && hi.is_finite() && lo <= hi {
            (lo, hi)
        } else {
            (0.0, 1.0)
        };
        if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
            let pad = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
            lo -= pad;
            hi += pad;
        }
        let raw = (hi - lo) / count.max(1) as f64;
        let power = raw.log10().floor();
        let base = 10f64.powf(power);
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * base)
            .find(|s| *s >= raw * (1.0 - 1e-9))
            .unwrap_or(10.0 * base);
        let min = (lo / step + 1e-9).floor() * step;
        let max = (hi / step - 1e-9).ceil() * step;
        let n = ((max - min) / step).round() as usize;
        let ticks: Vec<f64> = (0..=n).map(|i| min + i as f64 * step).collect();
        let magnitude = ticks.iter().fold(0.0f64, |m, t| m.max(t.abs()));
        let exponent = if magnitude > 0.0 && !(1e-2..1e5).contains(&magnitude) {
            magnitude.log10().floor() as i32
        } else {
            0
        };
        let scaled_step = step / 10f64.powi(exponent);
        let decimals = (-scaled_step.log10().floor()).max(0.0) as usize;
        Self {
            min,
            max,
            ticks,
            exponent,
            decimals,
        }
    }

    /// The label of tick value `v`.
    pub fn label(&self, v: f64) -> String {
        let x = v / 10f64.powi(self.exponent);
        let text = format!("{:.*}", self.decimals, x);
        if text
            .trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            "0".into()
        } else {
            text.replace('-', "\u{2212}")
        }
    }

    /// The axis title with the scale: `gap (mm)` or `planarity (x 10^-5)`.
    pub fn title(&self, quantity: &str, unit: &str) -> String {
        let scale = if self.exponent != 0 {
            format!("\u{00d7} 10{}", superscript(self.exponent))
        } else {
            String::new()
        };
        match (scale.is_empty(), unit.is_empty()) {
            (true, true) => quantity.to_string(),
            (true, false) => format!("{quantity} ({unit})"),
            (false, true) => format!("{quantity} ({scale})"),
            (false, false) => format!("{quantity} ({scale} {unit})"),
        }
    }

    /// Position of `v` in `[0, 1]` along the axis.
    pub fn fraction(&self, v: f64) -> f64 {
        (v - self.min) / (self.max - self.min)
    }
}

fn superscript(n: i32) -> String {
    n.to_string()
        .chars()
        .map(|c| match c {
            '-' => '\u{207b}',
            '0' => '\u{2070}',
            '1' => '\u{00b9}',
            '2' => '\u{00b2}',
            '3' => '\u{00b3}',
            d => char::from_u32(0x2070 + d.to_digit(10).unwrap_or(0)).unwrap_or(d),
        })
        .collect()
}

/// Summary statistics of a sample: count, min, median, max (NaN-free input).
pub fn stats(values: &[f64]) -> Option<(usize, f64, f64, f64)> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Some((n, v[0], median, v[n - 1]))
}

/// What a histogram shows.
#[derive(Clone, Debug)]
pub struct Histogram<'a> {
    /// Element id (`hist-gap`).
    pub id: &'a str,
    /// Heading inside the figure.
    pub title: &'a str,
    /// The quantity on the x axis (`primary gap`).
    pub quantity: &'a str,
    /// Its unit (`mm`), empty for a ratio.
    pub unit: &'a str,
    /// What one count is (`links`, `faces`, `vertices`).
    pub items: &'a str,
}

const W: f64 = 480.0;
const H: f64 = 280.0;
const LEFT: f64 = 56.0;
const RIGHT: f64 = 16.0;
const TOP: f64 = 46.0;
const BOTTOM: f64 = 52.0;

/// A histogram of `values` (non-finite values are left out) as an inline `<svg>`, with
/// about 20 bins on round boundaries, axes with ticks, and the count, min, median and max.
/// The root carries `data-n` (values counted) for tests.
pub fn histogram(values: &[f64], h: &Histogram<'_>) -> String {
    let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg id="{}" class="plot" viewBox="0 0 {W} {H}" role="img" data-n="{}" xmlns="http://www.w3.org/2000/svg"><title>{}</title>"#,
        escape(h.id),
        finite.len(),
        escape(h.title)
    );
    let _ = write!(
        s,
        r#"<text x="{LEFT}" y="18" class="title">{}</text>"#,
        escape(h.title)
    );
    let Some((n, lo, median, hi)) = stats(&finite) else {
        let _ = write!(
            s,
            r#"<text x="{}" y="{}" class="empty" text-anchor="middle">no {}</text></svg>"#,
            W / 2.0,
            H / 2.0,
            escape(h.items)
        );
        return s;
    };
    let x_axis = Axis::new(lo, hi, 6);
    // bins: a round division of the axis ticks, about 20 in all
    let per_tick = (20.0 / (x_axis.ticks.len() - 1).max(1) as f64)
        .round()
        .max(1.0) as usize;
    let per_tick = [1usize, 2, 4, 5, 10]
        .into_iter()
        .min_by_key(|k| k.abs_diff(per_tick))
        .unwrap_or(1);
    let bins = (x_axis.ticks.len() - 1).max(1) * per_tick;
    let width = (x_axis.max - x_axis.min) / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &finite {
        let b = (((v - x_axis.min) / width).floor().max(0.0) as usize).min(bins - 1);
        counts[b] += 1;
    }
    let y_axis = Axis::new(0.0, counts.iter().copied().max().unwrap_or(1) as f64, 4);
    let px = |v: f64| LEFT + x_axis.fraction(v) * (W - LEFT - RIGHT);
    let py = |c: f64| H - BOTTOM - y_axis.fraction(c) * (H - TOP - BOTTOM);
    // grid and y ticks (counts are whole numbers: skip fractional ticks)
    for t in y_axis.ticks.iter().filter(|t| t.fract() == 0.0) {
        let _ = write!(
            s,
            r#"<line class="grid" x1="{LEFT}" x2="{}" y1="{y:.1}" y2="{y:.1}"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"#,
            W - RIGHT,
            LEFT - 6.0,
            py(*t) + 4.0,
            y_axis.label(*t),
            y = py(*t)
        );
    }
    for (b, &c) in counts.iter().enumerate() {
        if c == 0 {
            continue;
        }
        let (a, z) = (
            x_axis.min + b as f64 * width,
            x_axis.min + (b + 1) as f64 * width,
        );
        let _ = write!(
            s,
            r#"<rect class="bar" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"><title>{} to {}: {c} {}</title></rect>"#,
            px(a) + 0.5,
            py(c as f64),
            (px(z) - px(a) - 1.0).max(0.5),
            py(0.0) - py(c as f64),
            x_axis.label(a),
            x_axis.label(z),
            escape(h.items)
        );
    }
    // x axis
    let _ = write!(
        s,
        r#"<line class="axis" x1="{LEFT}" x2="{}" y1="{y:.1}" y2="{y:.1}"/>"#,
        W - RIGHT,
        y = py(0.0)
    );
    for t in &x_axis.ticks {
        let _ = write!(
            s,
            r#"<line class="axis" x1="{x:.1}" x2="{x:.1}" y1="{:.1}" y2="{:.1}"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            py(0.0),
            py(0.0) + 4.0,
            py(0.0) + 17.0,
            x_axis.label(*t),
            x = px(*t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" class="label">{}</text>"#,
        LEFT + (W - LEFT - RIGHT) / 2.0,
        H - 14.0,
        escape(&x_axis.title(h.quantity, h.unit))
    );
    let _ = write!(
        s,
        r#"<text x="14" y="{:.1}" text-anchor="middle" class="label" transform="rotate(-90 14 {:.1})">{}</text>"#,
        TOP + (H - TOP - BOTTOM) / 2.0,
        TOP + (H - TOP - BOTTOM) / 2.0,
        escape(h.items)
    );
    let unit = if h.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", h.unit)
    };
    let _ = write!(
        s,
        r#"<text x="{LEFT}" y="34" class="stats">n {n}, min {}{unit}, median {}{unit}, max {}{unit}</text></svg>"#,
        short(lo),
        short(median),
        short(hi),
    );
    s
}

/// A short number for captions: 4 significant digits, scientific when tiny or huge.
pub fn short(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if !x.is_finite() {
        x.to_string()
    } else if (1e-3..1e6).contains(&x.abs()) {
        let decimals = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{:.*}", decimals, x).replace('-', "\u{2212}")
    } else {
        format!("{x:.3e}").replace('-', "\u{2212}")
    }
}

/// What a top view shows.
#[derive(Clone, Debug)]
pub struct TopView<'a> {
    /// Element id (`map-theta`).
    pub id: &'a str,
    /// Heading inside the figure.
    pub title: &'a str,
    /// The quantity of the colour bar (`theta`).
    pub quantity: &'a str,
    /// Its unit (`deg`).
    pub unit: &'a str,
}

/// Quads seen from above (their XY projection, x to the right, y up), each filled by the
/// colour of its value on [`COLOUR_MAP`], with a colour bar and a 1 m scale bar. Every
/// quad carries a tooltip `label: value unit`.
pub fn top_view(
    quads: &[[[f64; 3]; 4]],
    values: &[f64],
    labels: &[&str],
    v: &TopView<'_>,
) -> String {
    const MAP_W: f64 = 400.0;
    const BAR_W: f64 = 120.0;
    const PAD: f64 = 12.0;
    let mut s = String::new();
    let pts = quads.iter().flatten();
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    for p in pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    if quads.is_empty() || x1 <= x0 || y1 <= y0 {
        let _ = write!(
            s,
            r#"<svg id="{}" class="plot" viewBox="0 0 {W} 120" xmlns="http://www.w3.org/2000/svg"><text x="{}" y="60" text-anchor="middle" class="empty">no units</text></svg>"#,
            escape(v.id),
            W / 2.0
        );
        return s;
    }
    let scale = MAP_W / (x1 - x0);
    let map_h = (y1 - y0) * scale;
    let height = TOP + map_h + 40.0;
    let total_w = PAD + MAP_W + PAD + BAR_W;
    let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    let (lo, hi) = finite
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let axis = Axis::new(lo, hi, 5);
    let _ = write!(
        s,
        r#"<svg id="{}" class="plot" viewBox="0 0 {total_w} {height:.1}" role="img" data-n="{}" xmlns="http://www.w3.org/2000/svg"><title>{}</title><text x="{PAD}" y="18" class="title">{}</text>"#,
        escape(v.id),
        finite.len(),
        escape(v.title),
        escape(v.title)
    );
    let mx = |x: f64| PAD + (x - x0) * scale;
    let my = |y: f64| TOP + (y1 - y) * scale;
    let unit = if v.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", v.unit)
    };
    for (i, q) in quads.iter().enumerate() {
        let value = values.get(i).copied().unwrap_or(f64::NAN);
        let fill = if value.is_finite() {
            colour(axis.fraction(value))
        } else {
            "#cccccc".into()
        };
        let d: Vec<String> = q
            .iter()
            .map(|p| format!("{:.1},{:.1}", mx(p[0]), my(p[1])))
            .collect();
        let _ = write!(
            s,
            r#"<polygon points="{}" fill="{fill}"><title>{}: {}{unit}</title></polygon>"#,
            d.join(" "),
            escape(labels.get(i).copied().unwrap_or("")),
            short(value)
        );
    }
    // scale bar: 1 m
    let bar = 1000.0 * scale;
    let _ = write!(
        s,
        r#"<line class="axis" x1="{PAD}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}" stroke-width="2"/><text x="{PAD}" y="{:.1}">1 m</text><text x="{:.1}" y="{:.1}" text-anchor="end" class="stats">top view, x right, y up</text>"#,
        PAD + bar,
        height - 8.0,
        PAD + MAP_W,
        height - 8.0,
        y = height - 22.0
    );
    // colour bar
    let bx = PAD + MAP_W + PAD + 8.0;
    let (by0, by1) = (TOP, TOP + map_h.max(80.0));
    let steps = 32;
    for k in 0..steps {
        let t0 = k as f64 / steps as f64;
        let y = by1 - (k + 1) as f64 / steps as f64 * (by1 - by0);
        let _ = write!(
            s,
            r#"<rect x="{bx:.1}" y="{y:.1}" width="14" height="{:.2}" fill="{}"/>"#,
            (by1 - by0) / steps as f64 + 0.3,
            colour(t0 + 0.5 / steps as f64)
        );
    }
    for t in &axis.ticks {
        let y = by1 - axis.fraction(*t) * (by1 - by0);
        let _ = write!(
            s,
            r#"<line class="axis" x1="{:.1}" x2="{:.1}" y1="{y:.1}" y2="{y:.1}"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            bx + 14.0,
            bx + 18.0,
            bx + 20.0,
            y + 4.0,
            axis.label(*t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{bx:.1}" y="{:.1}" class="label">{}</text></svg>"#,
        TOP - 6.0,
        escape(&axis.title(v.quantity, v.unit))
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_have_round_ticks_covering_the_data() {
        let a = Axis::new(0.3, 25.4, 6);
        assert_eq!(a.ticks, vec![0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0]);
        assert_eq!(a.label(10.0), "10");
        assert_eq!(a.title("gap", "mm"), "gap (mm)");
        let tiny = Axis::new(1.2e-6, 2.5e-5, 5);
        assert!(tiny.min <= 1.2e-6 && tiny.max >= 2.5e-5 * (1.0 - 1e-9));
        assert_eq!(tiny.exponent, -5);
        assert_eq!(
            tiny.title("planarity", ""),
            "planarity (\u{00d7} 10\u{207b}\u{2075})"
        );
        assert_eq!(tiny.label(1e-5), "1.0");
        let flat = Axis::new(7.0, 7.0, 5);
        assert!(flat.min < 7.0 && flat.max > 7.0);
        let neg = Axis::new(-3.0, 2.0, 5);
        assert_eq!(neg.label(-2.0), "\u{2212}2");
        assert_eq!(neg.label(0.0), "0");
    }

    #[test]
    fn colour_map_ends_and_clamps() {
        assert_eq!(colour(0.0), "#440154");
        assert_eq!(colour(1.0), "#fde725");
        assert_eq!(colour(7.0), "#fde725");
        assert_eq!(colour(f64::NAN), "#440154");
        assert_eq!(colour(0.5), "#21918c");
    }

    #[test]
    fn histogram_counts_every_value_once() {
        let values: Vec<f64> = (0..100).map(|i| i as f64 * 0.25).collect();
        let svg = histogram(
            &values,
            &Histogram {
                id: "h",
                title: "gaps <test>",
                quantity: "gap",
                unit: "mm",
                items: "links",
            },
        );
        assert!(svg.contains(r#"data-n="100""#));
        assert!(svg.contains("gaps &lt;test&gt;"));
        let total: usize = svg
            .split("</title></rect>")
            .filter_map(|part| part.rsplit(": ").next())
            .filter_map(|t| t.split(' ').next()?.parse::<usize>().ok())
            .sum();
        assert_eq!(total, 100);
        assert!(svg.contains("gap (mm)"));
        let empty = histogram(
            &[f64::NAN],
            &Histogram {
                id: "e",
                title: "t",
                quantity: "q",
                unit: "",
                items: "faces",
            },
        );
        assert!(empty.contains("no faces") && empty.contains(r#"data-n="0""#));
    }

    #[test]
    fn top_view_colours_each_quad_and_labels_it() {
        let q = |x: f64| {
            [
                [x, 0.0, 0.0],
                [x + 300.0, 0.0, 0.0],
                [x + 300.0, 300.0, 0.0],
                [x, 300.0, 0.0],
            ]
        };
        let svg = top_view(
            &[q(0.0), q(300.0)],
            &[10.0, 20.0],
            &["A01-01", "A01-02"],
            &TopView {
                id: "m",
                title: "theta",
                quantity: "theta",
                unit: "deg",
            },
        );
        assert_eq!(svg.matches("<polygon").count(), 2);
        assert!(svg.contains("A01-02: 20.00 deg"));
        assert!(svg.contains(&format!(r#"fill="{}""#, colour(0.0))));
        assert!(svg.contains(&format!(r#"fill="{}""#, colour(1.0))));
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(25.3899), "25.39");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(-1.5), "\u{2212}1.500");
        assert_eq!(short(2.5e-5), "2.500e\u{2212}5");
    }
}
