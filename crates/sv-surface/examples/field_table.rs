//! The cross field of every target (`sv_surface::cross_field`): its singularities, and
//! what the boundary asks of a planar, conical hub mesh at each unit size:
//! `cargo run --release -p sv-surface --example field_table -- 300,150 fixtures/targets/*.obj`.
//!
//! Per target: the singularities of the field (index in quarter turns, +1 where a
//! valence-3 vertex belongs, -1 a valence-5 one) with their anisotropy `|k1 - k2| h`; and
//! along the boundary, the planarity of a square face of side `h` with one edge along the
//! boundary and one across it, `h |k1 - k2| |sin 2 phi| / 4` (`phi` the angle of the
//! boundary from a principal direction: the diagonal distance over the side), and the
//! smallest angle between the boundary and its conjugate direction (the direction a
//! planar boundary face's cross edges must take; 0 where the boundary runs along an
//! asymptotic line, 90 degrees along a curvature line).

use sv_surface::{cross_field, TargetIndex, DEFAULT_ALIGNMENT};

#[path = "shared/obj.rs"]
mod obj;
use obj::read_obj;

fn main() {
    let units: Vec<f64> = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "300,150".into())
        .split(',')
        .map(|s| s.parse().expect("unit size"))
        .collect();
    let files: Vec<String> = std::env::args().skip(2).collect();
    let alignment: f64 = std::env::var("ALIGN")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(DEFAULT_ALIGNMENT);
    print!("| target | singularities (index at x, y mm) | max anisotropy (1/m) |");
    for h in &units {
        print!(" boundary face planarity at {h} |");
    }
    println!(" boundary-conjugate angle min (deg) | field s |");
    for file in &files {
        let name = std::path::Path::new(file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let target = if file.starts_with("builtin:") {
            sv_surface::builtin_target(file.trim_start_matches("builtin:")).expect("builtin")
        } else {
            read_obj(file)
        };
        let index = TargetIndex::new(&target).expect("valid target");
        let t = std::time::Instant::now();
        let field = cross_field(&index, alignment).expect("field");
        let secs = t.elapsed().as_secs_f64();
        let v = &target.vertices;
        let sing: Vec<String> = field
            .singularities
            .iter()
            .map(|&(t, k)| {
                let tri = target.triangles[t];
                let c = (v[tri[0]].coords + v[tri[1]].coords + v[tri[2]].coords) / 3.0;
                format!("{k:+} at ({:.0}, {:.0})", c.x, c.y)
            })
            .collect();
        let amax = field.anisotropy.iter().copied().fold(0.0, f64::max);
        // boundary: face planarity per unit and the conjugate angle
        let (mut worst, mut conj_min) = (0.0f64, 90.0f64);
        for lp in index.loops() {
            let m = lp.len();
            for k in 0..m {
                let (a, b, c) = (lp[(k + m - 2) % m], lp[k], lp[(k + 2) % m]);
                // corners (the boundary turning by more than 20 degrees) are left out
                if (v[b] - v[a]).angle(&(v[c] - v[b])) > 20f64.to_radians() {
                    continue;
                }
                let s = v[c] - v[a];
                let n = field.normals[b];
                let s = (s - n * n.dot(&s)).normalize();
                let p = field.principal[b];
                let q = n.cross(&p);
                let (cs, sn) = (s.dot(&p), s.dot(&q));
                let (k1, k2) = field.curvatures[b];
                worst = worst.max(((k1 - k2) * cs * sn).abs() / 2.0);
                // conjugate of s: c = (-k2 sn, k1 cs)
                let (cx, cy) = (-k2 * sn, k1 * cs);
                let len = cx.hypot(cy);
                if len > 1e-12 {
                    let cosg = ((cs * cx + sn * cy) / len).abs().min(1.0);
                    conj_min = conj_min.min(cosg.acos().to_degrees());
                }
            }
        }
        print!(
            "| {name} | {} | {:.3} |",
            if sing.is_empty() {
                "none".into()
            } else {
                sing.join(", ")
            },
            amax * 1000.0
        );
        for h in &units {
            print!(" {:.4} |", worst * h);
        }
        println!(" {conj_min:.1} | {secs:.3} |");
    }
}
