//! `spinvalence build`: target surface -> hub mesh -> deployed frame, end to end.

use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use indicatif::ProgressBar;
use serde::Serialize;
use sv_frame::Progress;
use sv_surface::{SecondaryReport, TargetMesh};

use crate::cli::BuildArgs;
use crate::config::{self, BuildConfig};
use crate::output::{self, number, AtomicDir, AtomicFiles};
use crate::solve::{progress_bar, seconds};
use crate::{report, sheets, strips};

/// The files `build` writes beside `strips/`; `frame.json` last.
const FILES: [&str; 9] = [
    "mesh.obj",
    "frame.obj",
    "strips.json",
    "nest.json",
    "bom.csv",
    "report.html",
    "timings.json",
    "report.json",
    "frame.json",
];

/// Wall seconds per stage (`timings.json`); later stages add their own keys.
#[derive(Debug, Serialize)]
pub struct Timings {
    /// Target surface to hub mesh.
    pub secondary: f64,
    /// Primary-surface solve.
    pub primary: f64,
    /// Strips: unrolling, cut profiles, design-rule check, DXF and SVG.
    pub strips: f64,
    /// Nesting the strips onto sheets, sheet DXF and SVG.
    pub nest: f64,
    /// The report: report.html and bom.csv.
    pub report: f64,
    /// The whole command, reading and writing included.
    pub total: f64,
}

/// The options of each stage, derived from the config and checked.
pub struct StageOptions {
    /// The primary solve.
    pub solve: sv_frame::SolveOptions,
    /// Strips and unrolling.
    pub strips: sv_strips::StripOptions,
    /// Nesting onto sheets.
    pub nest: sv_nest::NestOptions,
}

/// The config after the command line has overridden the file, and the stage options it
/// gives, every value checked before any work starts.
pub fn resolve(args: &BuildArgs) -> Result<(BuildConfig, StageOptions)> {
    let mut cfg = match &args.config {
        Some(path) => {
            let text = output::read_text(path)?;
            config::parse(&text, &path.display().to_string())?
        }
        None => BuildConfig::default(),
    };
    if let Some(target) = &args.target {
        cfg.target = target.clone();
    }
    if let Some(size) = args.unit_size {
        cfg.secondary.unit_size = size;
    }
    if let Some(spin) = args.spin_angle {
        cfg.primary.spin_angle_deg = spin;
    }
    if let Some(e) = args.expansion {
        cfg.primary.expansion = e;
    }
    if let Some(out) = &args.out {
        cfg.out = out.clone();
    }
    if let Some(direction) = args.strip_direction {
        cfg.strips.direction = direction;
    }
    if let Some(s) = args.nest_seconds {
        cfg.nest.seconds = s;
    }
    if let Some(n) = args.nest_evaluations {
        cfg.nest.evaluations = Some(n);
    }
    let size = cfg.secondary.unit_size;
    if !(size.is_finite() && size > 0.0) {
        bail!("invalid unit size {size}: must be a positive length in mm");
    }
    cfg.secondary.check().map_err(|e| anyhow!("{e}"))?;
    let solve = cfg.primary.to_solve_options()?;
    let strips = cfg.strips.to_options()?;
    cfg.profile
        .validate()
        .map_err(|e| anyhow!("profile: {e}"))?;
    let nest = cfg.nest.to_options(cfg.profile.kerf)?;
    Ok((
        cfg,
        StageOptions {
            solve,
            strips,
            nest,
        },
    ))
}

/// Load `builtin:NAME` or an OBJ/STL triangle mesh.
pub fn load_target(spec: &str) -> Result<TargetMesh> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        return sv_surface::builtin_target(name).map_err(|e| anyhow!("{e}"));
    }
    let path = Path::new(spec);
    let bytes = output::read_bytes(path)?;
    let mesh = sv_io::read_tri_mesh(&bytes, spec)?;
    Ok(TargetMesh {
        vertices: mesh.vertices,
        triangles: mesh.triangles,
    })
}

