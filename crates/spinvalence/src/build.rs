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
    /// How far the nesting's search went in that time: its work budget, the work done and
    /// whether the clock cut it (`sv_nest::SearchReport`; a record of the run, so here
    /// and not in `nest.json`).
    pub nest_search: sv_nest::SearchReport,
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
    if let Some(layout) = &args.layout {
        cfg.surface.layout = Some(layout.clone());
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
    let mut solve = cfg.primary.to_solve_options()?;
    let strips = cfg.strips.to_options()?;
    cfg.profile
        .validate()
        .map_err(|e| anyhow!("profile: {e}"))?;
    // the units deploy as they are cut
    solve.cut = Some(cfg.profile.cut_widths());
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

/// Load `builtin:NAME` or an OBJ/STL triangle mesh (welded, oriented and checked by
/// `sv_io::read_target`; what was repaired is said on stderr unless `quiet`), and check
/// that it is drawn in millimetres at a size that holds 2 x 2 units of `unit` mm.
pub fn load_target(spec: &str, unit: f64, quiet: bool) -> Result<TargetMesh> {
    let mesh = if let Some(name) = spec.strip_prefix("builtin:") {
        sv_surface::builtin_target(name).map_err(|e| anyhow!("{e}"))?
    } else {
        let path = Path::new(spec);
        let bytes = output::read_bytes(path)?;
        let file = sv_io::read_target(&bytes, spec)?;
        let r = file.repairs;
        if !quiet && (r.welded > 0 || r.dropped > 0 || r.flipped > 0) {
            eprintln!(
                "note: {spec}: welded {} duplicate vertices, dropped {} collapsed triangles, turned {} triangles to their neighbours' orientation",
                r.welded, r.dropped, r.flipped
            );
        }
        TargetMesh {
            vertices: file.mesh.vertices,
            triangles: file.mesh.triangles,
        }
    };
    check_units(spec, &mesh, unit)?;
    Ok(mesh)
}

/// A target too small for 2 x 2 units is most often drawn in metres or inches: say so
/// with its bounding box and what it would measure in those units.
fn check_units(spec: &str, mesh: &TargetMesh, unit: f64) -> Result<()> {
    let Some(first) = mesh.vertices.first() else {
        return Ok(());
    };
    let (lo, hi) = mesh
        .vertices
        .iter()
        .fold((*first, *first), |(a, b), p| (a.inf(p), b.sup(p)));
    let size = hi - lo;
    let area = mesh.triangles.iter().fold(0.0, |a, t| {
        let [p, q, r] = t.map(|i| mesh.vertices[i]);
        a + 0.5 * (q - p).cross(&(r - p)).norm()
    });
    if area >= 4.0 * unit * unit {
        return Ok(());
    }
    let dims = |k: f64, u: &str| {
        format!(
            "{} x {} x {} {u}",
            number(size.x * k),
            number(size.y * k),
            number(size.z * k)
        )
    };
    let mut hints = Vec::new();
    for (factor, name, flag) in [(1000.0, "metres", "m"), (25.4, "inches", "in")] {
        let area_mm = area * factor * factor;
        if area_mm >= 4.0 * unit * unit {
            hints.push(format!(
                "if it is in {name} it is {} (scale it to mm, e.g. by {factor} for {flag})",
                dims(1.0, flag)
            ));
        }
    }
    bail!(
        "{spec}: the target's bounding box is {} and its area {} m^2, too small for 2 x 2 units of {} mm; targets are read in millimetres{}",
        dims(1.0, "mm"),
        number(area * 1e-6),
        number(unit),
        if hints.is_empty() {
            String::new()
        } else {
            format!("; {}", hints.join("; "))
        }
    )
}

/// What a finished build reports back: the hub mesh goals it could not meet (empty when
/// every goal holds), one line each naming the worst place.
pub struct Outcome {
    /// Unmet goals of the hub mesh (`SecondaryReport::unmet`).
    pub unmet: Vec<String>,
    /// Where the files went.
    pub out: std::path::PathBuf,
    /// The fold check's failing rows, as one warning line (`spinvalence check DIR`).
    pub fold_warning: Option<String>,
}

/// Load the designer's coarse layout (a quad OBJ, planarity not required).
fn load_layout(path: &Path) -> Result<sv_frame::QuadMesh> {
    let bytes = output::read_bytes(path)?;
    Ok(sv_io::read_quad_obj_bytes(
        &bytes,
        &path.display().to_string(),
    )?)
}

/// Run `build`. Nothing is written unless every stage succeeded; a hub mesh that misses
/// some goals is still carried through every stage and written (the outcome names them).
/// Every hub lap as cut must be long enough to weld (AWS D1.1: at least 5 t and 25 mm).
/// Nothing is written otherwise: the error names the shortest lap and the levers, with the
/// values that would give the minimum there (the lap of a square unit grows by
/// sqrt(2) - 1 = 0.414 mm per mm of unit size and shrinks by 2 sqrt(2) = 2.83 mm per mm the
/// hub lies deeper inside its tile: docs/geometry.md, "Sizes that can be welded").
fn weldable(solved: &sv_frame::Solved, min_overlap: f64, cfg: &BuildConfig) -> Result<()> {
    let overlaps = &solved.evaluation.overlaps;
    let Some((worst, lap)) = overlaps
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
    else {
        return Ok(());
    };
    if lap >= min_overlap {
        return Ok(());
    }
    let short = overlaps.iter().filter(|&&o| o < min_overlap).count();
    let l = &solved.links[worst];
    let deficit = min_overlap - lap;
    let p = &cfg.profile;
    bail!(
        "hub laps too short to weld: {short} of {} links below the minimum overlap {} mm, \
         the shortest {} mm between units {} and {}; raise secondary.unit_size to about {:.0} mm, \
         or make the hub lie {:.1} mm less deep in its tile (profile.leg_width {} or \
         profile.rim_width {} smaller, down to their minimum web), or lower primary.min_overlap",
        overlaps.len(),
        number(min_overlap),
        number(lap),
        l.faces[0],
        l.faces[1],
        (cfg.secondary.unit_size + deficit / (2f64.sqrt() - 1.0)).ceil(),
        deficit / (2.0 * 2f64.sqrt()),
        number(p.leg_width),
        number(p.rim_width),
    )
}

pub fn run(args: &BuildArgs) -> Result<Outcome> {
    let started = Instant::now();
    let (cfg, mut options) = resolve(args)?;
    let target = load_target(&cfg.target, cfg.secondary.unit_size, args.quiet)?;
    let layout = cfg.surface.layout.as_deref().map(load_layout).transpose()?;
    let files = AtomicFiles::create(&cfg.out, &FILES)?;
    let strips_dir = AtomicDir::create(&cfg.out, "strips")?;
    let sheets_dir = AtomicDir::create(&cfg.out, "sheets")?;

    let t0 = Instant::now();
    let bar = progress_bar(args.quiet, cfg.secondary.max_iterations, "hub mesh");
    let mut tick = |it: usize, energy: f64| {
        bar.set_position(it as u64);
        bar.set_message(format!("residual {energy:.3e}"));
    };
    let secondary = match &layout {
        Some(coarse) => {
            sv_surface::build_secondary_with_layout(&target, coarse, &cfg.secondary, &mut tick)
        }
        None => sv_surface::build_secondary(&target, &cfg.secondary, &mut tick),
    };
    bar.finish_and_clear();
    let (mesh, mut report) = secondary.map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    let secondary_s = t0.elapsed().as_secs_f64();
    // the hub mesh is ours: where its planarity goal is unmet the report says so, and the
    // primary solve still deploys it (hubs are best-fit rhombi) instead of refusing
    options.solve.planarity_tolerance = options
        .solve
        .planarity_tolerance
        .max(1.01 * report.planarity_max);

    let t1 = Instant::now();
    let bar = progress_bar(args.quiet, options.solve.max_iterations, "primary");
    let solved = sv_frame::solve(&mesh, &options.solve, &mut |p: Progress| {
        bar.set_position(p.iteration as u64);
        bar.set_message(format!("gap sum {} mm", number(p.gap_sum)));
    });
    finish(&bar);
    let solved = solved.map_err(|e| anyhow!("{}: primary solve: {e}", cfg.target))?;
    let primary_s = t1.elapsed().as_secs_f64();
    let min_overlap = cfg.primary.min_overlap(&cfg.profile)?;
    if let Err(short) = weldable(&solved, min_overlap, &cfg) {
        // on a hub mesh that met its goals the parameters are to blame: nothing is written;
        // on one that did not, short laps are one more unmet goal, and everything is written
        // for the user to look at
        if report.unmet.is_empty() {
            bail!("{}: {short}", cfg.target);
        }
        report.unmet.push(short.to_string());
    }

    let t2 = Instant::now();
    let mut frame = solved.to_frame_file(&mesh);
    let stage = strips::run(&mut frame, &options.strips, &cfg.profile)
        .map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    let strips_json = sv_io::inline_number_arrays(&serde_json::to_string_pretty(&stage.file)?);
    for (name, text) in &stage.drawings {
        strips_dir.write(name, text)?;
    }
    // the parts as cut, folded at their necks into the solved poses (`spinvalence check`)
    let fold = sv_strips::fold_check(
        &frame,
        &stage.file,
        &sv_strips::FoldLimits {
            min_overlap,
            ..sv_strips::FoldLimits::for_profile(&cfg.profile)
        },
    );
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
        nest_search: nested.report.search.clone(),
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
        for (k, line) in report.unmet.iter().enumerate() {
            let name = if k == 0 { "GOALS NOT MET" } else { "" };
            rows.insert(3 + k, vec![name.into(), line.clone()]);
        }
        rows.push(vec![
            "wrote".into(),
            written
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        ]);
        output::print_out(&output::table(&rows))?;
        output::print_out(&format!(
            "fold check of the parts as cut (spinvalence check {}):\n{}",
            cfg.out.display(),
            crate::check::render(&fold)
        ))?;
    }
    let failed: Vec<String> = fold
        .rows
        .iter()
        .filter(|r| !r.ok)
        .map(|r| {
            format!(
                "{} {} (limit {}) at {}",
                r.name,
                number(r.worst),
                number(r.limit),
                r.at
            )
        })
        .collect();
    let fold_warning = (!failed.is_empty()).then(|| {
        format!(
            "warning: fold check: {} of {} rows fail on the parts as cut: {}",
            failed.len(),
            fold.rows.len(),
            failed.join("; ")
        )
    });
    Ok(Outcome {
        unmet: report.unmet.clone(),
        out: cfg.out.clone(),
        fold_warning,
    })
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
