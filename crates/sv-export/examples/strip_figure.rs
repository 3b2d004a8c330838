//! Writes the DXF and SVG of the first strip of a curved `nx` x `ny` frame (4 x 3 by
//! default) into the directory given as the first argument, and prints how long
//! unrolling and profiling took.
//!
//! `cargo run -p sv-export --example strip_figure -- OUT_DIR [nx ny]`

use std::time::Instant;

use sv_frame::{solve, QuadMesh, SolveOptions};
use sv_strips::{profile_strip, unit_labels, unroll, ProfileParams, StripOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).cloned().unwrap_or_else(|| ".".into());
    let nx: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(4);
    let ny: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(3);
    // a sphere cap for small sizes; a gentle translational saddle (planar faces at any
    // size) for large ones
    let mesh = if nx * ny <= 64 {
        QuadMesh::sphere_cap(nx, ny, 3000.0, 300.0)
    } else {
        QuadMesh::translational(nx, ny, 300.0, |x| x * x / 40000.0, |y| -y * y / 40000.0)
    };
    let params = ProfileParams::default();
    // the units deploy as they are cut
    let options = SolveOptions {
        cut: Some(params.cut_widths()),
        ..Default::default()
    };
    let frame = solve(&mesh, &options, &mut |_| {})
        .expect("solve")
        .to_frame_file(&mesh);
    let t = Instant::now();
    let strips = unroll(&frame, &StripOptions::default()).expect("unroll");
    let labels = unit_labels(&strips, frame.units.len());
    let profiles: Vec<_> = strips
        .iter()
        .map(|s| {
            let names: Vec<String> = s.units.iter().map(|&u| labels[u].id.clone()).collect();
            profile_strip(s, &names, &params).expect("profile")
        })
        .collect();
    let took = t.elapsed();
    println!(
        "{} units, {} strips: unroll + profile {:.3} s",
        frame.units.len(),
        strips.len(),
        took.as_secs_f64()
    );
    std::fs::create_dir_all(&dir).expect("output directory");
    let (s, p) = (&strips[0], &profiles[0]);
    std::fs::write(
        format!("{dir}/{}.svg", s.id),
        sv_export::strip_svg(s, p, &params),
    )
    .expect("write svg");
    std::fs::write(format!("{dir}/{}.dxf", s.id), sv_export::strip_dxf(s, p)).expect("write dxf");
}
