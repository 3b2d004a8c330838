//! Write the acceptance targets of issue 3 as small OBJ triangle meshes (mm, Z up):
//! `cargo run -p sv-surface --example make_targets [-- OUT_DIR]` (default `fixtures/targets`).
//!
//! | file | surface | Gaussian curvature | boundary |
//! |---|---|---|---|
//! | `dome_lens.obj` | elliptic paraboloid (radii about 4 and 5 m) | positive | four outward-bulging arcs (lens-like, 3.7 x 3.0 m) |
//! | `cylinder_wave.obj` | cylinder, radius 3 m, axis X | zero | one wavy side, one slanted side |
//! | `hypar_pentagon.obj` | hyperbolic paraboloid z = xy / 4000 | negative | pentagon: a square with a gable on top |
//! | `wavy_mixed.obj` | z = 250 sin(2 pi x / 3000) cos(2 pi y / 2800) + arch | mixed | organic, wobbly sides |
//!
//! The last three do not meet every goal, and no hub mesh whose boundary follows theirs can
//! (docs/secondary.md, "Targets that cannot meet every goal"): planar faces with conical
//! vertices follow the principal curvature lines, and these boundaries cut across them
//! (the hypar's straight sides are its asymptotic lines). The next three have
//! non-rectangular plans whose sides are curvature lines (sectors of surfaces of
//! revolution bounded by two meridians and two parallels) and meet every goal:
//!
//! | file | surface | Gaussian curvature | boundary |
//! |---|---|---|---|
//! | `cone_sector.obj` | cone, slope 19 degrees | zero | annular sector, radii 1.8-4.2 m, 69 degrees |
//! | `trumpet_sector.obj` | z = 1400 ln(r / 1300) | negative | annular sector, radii 1.3-3.9 m, 74 degrees |
//! | `bell_sector.obj` | z = 1700 exp(-(r / 4000)^2) | mixed (sign changes at r = 2.83 m) | annular sector, radii 1.9-3.9 m, 92 degrees |
//!
//! Issue 16 adds the footprints and surfaces an architect draws (docs/secondary.md, "The
//! issue 16 suite"):
//!
//! | file | surface | boundary |
//! |---|---|---|
//! | `wave_canopy.obj` | z = 350 sin(x / 1000) cos(y / 1400) | rectangle 6 x 4 m |
//! | `egg_crate.obj` | z = 220 sin(pi x / 1200) sin(pi y / 1200) + 300 | square 4.8 m |
//! | `arched_tent.obj` | four-point tent z = 900 s t + 300 | square 5 m, sides arched inwards by 400 mm |
//! | `l_footprint.obj` | paraboloid shell z = 900 - r^2 / 9000 | L: 4 x 4 m less a 2 x 2 m quarter |
//! | `rounded_triangle.obj` | dome z = 800 - r^2 / 8000 | equilateral triangle, side 5 m, corners rounded (R 400 mm) |
//! | `oval_dome.obj` | ellipsoid cap | ellipse 3.0 x 2.0 m semi-axes |
//! | `skewed_vault.obj` | catenary vault (a = 1200 mm), span 3.6 m | parallelogram, ends skewed by 600 mm |
//! | `twisted_vault.obj` | arch section turning by 0.5 rad along its 6 m | twisted rectangle |
//! | `annulus_roof.obj` | paraboloid z = 900 - x^2 / 12000 - y^2 / 9000 | ellipse 3.2 x 2.6 m around a 1.2 x 0.9 m courtyard |
//! | `torus_patch.obj` | torus R = 3 m, r = 1.5 m, both curvature signs | two meridians and two parallels |
//! | `horseshoe.obj` | paraboloid z = 900 - r^2 / 15000 | a 1.5 m wide band bent round a half circle (R 2.25 m), half-round ends: no corner, its centre outside the plan |
//! | `two_courtyards.obj` | paraboloid z = 900 - x^2 / 16000 - y^2 / 12000 | rectangle 8 x 5 m round two rectangular courts (1.6 x 2.0 and 2.0 x 2.2 m): three boundary loops, 200 mm cells |
//! | `u_plan.obj` | paraboloid z = 900 - r^2 / 12000 | U: 6 x 4.5 m less a 2.4 x 2.5 m court open to the north (two reflex corners) |
//! | `t_plan.obj` | paraboloid z = 900 - r^2 / 12000 | T: a 6 x 1.8 m bar on a 2 x 3.2 m stem (two reflex corners; its plan's frame tilts with the dome off its centre) |
//! | `notch_plan.obj` | paraboloid z = 900 - r^2 / 12000 | rectangle 6 x 4 m with a notch 0.8 m wide, 1 m deep in one long side (its corners closer than the other layouts' corner window) |
//! | `round_courtyards.obj` | paraboloid z = 900 - x^2 / 16000 - y^2 / 12000 | ellipse 4 x 2.6 m semi-axes round two round courts (R 700 mm): three loops, no corner |
//!
//! The last four are triangulated in plan (spade's constrained Delaunay triangulation,
//! refined to 150 mm triangles).
//!
//! The frame's acceptance (docs/geometry.md, "Closing the joints") adds `hypar_square.obj`,
//! z = (x^2 - y^2) / 12000 over a 3.6 x 3.6 m square along its principal directions.
//!
//! Quadrilateral patches are `(s, t) in [-1, 1]^2 -> (x, y, z)` sampled on a 56 x 56 grid
//! (about 70 mm triangles); other footprints are the same grid mapped radially onto a
//! star-shaped polygon (its corners kept exactly), the annulus a 20 x 224 ring grid.
//! Written with one decimal (< 300 KB per file).

