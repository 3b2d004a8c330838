//! `spinvalence solve`: read and validate the hub mesh, solve, write frame.json + frame.obj.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use sv_frame::{MeshChecks, Progress, SolveOptions};

use crate::cli::SolveArgs;
use crate::output::{self, box_text, number, AtomicFiles};

/// Names of the files `solve` writes, the frame.json last (its presence means both are complete).
const FRAME_OBJ: &str = "frame.obj";
const FRAME_JSON: &str = "frame.json";

/// Check the parameters a user typed; one line per problem, naming the flag.
pub fn options(args: &SolveArgs) -> Result<SolveOptions> {
    let spin = args.spin_angle;
    if !(spin > 0.0 && spin < 90.0) {
        bail!("invalid --spin-angle {spin}: must be strictly between 0 and 90 degrees");
    }
    let e = args.expansion;
    if !(e.is_finite() && e >= 1.0) {
        bail!("invalid --expansion {e}: must be a finite number >= 1");
    }
    let tol = args.planarity_tolerance;
    if !(tol.is_finite() && tol > 0.0) {
        bail!("invalid --planarity-tolerance {tol}: must be a finite number > 0");
    }
    Ok(SolveOptions {
        spin_angle: spin.to_radians(),
        expansion: e,
        side: args.side.into(),
        objective: args.objective.into(),
        max_iterations: args.max_iterations,
        planarity_tolerance: tol,
        ..SolveOptions::default()
    })
}

/// Mean edge below which a hub mesh is not one of units cut from sheet steel in mm (the
/// thinnest sheet's least profile puts the hub 19.5 mm inside its tile, docs/geometry.md
/// 5.4): most often a mesh drawn in metres or inches.
const MIN_MEAN_EDGE: f64 = 20.0;
/// Largest mean edge a unit hint names (a unit of 2 m is already a large one).
const MAX_HINTED_EDGE: f64 = 2000.0;

/// A hub mesh whose faces are too small to be cut is refused with its bounding box and
/// what it would measure in metres or inches (a mesh in metres solved silently, with
/// 0.124 mm laps).
fn in_millimetres(name: &str, mesh: &sv_frame::QuadMesh) -> Result<()> {
    let mean = mesh.mean_edge();
    if mean >= MIN_MEAN_EDGE {
        return Ok(());
    }
    let hints: Vec<String> = [(1000.0, "metres"), (25.4, "inches")]
        .iter()
        .filter(|(k, _)| (MIN_MEAN_EDGE..=MAX_HINTED_EDGE).contains(&(mean * k)))
        .map(|(k, unit)| {
            format!(
                "in {unit} its mean edge is {} mm (scale it by {k})",
                number(mean * k)
            )
        })
        .collect();
    anyhow::bail!(
        "{name}: the hub mesh's mean edge is {} mm (its bounding box {}): too small for units cut from sheet steel; hub meshes are read in millimetres{}",
        number(mean),
        box_text(&mesh.vertices),
        if hints.is_empty() { String::new() } else { format!("; {}", hints.join("; ")) }
    )
}

/// Run `solve`. Nothing is written unless everything succeeded.
pub fn run(args: &SolveArgs) -> Result<()> {
    let started = Instant::now();
    let options = options(args)?;
    let name = args.mesh.display().to_string();
    let bytes = output::read_bytes(&args.mesh)?;
    let checks = MeshChecks {
        planarity_tolerance: options.planarity_tolerance,
    };
    let mesh = sv_io::read_and_validate_quad_obj_bytes(&bytes, &name, &checks)?;
    in_millimetres(&name, &mesh)?;
    // Fail on an unwritable output directory before the long part.
    let files = AtomicFiles::create(&args.out, &[FRAME_OBJ, FRAME_JSON])?;

    let bar = progress_bar(args.quiet, options.max_iterations, "solving");
    let solved = sv_frame::solve(&mesh, &options, &mut |p: Progress| {
        bar.set_length(p.max_iterations as u64);
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("gap sum {} mm", number(p.gap_sum)));
    });
    bar.finish_and_clear();
    let solved = solved.map_err(|e| anyhow::anyhow!("{name}: {e}"))?;

    let frame = solved.to_frame_file(&mesh);
    let obj = sv_io::frame_to_obj(&frame);
    let json = sv_io::frame_to_json(&frame);
    let written = files.commit(&[&obj, &json])?;

    if !args.quiet {
        let report = &solved.report;
        let overlaps = &solved.evaluation.overlaps;
        let min = overlaps.iter().copied().fold(f64::INFINITY, f64::min);
        let max = overlaps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let written: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        let rows = [
            ["units", &frame.units.len().to_string()],
            ["links", &frame.links.len().to_string()],
            [
                "gap sum",
                &format!(
                    "{} mm -> {} mm",
                    number(report.gap_sum_start),
                    number(report.gap_sum)
                ),
            ],
            ["gap max", &format!("{} mm", number(report.gap_max))],
            [
                "hub overlap",
                &format!("{} mm .. {} mm", number(min), number(max)),
            ],
            [
                "iterations",
                &format!(
                    "{} ({} factorisations)",
                    report.iterations, report.factorizations
                ),
            ],
            ["wall time", &seconds(started.elapsed())],
            ["wrote", &written.join(", ")],
        ];
        let rows: Vec<Vec<String>> = rows
            .iter()
            .map(|r| r.iter().map(|s| s.to_string()).collect())
            .collect();
        output::print_out(&output::table(&rows))?;
    }
    Ok(())
}

/// Seconds with three decimals.
pub fn seconds(d: Duration) -> String {
    format!("{:.3} s", d.as_secs_f64())
}

/// A bar on stderr, hidden for `--quiet` and when stderr is not a terminal.
pub fn progress_bar(quiet: bool, max_iterations: usize, what: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar =
        ProgressBar::with_draw_target(Some(max_iterations as u64), ProgressDrawTarget::stderr());
    if let Ok(style) = ProgressStyle::with_template(&format!(
        "{what} [{{bar:30}}] {{pos}}/{{len}} iterations, {{msg}} ({{elapsed}})"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{Cli, Command};
    use clap::Parser;

    fn parse(extra: &[&str]) -> SolveArgs {
        let mut argv = vec!["spinvalence", "solve", "--mesh", "m.obj", "--out", "o"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).unwrap().command {
            Command::Solve(args) => args,
            other => panic!("expected solve, got {other:?}"),
        }
    }

    #[test]
    fn parameters_in_range_pass_through_in_radians() {
        let o = options(&parse(&["--spin-angle", "30", "--expansion", "1.05"])).unwrap();
        assert!((o.spin_angle - 30f64.to_radians()).abs() < 1e-15);
        assert_eq!(o.expansion, 1.05);
    }

    #[test]
    fn parameters_out_of_range_name_the_flag() {
        for (flag, value) in [
            ("--spin-angle", "0"),
            ("--spin-angle", "90"),
            ("--spin-angle", "-10"),
            ("--spin-angle", "nan"),
            ("--spin-angle", "inf"),
            ("--expansion", "0.5"),
            ("--expansion", "inf"),
            ("--expansion", "NaN"),
            ("--planarity-tolerance", "0"),
            ("--planarity-tolerance", "-1"),
        ] {
            let err = options(&parse(&[flag, value])).unwrap_err().to_string();
            assert!(err.contains(flag), "{flag} {value}: {err}");
            assert!(!err.contains('\n'));
        }
    }
}
