//! Curves that are not arcs (SPLINE, ELLIPSE, arcs under a non-uniform block scale) turned
//! into arcs and lines within a stated tolerance, so that the sheet keeps arcs and the CAM
//! never sees a spline: adaptive sampling, then a greedy fit of the longest arc through
//! consecutive samples that stays within the tolerance of all of them.

use std::cell::Cell;

use sv_geom::Segment;

/// A parametric curve `t -> [x, y]` over `[t0, t1]`, smooth between `breaks`.
pub(crate) struct Curve<'a> {
    pub(crate) at: &'a dyn Fn(f64) -> [f64; 2],
    pub(crate) t0: f64,
    pub(crate) t1: f64,
    /// parameters where the curve may bend sharply (spline knots), inside `(t0, t1)`
    pub(crate) breaks: Vec<f64>,
}

/// Most samples of the curves of one file, all fits together (about a second of work): a
/// circle of 500 km radius at the default arc tolerance, or thousands of ordinary curves.
/// A file that needs more holds curves huge for their tolerance (wrong units, a corrupt
/// number, a tolerance of nanometres, a block that inserts itself scaled), and sampling
/// them would take hours and gigabytes.
pub(crate) const MAX_SAMPLES: usize = 1 << 22;

/// Samples of `curve` so dense that between two of them the curve stays within
/// `tolerance / 8` of their chord; `None` beyond `budget` samples.
fn samples(curve: &Curve<'_>, tolerance: f64, budget: usize) -> Option<Vec<[f64; 2]>> {
    let mut ts = vec![curve.t0];
    ts.extend(
        curve
            .breaks
            .iter()
            .copied()
            .filter(|&t| t > curve.t0 && t < curve.t1),
    );
    ts.push(curve.t1);
    let mut out = vec![(curve.at)(curve.t0)];
    for w in ts.windows(2) {
        // 8 starting intervals per span, each split while its middle leaves the chord
        let n = 8;
        for k in 0..n {
            let a = w[0] + (w[1] - w[0]) * k as f64 / n as f64;
            let b = w[0] + (w[1] - w[0]) * (k + 1) as f64 / n as f64;
            refine(curve, a, b, tolerance / 8.0, 0, budget, &mut out)?;
        }
    }
    Some(out)
}

fn refine(
    curve: &Curve<'_>,
    a: f64,
    b: f64,
    tol: f64,
    depth: u32,
    budget: usize,
    out: &mut Vec<[f64; 2]>,
) -> Option<()> {
    if out.len() > budget {
        return None;
    }
    let (pa, pb) = (*out.last().unwrap_or(&(curve.at)(a)), (curve.at)(b));
    let m = 0.5 * (a + b);
    let pm = (curve.at)(m);
    // the quarter points too: an S-bend can pass through the chord's middle
    let q1 = (curve.at)(0.5 * (a + m));
    let q3 = (curve.at)(0.5 * (m + b));
    let off = [pm, q1, q3]
        .iter()
        .map(|&p| sv_geom::planar::point_segment_distance(p, pa, pb))
        .fold(0.0, f64::max);
    if depth < 24 && off > tol {
        refine(curve, a, m, tol, depth + 1, budget, out)?;
        refine(curve, m, b, tol, depth + 1, budget, out)?;
    } else {
        out.push(pb);
    }
    Some(())
}