use std::f64::consts::PI;
use std::fmt::Write as _;

const N: usize = 56;

type Map = fn(f64, f64) -> (f64, f64, f64);

fn dome(s: f64, t: f64) -> (f64, f64, f64) {
    let x = 1850.0 * s * (1.0 + 0.1 * (1.0 - t * t));
    let y = 1500.0 * t * (1.0 + 0.1 * (1.0 - s * s));
    (x, y, 600.0 - x * x / 8000.0 - y * y / 10000.0)
}

fn cylinder(s: f64, t: f64) -> (f64, f64, f64) {
    let x = 2000.0 * s + 250.0 * t;
    let wave = 180.0 * (PI * s).sin() * (t + 1.0) / 2.0;
    let y = 1600.0 * t + wave;
    let r: f64 = 3000.0;
    (x, y, (r * r - y * y).sqrt() - r)
}

fn hypar(s: f64, t: f64) -> (f64, f64, f64) {
    let x = 1900.0 * s;
    let gable = 450.0 * (1.0 - s.abs()) * (t + 1.0) / 2.0;
    let y = 1700.0 * t + gable;
    (x, y, x * y / 4000.0)
}

/// The hypar of the frame's acceptance (issue 14): z = (x^2 - y^2) / 12000 over a square of
/// 3.6 m whose sides run along its principal directions.
fn hypar_square(s: f64, t: f64) -> (f64, f64, f64) {
    let (x, y) = (1800.0 * s, 1800.0 * t);
    (x, y, (x * x - y * y) / 12000.0)
}

fn wavy(s: f64, t: f64) -> (f64, f64, f64) {
    let x = 2300.0 * s * (1.0 + 0.06 * (PI * t).sin() * s);
    let y = 1700.0 * t * (1.0 + 0.07 * (1.5 * PI * s).cos());
    let z = 250.0 * (2.0 * PI * x / 3000.0).sin() * (2.0 * PI * y / 2800.0).cos()
        + 400.0 * (1.0 - (x / 2600.0).powi(2));
    (x, y, z)
}

/// Point at radius `r`, polar angle `phi` from the Y axis, of a surface of revolution with
/// profile `height(r)`, its axis at `(0, -centre)`.
fn revolution(r: f64, phi: f64, centre: f64, height: f64) -> (f64, f64, f64) {
    (r * phi.sin(), r * phi.cos() - centre, height)
}

