//! Print the secondary-stage figures for every built-in target:
//! `cargo run --release -p sv-surface --example secondary_figures [unit_size]`.

use sv_surface::{build_secondary, builtin_target, SecondaryOptions, BUILTIN_NAMES};

fn main() {
    let unit: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(300.0);
    let names: Vec<String> = std::env::args().skip(2).collect();
    let iters = std::env::var("ITERS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let opts = SecondaryOptions {
        unit_size: unit,
        max_iterations: iters,
        ..Default::default()
    };
    for name in BUILTIN_NAMES {
        if !names.is_empty() && !names.iter().any(|n| n == name) {
            continue;
        }
        let target = builtin_target(name).expect("builtin");
        let t = std::time::Instant::now();
        let verbose = std::env::var("VERBOSE").is_ok();
        match build_secondary(&target, &opts, &mut |i, e| if verbose { println!("  it {i} energy {e:.3e}") }) {
            Ok((_, r)) => println!(
                "{name:9} faces {:5} plan {:.5} (f{}) cone {:.3} deg (v{}) close {:.4} bnd {:.4} cover {:.3} ratio {:.3} (max {:.2}) nonconvex {} it {} {:.2}s unmet {:?}",
                r.faces, r.planarity_max, r.planarity_worst_face, r.conical_max_deg, r.conical_worst_vertex, r.closeness_max, r.boundary_max, r.coverage,
                r.edge_ratio_fraction, r.edge_ratio_max, r.non_convex_faces.len(), r.iterations, t.elapsed().as_secs_f64(), r.unmet
            ),
            Err(e) => println!("{name:9} error: {e} ({:.2}s)", t.elapsed().as_secs_f64()),
        }
    }
}
