//! The issue 16 suite table of docs/secondary.md: the secondary stage on every target at
//! the given unit sizes, one row per (target, size) with the unmet goals as letters
//! (P planarity, C conical, D distance, B boundary, A covered area, E edge ratio, S face
//! sides), and per goal the count of pairs that miss it:
//! `cargo run --release -p sv-surface --example suite_table -- 300,150 fixtures/targets/*.obj`.

use std::time::Instant;

use sv_surface::{build_secondary, Goals};

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
    let g = Goals::default();
    let letters = "PCDBAES";
    let mut fails = [0usize; 7];
    let (mut pairs, mut all) = (0, 0);
    println!("| target | unit | faces | planarity | conical (deg) | closeness | boundary | coverage | edge ratio <= 1.25 | sides / unit | irregular | iterations | unmet | s |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &unit in &units {
        for file in &files {
            let name = std::path::Path::new(file.trim_start_matches("builtin:"))
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let target = if file.starts_with("builtin:") {
                sv_surface::builtin_target(file).expect("builtin")
            } else {
                read_obj(file)
            };
            let opts = sv_surface::SecondaryOptions {
                unit_size: unit,
                ..Default::default()
            };
            let t = Instant::now();
            let (_, r) = match build_secondary(&target, &opts, &mut |_, _| {}) {
                Ok(x) => x,
                Err(e) => {
                    println!("| {name} | {unit} | error: {e} |");
                    continue;
                }
            };
            let secs = t.elapsed().as_secs_f64();
            let miss = [
                r.planarity_max > g.planarity,
                r.conical_max_deg > g.conical_deg,
                r.closeness_max > g.closeness,
                r.boundary_max > g.boundary,
                r.coverage < g.coverage,
                r.edge_ratio_fraction < g.edge_ratio_fraction,
                r.side_min < g.side_range.0 || r.side_max > g.side_range.1,
            ];
            let mut unmet: String = letters
                .chars()
                .zip(miss)
                .filter(|&(_, m)| m)
                .map(|(c, _)| c)
                .collect();
            for (k, &m) in miss.iter().enumerate() {
                fails[k] += usize::from(m);
            }
            pairs += 1;
            if unmet.is_empty() && r.unmet.is_empty() {
                all += 1;
                unmet = "all met".into();
            }
            println!(
                "| {name} | {unit} | {} | {:.5} | {:.3} | {:.4} | {:.4} | {:.3} | {:.3} | {:.2}-{:.2} | {} | {} | {unmet} | {secs:.2} |",
                r.faces,
                r.planarity_max,
                r.conical_max_deg,
                r.closeness_max,
                r.boundary_max,
                r.coverage,
                r.edge_ratio_fraction,
                r.side_min,
                r.side_max,
                r.irregular_vertices.len(),
                r.iterations,
            );
        }
    }
    let per: Vec<String> = letters
        .chars()
        .zip(fails)
        .map(|(c, n)| format!("{c} {n}"))
        .collect();
    println!(
        "every goal met on {all} of {pairs} pairs; failures per goal: {}",
        per.join(", ")
    );
}