fn cone(s: f64, t: f64) -> (f64, f64, f64) {
    let r = 3000.0 + 1200.0 * t;
    revolution(r, 0.6 * s, 3000.0, 1800.0 * (1.0 - r / 5200.0))
}

fn trumpet(s: f64, t: f64) -> (f64, f64, f64) {
    let r = 2600.0 + 1300.0 * t;
    revolution(r, 0.65 * s, 2600.0, 1400.0 * (r / 1300.0).ln())
}

fn bell(s: f64, t: f64) -> (f64, f64, f64) {
    let r = 2900.0 + 1000.0 * t;
    revolution(r, 0.8 * s, 2900.0, 1700.0 * (-(r / 4000.0).powi(2)).exp())
}

fn wave_canopy(s: f64, t: f64) -> (f64, f64, f64) {
    let (x, y) = (3000.0 * s, 2000.0 * t);
    (x, y, 350.0 * (x / 1000.0).sin() * (y / 1400.0).cos())
}

fn egg_crate(s: f64, t: f64) -> (f64, f64, f64) {
    let (x, y) = (2400.0 * s, 2400.0 * t);
    let z = 220.0 * (PI * x / 1200.0).sin() * (PI * y / 1200.0).sin() + 300.0;
    (x, y, z)
}

fn arched_tent(s: f64, t: f64) -> (f64, f64, f64) {
    let x = 2500.0 * s - 400.0 * s * (1.0 - t * t);
    let y = 2500.0 * t - 400.0 * t * (1.0 - s * s);
    (x, y, 900.0 * s * t + 300.0)
}

fn skewed_vault(s: f64, t: f64) -> (f64, f64, f64) {
    let (x, y) = (3000.0 * s + 600.0 * t, 1800.0 * t);
    let a: f64 = 1200.0;
    (x, y, a * ((1800.0 / a).cosh() - (y / a).cosh()))
}

fn twisted_vault(s: f64, t: f64) -> (f64, f64, f64) {
    let (x, w) = (3000.0 * s, 1700.0 * t);
    let h = 900.0 * (1.0 - t * t);
    let turn = 0.25 * s;
    (
        x,
        w * turn.cos() - h * turn.sin(),
        w * turn.sin() + h * turn.cos(),
    )
}

fn torus(s: f64, t: f64) -> (f64, f64, f64) {
    let (u, v) = (-0.5 * s, 1.0 + 0.9 * t);
    let (big, small) = (3000.0, 1500.0);
    let rho = big + small * v.cos();
    (rho * u.sin(), rho * u.cos() - big, small * v.sin())
}

fn l_height(x: f64, y: f64) -> f64 {
    900.0 - (x * x + y * y) / 9000.0
}

fn dome_height(x: f64, y: f64) -> f64 {
    800.0 - (x * x + y * y) / 8000.0
}

fn oval_height(x: f64, y: f64) -> f64 {
    1200.0 * (1.0 - (x / 3600.0).powi(2) - (y / 2600.0).powi(2)).sqrt() - 300.0
}

fn annulus_height(x: f64, y: f64) -> f64 {
    900.0 - x * x / 12000.0 - y * y / 9000.0
}

/// Vertices (one line each, `v x y z`) then triangles of the `N x N` grid whose point
/// `(i, j)` is `point(i, j)` (1-based `f a b c`, diagonals turning at the centre lines).
fn grid_obj(name: &str, point: &dyn Fn(usize, usize) -> (f64, f64, f64)) -> String {
    let mut out = format!("# spinvalence acceptance target {name}, mm, Z up\n");
    for j in 0..=N {
        for i in 0..=N {
            let (x, y, z) = point(i, j);
            let _ = writeln!(out, "v {x:.1} {y:.1} {z:.1}");
        }
    }
    let id = |i: usize, j: usize| j * (N + 1) + i + 1;
    for j in 0..N {
        for i in 0..N {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i < N / 2) == (j < N / 2) {
                let _ = writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}");
            } else {
                let _ = writeln!(out, "f {a} {b} {d}\nf {b} {c} {d}");
            }
        }
    }
    out
}