/// The circle through three points: centre and radius; `None` when they are collinear.
fn circle(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Option<([f64; 2], f64)> {
    let (bx, by) = (b[0] - a[0], b[1] - a[1]);
    let (cx, cy) = (c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    let scale = (bx * bx + by * by).max(cx * cx + cy * cy);
    if d.abs() <= 1e-12 * scale {
        return None;
    }
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    Some(([a[0] + ux, a[1] + uy], ux.hypot(uy)))
}

/// The arc (or line) from `p[i]` to `p[j]` within `tol` of every sample between, if any.
fn fit(p: &[[f64; 2]], i: usize, j: usize, tol: f64) -> Option<Segment> {
    let line = Segment {
        start: p[i],
        end: p[j],
        bulge: 0.0,
    };
    if j == i + 1 {
        return Some(line);
    }
    if p[i + 1..j]
        .iter()
        .all(|&q| sv_geom::planar::point_segment_distance(q, p[i], p[j]) <= tol)
    {
        return Some(line);
    }
    let m = (i + j) / 2;
    let (c, r) = circle(p[i], p[m], p[j])?;
    if r > 1e7 {
        return None;
    }
    // the samples go round the centre one way, less than a full turn, on the circle
    let angle = |q: [f64; 2]| (q[1] - c[1]).atan2(q[0] - c[0]);
    let mut sweep = 0.0;
    let mut sign = 0.0;
    let mut prev = angle(p[i]);
    for q in &p[i + 1..=j] {
        if ((q[0] - c[0]).hypot(q[1] - c[1]) - r).abs() > tol {
            return None;
        }
        let a = angle(*q);
        let d = (a - prev + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        if sign == 0.0 {
            sign = d.signum();
        } else if d * sign < 0.0 {
            return None;
        }
        sweep += d;
        prev = a;
    }
    if sweep.abs() >= std::f64::consts::TAU - 1e-6 {
        return None;
    }
    // the chord between two samples stays close to the arc only if they are close
    Some(Segment {
        start: p[i],
        end: p[j],
        bulge: (sweep / 4.0).tan(),
    })
}

/// Arcs and lines within `tolerance` (mm) of `curve`, from its start to its end, taking
/// its samples from `samples_left` (the file's, from [`MAX_SAMPLES`]); an error when they
/// run out.
pub(crate) fn fit_arcs(
    curve: &Curve<'_>,
    tolerance: f64,
    samples_left: &Cell<usize>,
) -> Result<Vec<Segment>, String> {
    let p = samples(curve, tolerance, samples_left.get()).ok_or_else(|| {
        // the file's samples are spent: every later curve is refused at once, not
        // sampled up to the same limit again (thousands of copies of one huge curve)
        samples_left.set(0);
        format!(
            "too large for the arc tolerance {tolerance} mm (the file's curves need over {MAX_SAMPLES} samples): drawn in the wrong units, or a corrupt number?"
        )
    })?;
    samples_left.set(samples_left.get().saturating_sub(p.len()));
    let tol = tolerance / 2.0;
    let n = p.len() - 1;
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        // the longest fit: grow the step while it fits, then bisect back
        let mut good = i + 1;
        let mut step = 2;
        while i + step <= n && fit(&p, i, i + step, tol).is_some() {
            good = i + step;
            step *= 2;
        }
        let (mut lo, mut hi) = (good, (i + step).min(n + 1));
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if fit(&p, i, mid, tol).is_some() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        if let Some(s) = fit(&p, i, lo, tol) {
            out.push(s);
        }
        i = lo;
    }
    Ok(out)
}

/// A NURBS curve: degree, knots, control points and weights (empty: all 1).
pub(crate) struct Nurbs {
    pub(crate) degree: usize,
    pub(crate) knots: Vec<f64>,
    pub(crate) points: Vec<[f64; 2]>,
    pub(crate) weights: Vec<f64>,
}

impl Nurbs {
    /// Why the data is not a valid NURBS curve, if it is not.
    pub(crate) fn problem(&self) -> Option<String> {
        let (p, n) = (self.degree, self.points.len());
        if p < 1 {
            return Some(format!("degree {p}"));
        }
        if n < p + 1 {
            return Some(format!("{n} control points for degree {p}"));
        }
        if self.knots.len() != n + p + 1 {
            return Some(format!(
                "{} knots for {n} control points of degree {p} (expected {})",
                self.knots.len(),
                n + p + 1
            ));
        }
        if self.knots.iter().any(|k| !k.is_finite())
            || self.knots.windows(2).any(|w| w[1] < w[0])
            || self.knots[p] >= self.knots[n]
        {
            return Some("knots not increasing".into());
        }
        if !self.weights.is_empty()
            && (self.weights.len() != n || self.weights.iter().any(|w| !w.is_finite() || *w <= 0.0))
        {
            return Some(format!(
                "{} weights for {n} control points",
                self.weights.len()
            ));
        }
        if self.points.iter().flatten().any(|v| !v.is_finite()) {
            return Some("non-finite control point".into());
        }
        None
    }

    /// The parameter range.
    pub(crate) fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    /// Distinct inner knots (where the curve may be less smooth).
    pub(crate) fn breaks(&self) -> Vec<f64> {
        let (a, b) = self.domain();
        let mut k: Vec<f64> = self
            .knots
            .iter()
            .copied()
            .filter(|&t| t > a && t < b)
            .collect();
        k.dedup();
        k
    }

    /// The point at `t` (de Boor on homogeneous coordinates).
    pub(crate) fn at(&self, t: f64) -> [f64; 2] {
        let p = self.degree;
        let n = self.points.len();
        let (a, b) = self.domain();
        let t = t.clamp(a, b);
        // span k with knots[k] <= t < knots[k + 1], the last non-empty one at the end
        let mut k = p;
        while k + 1 < n && self.knots[k + 1] <= t {
            k += 1;
        }
        let w = |i: usize| self.weights.get(i).copied().unwrap_or(1.0);
        let mut d: Vec<[f64; 3]> = (0..=p)
            .map(|j| {
                let i = j + k - p;
                let wi = w(i);
                [self.points[i][0] * wi, self.points[i][1] * wi, wi]
            })
            .collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = j + k - p;
                let den = self.knots[i + p + 1 - r] - self.knots[i];
                let alpha = if den > 0.0 {
                    (t - self.knots[i]) / den
                } else {
                    0.0
                };
                for c in 0..3 {
                    d[j][c] = (1.0 - alpha) * d[j - 1][c] + alpha * d[j][c];
                }
            }
        }
        let [x, y, wt] = d[p];
        [x / wt, y / wt]
    }
}

