//! Secondary-stage timings (target validation, initial grid and optimisation) on the
//! saddle (hypar-like, negative curvature) at about 100, 1,000 and 10,000 faces:
//! `cargo bench -p sv-surface --bench secondary`. The 10,000-face case uses the saddle
//! scaled by 3 (12 x 12 m) at 120 mm units.

use criterion::{criterion_group, criterion_main, Criterion};
use sv_surface::{build_secondary, builtin_target, SecondaryOptions, TargetMesh};

fn scaled(target: &TargetMesh, k: f64) -> TargetMesh {
    TargetMesh {
        vertices: target
            .vertices
            .iter()
            .map(|p| sv_geom::Point3::from(p.coords * k))
            .collect(),
        triangles: target.triangles.clone(),
    }
}

fn secondary(c: &mut Criterion) {
    let saddle = builtin_target("saddle").expect("builtin");
    let big = scaled(&saddle, 3.0);
    let mut group = c.benchmark_group("secondary");
    group.sample_size(10);
    for (label, target, unit) in [
        ("saddle_100_faces", &saddle, 400.0),
        ("saddle_1000_faces", &saddle, 125.0),
        ("saddle_10000_faces", &big, 120.0),
    ] {
        let opts = SecondaryOptions {
            unit_size: unit,
            ..Default::default()
        };
        let (mesh, _) = build_secondary(target, &opts, &mut |_, _| {}).expect("secondary");
        eprintln!("{label}: {} faces", mesh.faces.len());
        group.bench_function(label, |b| {
            b.iter(|| build_secondary(target, &opts, &mut |_, _| {}).expect("secondary"))
        });
    }
    group.finish();
}

criterion_group!(benches, secondary);
criterion_main!(benches);