fn grid_coord(i: usize) -> f64 {
    2.0 * i as f64 / N as f64 - 1.0
}

fn obj(name: &str, map: Map) -> String {
    grid_obj(name, &|i, j| map(grid_coord(i), grid_coord(j)))
}

/// The closed polygon `corners` (counter-clockwise) sampled at `4 N` points by arc length,
/// every corner where the polygon turns by more than 20 degrees on a sample.
fn boundary_samples(corners: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let m = corners.len();
    let turn = |k: usize| {
        let (a, b, c) = (corners[(k + m - 1) % m], corners[k], corners[(k + 1) % m]);
        let (u, v) = ((b.0 - a.0, b.1 - a.1), (c.0 - b.0, c.1 - b.1));
        (u.0 * v.1 - u.1 * v.0).atan2(u.0 * v.0 + u.1 * v.1).abs()
    };
    let sharp: Vec<usize> = (0..m).filter(|&k| turn(k) > 20f64.to_radians()).collect();
    let starts = if sharp.is_empty() { vec![0] } else { sharp };
    // runs of the polygon between sharp corners, as point lists
    let runs: Vec<Vec<(f64, f64)>> = (0..starts.len())
        .map(|r| {
            let (a, b) = (starts[r], starts[(r + 1) % starts.len()]);
            let len = if b > a { b - a } else { b + m - a };
            (0..=len).map(|k| corners[(a + k) % m]).collect()
        })
        .collect();
    let length = |run: &[(f64, f64)]| {
        run.windows(2)
            .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
            .sum::<f64>()
    };
    let total: f64 = runs.iter().map(|r| length(r)).sum();
    // samples per run by largest remainder, 4 N in all
    let share: Vec<f64> = runs
        .iter()
        .map(|r| 4.0 * N as f64 * length(r) / total)
        .collect();
    let mut count: Vec<usize> = share.iter().map(|s| s.floor().max(1.0) as usize).collect();
    while count.iter().sum::<usize>() < 4 * N {
        let k = (0..runs.len())
            .max_by(|&a, &b| (share[a] - count[a] as f64).total_cmp(&(share[b] - count[b] as f64)))
            .unwrap_or(0);
        count[k] += 1;
    }
    let mut out = Vec::with_capacity(4 * N);
    for (run, &n) in runs.iter().zip(&count) {
        let len = length(run);
        let mut seg = 0;
        let mut before = 0.0;
        for k in 0..n {
            let target = len * k as f64 / n as f64;
            loop {
                let (a, b) = (run[seg], run[seg + 1]);
                let l = (b.0 - a.0).hypot(b.1 - a.1);
                if before + l >= target || seg + 2 == run.len() {
                    let f = if l > 0.0 { (target - before) / l } else { 0.0 };
                    out.push((a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f));
                    break;
                }
                before += l;
                seg += 1;
            }
        }
    }
    out
}

/// The grid mapped onto a footprint star-shaped about the origin: grid point `(s, t)` lies
/// on the square of half-size `rho = max(|s|, |t|)` at perimeter fraction `tau`; it goes to
/// `rho` times the boundary point at `tau`, lifted by `height`.
fn footprint_obj(name: &str, corners: &[(f64, f64)], height: fn(f64, f64) -> f64) -> String {
    footprint_obj_placed(name, corners, &|x, y| (x, y, height(x, y)))
}

