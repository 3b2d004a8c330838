//! Strip-stage timings on the 1,000-unit build: the built-in pavilion scaled by 1.9
//! (about 11 x 8 m) at the default 300 mm units, solved with the default options, then
//! unrolled, profiled and design-rule checked with the default 3 mm steel parameters:
//! `cargo bench -p sv-strips --bench strips`.

use criterion::{criterion_group, criterion_main, Criterion};
use sv_frame::{solve, SolveOptions};
use sv_strips::{check_profile, profile_strip, unit_labels, unroll, ProfileParams, StripOptions};
use sv_surface::{build_secondary, builtin_target, SecondaryOptions, TargetMesh};

fn thousand_unit_frame() -> sv_frame::FrameFile {
    let pavilion = builtin_target("pavilion").expect("builtin");
    let target = TargetMesh {
        vertices: pavilion
            .vertices
            .iter()
            .map(|p| sv_geom::Point3::from(p.coords * 1.9))
            .collect(),
        triangles: pavilion.triangles.clone(),
    };
    let (mesh, _) =
        build_secondary(&target, &SecondaryOptions::default(), &mut |_, _| {}).expect("secondary");
    solve(&mesh, &SolveOptions::default(), &mut |_| {})
        .expect("primary")
        .to_frame_file(&mesh)
}

fn strips(c: &mut Criterion) {
    let frame = thousand_unit_frame();
    let options = StripOptions::default();
    let params = ProfileParams::default();
    eprintln!(
        "strips bench: {} units in {} strips",
        frame.units.len(),
        unroll(&frame, &options).expect("unroll").len()
    );
    let mut group = c.benchmark_group("strips");
    group.sample_size(10);
    group.bench_function("unroll_1000_units", |b| {
        b.iter(|| unroll(&frame, &options).expect("unroll"))
    });
    let flat = unroll(&frame, &options).expect("unroll");
    let labels = unit_labels(&flat, frame.units.len());
    let names: Vec<Vec<String>> = flat
        .iter()
        .map(|s| s.units.iter().map(|&u| labels[u].id.clone()).collect())
        .collect();
    group.bench_function("profile_and_drc_1000_units", |b| {
        b.iter(|| {
            let mut violations = 0;
            for (s, n) in flat.iter().zip(&names) {
                let p = profile_strip(s, n, &params).expect("profile");
                violations += check_profile(s, &p, &params).len();
            }
            assert_eq!(violations, 0);
        })
    });
    group.bench_function("unroll_profile_drc_1000_units", |b| {
        b.iter(|| {
            let flat = unroll(&frame, &options).expect("unroll");
            for (s, n) in flat.iter().zip(&names) {
                let p = profile_strip(s, n, &params).expect("profile");
                assert!(check_profile(s, &p, &params).is_empty());
            }
        })
    });
    group.finish();
}

criterion_group!(benches, strips);
criterion_main!(benches);
