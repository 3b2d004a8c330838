//! Primary-surface solve on curved meshes of 10^2, 10^3 and 10^4 units.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;
use sv_frame::{solve, QuadMesh, SolveOptions};

fn sphere_caps(c: &mut Criterion) {
    let mut group = c.benchmark_group("primary_solve_sphere_cap");
    group.sample_size(10);
    for n in [10usize, 32, 100] {
        // a cap spanning about one radian, so curvature per unit shrinks as n grows
        let mesh = QuadMesh::sphere_cap(n, n, 300.0 * n as f64, 300.0);
        group.bench_with_input(BenchmarkId::from_parameter(n * n), &mesh, |b, mesh| {
            b.iter(|| solve(black_box(mesh), &SolveOptions::default(), &mut |_| {}).unwrap())
        });
    }
    group.finish();
}

fn saddles(c: &mut Criterion) {
    let mut group = c.benchmark_group("primary_solve_saddle");
    group.sample_size(10);
    for n in [10usize, 32, 100] {
        let r = 300.0 * n as f64;
        let mesh = QuadMesh::translational(
            n,
            n,
            300.0,
            move |x| x * x / (2.0 * r),
            move |y| -y * y / (2.0 * r),
        );
        group.bench_with_input(BenchmarkId::from_parameter(n * n), &mesh, |b, mesh| {
            b.iter(|| solve(black_box(mesh), &SolveOptions::default(), &mut |_| {}).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, sphere_caps, saddles);
criterion_main!(benches);