/// [`footprint_obj`] with the plan point `(x, y)` placed at `place(x, y)` (a bend).
fn footprint_obj_placed(
    name: &str,
    corners: &[(f64, f64)],
    place: &dyn Fn(f64, f64) -> (f64, f64, f64),
) -> String {
    let rim = boundary_samples(corners);
    let at = |tau: f64| {
        let x = tau.rem_euclid(1.0) * rim.len() as f64;
        let k = (x.floor() as usize).min(rim.len() - 1);
        let f = x - k as f64;
        let (a, b) = (rim[k], rim[(k + 1) % rim.len()]);
        (a.0 + (b.0 - a.0) * f, a.1 + (b.1 - a.1) * f)
    };
    grid_obj(name, &|i, j| {
        let (s, t) = (grid_coord(i), grid_coord(j));
        let rho = s.abs().max(t.abs());
        if rho == 0.0 {
            return place(0.0, 0.0);
        }
        let (a, b) = (s / rho, t / rho);
        // counter-clockwise from the south-east corner: east, north, west, south sides
        let tau = if a >= 1.0 - 1e-12 && b < 1.0 {
            (b + 1.0) / 8.0
        } else if b >= 1.0 - 1e-12 && a > -1.0 {
            (1.0 + (1.0 - a) / 2.0) / 4.0
        } else if a <= -1.0 + 1e-12 && b > -1.0 {
            (2.0 + (1.0 - b) / 2.0) / 4.0
        } else {
            (3.0 + (a + 1.0) / 2.0) / 4.0
        };
        let (x, y) = at(tau);
        place(rho * x, rho * y)
    })
}

/// Horseshoe: a stadium (a 2 x 1.5 m band whose centreline, 7.07 m long, is a half circle of
/// radius 2.25 m, with half-round ends) bent onto that half circle: the arch opens south,
/// its legs end in half circles below the x axis; no corner, and its centre lies in the
/// opening (outside the plan).
fn horseshoe_obj() -> String {
    let (radius, half) = (2250.0, 750.0);
    let straight = PI * radius / 2.0;
    let mut stadium = Vec::new();
    for end in [1.0, -1.0] {
        for k in 0..=24 {
            let phi = -PI / 2.0 + PI * k as f64 / 24.0;
            stadium.push((end * (straight + half * phi.cos()), end * half * phi.sin()));
        }
    }
    footprint_obj_placed("horseshoe", &stadium, &|x, y| {
        let (theta, r) = (PI / 2.0 - x / radius, radius + y);
        let (px, py) = (r * theta.cos(), r * theta.sin());
        (px, py, horseshoe_height(px, py))
    })
}

fn horseshoe_height(x: f64, y: f64) -> f64 {
    900.0 - (x * x + y * y) / 15000.0
}

/// A roof round two courtyards: an 8 x 5 m rectangle of 200 mm cells (two triangles each)
/// less the cells of two rectangular courts, lifted onto a paraboloid; only the vertices of
/// the cells kept are written.
fn two_courtyards_obj() -> String {
    let (nx, ny, cell) = (40usize, 25usize, 200.0);
    let courts = [(5..13, 6..16), (23..33, 8..19)];
    let kept = |i: usize, j: usize| {
        !courts
            .iter()
            .any(|(ci, cj)| ci.contains(&i) && cj.contains(&j))
    };
    let mut id = vec![0usize; (nx + 1) * (ny + 1)];
    let mut out = String::from("# spinvalence acceptance target two_courtyards, mm, Z up\n");
    let mut next = 1;
    for j in 0..=ny {
        for i in 0..=nx {
            let used = (i.saturating_sub(1)..=i.min(nx - 1))
                .any(|a| (j.saturating_sub(1)..=j.min(ny - 1)).any(|b| kept(a, b)));
            if used {
                let (x, y) = (-4000.0 + cell * i as f64, -2500.0 + cell * j as f64);
                let z = 900.0 - x * x / 16000.0 - y * y / 12000.0;
                let _ = writeln!(out, "v {x:.1} {y:.1} {z:.1}");
                id[j * (nx + 1) + i] = next;
                next += 1;
            }
        }
    }
    let at = |i: usize, j: usize| id[j * (nx + 1) + i];
    for j in 0..ny {
        for i in 0..nx {
            if kept(i, j) {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                let _ = writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}");
            }
        }
    }
    out
}