/// An interpolating cubic through `points` (chord-length parameters, natural ends, or the
/// given end tangents): the curve of a SPLINE written with fit points only.
pub(crate) struct Interpolant {
    t: Vec<f64>,
    p: Vec<[f64; 2]>,
    /// derivatives at the points
    d: Vec<[f64; 2]>,
}

impl Interpolant {
    pub(crate) fn new(points: &[[f64; 2]], start: Option<[f64; 2]>, end: Option<[f64; 2]>) -> Self {
        let n = points.len();
        let mut t = vec![0.0; n];
        for i in 1..n {
            let d = (points[i][0] - points[i - 1][0]).hypot(points[i][1] - points[i - 1][1]);
            t[i] = t[i - 1] + d.max(1e-12);
        }
        // derivatives from the C2 conditions (a tridiagonal system per coordinate)
        let mut d = vec![[0.0; 2]; n];
        if n >= 2 {
            for c in 0..2 {
                let mut lower = vec![0.0; n];
                let mut diag = vec![0.0; n];
                let mut upper = vec![0.0; n];
                let mut rhs = vec![0.0; n];
                for i in 0..n {
                    if i == 0 || i == n - 1 {
                        let given = if i == 0 { start } else { end };
                        if let Some(g) = given {
                            // chord-length parameters: a unit tangent per unit of t
                            let len = g[0].hypot(g[1]).max(1e-300);
                            diag[i] = 1.0;
                            rhs[i] = g[c] / len;
                            continue;
                        }
                        // natural end: second derivative 0
                        let (j, k) = if i == 0 { (0, 1) } else { (n - 2, n - 1) };
                        let h = t[k] - t[j];
                        let slope = (points[k][c] - points[j][c]) / h;
                        diag[i] = 2.0;
                        if i == 0 {
                            upper[i] = 1.0;
                        } else {
                            lower[i] = 1.0;
                        }
                        rhs[i] = 3.0 * slope;
                        continue;
                    }
                    let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
                    let (s0, s1) = (
                        (points[i][c] - points[i - 1][c]) / h0,
                        (points[i + 1][c] - points[i][c]) / h1,
                    );
                    lower[i] = h1;
                    diag[i] = 2.0 * (h0 + h1);
                    upper[i] = h0;
                    rhs[i] = 3.0 * (h1 * s0 + h0 * s1);
                }
                // Thomas algorithm
                for i in 1..n {
                    let m = lower[i] / diag[i - 1];
                    diag[i] -= m * upper[i - 1];
                    rhs[i] -= m * rhs[i - 1];
                }
                let mut x = vec![0.0; n];
                x[n - 1] = rhs[n - 1] / diag[n - 1];
                for i in (0..n - 1).rev() {
                    x[i] = (rhs[i] - upper[i] * x[i + 1]) / diag[i];
                }
                for i in 0..n {
                    d[i][c] = x[i];
                }
            }
        }
        Self {
            t,
            p: points.to_vec(),
            d,
        }
    }

    pub(crate) fn domain(&self) -> (f64, f64) {
        (self.t[0], *self.t.last().unwrap_or(&0.0))
    }

    pub(crate) fn breaks(&self) -> Vec<f64> {
        self.t[1..self.t.len().saturating_sub(1)].to_vec()
    }