/// Run `build`. Nothing is written unless every stage succeeded.
pub fn run(args: &BuildArgs) -> Result<()> {
    let started = Instant::now();
    let (cfg, options) = resolve(args)?;
    let target = load_target(&cfg.target)?;
    let files = AtomicFiles::create(&cfg.out, &FILES)?;
    let strips_dir = AtomicDir::create(&cfg.out, "strips")?;
    let sheets_dir = AtomicDir::create(&cfg.out, "sheets")?;

    let t0 = Instant::now();
    let bar = progress_bar(args.quiet, cfg.secondary.max_iterations, "hub mesh");
    let secondary = sv_surface::build_secondary(&target, &cfg.secondary, &mut |it, energy| {
        bar.set_position(it as u64);
        bar.set_message(format!("residual {energy:.3e}"));
    });
    bar.finish_and_clear();
    let (mesh, report) = secondary.map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    let secondary_s = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let bar = progress_bar(args.quiet, options.solve.max_iterations, "primary");
    let solved = sv_frame::solve(&mesh, &options.solve, &mut |p: Progress| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("gap sum {} mm", number(p.gap_sum)));
    });
    finish(&bar);
    let solved = solved.map_err(|e| anyhow!("{}: primary solve: {e}", cfg.target))?;
    let primary_s = t1.elapsed().as_secs_f64();

    let t2 = Instant::now();
    let mut frame = solved.to_frame_file(&mesh);
    let stage = strips::run(&mut frame, &options.strips, &cfg.profile)
        .map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    let strips_json = sv_io::inline_number_arrays(&serde_json::to_string_pretty(&stage.file)?);
    for (name, text) in &stage.drawings {
        strips_dir.write(name, text)?;
    }
    let strips_s = t2.elapsed().as_secs_f64();

    let t3 = Instant::now();
    let parts: Vec<sv_export::SheetPart> = stage
        .strips
        .iter()
        .zip(&stage.profiles)
        .map(|(s, p)| sv_export::strip_sheet_part(s, p))
        .collect();
    let nested = sheets::run(
        &parts,
        &options.nest,
        Some(cfg.profile.thickness),
        &sv_export::ShopConvention::default(),
        args.quiet,
    )?;
    if let Some(l) = nested.report.left_out.first() {
        bail!("nesting: strip {} was left out: {}", l.part, l.reason);
    }
    if let Some(w) = sheets::cut_warning(&nested.report, cfg.nest.seconds) {
        eprintln!("{w}");
    }
    for (name, text) in &nested.drawings {
        sheets_dir.write(name, text)?;
    }
    let nest_json = serde_json::to_string_pretty(&nested.report)?;
    let nest_s = t3.elapsed().as_secs_f64();

    let t4 = Instant::now();
    let nest_input = sv_report::NestInput {
        report: &nested.report,
        sheet_files: &nested.sheet_files,
    };
    let report_stage = report::run(&cfg.target, &frame, &stage.file, Some(nest_input), &report)?;
    let report_s = t4.elapsed().as_secs_f64();

    let header = format!("spinvalence hub mesh of {}, mm, Z up", cfg.target);
    let mesh_obj = sv_io::write_quad_obj(&mesh, &header);
    let frame_obj = sv_io::frame_to_obj(&frame);
    let frame_json = sv_io::frame_to_json(&frame);
    let report_json = serde_json::to_string_pretty(&report)?;
    let timings = Timings {
        secondary: secondary_s,
        primary: primary_s,
        strips: strips_s,
        nest: nest_s,
        report: report_s,
        total: started.elapsed().as_secs_f64(),
    };
    let timings_json = serde_json::to_string_pretty(&timings)?;
    let strips_path = strips_dir.commit()?;
    let sheets_path = sheets_dir.commit()?;
    let mut written = files.commit(&[
        &mesh_obj,
        &frame_obj,
        &strips_json,
        &nest_json,
        &report_stage.bom,
        &report_stage.html,
        &timings_json,
        &report_json,
        &frame_json,
    ])?;
    written.insert(0, sheets_path.join(""));
    written.insert(0, strips_path.join(""));

    if !args.quiet {
        let overlaps = &solved.evaluation.overlaps;
        let min = overlaps.iter().copied().fold(f64::INFINITY, f64::min);
        let max = overlaps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let unit = report.mean_edge;
        let mut rows = summary_rows(&cfg, &report, unit, &solved.report, (min, max), &timings);
        // the stage rows go before the last two (timings and total)
        let mut stage_rows = vec![vec![
            "strips".into(),
            format!(
                "{} (longest {}, worst pin bend {:.1} deg, twist {:.1} deg)",
                stage.strips.len(),
                number(stage.strips.iter().map(|s| s.size[0]).fold(0.0, f64::max)) + " mm",
                stage.worst_pin.0.to_degrees(),
                stage.worst_pin.1.to_degrees()
            ),
        ]];
        stage_rows.extend(sheets::summary_rows(&nested.report, cfg.nest.seconds));
        let report_path = cfg.out.join("report.html").display().to_string();
        stage_rows.extend(report::summary_rows(&report_stage, &report_path));
        let at = rows.len() - 2;
        rows.splice(at..at, stage_rows);
        rows.push(vec![
            "wrote".into(),
            written
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ]);
        output::print_out(&output::table(&rows))?;
    }
    Ok(())
}

fn finish(bar: &ProgressBar) {
    bar.finish_and_clear();
}

fn summary_rows(
    cfg: &BuildConfig,
    s: &SecondaryReport,
    unit: f64,
    p: &sv_frame::SolveReport,
    overlap: (f64, f64),
    t: &Timings,
) -> Vec<Vec<String>> {
    let mm = |x: f64| format!("{} mm", number(x));
    let rows: Vec<[String; 2]> = vec![
        ["target".into(), cfg.target.clone()],
        ["units".into(), s.faces.to_string()],
        ["mean edge".into(), mm(unit)],
        [
            "planarity max".into(),
            format!("{:.5} (diagonal distance / edge)", s.planarity_max),
        ],
        [
            "conical residual max".into(),
            format!("{:.3} deg", s.conical_max_deg),
        ],
        [
            "distance to target max".into(),
            format!(
                "{} ({:.2} % of the edge)",
                mm(s.closeness_max * unit),
                100.0 * s.closeness_max
            ),
        ],
        [
            "boundary distance max".into(),
            format!(
                "{} ({:.2} % of the edge)",
                mm(s.boundary_max * unit),
                100.0 * s.boundary_max
            ),
        ],
        [
            "target area covered".into(),
            format!("{:.1} %", 100.0 * s.coverage),
        ],
        [
            "faces with edge ratio <= 1.25".into(),
            format!("{:.1} %", 100.0 * s.edge_ratio_fraction),
        ],
        ["gap max".into(), mm(p.gap_max)],
        [
            "gap sum".into(),
            format!("{} -> {}", mm(p.gap_sum_start), mm(p.gap_sum)),
        ],
        [
            "hub overlap".into(),
            format!("{} .. {}", mm(overlap.0), mm(overlap.1)),
        ],
        [
            "time secondary / primary / strips / nest / report".into(),
            format!(
                "{:.3} s / {:.3} s / {:.3} s / {:.3} s / {:.3} s",
                t.secondary, t.primary, t.strips, t.nest, t.report
            ),
        ],
        [
            "time total".into(),
            seconds(std::time::Duration::from_secs_f64(t.total)),
        ],
    ];
    rows.into_iter().map(|r| r.to_vec()).collect()
}
