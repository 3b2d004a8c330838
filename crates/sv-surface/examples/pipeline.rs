//! Secondary stage then the primary solve, with the figures of issue 3:
//! `cargo run --release -p sv-surface --example pipeline -- UNIT [builtin:NAME|FILE.obj ...]`.

use std::time::Instant;

use sv_surface::{build_secondary, builtin_target, SecondaryOptions, BUILTIN_NAMES};

#[path = "shared/obj.rs"]
mod obj;
use obj::read_obj;

fn main() {
    let unit: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(300.0);
    let mut specs: Vec<String> = std::env::args().skip(2).collect();
    if specs.is_empty() {
        specs = BUILTIN_NAMES
            .iter()
            .map(|n| format!("builtin:{n}"))
            .collect();
    }
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let d = SecondaryOptions::default();
    let opts = SecondaryOptions {
        unit_size: unit,
        edge_weight: env("EDGE", d.edge_weight),
        fairness_weight: env("FAIR", d.fairness_weight),
        closeness_weight: env("CLOSE", d.closeness_weight),
        max_iterations: env("ITERS", d.max_iterations as f64) as usize,
        ..d
    };
    println!("| target | unit | faces | planarity max | conical max (deg) | closeness | boundary | coverage | edge ratio <= 1.25 | fit max | sides / unit | irregular | gap max (mm) | gap % unit | secondary s | primary s |");
    for spec in specs {
        let target = if spec.starts_with("builtin:") {
            builtin_target(&spec).expect("builtin")
        } else {
            read_obj(&spec)
        };
        let t = Instant::now();
        let (mesh, r) = match build_secondary(&target, &opts, &mut |_, _| {}) {
            Ok(x) => x,
            Err(e) => {
                println!("| {spec} | {unit} | error: {e} |");
                continue;
            }
        };
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let solved = sv_frame::solve(&mesh, &sv_frame::SolveOptions::default(), &mut |_| {});
        let tp = t.elapsed().as_secs_f64();
        let gap = match &solved {
            Ok(s) => s.report.gap_max,
            Err(e) => {
                println!("  primary error: {e}");
                f64::NAN
            }
        };
        println!(
            "| {spec} | {unit} | {} | {:.5} | {:.3} | {:.4} | {:.4} | {:.3} | {:.3} | {:.4} | {:.2}-{:.2} | {} | {:.1} | {:.2} % | {:.2} | {:.2} |",
            r.faces,
            r.planarity_max,
            r.conical_max_deg,
            r.closeness_max,
            r.boundary_max,
            r.coverage,
            r.edge_ratio_fraction,
            r.rhombus_fit_max,
            r.side_min,
            r.side_max,
            r.irregular_vertices.len(),
            gap,
            100.0 * gap / unit,
            ts,
            tp
        );
        println!(
            "  fit worst face {}, iterations {}",
            r.rhombus_fit_worst_face, r.iterations
        );
        if !r.unmet.is_empty() {
            println!("  unmet: {:?} (iterations {})", r.unmet, r.iterations);
        }
        if std::env::var("GAPS").is_ok() {
            if let Ok(s) = &solved {
                let mut worst: Vec<(f64, usize)> =
                    s.evaluation.gaps.iter().copied().zip(0..).collect();
                worst.sort_by(|a, b| b.0.total_cmp(&a.0));
                for &(g, l) in worst.iter().take(5) {
                    let link = s.links[l];
                    println!(
                        "  gap {g:.1} mm link {:?} faces {:?}",
                        link.edge, link.faces
                    );
                }
            }
        }
    }
}
