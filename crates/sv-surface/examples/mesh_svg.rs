//! The hub mesh of one target in plan (X right, Y up) as an SVG to look at, each face
//! coloured by the goal it misses (red planarity, orange face sides, purple edge ratio,
//! grey all met), irregular vertices dotted (blue valence 3, green valence 5), the target
//! boundary in black and the cross field's singularities as crosses:
//! `cargo run --release -p sv-surface --example mesh_svg -- UNIT FILE.obj OUT.svg`.

use std::fmt::Write as _;

use sv_surface::{build_secondary, cross_field, Goals, SecondaryOptions, TargetIndex};

#[path = "shared/obj.rs"]
mod obj;
use obj::read_obj;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let unit: f64 = args[1].parse().expect("unit size");
    let target = read_obj(&args[2]);
    let opts = SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    };
    let (mesh, report) = build_secondary(&target, &opts, &mut |_, _| {}).expect("build");
    let index = TargetIndex::new(&target).expect("target");
    let field = cross_field(&index, sv_surface::DEFAULT_ALIGNMENT).expect("field");
    let g = Goals::default();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &target.vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let pad = 0.03 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let (w, h) = (hi[0] - lo[0] + 2.0 * pad, hi[1] - lo[1] + 2.0 * pad);
    let px = |x: f64| x - lo[0] + pad;
    let py = |y: f64| hi[1] + pad - y;
    let mut s = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 {w:.0} {h:.0}' width='1000' height='{:.0}'>\n",
        1000.0 * h / w
    );
    let stroke = 0.002 * w;
    for (f, face) in mesh.faces.iter().enumerate() {
        let p = mesh.face_points(f);
        let e: Vec<f64> = (0..4).map(|k| (p[(k + 1) % 4] - p[k]).norm()).collect();
        let mean = e.iter().sum::<f64>() / 4.0;
        let plan = sv_geom::quad_diagonal_distance(&p) / mean;
        let (emin, emax) = e
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        let side_bad = emin / unit < g.side_range.0 || emax / unit > g.side_range.1;
        let colour = if plan > g.planarity {
            "#f08080"
        } else if side_bad {
            "#ffb347"
        } else if emax / emin > sv_surface::EDGE_RATIO_LIMIT {
            "#c8a2c8"
        } else {
            "#e8e8e8"
        };
        let pts: Vec<String> = face
            .iter()
            .map(|&v| {
                format!(
                    "{:.1},{:.1}",
                    px(mesh.vertices[v].x),
                    py(mesh.vertices[v].y)
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "<polygon points='{}' fill='{colour}' stroke='#555' stroke-width='{stroke:.1}'/>",
            pts.join(" ")
        );
    }
    let v = &target.vertices;
    for lp in index.loops() {
        let pts: Vec<String> = lp
            .iter()
            .map(|&i| format!("{:.1},{:.1}", px(v[i].x), py(v[i].y)))
            .collect();
        let _ = writeln!(
            s,
            "<polygon points='{}' fill='none' stroke='black' stroke-width='{:.1}'/>",
            pts.join(" "),
            2.0 * stroke
        );
    }
    let mut valence = vec![0usize; mesh.vertices.len()];
    for face in &mesh.faces {
        for &i in face {
            valence[i] += 1;
        }
    }
    for &i in &report.irregular_vertices {
        let colour = if valence[i] == 3 { "blue" } else { "green" };
        let p = mesh.vertices[i];
        let _ = writeln!(
            s,
            "<circle cx='{:.1}' cy='{:.1}' r='{:.1}' fill='{colour}'/>",
            px(p.x),
            py(p.y),
            6.0 * stroke
        );
    }
    for &(t, k) in &field.singularities {
        let c = (v[target.triangles[t][0]].coords
            + v[target.triangles[t][1]].coords
            + v[target.triangles[t][2]].coords)
            / 3.0;
        let colour = if k > 0 { "blue" } else { "green" };
        let r = 10.0 * stroke;
        let _ = writeln!(
            s,
            "<path d='M{:.1} {:.1}l{r:.1} {r:.1}m0 {:.1}l{:.1} {r:.1}' stroke='{colour}' stroke-width='{stroke:.1}'/>",
            px(c.x) - r / 2.0,
            py(c.y) - r / 2.0,
            -r,
            -r
        );
    }
    s.push_str("</svg>\n");
    std::fs::write(&args[3], s).expect("write SVG");
    println!(
        "{}: {} faces, unmet {:?}",
        args[3], report.faces, report.unmet
    );
}
