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
//! Each is a curvilinear quadrilateral patch `(s, t) in [-1, 1]^2 -> (x, y)` sampled on a
//! 56 x 56 grid (about 70 mm triangles), written with one decimal (< 300 KB per file).

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

fn obj(name: &str, map: Map) -> String {
    let mut out = format!("# spinvalence acceptance target {name}, mm, Z up\n");
    for j in 0..=N {
        for i in 0..=N {
            let s = 2.0 * i as f64 / N as f64 - 1.0;
            let t = 2.0 * j as f64 / N as f64 - 1.0;
            let (x, y, z) = map(s, t);
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

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "fixtures/targets".into());
    std::fs::create_dir_all(&dir).expect("create output directory");
    let targets: [(&str, Map); 7] = [
        ("dome_lens", dome),
        ("cylinder_wave", cylinder),
        ("hypar_pentagon", hypar),
        ("wavy_mixed", wavy),
        ("cone_sector", cone),
        ("trumpet_sector", trumpet),
        ("bell_sector", bell),
    ];
    for (name, map) in targets {
        let path = format!("{dir}/{name}.obj");
        let text = obj(name, map);
        std::fs::write(&path, &text).expect("write OBJ");
        println!("{path}: {} bytes", text.len());
    }
}
