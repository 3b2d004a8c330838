//! Draw the figures of `docs/geometry.md` from the real geometry:
//! `cargo run -p sv-frame --example figures -- docs/figures`.
//!
//! Every picture is computed with `sv_unit` / `sv_frame` (deployments, hubs, a solve) and
//! written as a hand-made SVG (no drawing crate). The program also prints the figures it
//! quotes in the text (depths, overlaps, gaps of the solved cap for each side policy).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sv_frame::{evaluate, hubs_from_mesh, solve, QuadMesh, SidePolicy, SolveOptions};
use sv_geom::{Point3, Real, Vector3};
use sv_unit::{deploy, depth_squared, rotation, AxisCase, Deployment, Rhombus};

/// Unit side used throughout (mm).
const SIDE: Real = 300.0;

// ---------------------------------------------------------------------------------------
// A tiny SVG writer
// ---------------------------------------------------------------------------------------

struct Svg {
    w: Real,
    h: Real,
    body: String,
}

impl Svg {
    fn new(w: Real, h: Real) -> Self {
        let mut s = Self {
            w,
            h,
            body: String::new(),
        };
        s.raw(&format!(
            r#"<rect x="0" y="0" width="{w}" height="{h}" fill="white"/>"#
        ));
        s
    }
    fn raw(&mut self, s: &str) {
        self.body.push_str(s);
        self.body.push('\n');
    }
    fn line(&mut self, a: (Real, Real), b: (Real, Real), style: &str) {
        self.raw(&format!(
            r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" {style}/>"#,
            a.0, a.1, b.0, b.1
        ));
    }
    fn polyline(&mut self, pts: &[(Real, Real)], style: &str) {
        if pts.len() < 2 {
            return;
        }
        let mut d = String::new();
        for p in pts {
            let _ = write!(d, "{:.2},{:.2} ", p.0, p.1);
        }
        self.raw(&format!(r#"<polyline points="{d}" fill="none" {style}/>"#));
    }
    fn polygon(&mut self, pts: &[(Real, Real)], style: &str) {
        let mut d = String::new();
        for p in pts {
            let _ = write!(d, "{:.2},{:.2} ", p.0, p.1);
        }
        self.raw(&format!(r#"<polygon points="{d}" {style}/>"#));
    }
    fn circle(&mut self, c: (Real, Real), r: Real, style: &str) {
        self.raw(&format!(
            r#"<circle cx="{:.2}" cy="{:.2}" r="{r:.2}" {style}/>"#,
            c.0, c.1
        ));
    }
    fn rect(&mut self, x: Real, y: Real, w: Real, h: Real, style: &str) {
        self.raw(&format!(
            r#"<rect x="{x:.2}" y="{y:.2}" width="{w:.2}" height="{h:.2}" {style}/>"#
        ));
    }
    /// Text; `anchor` is start, middle or end.
    fn text(&mut self, p: (Real, Real), size: Real, anchor: &str, s: &str) {
        self.text_styled(p, size, anchor, s, "fill=\"#222\"");
    }
    fn text_styled(&mut self, p: (Real, Real), size: Real, anchor: &str, s: &str, style: &str) {
        let s = s
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;");
        self.raw(&format!(
            r#"<text x="{:.2}" y="{:.2}" font-family="DejaVu Sans, Arial, sans-serif" font-size="{size}" text-anchor="{anchor}" {style}>{s}</text>"#,
            p.0, p.1
        ));
    }
    /// An arrow from `a` to `b` with a filled head.
    fn arrow(&mut self, a: (Real, Real), b: (Real, Real), colour: &str, width: Real) {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = dx.hypot(dy).max(1e-9);
        let (ux, uy) = (dx / len, dy / len);
        let head = 7.0_f64.min(len * 0.5);
        let base = (b.0 - ux * head, b.1 - uy * head);
        self.line(
            a,
            base,
            &format!(r#"stroke="{colour}" stroke-width="{width}""#),
        );
        self.polygon(
            &[
                b,
                (base.0 - uy * head * 0.45, base.1 + ux * head * 0.45),
                (base.0 + uy * head * 0.45, base.1 - ux * head * 0.45),
            ],
            &format!(r#"fill="{colour}""#),
        );
    }
    fn finish(self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n{b}</svg>\n",
            w = self.w,
            h = self.h,
            b = self.body
        )
    }
}

/// Viridis-like colour map on `[0, 1]`.
fn colour(t: Real) -> String {
    const STOPS: [[Real; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as Real;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as Real;
    let c: Vec<u8> = (0..3)
        .map(|k| (STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// A horizontal colour bar with tick labels.
fn colour_bar(svg: &mut Svg, x: Real, y: Real, w: Real, max: Real, label: &str, ticks: &[Real]) {
    let n = 60;
    for i in 0..n {
        let t = i as Real / n as Real;
        svg.rect(
            x + t * w,
            y,
            w / n as Real + 0.6,
            12.0,
            &format!(r#"fill="{}""#, colour(t)),
        );
    }
    svg.rect(
        x,
        y,
        w,
        12.0,
        r##"fill="none" stroke="#444" stroke-width="0.6""##,
    );
    for &v in ticks {
        let px = x + v / max * w;
        svg.line((px, y + 12.0), (px, y + 16.0), r##"stroke="#444""##);
        svg.text((px, y + 27.0), 11.0, "middle", &trim(v));
    }
    svg.text((x + w / 2.0, y - 5.0), 12.0, "middle", label);
}

fn trim(v: Real) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

// ---------------------------------------------------------------------------------------
// Projections
// ---------------------------------------------------------------------------------------

/// Orthographic view: azimuth and elevation of the eye (rad), scale, screen origin.
#[derive(Clone, Copy)]
struct View {
    right: Vector3,
    up: Vector3,
    scale: Real,
    origin: (Real, Real),
}

impl View {
    fn plan(scale: Real, origin: (Real, Real)) -> Self {
        Self {
            right: Vector3::x(),
            up: Vector3::y(),
            scale,
            origin,
        }
    }
    fn axo(azimuth: Real, elevation: Real, scale: Real, origin: (Real, Real)) -> Self {
        let eye = Vector3::new(
            elevation.cos() * azimuth.cos(),
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
        );
        let right = Vector3::z().cross(&eye).normalize();
        let up = eye.cross(&right);
        Self {
            right,
            up,
            scale,
            origin,
        }
    }
    fn p(&self, p: &Point3) -> (Real, Real) {
        (
            self.origin.0 + self.scale * p.coords.dot(&self.right),
            self.origin.1 - self.scale * p.coords.dot(&self.up),
        )
    }
}

const HUB_STYLE: &str =
    r##"fill="#4a7fc1" fill-opacity="0.35" stroke="#1f4e8c" stroke-width="1.6""##;
const PRIMARY_STYLE: &str =
    r##"fill="#e8923a" fill-opacity="0.35" stroke="#b35a00" stroke-width="1.6""##;
const LEG_STYLE: &str = r##"stroke="#2a9d4b" stroke-width="2.2""##;

// ---------------------------------------------------------------------------------------
// (a) one unit
// ---------------------------------------------------------------------------------------

fn draw_unit(svg: &mut Svg, view: &View, phi_deg: Real, labels: bool) {
    let a = SIDE / 2f64.sqrt();
    let rh = Rhombus::new(a, a).expect("rhombus");
    let dep = Deployment::new(FRAC_PI_4, phi_deg.to_radians());
    let d = deploy(&rh, &dep).expect("feasible");
    let prim: Vec<_> = d.primary.iter().map(|p| view.p(p)).collect();
    let hub: Vec<_> = d.hub.iter().map(|p| view.p(p)).collect();
    // draw the lower layer first
    let hub_above = d.translation.z > 0.0;
    let mut layers = [(&prim, PRIMARY_STYLE), (&hub, HUB_STYLE)];
    if !hub_above {
        layers.swap(0, 1);
    }
    svg.polygon(layers[0].0, layers[0].1);
    for i in 0..4 {
        svg.line(hub[i], prim[(i + 1) % 4], LEG_STYLE);
    }
    svg.polygon(layers[1].0, layers[1].1);
    for i in 0..4 {
        svg.circle(hub[i], 2.6, r##"fill="#1f4e8c""##);
        svg.circle(prim[i], 2.6, r##"fill="#b35a00""##);
    }
    let o = view.p(&Point3::origin());
    let hc = view.p(&Point3::from(d.translation));
    // P from the primary centroid to the hub centroid, the axis direction t at the origin
    svg.arrow(o, hc, "#c0392b", 1.6);
    let t_tip = view.p(&Point3::from(d.axis * 110.0));
    svg.arrow(o, t_tip, "#6c3483", 1.4);
    if labels {
        let off = |p: (Real, Real), c: (Real, Real), k: Real| {
            let (dx, dy) = (p.0 - c.0, p.1 - c.1);
            let l = dx.hypot(dy).max(1e-9);
            (p.0 + dx / l * k, p.1 + dy / l * k + 4.0)
        };
        for i in 0..4 {
            svg.text_styled(
                off(prim[i], o, 13.0),
                12.0,
                "middle",
                &format!("r{}", i + 1),
                r##"fill="#b35a00""##,
            );
            svg.text_styled(
                off(hub[i], hc, 13.0),
                12.0,
                "middle",
                &format!("s{}", i + 1),
                r##"fill="#1f4e8c""##,
            );
        }
        svg.text_styled(
            (t_tip.0 + 4.0, t_tip.1 - 3.0),
            12.0,
            "start",
            "t",
            r##"fill="#6c3483" font-style="italic""##,
        );
        let mid = ((o.0 + hc.0) / 2.0, (o.1 + hc.1) / 2.0);
        svg.text_styled(
            (mid.0 - 6.0, mid.1),
            12.0,
            "end",
            "P",
            r##"fill="#c0392b" font-weight="bold""##,
        );
    }
}

fn figure_unit() -> String {
    let mut svg = Svg::new(900.0, 800.0);
    svg.text(
        (450.0, 26.0),
        17.0,
        "middle",
        "One unit: side 300 mm, theta = 45 deg (primary frame, primary tile at z = 0)",
    );
    let scale = 0.5;
    for (row, phi) in [0.0, 20.0].into_iter().enumerate() {
        let y0 = 220.0 + row as Real * 330.0;
        let plan = View::plan(scale, (200.0, y0));
        let axo = View::axo(-0.95, 0.42, scale, (620.0, y0 + 50.0));
        draw_unit(&mut svg, &plan, phi, true);
        draw_unit(&mut svg, &axo, phi, true);
        let a = SIDE / 2f64.sqrt();
        let d = deploy(
            &Rhombus::new(a, a).expect("rhombus"),
            &Deployment::new(FRAC_PI_4, Real::to_radians(phi)),
        )
        .expect("feasible");
        svg.text_styled(
            (30.0, y0 - 150.0),
            14.0,
            "start",
            &format!(
                "phi = {phi} deg:   |P| = {:.1} mm,   P = ({:.1}, {:.1}, {:.1}) mm",
                d.translation.norm(),
                d.translation.x,
                d.translation.y,
                d.translation.z
            ),
            r##"fill="#222" font-weight="bold""##,
        );
        svg.text(
            (200.0, y0 + 150.0),
            12.0,
            "middle",
            "plan (looking down -z)",
        );
        svg.text((620.0, y0 + 150.0), 12.0, "middle", "axonometric");
    }
    // legend
    let ly = 745.0;
    svg.rect(40.0, ly - 11.0, 22.0, 13.0, HUB_STYLE);
    svg.text(
        (68.0, ly),
        13.0,
        "start",
        "hub s_i = R r_i + P (secondary layer)",
    );
    svg.rect(330.0, ly - 11.0, 22.0, 13.0, PRIMARY_STYLE);
    svg.text((358.0, ly), 13.0, "start", "primary tile r_i");
    svg.line((480.0, ly - 4.0), (502.0, ly - 4.0), LEG_STYLE);
    svg.text((508.0, ly), 13.0, "start", "leg i: s_i to r_(i+1)");
    svg.arrow((650.0, ly - 4.0), (672.0, ly - 4.0), "#c0392b", 1.6);
    svg.text((678.0, ly), 13.0, "start", "P");
    svg.arrow((705.0, ly - 4.0), (727.0, ly - 4.0), "#6c3483", 1.4);
    svg.text((733.0, ly), 13.0, "start", "axis direction t");
    svg.text(
        (450.0, 778.0),
        12.0,
        "middle",
        "every leg is exactly as long as the side it was cut along: |s_i - r_(i+1)| = |r_i - r_(i+1)|",
    );
    svg.finish()
}

// ---------------------------------------------------------------------------------------
// (b) configuration space
// ---------------------------------------------------------------------------------------

/// `d = (R r1 - r2) x (R r2 + r1)` for the paper's case (t . r1 = 0).
fn d_vector(a: Real, b: Real, theta: Real, phi: Real, case: AxisCase) -> Vector3 {
    let (t, _) = sv_unit::axis(case, phi);
    let r = rotation(&t, theta);
    let (r1, r2) = (Vector3::new(a, 0.0, 0.0), Vector3::new(0.0, b, 0.0));
    (r * r1 - r2).cross(&(r * r2 + r1))
}

/// The degenerate curve of case `t . r1 = 0`: `cos(phi) = (a/b) cot(theta/2)`.
fn degenerate_curve(a: Real, b: Real) -> Vec<(Real, Real)> {
    let theta0 = 2.0 * (a / b).atan();
    let mut out = Vec::new();
    let n = 200;
    for i in 0..=n {
        let theta = theta0 + (PI - theta0) * i as Real / n as Real;
        let c = (a / b) / (theta / 2.0).tan();
        if c <= 1.0 {
            let phi = c.clamp(-1.0, 1.0).acos();
            // check against the closed form: d vanishes on the curve
            let dn = d_vector(a, b, theta, phi, AxisCase::OrthogonalToR1).norm();
            assert!(dn < 1e-9 * a * b, "d = {dn} at {theta}, {phi}");
            out.push((theta, phi));
        }
    }
    out
}

fn figure_configuration_space() -> String {
    let (w, h) = (920.0, 600.0);
    let mut svg = Svg::new(w, h);
    let a = SIDE / 2f64.sqrt();
    let rh = Rhombus::new(a, a).expect("rhombus");
    // plot area: theta in [-30, 180] deg, phi in [-135, 135] deg
    let (px0, py0, pw, ph) = (90.0, 60.0, 600.0, 480.0);
    let (th_min, th_max, ph_min, ph_max) = (-30.0, 180.0, -135.0, 135.0);
    let sx = |th: Real| px0 + (th - th_min) / (th_max - th_min) * pw;
    let sy = |phi: Real| py0 + (ph_max - phi) / (ph_max - ph_min) * ph;
    let depth_max = (2.0 * a * a).sqrt();
    let (nx, ny) = (105, 108);
    for i in 0..nx {
        for j in 0..ny {
            let th = th_min + (i as Real + 0.5) / nx as Real * (th_max - th_min);
            let phi = ph_max - (j as Real + 0.5) / ny as Real * (ph_max - ph_min);
            let g = depth_squared(&rh, th.to_radians(), phi.to_radians());
            let x = sx(th_min + i as Real / nx as Real * (th_max - th_min));
            let y = sy(ph_max - j as Real / ny as Real * (ph_max - ph_min));
            let cw = pw / nx as Real + 0.4;
            let chh = ph / ny as Real + 0.4;
            if g < 0.0 {
                svg.rect(x, y, cw, chh, r##"fill="#d9d9d9""##);
            } else if th < 0.0 || phi.abs() > 90.0 {
                // (theta, t) and (-theta, -t) are one rotation: a copy of the domain
                svg.rect(x, y, cw, chh, r##"fill="#f2f2f2""##);
            } else {
                // |P| from the kinematics itself (equal to sqrt(g) by construction)
                let dep = Deployment::new(th.to_radians(), phi.to_radians());
                let depth = deploy(&rh, &dep)
                    .map(|d| d.translation.norm())
                    .unwrap_or(g.sqrt());
                svg.rect(
                    x,
                    y,
                    cw,
                    chh,
                    &format!(r#"fill="{}""#, colour(depth / depth_max)),
                );
            }
        }
    }
    // hatching of the infeasible part
    for i in 0..60 {
        let x = px0 - ph + i as Real * 18.0;
        svg.line(
            (x, py0 + ph),
            (x + ph, py0),
            r##"stroke="#aaaaaa" stroke-width="0.7" clip-path="url(#infeasible)""##,
        );
    }
    // clip path: union of infeasible rectangles (theta < 0 with |phi| < 90, |phi| > 90 with theta > 0)
    svg.raw(&format!(
        r#"<defs><clipPath id="infeasible"><rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}"/><rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}"/><rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}"/></clipPath></defs>"#,
        sx(th_min), sy(90.0), sx(0.0) - sx(th_min), sy(-90.0) - sy(90.0),
        sx(0.0), sy(ph_max), sx(th_max) - sx(0.0), sy(90.0) - sy(ph_max),
        sx(0.0), sy(-90.0), sx(th_max) - sx(0.0), sy(ph_min) - sy(-90.0),
    ));
    // contours of |P| (exact: cos(phi) = h^2 / (2 a b sin(theta)))
    for level in [50.0, 100.0, 150.0, 200.0, 250.0, 290.0] {
        let labelled = level > 60.0;
        let mut upper = Vec::new();
        let mut lower = Vec::new();
        let n = 720;
        for i in 1..n {
            let th = i as Real / n as Real * PI;
            let c = level * level / (2.0 * a * a * th.sin());
            if c <= 1.0 {
                let phi = c.acos().to_degrees();
                upper.push((sx(th.to_degrees()), sy(phi)));
                lower.push((sx(th.to_degrees()), sy(-phi)));
            }
        }
        lower.reverse();
        upper.extend(lower);
        if let Some(&first) = upper.first() {
            upper.push(first);
        }
        svg.polyline(
            &upper,
            r##"stroke="white" stroke-width="1" stroke-opacity="0.85""##,
        );
        // label on the phi = 0 line, at the smaller theta
        let th_label = ((level * level) / (2.0 * a * a)).asin().to_degrees();
        if labelled {
            svg.text_styled(
                (sx(th_label) + 2.0, sy(0.0) - 5.0),
                10.0,
                "start",
                &format!("{level:.0}"),
                r##"fill="white""##,
            );
        }
    }
    // solver box
    svg.rect(
        sx(0.05f64.to_degrees()),
        sy(1.2f64.to_degrees()),
        sx(1.5f64.to_degrees()) - sx(0.05f64.to_degrees()),
        sy(-1.2f64.to_degrees()) - sy(1.2f64.to_degrees()),
        r##"fill="none" stroke="black" stroke-width="1.4" stroke-dasharray="6,4""##,
    );
    svg.text_styled(
        (
            sx(1.5f64.to_degrees()) - 4.0,
            sy(1.2f64.to_degrees()) + 14.0,
        ),
        11.0,
        "end",
        "solver bounds",
        r##"fill="black""##,
    );
    // degenerate sets: square (solid) and a rhombus a/b = 0.8 (dashed)
    for (ratio, style, dot) in [
        (1.0, r##"stroke="#ff3366" stroke-width="2.4""##, "#ff3366"),
        (
            0.8,
            r##"stroke="#ff3366" stroke-width="1.6" stroke-dasharray="4,3""##,
            "#ffffff",
        ),
    ] {
        let (ra, rb) = (ratio * 200.0, 200.0);
        let curve = degenerate_curve(ra, rb);
        for sign in [1.0, -1.0] {
            let pts: Vec<_> = curve
                .iter()
                .map(|&(t, p)| (sx(t.to_degrees()), sy(sign * p.to_degrees())))
                .collect();
            svg.polyline(&pts, style);
        }
        // the isolated point on phi = 0: theta = 2 atan(b / a)
        let iso = 2.0 * (rb / ra).atan();
        let dn = d_vector(ra, rb, iso, 0.0, AxisCase::OrthogonalToR1).norm();
        assert!(dn < 1e-9 * ra * rb);
        svg.circle(
            (sx(iso.to_degrees()), sy(0.0)),
            4.0,
            &format!(r##"fill="{dot}" stroke="#ff3366" stroke-width="1.5""##),
        );
    }
    // start of the solve, flat state, axis in the plane
    svg.circle(
        (sx(45.0), sy(0.0)),
        4.5,
        r##"fill="white" stroke="black" stroke-width="1.5""##,
    );
    svg.text_styled(
        (sx(45.0), sy(0.0) + 18.0),
        11.0,
        "middle",
        "start: theta = alpha",
        r##"fill="white""##,
    );
    // axes
    svg.rect(px0, py0, pw, ph, r##"fill="none" stroke="#333""##);
    for th in (-30..=180).step_by(30) {
        let x = sx(th as Real);
        svg.line((x, py0 + ph), (x, py0 + ph + 5.0), r##"stroke="#333""##);
        svg.text((x, py0 + ph + 19.0), 12.0, "middle", &format!("{th}"));
    }
    for phi in (-135..=135).step_by(45) {
        let y = sy(phi as Real);
        svg.line((px0 - 5.0, y), (px0, y), r##"stroke="#333""##);
        svg.text((px0 - 8.0, y + 4.0), 12.0, "end", &format!("{phi}"));
    }
    svg.line(
        (sx(0.0), py0),
        (sx(0.0), py0 + ph),
        r##"stroke="#333" stroke-width="1""##,
    );
    svg.text(
        (px0 + pw / 2.0, py0 + ph + 40.0),
        13.0,
        "middle",
        "theta (deg): rotation about the axis t",
    );
    svg.raw(&format!(
        r#"<text x="30" y="{:.1}" font-family="DejaVu Sans, Arial, sans-serif" font-size="13" text-anchor="middle" transform="rotate(-90 30 {:.1})">phi (deg): tilt of t from the tile normal</text>"#,
        py0 + ph / 2.0,
        py0 + ph / 2.0
    ));
    svg.text(
        (w / 2.0, 30.0),
        16.0,
        "middle",
        "Configuration space: frame depth |P| (mm) of a 300 mm square unit, case t . r1 = 0",
    );
    // legend at the right
    let lx = 710.0;
    colour_bar(
        &mut svg,
        lx,
        90.0,
        170.0,
        depth_max,
        "|P| (mm)",
        &[0.0, 100.0, 200.0, 300.0],
    );
    let notes = [
        "grey, hatched: infeasible,",
        "   sin(theta) cos(phi) < 0",
        "light grey: the same rotations",
        "   again, (theta, t) = (-theta, -t)",
        "theta = 0: flat state, P = 0",
        "phi = +-90: axis in the tile",
        "   plane, P = 0",
        "solid red line and dot:",
        "   degenerate set of a square",
        "   (d = 0, P not unique)",
        "dashed red line, white dot:",
        "   degenerate set, a/b = 0.8",
        "black dot: solver start (45, 0)",
        "black dashes: solver bounds",
        "white lines: |P| = 50 ... 290 mm",
    ];
    for (i, line) in notes.iter().enumerate() {
        let indent = if line.starts_with(' ') { 12.0 } else { 0.0 };
        svg.text(
            (lx - 5.0 + indent, 165.0 + i as Real * 17.0),
            11.5,
            "start",
            line.trim_start(),
        );
    }
    svg.finish()
}

// ---------------------------------------------------------------------------------------
// (c) flat 3 x 3 grid at theta = alpha
// ---------------------------------------------------------------------------------------

fn figure_flat_grid() -> (String, Real, Real, Real) {
    let mesh = QuadMesh::grid(3, 3, SIDE);
    let alpha = FRAC_PI_4;
    let hubs = hubs_from_mesh(&mesh, alpha).expect("hubs");
    let links = mesh.links();
    let deps = vec![Deployment::new(alpha, 0.0); hubs.len()];
    let units = sv_frame::FrameUnits::new(&hubs, 1.0, None).expect("units");
    let poses: Vec<_> = (0..hubs.len())
        .map(|f| units.pose(f, &hubs[f], &deps[f]).expect("pose"))
        .collect();
    let ev = evaluate(&hubs, &links, &poses, &units).expect("evaluate");
    let gap_max = ev.gaps.iter().copied().fold(0.0, Real::max);
    let overlap = ev.overlaps[0];
    // primary corners in world coordinates: R^T (r_i - P) in the hub frame
    let prim: Vec<[Point3; 4]> = hubs
        .iter()
        .zip(&deps)
        .map(|(h, dep)| {
            let d = deploy(&h.rhombus, dep).expect("feasible");
            let rt = d.rotation.transpose();
            let rs = h.rhombus.corners();
            std::array::from_fn(|i| h.to_world(&Point3::from(rt * (rs[i] - d.translation))))
        })
        .collect();
    let depth = -prim[0][0].z;
    let (w, hgt) = (960.0, 770.0);
    let mut svg = Svg::new(w, hgt);
    let scale = 0.45;
    let plan = View::plan(scale, (95.0, 525.0));
    svg.text(
        (w / 2.0, 28.0),
        16.0,
        "middle",
        "Flat 3 x 3 grid of 300 mm squares, spin angle alpha = 45 deg, every unit at theta = alpha, phi = 0",
    );
    for p in &prim {
        let pts: Vec<_> = p.iter().map(|q| plan.p(q)).collect();
        svg.polygon(
            &pts,
            r##"fill="#e8923a" fill-opacity="0.22" stroke="none""##,
        );
    }
    for h in &hubs {
        let pts: Vec<_> = h.corners().iter().map(|q| plan.p(q)).collect();
        svg.polygon(
            &pts,
            r##"fill="#4a7fc1" fill-opacity="0.35" stroke="#1f4e8c" stroke-width="1.4""##,
        );
    }
    for (f, h) in hubs.iter().enumerate() {
        for i in 0..4 {
            svg.line(
                plan.p(&h.corner(i)),
                plan.p(&prim[f][(i + 1) % 4]),
                r##"stroke="#2a9d4b" stroke-width="1.4""##,
            );
        }
    }
    for p in &prim {
        let pts: Vec<_> = p.iter().map(|q| plan.p(q)).collect();
        svg.polygon(
            &pts,
            r##"fill="none" stroke="#b35a00" stroke-width="2.2" stroke-dasharray="7,3""##,
        );
    }
    // overlap dimension across the link between units 3 and 4 (middle row, left pair)
    let (f, g) = (3usize, 4usize);
    let li = links
        .iter()
        .position(|l| l.faces == [f, g] || l.faces == [g, f])
        .expect("link");
    let l = links[li];
    let (uf, ug) = if l.faces[0] == f {
        (l.slots[0], l.slots[1])
    } else {
        (l.slots[1], l.slots[0])
    };
    let tip_f = plan.p(&hubs[f].corner(uf));
    let tip_g = plan.p(&hubs[g].corner(ug));
    let dy = 80.0;
    for t in [tip_f, tip_g] {
        svg.line(
            t,
            (t.0, t.1 - dy - 6.0),
            r##"stroke="#111" stroke-width="0.8" stroke-dasharray="3,2""##,
        );
    }
    let yd = tip_f.1 - dy;
    for t in [tip_f, tip_g] {
        svg.circle(t, 3.5, r##"fill="#0d2c54""##);
    }
    svg.arrow(((tip_f.0 + tip_g.0) / 2.0, yd), (tip_f.0, yd), "#111", 1.0);
    svg.arrow(((tip_f.0 + tip_g.0) / 2.0, yd), (tip_g.0, yd), "#111", 1.0);
    svg.text_styled(
        ((tip_f.0 + tip_g.0) / 2.0, yd - 7.0),
        13.0,
        "middle",
        &format!("hub overlap {:.1} mm", ev.overlaps[li]),
        r##"fill="#111" font-weight="bold" stroke="white" stroke-width="3" paint-order="stroke""##,
    );
    // label the corners facing that link
    svg.text_styled(
        (tip_f.0 + 4.0, tip_f.1 + 30.0),
        11.0,
        "start",
        &format!("corner {uf} of unit {f}"),
        r##"fill="#0d2c54" stroke="white" stroke-width="3" paint-order="stroke""##,
    );
    svg.text_styled(
        (tip_g.0 - 4.0, tip_g.1 - 22.0),
        11.0,
        "end",
        &format!("corner {ug} of unit {g}"),
        r##"fill="#0d2c54" stroke="white" stroke-width="3" paint-order="stroke""##,
    );
    for (fi, h) in hubs.iter().enumerate() {
        let c = plan.p(&h.centre);
        svg.text_styled(
            (c.0, c.1 + 4.0),
            12.0,
            "middle",
            &format!("{fi}"),
            r##"fill="#0d2c54""##,
        );
    }
    // elevation of the middle row, same scale, below the plan
    let el = View {
        right: Vector3::x(),
        up: Vector3::z(),
        scale,
        origin: (95.0, 620.0),
    };
    svg.text(
        (95.0 + 1.5 * SIDE * scale, 596.0),
        13.0,
        "middle",
        "elevation of the middle row (units 3, 4, 5), same scale",
    );
    for f in 3..6 {
        let h = &hubs[f];
        let hc: Vec<_> = h.corners().iter().map(|q| el.p(q)).collect();
        let pc: Vec<_> = prim[f].iter().map(|q| el.p(q)).collect();
        let span = |v: &Vec<(Real, Real)>| {
            let lo = v.iter().map(|p| p.0).fold(Real::INFINITY, Real::min);
            let hi = v.iter().map(|p| p.0).fold(Real::NEG_INFINITY, Real::max);
            (lo, hi)
        };
        let (h0, h1) = span(&hc);
        let (p0, p1) = span(&pc);
        for i in 0..4 {
            svg.line(
                hc[i],
                pc[(i + 1) % 4],
                r##"stroke="#2a9d4b" stroke-width="1.2""##,
            );
        }
        svg.line(
            (p0, pc[0].1),
            (p1, pc[0].1),
            r##"stroke="#b35a00" stroke-width="5" stroke-opacity="0.8""##,
        );
        svg.line(
            (h0, hc[0].1),
            (h1, hc[0].1),
            r##"stroke="#1f4e8c" stroke-width="5" stroke-opacity="0.6""##,
        );
    }
    let z0 = el.p(&Point3::new(0.0, 0.0, 0.0)).1;
    let z1 = el.p(&Point3::new(0.0, 0.0, -depth)).1;
    let xd = el.p(&Point3::new(3.0 * SIDE, 0.0, 0.0)).0 + 50.0;
    svg.line(
        (xd - 10.0, z0),
        (xd + 4.0, z0),
        r##"stroke="#111" stroke-width="0.8""##,
    );
    svg.line(
        (xd - 10.0, z1),
        (xd + 4.0, z1),
        r##"stroke="#111" stroke-width="0.8""##,
    );
    svg.arrow((xd, (z0 + z1) / 2.0), (xd, z0), "#111", 1.0);
    svg.arrow((xd, (z0 + z1) / 2.0), (xd, z1), "#111", 1.0);
    svg.text(
        (xd + 6.0, (z0 + z1) / 2.0 + 4.0),
        12.0,
        "start",
        &format!("h = {depth:.1} mm"),
    );
    svg.text_styled((58.0, z0 + 4.0), 11.0, "end", "hubs", r##"fill="#1f4e8c""##);
    svg.text_styled(
        (58.0, z1 + 4.0),
        11.0,
        "end",
        "primary",
        r##"fill="#b35a00""##,
    );
    // notes
    let ex = 610.0;
    let notes = [
        "hubs (blue): the squares spun by alpha;".to_string(),
        "   corner k points across edge k; where two".to_string(),
        "   hubs overlap the blue is darker".to_string(),
        "primary tiles (orange, dashed outline): the".to_string(),
        "   mesh squares moved down by the depth".to_string(),
        "   h = sqrt(2 sin(theta) a b)".to_string(),
        "legs (green): hub corner i to primary corner i+1".to_string(),
        String::new(),
        format!("largest gap between facing sides: {gap_max:.1e} mm"),
        format!(
            "hub overlap = (sqrt(2) - 1) x side = {:.1} mm",
            (2f64.sqrt() - 1.0) * SIDE
        ),
    ];
    for (i, n) in notes.iter().enumerate() {
        let indent = if n.starts_with(' ') { 12.0 } else { 0.0 };
        svg.text(
            (ex + indent, 110.0 + i as Real * 19.0),
            12.5,
            "start",
            n.trim_start(),
        );
    }
    (svg.finish(), gap_max, overlap, depth)
}

// ---------------------------------------------------------------------------------------
// (d) section through a solved sphere cap
// ---------------------------------------------------------------------------------------

/// The section of a planar polygon with the plane y = 0: the two extreme crossing points
/// along x, as (x, z).
fn section_y0(poly: &[Point3]) -> Option<((Real, Real), (Real, Real))> {
    let mut pts: Vec<(Real, Real)> = Vec::new();
    let n = poly.len();
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        if p.y.abs() < 1e-9 {
            pts.push((p.x, p.z));
        }
        if (p.y < 0.0 && q.y > 0.0) || (p.y > 0.0 && q.y < 0.0) {
            let t = p.y / (p.y - q.y);
            pts.push((p.x + (q.x - p.x) * t, p.z + (q.z - p.z) * t));
        }
    }
    let lo = pts.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0))?;
    let hi = pts.iter().copied().max_by(|a, b| a.0.total_cmp(&b.0))?;
    Some((lo, hi))
}

fn figure_cap_section() -> (String, Vec<(String, Real, Real)>) {
    let (n, radius) = (9usize, 3000.0);
    let mesh = QuadMesh::sphere_cap(n, n, radius, SIDE);
    // side policies, for the text
    let mut figures = Vec::new();
    for (name, side) in [
        ("auto", SidePolicy::Auto),
        ("normal (hubs outside)", SidePolicy::Normal),
        ("opposite (hubs inside)", SidePolicy::Opposite),
    ] {
        let s = solve(
            &mesh,
            &SolveOptions {
                side,
                ..Default::default()
            },
            &mut |_| {},
        )
        .expect("solve");
        figures.push((name.to_string(), s.report.gap_sum, s.report.gap_max));
    }
    let solved = solve(&mesh, &SolveOptions::default(), &mut |_| {}).expect("solve");
    let file = solved.to_frame_file(&mesh);
    let pt = |a: &[Real; 3]| Point3::new(a[0], a[1], a[2]);
    let gmax = solved.report.gap_max.max(1e-9);
    let bar_max = (gmax * 1.05 * 2.0).ceil() / 2.0;

    let (w, h) = (1000.0, 750.0);
    let mut svg = Svg::new(w, h);
    svg.text(
        (w / 2.0, 28.0),
        16.0,
        "middle",
        &format!(
            "Solved sphere cap: R = {radius:.0} mm, {n} x {n} units of 300 mm, side policy auto; gap sum {:.1} mm, max {:.2} mm",
            solved.report.gap_sum, solved.report.gap_max
        ),
    );
    // ---- section (x, z) through the middle row ----
    let sec = View {
        right: Vector3::x(),
        up: Vector3::z(),
        scale: 0.3,
        origin: (w / 2.0 + 30.0, 170.0),
    };
    let xz = |p: (Real, Real)| sec.p(&Point3::new(p.0, 0.0, p.1));
    // the sphere
    let mut arc = Vec::new();
    for i in 0..=100 {
        let a = -0.55 + 1.1 * i as Real / 100.0;
        arc.push(xz((radius * a.sin(), radius * a.cos() - radius)));
    }
    svg.polyline(
        &arc,
        r##"stroke="#999" stroke-width="0.8" stroke-dasharray="5,4""##,
    );
    let row = n / 2;
    for i in 0..n {
        let f = row * n + i;
        let u = &file.units[f];
        let hub: Vec<Point3> = u.hub.iter().map(pt).collect();
        let prim: Vec<Point3> = u.primary.iter().map(pt).collect();
        if let Some((a, b)) = section_y0(&prim) {
            svg.line(
                xz(a),
                xz(b),
                r##"stroke="#b35a00" stroke-width="4" stroke-linecap="round""##,
            );
        }
        if let Some((a, b)) = section_y0(&hub) {
            svg.line(xz(a), xz(b), r##"stroke="#1f4e8c" stroke-width="4" stroke-opacity="0.75" stroke-linecap="round""##);
        }
        // legs as seen in the section (projected onto y = 0), thin
        for k in 0..4 {
            let (s, r) = (hub[k], prim[(k + 1) % 4]);
            svg.line(
                xz((s.x, s.z)),
                xz((r.x, r.z)),
                r##"stroke="#2a9d4b" stroke-width="0.6" stroke-opacity="0.6""##,
            );
        }
    }
    // name the two layers at the left end of the row
    if let (Some((ph, _)), Some((hh, _))) = (
        section_y0(
            &file.units[row * n]
                .primary
                .iter()
                .map(pt)
                .collect::<Vec<_>>(),
        ),
        section_y0(&file.units[row * n].hub.iter().map(pt).collect::<Vec<_>>()),
    ) {
        let (pp, hp) = (xz(ph), xz(hh));
        svg.text_styled(
            (pp.0 - 8.0, pp.1),
            12.0,
            "end",
            "primary tiles",
            r##"fill="#b35a00""##,
        );
        svg.text_styled(
            (hp.0 - 8.0, hp.1 + 4.0),
            12.0,
            "end",
            "hubs",
            r##"fill="#1f4e8c""##,
        );
    }
    // links of that row: gap as colour at the closest points
    for (li, l) in file.links.iter().enumerate() {
        let [a, b] = l.units;
        if a / n != row || b / n != row {
            continue;
        }
        let slots = l.slots.expect("slots");
        let mid = |u: usize, k: usize| {
            let p = &file.units[u].primary;
            let (p0, p1) = (pt(&p[k]), pt(&p[(k + 1) % 4]));
            Point3::from((p0.coords + p1.coords) / 2.0)
        };
        let m = Point3::from((mid(a, slots[0]).coords + mid(b, slots[1]).coords) / 2.0);
        let g = solved.evaluation.gaps[li];
        let c = xz((m.x, m.z));
        svg.circle(
            (c.0, c.1 - 14.0),
            6.5,
            &format!(
                r##"fill="{}" stroke="#222" stroke-width="0.8""##,
                colour(g / bar_max)
            ),
        );
        svg.text((c.0, c.1 - 25.0), 10.0, "middle", &format!("{g:.2}"));
    }
    svg.text_styled(
        (w / 2.0, 318.0),
        12.5,
        "middle",
        "section y = 0 through the middle row (to scale): hubs (blue) inside on the concave side, primary tiles (orange) outside; numbers: gap (mm) of each link",
        r##"fill="#222""##,
    );
    // ---- plan of all links coloured by gap ----
    let plan = View::plan(0.12, (300.0, 530.0));
    for (f, u) in file.units.iter().enumerate() {
        let _ = f;
        let hub: Vec<_> = u.hub.iter().map(|p| plan.p(&pt(p))).collect();
        svg.polygon(
            &hub,
            r##"fill="#4a7fc1" fill-opacity="0.15" stroke="#1f4e8c" stroke-width="0.5""##,
        );
    }
    for (li, l) in file.links.iter().enumerate() {
        let (v, wv) = (l.edge[0], l.edge[1]);
        let a = pt(&file.mesh.vertices[v]);
        let b = pt(&file.mesh.vertices[wv]);
        let g = solved.evaluation.gaps[li];
        svg.line(
            plan.p(&a),
            plan.p(&b),
            &format!(
                r#"stroke="{}" stroke-width="4" stroke-linecap="round""#,
                colour(g / bar_max)
            ),
        );
    }
    let yline = plan.p(&Point3::new(-1400.0, 0.0, 0.0));
    let yline2 = plan.p(&Point3::new(1400.0, 0.0, 0.0));
    svg.line(
        yline,
        yline2,
        r##"stroke="#c0392b" stroke-width="1" stroke-dasharray="4,3""##,
    );
    svg.text_styled(
        (yline2.0 + 6.0, yline2.1 + 4.0),
        11.0,
        "start",
        "section",
        r##"fill="#c0392b""##,
    );
    svg.text(
        (300.0, 730.0),
        12.5,
        "middle",
        "plan: every link (mesh edge) coloured by its gap",
    );
    colour_bar(
        &mut svg,
        560.0,
        450.0,
        300.0,
        bar_max,
        "gap between facing primary sides (mm)",
        &[
            0.0,
            bar_max / 4.0,
            bar_max / 2.0,
            3.0 * bar_max / 4.0,
            bar_max,
        ],
    );
    let mut y = 530.0;
    svg.text(
        (560.0, y),
        13.0,
        "start",
        "same cap, by side policy (gap sum / max, mm):",
    );
    for (name, sum, max) in &figures {
        y += 19.0;
        svg.text(
            (575.0, y),
            12.5,
            "start",
            &format!("{name}: {sum:.1} / {max:.2}"),
        );
    }
    y += 28.0;
    svg.text(
        (560.0, y),
        12.5,
        "start",
        "auto puts the hubs of a dome on its concave side,",
    );
    svg.text(
        (560.0, y + 17.0),
        12.5,
        "start",
        "so the primary layer lies outside the hub layer.",
    );
    (svg.finish(), figures)
}

fn write(dir: &Path, name: &str, svg: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, svg).unwrap_or_else(|e| panic!("cannot write {}: {e}", p.display()));
    println!("wrote {}", p.display());
    p
}

fn main() {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "docs/figures".into()),
    );
    std::fs::create_dir_all(&dir).expect("create output directory");
    write(&dir, "unit.svg", &figure_unit());
    write(
        &dir,
        "configuration_space.svg",
        &figure_configuration_space(),
    );
    let (grid, gap_max, overlap, depth) = figure_flat_grid();
    write(&dir, "flat_grid.svg", &grid);
    println!(
        "flat grid at theta = alpha: max gap {gap_max:.2e} mm, hub overlap {overlap:.3} mm, depth {depth:.3} mm"
    );
    let (cap, figures) = figure_cap_section();
    write(&dir, "cap_section.svg", &cap);
    for (name, sum, max) in figures {
        println!("sphere cap 9x9, R 3000: side {name}: gap sum {sum:.2} mm, max {max:.3} mm");
    }
    // the degenerate square point is where the kinematics refuses to answer
    let a = SIDE / 2f64.sqrt();
    let rh = Rhombus::new(a, a).expect("rhombus");
    println!(
        "square at theta = 90 deg, phi = 0: {:?}",
        deploy(&rh, &Deployment::new(FRAC_PI_2, 0.0)).err()
    );
}