/// Closed polygons (the outer one first, then the courts) triangulated in plan, refined
/// to triangles of about 150 mm with no angle under 25 degrees, the courts left out, and
/// lifted by `height`.
fn plan_obj(name: &str, loops: &[Vec<(f64, f64)>], height: fn(f64, f64) -> f64) -> String {
    use spade::{
        AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
    };
    let side: f64 = 150.0;
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    for lp in loops {
        let m = lp.len();
        let mut points = Vec::new();
        for k in 0..m {
            let (a, b) = (lp[k], lp[(k + 1) % m]);
            let n = ((b.0 - a.0).hypot(b.1 - a.1) / side).ceil().max(1.0) as usize;
            points.extend((0..n).map(|i| {
                let t = i as f64 / n as f64;
                (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
            }));
        }
        let handles: Vec<_> = points
            .iter()
            .map(|p| cdt.insert(Point2::new(p.0, p.1)).expect("finite point"))
            .collect();
        for k in 0..handles.len() {
            cdt.add_constraint(handles[k], handles[(k + 1) % handles.len()]);
        }
    }
    let refined = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_max_allowed_area(3f64.sqrt() / 4.0 * side * side)
            .with_angle_limit(AngleLimit::from_deg(25.0)),
    );
    let outside: std::collections::HashSet<_> = refined.excluded_faces.into_iter().collect();
    let mut out = format!("# spinvalence acceptance target {name}, mm, Z up\n");
    for v in cdt.vertices() {
        let p = v.position();
        let _ = writeln!(out, "v {:.1} {:.1} {:.1}", p.x, p.y, height(p.x, p.y));
    }
    for f in cdt.inner_faces() {
        if !outside.contains(&f.fix()) {
            let [a, b, c] = f.vertices().map(|v| v.fix().index() + 1);
            let _ = writeln!(out, "f {a} {b} {c}");
        }
    }
    out
}

fn courtyard_height(x: f64, y: f64) -> f64 {
    900.0 - x * x / 16000.0 - y * y / 12000.0
}

fn dome_900(x: f64, y: f64) -> f64 {
    900.0 - (x * x + y * y) / 12000.0
}

/// Points of an ellipse with semi-axes `a`, `b` about `centre`, counter-clockwise.
fn ellipse(a: f64, b: f64, centre: (f64, f64), n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let phi = 2.0 * PI * k as f64 / n as f64;
            (centre.0 + a * phi.cos(), centre.1 + b * phi.sin())
        })
        .collect()
}

/// Equilateral triangle of side `side` about the origin, corners rounded with `radius`.
fn rounded_triangle(side: f64, radius: f64) -> Vec<(f64, f64)> {
    let r_in = side / (2.0 * 3f64.sqrt()) - radius; // the arcs' centres lie on a smaller triangle
    let r_centre = 2.0 * r_in;
    let mut out = Vec::new();
    for k in 0..3 {
        let dir = PI / 2.0 + 2.0 * PI * k as f64 / 3.0;
        let c = (r_centre * dir.cos(), r_centre * dir.sin());
        for i in 0..=16 {
            let phi = dir - PI / 3.0 + 2.0 * PI / 3.0 * i as f64 / 16.0;
            out.push((c.0 + radius * phi.cos(), c.1 + radius * phi.sin()));
        }
    }
    out
}

/// Ring grid between two closed curves given at the same `m` angles: `rings` x `m`.
fn annulus_obj(name: &str, outer: &[(f64, f64)], inner: &[(f64, f64)], rings: usize) -> String {
    let m = outer.len();
    let mut out = format!("# spinvalence acceptance target {name}, mm, Z up\n");
    for j in 0..=rings {
        let f = j as f64 / rings as f64;
        for k in 0..m {
            let x = inner[k].0 + (outer[k].0 - inner[k].0) * f;
            let y = inner[k].1 + (outer[k].1 - inner[k].1) * f;
            let _ = writeln!(out, "v {x:.1} {y:.1} {:.1}", annulus_height(x, y));
        }
    }
    let id = |j: usize, k: usize| j * m + k % m + 1;
    for j in 0..rings {
        for k in 0..m {
            let (a, b, c, d) = (id(j, k), id(j + 1, k), id(j + 1, k + 1), id(j, k + 1));
            let _ = writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}");
        }
    }
    out
}