    /// The point at `t` (cubic Hermite on the span holding it).
    pub(crate) fn at(&self, t: f64) -> [f64; 2] {
        let n = self.t.len();
        if n == 1 {
            return self.p[0];
        }
        let mut i = 0;
        while i + 2 < n && self.t[i + 1] <= t {
            i += 1;
        }
        let h = self.t[i + 1] - self.t[i];
        let s = ((t - self.t[i]) / h).clamp(0.0, 1.0);
        let (h00, h10) = (
            2.0 * s.powi(3) - 3.0 * s * s + 1.0,
            s.powi(3) - 2.0 * s * s + s,
        );
        let (h01, h11) = (-2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
        let c = |k: usize| {
            h00 * self.p[i][k]
                + h10 * h * self.d[i][k]
                + h01 * self.p[i + 1][k]
                + h11 * h * self.d[i + 1][k]
        };
        [c(0), c(1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_geom::Contour;

    /// The largest distance from the samples of `f` to the fitted segments.
    fn deviation(f: &dyn Fn(f64) -> [f64; 2], t0: f64, t1: f64, segs: &[Segment]) -> f64 {
        let c = Contour::new(
            segs.iter()
                .map(|s| sv_geom::Vertex::new(s.start[0], s.start[1], s.bulge))
                .collect(),
        );
        let flat = c.flatten(1e-5);
        (0..=2000)
            .map(|k| {
                let p = f(t0 + (t1 - t0) * k as f64 / 2000.0);
                sv_geom::planar::boundary_distance(p, &flat)
            })
            .fold(0.0, f64::max)
    }

    /// `f` over one turn, `[0, 2 pi]`.
    fn turn(f: &dyn Fn(f64) -> [f64; 2]) -> Curve<'_> {
        Curve {
            at: f,
            t0: 0.0,
            t1: std::f64::consts::TAU,
            breaks: vec![],
        }
    }

    /// A curve that runs out of the file's samples spends them: the next one is refused at
    /// once (thousands of copies of one huge curve were each sampled up to the limit).
    #[test]
    fn a_curve_past_the_samples_left_spends_them() {
        let f = |t: f64| [1e6 * t.cos(), 4e5 * t.sin()];
        let left = Cell::new(5000);
        let e = fit_arcs(&turn(&f), 0.01, &left).unwrap_err();
        assert!(
            e.starts_with("too large for the arc tolerance 0.01 mm"),
            "{e}"
        );
        assert_eq!(left.get(), 0);
        // a small curve now has none either
        let g = |t: f64| [t, 0.0];
        let small = Curve {
            at: &g,
            t0: 0.0,
            t1: 1.0,
            breaks: vec![],
        };
        assert!(fit_arcs(&small, 0.01, &left).is_err());
    }

    #[test]
    fn an_ellipse_becomes_few_arcs_within_the_tolerance() {
        let f = |t: f64| [100.0 * t.cos(), 40.0 * t.sin()];
        let segs = fit_arcs(&turn(&f), 0.01, &Cell::new(MAX_SAMPLES)).unwrap();
        assert!(
            segs.len() < 60 && segs.iter().all(|s| s.bulge != 0.0),
            "{}",
            segs.len()
        );
        // closed: the last arc ends where the first begins
        let (a, b) = (segs[0].start, segs.last().unwrap().end);
        assert!((a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9);
        let dev = deviation(&f, 0.0, std::f64::consts::TAU, &segs);
        assert!(dev <= 0.01, "{dev}");
        let area: f64 = Contour::new(
            segs.iter()
                .map(|s| sv_geom::Vertex::new(s.start[0], s.start[1], s.bulge))
                .collect(),
        )
        .area();
        let exact = std::f64::consts::PI * 100.0 * 40.0;
        assert!((area - exact).abs() / exact < 1e-5, "{area} {exact}");
    }

    #[test]
    fn a_nurbs_circle_is_a_circle_and_lines_stay_lines() {
        // the rational quadratic quarter circle of radius 10
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let n = Nurbs {
            degree: 2,
            knots: vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            points: vec![[10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
            weights: vec![1.0, w, 1.0],
        };
        assert!(n.problem().is_none());
        for k in 0..=10 {
            let p = n.at(k as f64 / 10.0);
            assert!((p[0].hypot(p[1]) - 10.0).abs() < 1e-9);
        }
        let fit = |n: &Nurbs| {
            let f = |t: f64| n.at(t);
            let (t0, t1) = n.domain();
            fit_arcs(
                &Curve {
                    at: &f,
                    t0,
                    t1,
                    breaks: n.breaks(),
                },
                0.01,
                &Cell::new(MAX_SAMPLES),
            )
            .unwrap()
        };
        let segs = fit(&n);
        assert_eq!(segs.len(), 1);
        assert!((segs[0].arc().unwrap().0 - 10.0).abs() < 1e-6);
        let line = Nurbs {
            degree: 1,
            knots: vec![0.0, 0.0, 1.0, 2.0, 2.0],
            points: vec![[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]],
            weights: vec![],
        };
        let segs = fit(&line);
        assert_eq!(segs.len(), 2);
        assert!(segs.iter().all(|s| s.bulge == 0.0));
        assert!(Nurbs {
            knots: vec![0.0; 3],
            ..line
        }
        .problem()
        .is_some());
    }

    #[test]
    fn interpolation_passes_through_the_fit_points() {
        let pts = [[0.0, 0.0], [10.0, 10.0], [20.0, 0.0], [30.0, 10.0]];
        let s = Interpolant::new(&pts, None, None);
        for (i, p) in pts.iter().enumerate() {
            let q = s.at(s.t[i]);
            assert!((q[0] - p[0]).abs() < 1e-9 && (q[1] - p[1]).abs() < 1e-9);
        }
    }
}