fn footprints() -> Vec<(&'static str, String)> {
    let l = [
        (-1600.0, -1600.0),
        (2400.0, -1600.0),
        (2400.0, 400.0),
        (400.0, 400.0),
        (400.0, 2400.0),
        (-1600.0, 2400.0),
    ];
    vec![
        ("l_footprint", footprint_obj("l_footprint", &l, l_height)),
        (
            "rounded_triangle",
            footprint_obj(
                "rounded_triangle",
                &rounded_triangle(5000.0, 400.0),
                dome_height,
            ),
        ),
        (
            "oval_dome",
            footprint_obj(
                "oval_dome",
                &ellipse(3000.0, 2000.0, (0.0, 0.0), 448),
                oval_height,
            ),
        ),
        (
            "annulus_roof",
            annulus_obj(
                "annulus_roof",
                &ellipse(3200.0, 2600.0, (0.0, 0.0), 4 * N),
                &ellipse(1200.0, 900.0, (300.0, 200.0), 4 * N),
                20,
            ),
        ),
        ("horseshoe", horseshoe_obj()),
        ("two_courtyards", two_courtyards_obj()),
        (
            "u_plan",
            plan_obj(
                "u_plan",
                &[vec![
                    (-3000.0, -2250.0),
                    (3000.0, -2250.0),
                    (3000.0, 2250.0),
                    (1200.0, 2250.0),
                    (1200.0, -250.0),
                    (-1200.0, -250.0),
                    (-1200.0, 2250.0),
                    (-3000.0, 2250.0),
                ]],
                dome_900,
            ),
        ),
        (
            "t_plan",
            plan_obj(
                "t_plan",
                &[vec![
                    (-3000.0, 1000.0),
                    (-1000.0, 1000.0),
                    (-1000.0, -2200.0),
                    (1000.0, -2200.0),
                    (1000.0, 1000.0),
                    (3000.0, 1000.0),
                    (3000.0, 2800.0),
                    (-3000.0, 2800.0),
                ]],
                dome_900,
            ),
        ),
        (
            "notch_plan",
            plan_obj(
                "notch_plan",
                &[vec![
                    (-3000.0, -2000.0),
                    (3000.0, -2000.0),
                    (3000.0, 2000.0),
                    (400.0, 2000.0),
                    (400.0, 1000.0),
                    (-400.0, 1000.0),
                    (-400.0, 2000.0),
                    (-3000.0, 2000.0),
                ]],
                dome_900,
            ),
        ),
        (
            "round_courtyards",
            plan_obj(
                "round_courtyards",
                &[
                    ellipse(4000.0, 2600.0, (0.0, 0.0), 160),
                    ellipse(700.0, 700.0, (-1800.0, 0.0), 32),
                    ellipse(700.0, 700.0, (1800.0, 200.0), 32),
                ],
                courtyard_height,
            ),
        ),
    ]
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fixtures/targets".into());
    std::fs::create_dir_all(&dir).expect("create output directory");
    let targets: [(&str, Map); 14] = [
        ("dome_lens", dome),
        ("cylinder_wave", cylinder),
        ("hypar_pentagon", hypar),
        ("wavy_mixed", wavy),
        ("cone_sector", cone),
        ("trumpet_sector", trumpet),
        ("bell_sector", bell),
        ("wave_canopy", wave_canopy),
        ("egg_crate", egg_crate),
        ("arched_tent", arched_tent),
        ("skewed_vault", skewed_vault),
        ("twisted_vault", twisted_vault),
        ("torus_patch", torus),
        ("hypar_square", hypar_square),
    ];
    let files = targets
        .into_iter()
        .map(|(name, map)| (name, obj(name, map)))
        .chain(footprints());
    for (name, text) in files {
        let path = format!("{dir}/{name}.obj");
        std::fs::write(&path, &text).expect("write OBJ");
        println!("{path}: {} bytes", text.len());
    }
}
