//! `spinvalence build`: target surface -> hub mesh -> deployed frame, end to end.

use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use indicatif::ProgressBar;
use rayon::prelude::*;
use serde::Serialize;
use sv_frame::Progress;
use sv_surface::{SecondaryReport, TargetMesh};

use crate::cli::BuildArgs;
use crate::config::{self, BuildConfig, Overlap, OverlapRule};
use crate::output::{self, bounding_box, box_text, number, AtomicDir, AtomicFiles};
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
    /// Closing the joints (hub mesh and plates together).
    pub joints: f64,
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
    /// The sheet the parts are cut from, and why that one (the summary's "sheet" row).
    pub sheet: String,
    /// Why no sheet's hub laps can reach the weld minimum at this unit size, where none
    /// can: the build then leaves the joints open and names the laps as an unmet goal.
    pub unweldable: Option<String>,
}

/// The config after the command line has overridden the file, and the stage options it
/// gives, every value checked before any work starts.
pub fn resolve(args: &BuildArgs) -> Result<(BuildConfig, StageOptions)> {
    let (mut cfg, profile_given) = match &args.config {
        Some(path) => {
            let text = output::read_text(path)?;
            let file = config::read(&text, &path.display().to_string())?;
            (file.config, file.sets_profile)
        }
        None => (BuildConfig::default(), false),
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
        bail!("invalid secondary.unit_size (--unit-size) {size}: must be a positive length in mm");
    }
    cfg.secondary
        .check()
        .map_err(|e| anyhow!("secondary: {e}"))?;
    cfg.primary.min_overlap(&cfg.profile)?;
    let (sheet, unweldable) = sheet_for_unit_size(&mut cfg, profile_given);
    if !cfg.joints.close && cfg.frame != crate::config::FrameConfig::default() {
        let what = if cfg.frame.laps_touch {
            "laps_touch"
        } else {
            "overlap"
        };
        bail!("frame: parameter {what} needs the joint solve ([joints] close = true)");
    }
    // a hub lap asked for must be one the welds take
    cfg.frame
        .overlap_targets(&[], cfg.primary.min_overlap(&cfg.profile)?)?;
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
            sheet,
            unweldable,
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
        let repairs: Vec<String> = [
            (r.welded, "welded {} duplicate vertices"),
            (r.unused, "left out {} vertices no face uses"),
            (r.dropped, "dropped {} collapsed triangles"),
            (
                r.flipped,
                "turned {} triangles to their neighbours' orientation",
            ),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, text)| text.replace("{}", &n.to_string()))
        .collect();
        if !quiet && !repairs.is_empty() {
            eprintln!("note: {spec}: {}", repairs.join(", "));
        }
        TargetMesh {
            vertices: file.mesh.vertices,
            triangles: file.mesh.triangles,
        }
    };
    check_units(spec, &mesh, unit)?;
    Ok(mesh)
}

/// The sheet the build cuts, and why: the config's `[profile]` where it has one; else the
/// default, or, where the default's hub laps cannot reach the weld minimum at this unit
/// size, the thickest sheet whose least profile can (`ProfileParams::for_unit_size`: the
/// flat grid's estimate, docs/geometry.md 5.4). Where no sheet's can, not even the config's,
/// the second value says why, naming the least unit size and the weld minimum that would
/// do; the build then cuts the config's sheet, or the one with the shallowest hub.
fn sheet_for_unit_size(cfg: &mut BuildConfig, given: bool) -> (String, Option<String>) {
    let mm = |x: f64| format!("{} mm", number(x));
    let p = &cfg.profile;
    let unit = cfg.secondary.unit_size;
    // a weld minimum that cannot be read was refused before this
    let minimum = |q: &sv_strips::ProfileParams| cfg.primary.min_overlap(q).unwrap_or(0.0);
    let Some(fits) = p.for_unit_size(unit, minimum) else {
        let why = no_sheet_welds(p, unit, minimum);
        if given {
            return (
                format!("{} (the config's [profile])", mm(p.thickness)),
                Some(why),
            );
        }
        let best = p.shallowest_hub();
        let row = format!(
            "{} at its least widths (leg {}, neck {}, rim {}, slots {}), the shallowest hub \
             the profile rules allow; no sheet's hub laps reach the weld minimum at {} units",
            mm(best.thickness),
            number(best.leg_width),
            number(best.neck_width),
            number(best.rim_width),
            number(best.slot_width),
            mm(unit),
        );
        cfg.profile = best;
        return (row, Some(why));
    };
    if given {
        return (
            format!("{} (the config's [profile])", mm(p.thickness)),
            None,
        );
    }
    if fits == *p {
        return (format!("{} (the default)", mm(p.thickness)), None);
    }
    let why = format!(
        "{} at its least widths (leg {}, neck {}, rim {}, slots {}), chosen for {} units: the \
         default {} sheet's hub laps would be about {} there, short of the weld minimum {} \
         ([profile] in a config file sets the sheet)",
        mm(fits.thickness),
        number(fits.leg_width),
        number(fits.neck_width),
        number(fits.rim_width),
        number(fits.slot_width),
        mm(unit),
        mm(p.thickness),
        mm(p.flat_lap(unit)),
        mm(minimum(p)),
    );
    cfg.profile = fits;
    (why, None)
}

/// Why no sheet's hub laps reach the weld minimum at `unit` mm, with the two levers: the
/// least unit size at which the sheet with the shallowest hub (the thinnest sheet the
/// profile's rules allow, at its least widths) reaches it, and the weld minimum that sheet
/// reaches at this size, both by the flat grid's lap (docs/geometry.md 5.4); the shortest
/// lap of every curved target measured was shorter than that.
fn no_sheet_welds(
    p: &sv_strips::ProfileParams,
    unit: f64,
    minimum: impl Fn(&sv_strips::ProfileParams) -> f64,
) -> String {
    let best = p.shallowest_hub();
    let need = minimum(&best);
    let lap = best.flat_lap(unit);
    let least_unit = best.unit_for_flat_lap(need);
    let (reach, lower) = if lap > 0.0 {
        let most = (lap * 10.0).floor() / 10.0;
        (
            format!("the most is about {} mm", number(lap)),
            format!(
                ", or lower primary.min_overlap to {most:.1} mm or less (short of the AWS \
                 D1.1 lap of max(5 t, 25 mm))"
            ),
        )
    } else {
        (
            format!(
                "the hub plates miss each other by about {} mm",
                number(-lap)
            ),
            String::new(),
        )
    };
    format!(
        "secondary.unit_size {}: no sheet's hub laps reach the weld minimum {} mm at this \
         unit size: {reach} with {} mm sheet at its least widths (leg {}, rim {}, slots {}; \
         the flat grid's lap, docs/geometry.md 5.4); raise secondary.unit_size to at least \
         {:.0} mm{lower}",
        number(unit),
        number(need),
        number(best.thickness),
        number(best.leg_width),
        number(best.rim_width),
        number(best.slot_width),
        least_unit.ceil(),
    )
}

/// Units a build takes at most: ten times the 10,000 of the benchmarks. A target that
/// needs more (a site plan in mm with 300 mm units, a target in micrometres) would take
/// gigabytes and hours before a first result; it is refused at once with the unit size
/// that fits.
const MAX_UNITS: f64 = 100_000.0;

/// A designer's layout must be drawn where the target is, in the same unit: its bounding
/// box within 5 times the target's size either way, its centre within the target's
/// half-diagonal of the target's centre. Otherwise both boxes are named (a layout in
/// metres laid onto a target in mm had come out as a degenerate face of the primary solve).
fn layout_on_target(path: &Path, coarse: &sv_frame::QuadMesh, target: &TargetMesh) -> Result<()> {
    let (tl, th) = bounding_box(&target.vertices);
    let (ll, lh) = bounding_box(&coarse.vertices);
    let (t_size, l_size) = ((th - tl).norm(), (lh - ll).norm());
    let off = ((ll - tl) + (lh - th)).norm() / 2.0;
    let why = if !(0.2 * t_size..=5.0 * t_size).contains(&l_size) {
        format!(
            "its size is {} times the target's (layouts are read in millimetres, as targets)",
            number(l_size / t_size)
        )
    } else if off > 0.5 * t_size {
        format!(
            "its centre is {} mm from the target's: it does not lie on the target",
            number(off)
        )
    } else {
        return Ok(());
    };
    bail!(
        "{}: the layout's bounding box is {}, the target's {}: {why}",
        path.display(),
        box_text(&coarse.vertices),
        box_text(&target.vertices)
    )
}

/// A target too small for 2 x 2 units is most often drawn in metres or inches: say so
/// with its bounding box and what it would measure in those units. One that needs more
/// than [`MAX_UNITS`] is refused with the unit size that would fit.
fn check_units(spec: &str, mesh: &TargetMesh, unit: f64) -> Result<()> {
    if mesh.vertices.is_empty() {
        return Ok(());
    }
    let (lo, hi) = bounding_box(&mesh.vertices);
    let size = hi - lo;
    let area = mesh.triangles.iter().fold(0.0, |a, t| {
        let [p, q, r] = t.map(|i| mesh.vertices[i]);
        a + 0.5 * (q - p).cross(&(r - p)).norm()
    });
    let dims = |k: f64, u: &str| {
        format!(
            "{} x {} x {} {u}",
            number(size.x * k),
            number(size.y * k),
            number(size.z * k)
        )
    };
    let units = area / (unit * unit);
    if units > MAX_UNITS {
        bail!(
            "{spec}: the target's bounding box is {} and its area {} m^2: at {} mm it needs about {:.0} units, more than the {:.0} a build takes; raise secondary.unit_size (--unit-size) to at least {} mm, or check that the target is drawn in millimetres",
            dims(1.0, "mm"),
            number(area * 1e-6),
            number(unit),
            units,
            MAX_UNITS,
            (area / MAX_UNITS).sqrt().ceil()
        );
    }
    if units >= 4.0 {
        return Ok(());
    }
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

/// What a finished build reports back: the goals it could not meet (empty when every goal
/// holds), one line each naming the worst place.
pub struct Outcome {
    /// Unmet goals (`SecondaryReport::unmet`): the hub mesh's, then laps too short to
    /// weld, joints not closed, parts that cannot be cut or that fail the fold check.
    pub unmet: Vec<String>,
    /// Where the files went.
    pub out: std::path::PathBuf,
    /// Whether the strips could not be cut: only the hub mesh, the frame and the report
    /// were written.
    pub partial: bool,
}

/// Load the designer's coarse layout (a quad OBJ, planarity not required).
fn load_layout(path: &Path) -> Result<sv_frame::QuadMesh> {
    let bytes = output::read_bytes(path)?;
    Ok(sv_io::read_quad_obj_bytes(
        &bytes,
        &path.display().to_string(),
    )?)
}

/// Every hub lap as cut must be long enough to weld (AWS D1.1: at least 5 t and 25 mm):
/// where one is not, the error names the shortest lap and the levers, with the values that
/// would give the minimum there (the lap of a square unit grows by sqrt(2) - 1 = 0.414 mm
/// per mm of unit size and shrinks by 2 sqrt(2) = 2.83 mm per mm the hub lies deeper inside
/// its tile: docs/geometry.md, "Sizes that can be welded"); `run` takes it as an unmet goal.
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
    let shallower = deficit / (2.0 * 2f64.sqrt());
    // the hubs lap most at 45 degrees (measured on the dome: the shortest lap -9.9 mm at
    // 76 degrees, -16.7 at 78, -35.5 at 10, where 45 laps every link)
    let spin = cfg.primary.spin_angle_deg;
    let spin_lever = if (spin - 45.0).abs() > 2.0 {
        format!(
            ", or a spin angle nearer 45 degrees (asked {}: the hubs lap most at 45)",
            number(spin)
        )
    } else {
        String::new()
    };
    bail!(
        "hub laps too short to weld: {short} of {} links below the minimum overlap {} mm, \
         the shortest {} mm between the hubs of faces {} and {} (mesh.obj); raise \
         secondary.unit_size to about {:.0} mm, or make the hub lie {:.1} mm less deep in its \
         tile ({}){spin_lever}, or lower primary.min_overlap",
        overlaps.len(),
        number(min_overlap),
        number(lap),
        l.faces[0] + 1,
        l.faces[1] + 1,
        (cfg.secondary.unit_size + deficit / (2f64.sqrt() - 1.0)).ceil(),
        shallower,
        shallower_hub(&cfg.profile, shallower),
    )
}

/// How the hub can lie `by` mm less deep in its tile: narrower legs or rim where the
/// sheet's rules allow it, else the thickest sheet in 0.5 mm steps whose least profile
/// does it, with its widths.
fn shallower_hub(p: &sv_strips::ProfileParams, by: f64) -> String {
    let least = p.least_for(p.thickness);
    if least
        .as_ref()
        .is_some_and(|l| l.hub_inset() <= p.hub_inset() - by)
    {
        return format!(
            "profile.leg_width {} or profile.rim_width {} smaller, down to their minimum web",
            number(p.leg_width),
            number(p.rim_width)
        );
    }
    let thinner = p
        .thinner_least()
        .find(|l| l.hub_inset() <= p.hub_inset() - by);
    match thinner {
        Some(l) => format!(
            "the legs and rim are the narrowest {} mm sheet allows: a thinner sheet, \
             profile.thickness = {}, leg_width = {}, neck_width = {}, rim_width = {}, \
             slot_width = {}, neck_length = {}, fillet_radius = {}",
            number(p.thickness),
            number(l.thickness),
            number(l.leg_width),
            number(l.neck_width),
            number(l.rim_width),
            number(l.slot_width),
            number(l.neck_length),
            number(l.fillet_radius)
        ),
        None => format!(
            "no sheet's least profile does: the legs and rim are the narrowest {} mm sheet \
             allows",
            number(p.thickness)
        ),
    }
}

/// Run `build`. Bad input writes nothing. Unmet goals (the hub mesh's, hub laps too short to
/// weld) do not stop it: every stage runs and everything is written, the outcome naming
/// them; where the strips cannot be cut, the hub mesh, the frame and the report are still
/// written ([`write_without_strips`]). Otherwise files appear all together or not at all.
pub fn run(args: &BuildArgs) -> Result<Outcome> {
    let started = Instant::now();
    let (mut cfg, mut options) = resolve(args)?;
    let target = load_target(&cfg.target, cfg.secondary.unit_size, args.quiet)?;
    let layout = cfg.surface.layout.as_deref().map(load_layout).transpose()?;
    if let (Some(path), Some(coarse)) = (&cfg.surface.layout, &layout) {
        layout_on_target(path, coarse, &target)?;
    }
    let files = AtomicFiles::create(&cfg.out, &FILES)?;
    let strips_dir = AtomicDir::create(&cfg.out, "strips", output::DRAWINGS)?;
    let sheets_dir = AtomicDir::create(&cfg.out, "sheets", output::DRAWINGS)?;

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
    let (mesh, mut report) = secondary.map_err(|e| match (&cfg.surface.layout, &layout) {
        // the designer's layout is what is wrong: its file, not the target's
        (Some(path), _) if matches!(e, sv_surface::SurfaceError::InvalidLayout(_)) => {
            anyhow!("{}: {e}", path.display())
        }
        // a layout that does not lie on the target (another unit, another place) most
        // often: both boxes side by side
        (Some(path), Some(coarse)) => anyhow!(
            "{} with the layout {}: {e} (the target's bounding box is {}, the layout's {})",
            cfg.target,
            path.display(),
            box_text(&target.vertices),
            box_text(&coarse.vertices)
        ),
        _ => anyhow!("{}: {e}", cfg.target),
    })?;
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

    // close the joints: the hub mesh and every unit's plates moved together, so that the
    // parts as cut meet (bridges fold, plates of neighbouring strips touch)
    let t_joints = Instant::now();
    // where no sheet's laps reach the weld minimum the joint solve cannot make them (it
    // lifts short laps by a few mm, not by tens), so the joints are left open
    // where the solve itself fails in every direction (a hub mesh far from its goals can
    // shrink a tile below its cut), the primary solve's frame is kept with the joints open
    let mut joints_failed = None;
    let mut joint_notes = Vec::new();
    let (mesh, solved, joints) = if cfg.joints.close && options.unweldable.is_none() {
        let (closed, notes) = close_the_joints(
            args,
            &mut cfg,
            &mut options,
            &target,
            (&mesh, &solved),
            &mut report,
            min_overlap,
        )?;
        joint_notes = notes;
        match closed {
            Ok((mesh, solved, joint_report)) => (mesh, solved, Some(joint_report)),
            Err(why) => {
                joints_failed = Some(why);
                (mesh, solved, None)
            }
        }
    } else {
        (mesh, solved, None)
    };
    let joints_s = t_joints.elapsed().as_secs_f64();
    // laps too short to weld are an unmet goal: everything that can be made is still made
    // and written for the user to look at, and the build exits with its own code
    if let Some(why) = &options.unweldable {
        report.unmet.push(format!(
            "hub laps too short to weld: {why}; the joints were left open"
        ));
    } else {
        if let Some(why) = &joints_failed {
            report.unmet.push(format!(
                "joints not closed: {why}; the joints were left open as the primary solve deployed them"
            ));
        }
        if let Err(short) = weldable(&solved, min_overlap, &cfg) {
            report.unmet.push(short.to_string());
        }
    }
    let summary_head = |report: &SecondaryReport, frame: &sv_frame::FrameFile, t: &Timings| {
        let mut rows = summary_rows(
            &cfg,
            report,
            &options.sheet,
            &solved.report,
            &hub_overlap_text(frame, HeldLaps::of(cfg.frame.overlap)),
            t,
        );
        let at = rows.len() - 2;
        let joint = match &joints {
            Some(j) => {
                let mut joint = joint_rows(j, cfg.strips.direction, frame);
                let tried_both = cfg.joints.both_directions && args.strip_direction.is_none();
                joint.push(open_joints_row(
                    frame,
                    tried_both,
                    HeldLaps::of(cfg.frame.overlap),
                ));
                joint.extend(joint_notes.iter().cloned());
                joint
            }
            None if cfg.joints.close => vec![vec![
                "joints".into(),
                if joints_failed.is_some() {
                    "left open: closing them failed or made the hub mesh worse (GOALS NOT MET)"
                } else {
                    "left open: no sheet's hub laps reach the weld minimum at this unit size"
                }
                .into(),
            ]],
            None => Vec::new(),
        };
        rows.splice(at..at, joint);
        for (k, line) in report.unmet.iter().enumerate() {
            let name = if k == 0 { "GOALS NOT MET" } else { "" };
            rows.insert(3 + k, vec![name.into(), line.clone()]);
        }
        rows
    };

    let t2 = Instant::now();
    let mut frame = solved.to_frame_file(&mesh);
    let stage = match strips::run(&mut frame, &options.strips, &cfg.profile) {
        Ok(stage) => stage,
        Err(e) => {
            // parts that cannot be cut are never written; the hub mesh, the frame and the
            // report still are, with the reason among the unmet goals
            report.unmet.push(format!("no strips cut: {e}"));
            let timings = Timings {
                secondary: secondary_s,
                primary: primary_s,
                joints: joints_s,
                strips: t2.elapsed().as_secs_f64(),
                nest: 0.0,
                report: 0.0,
                total: started.elapsed().as_secs_f64(),
                nest_search: sv_nest::SearchReport::default(),
            };
            drop(files);
            let written = write_without_strips(
                &cfg,
                &mesh,
                &frame,
                &report,
                &timings,
                [strips_dir, sheets_dir],
            )?;
            if !args.quiet {
                let mut rows = summary_head(&report, &frame, &timings);
                let at = rows.len() - 2;
                rows.insert(
                    at,
                    vec![
                        "strips".into(),
                        "none cut (see GOALS NOT MET); strips/ and sheets/ are empty".into(),
                    ],
                );
                rows.push(vec!["wrote".into(), paths_text(&written)]);
                output::print_out(&output::table(&rows))?;
            }
            return Ok(Outcome {
                unmet: report.unmet.clone(),
                out: cfg.out.clone(),
                partial: true,
            });
        }
    };
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
    // the parts as cut are the truth: a row of their fold check that fails (an open weld,
    // a leg through a neighbour) is a goal not met, as `spinvalence check DIR` says
    if let Some(failed) = fold_failures(&fold) {
        report.unmet.push(failed);
    }

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
    let report_stage = report::run(
        &cfg.target,
        &frame,
        &stage.file,
        Some(nest_input),
        &report,
        Some(&fold),
    )?;
    let report_s = t4.elapsed().as_secs_f64();

    let [mesh_obj, frame_obj, frame_json] = frame_texts(&cfg.target, &mesh, &frame);
    let report_json = serde_json::to_string_pretty(&ReportJson {
        hub_mesh: &report,
        fold_check: Some(&fold),
    })?;
    let timings = Timings {
        secondary: secondary_s,
        primary: primary_s,
        joints: joints_s,
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
        let mut rows = summary_head(&report, &frame, &timings);
        // the stage rows go before the last two (timings and total)
        let mut stage_rows = vec![vec!["strips".into(), strips_row(&stage, &frame)]];
        stage_rows.extend(sheets::summary_rows(&nested.report, cfg.nest.seconds));
        let report_path = cfg.out.join("report.html").display().to_string();
        stage_rows.extend(report::summary_rows(&report_stage, &report_path));
        let at = rows.len() - 2;
        rows.splice(at..at, stage_rows);
        rows.push(vec!["wrote".into(), paths_text(&written)]);
        output::print_out(&output::table(&rows))?;
        output::print_out(&format!(
            "fold check of the parts as cut (spinvalence check {}):\n{}",
            cfg.out.display(),
            crate::check::render(&fold)
        ))?;
    }
    Ok(Outcome {
        unmet: report.unmet.clone(),
        out: cfg.out.clone(),
        partial: false,
    })
}

/// `report.json`: the hub mesh against the target (the fields of `SecondaryReport`, at the
/// top level as before) and, where the strips were cut, the fold check of the parts as cut
/// (`spinvalence check DIR`'s rows).
#[derive(Serialize)]
struct ReportJson<'a> {
    #[serde(flatten)]
    hub_mesh: &'a SecondaryReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    fold_check: Option<&'a sv_frame::CheckReport>,
}

/// The summary's `strips` row: how many, the longest, the worst pin bend and twist, and
/// the bridges that could not be cut.
fn strips_row(stage: &strips::StripsStage, frame: &sv_frame::FrameFile) -> String {
    let mut row = format!(
        "{} (longest {}, worst pin bend {:.1} deg, twist {:.1} deg)",
        stage.strips.len(),
        number(stage.strips.iter().map(|s| s.size[0]).fold(0.0, f64::max)) + " mm",
        stage.worst_pin.0.to_degrees(),
        stage.worst_pin.1.to_degrees()
    );
    if !stage.breaks.is_empty() {
        let named: Vec<String> = stage
            .breaks
            .iter()
            .take(3)
            .map(|&units| link_name(frame, units))
            .collect();
        row.push_str(&format!(
            "; {} bridges could not be cut (facing sides overlap too little): the strips \
             end there, welded on site ({}{})",
            stage.breaks.len(),
            named.join("; "),
            if stage.breaks.len() > 3 { "; ..." } else { "" }
        ));
    }
    row
}

/// The fold check's failing rows as one unmet goal, if any fails.
fn fold_failures(fold: &sv_frame::CheckReport) -> Option<String> {
    let failed = crate::check::failures(fold);
    (!failed.is_empty()).then(|| {
        format!(
            "fold check: {} of {} rows fail on the parts as cut: {}",
            failed.len(),
            fold.rows.len(),
            failed.join("; ")
        )
    })
}

fn paths_text(paths: &[std::path::PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(", ")
}

/// The files of a build whose strips could not be cut: the hub mesh, the frame and the
/// report (without strips and sheets) with the timings. `strips/` and `sheets/` are left
/// empty and `strips.json`, `nest.json` and `bom.csv` removed, so that no part of an
/// earlier build in the directory passes for one of this build.
fn write_without_strips(
    cfg: &BuildConfig,
    mesh: &sv_frame::QuadMesh,
    frame: &sv_frame::FrameFile,
    report: &SecondaryReport,
    timings: &Timings,
    dirs: [AtomicDir; 2],
) -> Result<Vec<std::path::PathBuf>> {
    let names = [
        "mesh.obj",
        "frame.obj",
        "report.html",
        "timings.json",
        "report.json",
        "frame.json",
    ];
    let files = AtomicFiles::create(&cfg.out, &names)?;
    let no_strips = sv_strips::StripsFile::new(
        &[],
        &[],
        &cfg.profile,
        frame.params.expansion,
        &sv_strips::StripOptions::default(),
    );
    let html = report::run(&cfg.target, frame, &no_strips, None, report, None)?.html;
    let [mesh_obj, frame_obj, frame_json] = frame_texts(&cfg.target, mesh, frame);
    let written = files.commit(&[
        &mesh_obj,
        &frame_obj,
        &html,
        &serde_json::to_string_pretty(timings)?,
        &serde_json::to_string_pretty(&ReportJson {
            hub_mesh: report,
            fold_check: None,
        })?,
        &frame_json,
    ])?;
    for dir in dirs {
        dir.commit()?;
    }
    for name in ["strips.json", "nest.json", "bom.csv"] {
        let path = cfg.out.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                bail!("{}: {}", path.display(), output::io_message(&e))
            }
            _ => {}
        }
    }
    Ok(written)
}

/// The texts of mesh.obj, frame.obj and frame.json: the hub mesh of `target` and the frame
/// on it.
fn frame_texts(
    target: &str,
    mesh: &sv_frame::QuadMesh,
    frame: &sv_frame::FrameFile,
) -> [String; 3] {
    let header = format!("spinvalence hub mesh of {target}, mm, Z up");
    [
        sv_io::write_quad_obj(mesh, &header),
        sv_io::frame_to_obj(frame),
        sv_io::frame_to_json(frame),
    ]
}

/// What closing the joints gives: the moved hub mesh, the frame on it, and the report.
type Closed = (sv_frame::QuadMesh, sv_frame::Solved, sv_frame::JointReport);
/// One strip direction's joint solve: how well its joints hold, the direction and the
/// frame, or why it failed.
type Attempt = std::result::Result<Kept, String>;
/// Rows of the summary table: a name and its text.
type SummaryRows = Vec<Vec<String>>;
/// A strip direction's joint solve that could be kept: its score, direction and frame.
type Kept = (JointScore, sv_strips::StripDirection, Closed);

/// Where the kept strip direction ends with joints outside their limits, but none by more
/// than this many times (a weld at most 3 mm apart against 1.5), every direction is solved
/// once more with twice the iterations (`[joints] longer_solve`): at 300 mm the torus patch
/// ended with 6 welds open (2.77 mm) after 250 iterations and closed every joint with 500.
const LONGER_SOLVE_WITHIN: f64 = 2.0;

/// The joint solve of a build (`[joints] close`): the hub mesh and every unit's plates
/// moved together so that the parts as cut meet, in the strips' direction the command line
/// names or, unless it does, in the better of both; with the hub laps held to one length,
/// each length of `[frame] overlap` in turn until every joint holds. The strips' direction
/// goes into `cfg` and `options`; `report` is measured again on the moved hub mesh. The
/// inner error says why the solve failed in every direction tried (the outer one is the
/// configuration's); the rows are the summary's (the lengths tried, the longer solve).
fn close_the_joints(
    args: &BuildArgs,
    cfg: &mut BuildConfig,
    options: &mut StageOptions,
    target: &TargetMesh,
    (mesh, solved): (&sv_frame::QuadMesh, &sv_frame::Solved),
    report: &mut SecondaryReport,
    min_overlap: f64,
) -> Result<(std::result::Result<Closed, String>, SummaryRows)> {
    let frame0 = solved.to_frame_file(mesh);
    let surface =
        sv_surface::TargetSurface::new(target, mesh).map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    let p = &cfg.profile;
    let laps = cfg
        .frame
        .overlap_targets(&solved.evaluation.overlaps, min_overlap)?;
    let (short, long) = sv_surface::Goals::default().side_range;
    let unit = cfg.secondary.unit_size;
    let joint_options = sv_frame::JointOptions {
        max_iterations: cfg.joints.max_iterations,
        split_iterations: cfg.joints.split_iterations,
        min_overlap,
        face_sides: Some((short * unit, long * unit)),
        laps_touch: cfg.frame.laps_touch,
        limits: p.joint_limits(),
        bridge_width: p.neck_width,
        bridge_room: 2.0 * p.neck_width,
        thickness: p.thickness,
        ..sv_frame::JointOptions::default()
    };
    // the strips' direction decides which joints are bridges: unless the command line
    // names one, both are tried and the one whose joints hold better is kept
    let first = cfg.strips.direction;
    let directions = if cfg.joints.both_directions && args.strip_direction.is_none() {
        vec![first, other_direction(first)]
    } else {
        vec![first]
    };
    // the directions are solved side by side (each is deterministic on its own; the
    // best is chosen in the order above), their bars drawn together
    let bars = indicatif::MultiProgress::new();
    let solve_in = |direction: sv_strips::StripDirection,
                    max_iterations: usize,
                    overlap: Option<sv_frame::LapGoal>|
     -> Result<Attempt> {
        let strip_options = sv_strips::StripOptions {
            direction,
            ..options.strips.clone()
        };
        let plan = sv_strips::strip_plan(&frame0, &strip_options)
            .map_err(|e| anyhow!("{}: strips: {e}", cfg.target))?;
        let joint_options = sv_frame::JointOptions {
            pieces: plan.pieces,
            max_iterations,
            overlap,
            ..joint_options.clone()
        };
        let mut what = format!("joints, strips along {}", direction_name(direction));
        if let Some(goal) = &overlap {
            what.push_str(&format!(", laps {} mm", number(goal.length)));
        }
        let bar = progress_bar(args.quiet, joint_options.max_iterations, &what);
        let bar = if bar.is_hidden() { bar } else { bars.add(bar) };
        let closed = sv_frame::close_joints(
            mesh,
            solved,
            &surface,
            &plan.bridges,
            &joint_options,
            &mut |it, energy| {
                // rounds after bridges are split run past the planned iterations
                if it as u64 > bar.length().unwrap_or(0) {
                    bar.set_length((it + joint_options.split_iterations) as u64);
                }
                bar.set_position(it as u64);
                bar.set_message(format!("residual {energy:.3e}"));
            },
        );
        finish(&bar);
        Ok(match closed {
            Ok(closed) => {
                let score = JointScore::of(&closed, &joint_options.limits, min_overlap);
                Ok((score, direction, closed))
            }
            Err(e) => Err(format!("strips along {}: {e}", direction_name(direction))),
        })
    };
    // the best of every direction tried with `max_iterations` and the hub laps held to
    // `overlap`: the first kept where both hold as well; where none could be solved, why,
    // for each
    let best_of = |max_iterations: usize,
                   overlap: Option<sv_frame::LapGoal>|
     -> Result<std::result::Result<Kept, Vec<String>>> {
        let attempts: Vec<Result<Attempt>> = directions
            .par_iter()
            .map(|&direction| solve_in(direction, max_iterations, overlap))
            .collect();
        let mut best: Option<Kept> = None;
        let mut failed = Vec::new();
        for attempt in attempts {
            match attempt? {
                Ok((score, direction, closed)) => {
                    if best.as_ref().is_none_or(|(s, _, _)| score.better_than(s)) {
                        best = Some((score, direction, closed));
                    }
                }
                Err(why) => failed.push(why),
            }
        }
        Ok(best.ok_or(failed))
    };
    // the hub laps held to one length: each length in turn until every joint holds, the
    // best kept (free laps: one solve)
    let mut notes = Vec::new();
    let goals: Vec<Option<sv_frame::LapGoal>> = if laps.is_empty() {
        vec![None]
    } else {
        laps.into_iter().map(Some).collect()
    };
    let mut best: std::result::Result<Kept, Vec<String>> = Err(Vec::new());
    let mut tried = Vec::new();
    for goal in &goals {
        let attempt = best_of(cfg.joints.max_iterations, *goal)?;
        let holds = matches!(&attempt, Ok((s, _, _)) if s.holds());
        if let Some(goal) = goal {
            tried.push(format!("{} mm: {}", number(goal.length), outcome(&attempt)));
        }
        best = match (best, attempt) {
            (Ok(b), Ok(a)) if a.0.better_than(&b.0) => Ok(a),
            (Ok(b), _) => Ok(b),
            (Err(_), Ok(a)) => Ok(a),
            (Err(mut why), Err(more)) => {
                why.extend(more);
                Err(why)
            }
        };
        if holds {
            break;
        }
    }
    if goals.len() > 1 {
        let kept = match &best {
            Ok((_, _, (_, solved, _))) => solved
                .joints
                .as_ref()
                .and_then(|j| j.hub_lap)
                .map_or("none".into(), |g| format!("{} mm", number(g.length))),
            Err(_) => "none".into(),
        };
        notes.push(vec![
            "hub lap lengths".into(),
            format!(
                "tried until every joint holds: {}; kept {kept}",
                tried.join("; ")
            ),
        ]);
    }
    // joints left just outside their limits: every direction once more with twice the
    // iterations (the laps held to the kept length), kept where it holds better
    if let Ok((score, _, (_, first_solved, first))) = &best {
        if cfg.joints.longer_solve && score.nearly_holds() {
            let iterations = 2 * cfg.joints.max_iterations;
            let overlap = first_solved.joints.as_ref().and_then(|j| j.hub_lap);
            let again = best_of(iterations, overlap)?;
            let after = outcome(&again);
            let kept = matches!(&again, Ok((s, _, _)) if s.better_than(score));
            let verdict = if kept {
                "kept"
            } else {
                "not kept (it held no better)"
            };
            notes.push(vec![
                "longer solve".into(),
                format!(
                    "{} after {} iterations, none past {LONGER_SOLVE_WITHIN} times its limit; \
                     solved again with max_iterations {iterations}: {after}, {verdict}",
                    score.describe(),
                    first.iterations,
                ),
            ]);
            if kept {
                best = again;
            }
        }
    }
    let (_, direction, (mesh, solved, joint_report)) = match best {
        Ok(kept) => kept,
        Err(failed) => return Ok((Err(failed.join("; ")), notes)),
    };
    // the hub mesh moved: its goals are measured again (conicality, the paper's stand-in
    // for tiles that can meet, is not held where the joints themselves are closed)
    let mut again = sv_surface::measure_hub_mesh(surface.index(), &mesh, cfg.secondary.unit_size)
        .map_err(|e| anyhow!("{}: {e}", cfg.target))?;
    options.strips.direction = direction;
    cfg.strips.direction = direction;
    again.unmet.retain(|u| !u.starts_with("conical"));
    again.iterations = report.iterations;
    again.layout = std::mem::take(&mut report.layout);
    *report = again;
    Ok((Ok((mesh, solved, joint_report)), notes))
}

/// How the best of the strip directions held, in words (the summary's rows): its score and
/// direction, or why every direction failed.
fn outcome(best: &std::result::Result<Kept, Vec<String>>) -> String {
    match best {
        Ok((s, d, _)) => format!("{} (strips along {})", s.describe(), direction_name(*d)),
        Err(why) => format!("failed ({})", why.join("; ")),
    }
}

fn direction_name(d: sv_strips::StripDirection) -> &'static str {
    match d {
        sv_strips::StripDirection::U => "u",
        sv_strips::StripDirection::V => "v",
    }
}

fn other_direction(d: sv_strips::StripDirection) -> sv_strips::StripDirection {
    match d {
        sv_strips::StripDirection::U => sv_strips::StripDirection::V,
        sv_strips::StripDirection::V => sv_strips::StripDirection::U,
    }
}

/// How well a frame's joints hold: how many hub laps are below the weld minimum (a build
/// with any is not written), then whether any joint is outside its limits, then how many
/// joints the strips do not make as planned (outside their limits, or bridges split and
/// welded on site instead), then the worst excess as a multiple of its limit.
#[derive(Clone, Copy, Debug)]
struct JointScore {
    short_laps: usize,
    failing: usize,
    splits: usize,
    worst: f64,
}

impl JointScore {
    fn of((_, solved, report): &Closed, limits: &sv_frame::JointLimits, min_overlap: f64) -> Self {
        let records = solved.joints.as_ref().map_or(&[][..], |j| &j.records[..]);
        Self {
            short_laps: solved
                .evaluation
                .overlaps
                .iter()
                .filter(|&&o| o < min_overlap)
                .count(),
            failing: records.iter().filter(|j| !limits.holds(j)).count(),
            splits: report.splits.len(),
            worst: records.iter().map(|j| limits.excess(j)).fold(0.0, f64::max),
        }
    }

    /// The key, least best: 87 bridges split to leave 4 welds open is worse than none
    /// split and 5 open (the saddle at 300 mm), but a frame whose joints all hold is better
    /// than any that does not.
    fn key(&self) -> (usize, bool, usize, f64) {
        (
            self.short_laps,
            self.failing > 0,
            self.failing + self.splits,
            self.worst,
        )
    }

    fn better_than(&self, other: &Self) -> bool {
        self.key() < other.key()
    }

    /// The score in words: `3 joints outside their limits (the worst 1.78 times its limit), 2
    /// bridges split`.
    fn describe(&self) -> String {
        format!(
            "{} joints outside their limits (the worst {:.2} times its limit), {} bridges split",
            self.failing, self.worst, self.splits
        )
    }

    /// Every joint within its limits and every hub lap long enough to weld.
    fn holds(&self) -> bool {
        self.short_laps == 0 && self.failing == 0
    }

    /// Joints outside their limits, but none by more than [`LONGER_SOLVE_WITHIN`] times,
    /// and every hub lap long enough to weld.
    fn nearly_holds(&self) -> bool {
        self.short_laps == 0 && self.failing > 0 && self.worst <= LONGER_SOLVE_WITHIN
    }
}

/// The summary's rows of the joint solve: the worst bridge and weld, before and after.
/// The strips are split where the solve could not make a bridge: those are named with how
/// far off they were.
fn joint_rows(
    j: &sv_frame::JointReport,
    d: sv_strips::StripDirection,
    frame: &sv_frame::FrameFile,
) -> Vec<Vec<String>> {
    let (a, b) = (&j.start, &j.end);
    let mut bridges = format!(
        "strips along {}: apart {} -> {} mm, bent {:.1} -> {:.1} deg, twisted {:.1} -> {:.1} deg",
        direction_name(d),
        number(a.bridge_gap),
        number(b.bridge_gap),
        a.bridge_bend.to_degrees(),
        b.bridge_bend.to_degrees(),
        a.bridge_twist.to_degrees(),
        b.bridge_twist.to_degrees()
    );
    if !j.splits.is_empty() {
        let named: Vec<String> = j
            .splits
            .iter()
            .take(3)
            .filter_map(|(l, r)| {
                Some(format!(
                    "{} apart {} mm, bent {:.1} deg",
                    link_name(frame, frame.links.get(*l)?.units),
                    number(r.gap),
                    r.bend.abs().to_degrees()
                ))
            })
            .collect();
        bridges.push_str(&format!(
            "; {} bridges the solve could not make: the strips are split there and welded on \
             site ({}{})",
            j.splits.len(),
            named.join("; "),
            if j.splits.len() > 3 { "; ..." } else { "" }
        ));
    }
    let mut rows = vec![
        vec!["bridges (in strips)".into(), bridges],
        vec![
            "welds (between strips)".into(),
            format!(
                "apart {} -> {} mm, plates into each other (here and across bridges' slots) {} -> {} \
                 mm ({} iterations)",
                number(a.weld_gap),
                number(b.weld_gap),
                number(a.collision),
                number(b.collision),
                j.iterations
            ),
        ],
    ];
    rows.extend(spin_row(frame));
    rows
}

/// The spin the hubs were given, where the joint solve turned them from the one asked
/// (`units[].spin`): the asked angle and the range built, so that a frame asked at 10
/// degrees and built at 17-25 says so.
fn spin_row(frame: &sv_frame::FrameFile) -> Option<Vec<String>> {
    let spins: Vec<f64> = frame.units.iter().filter_map(|u| u.spin).collect();
    let lo = spins.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = spins.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (!spins.is_empty()).then(|| {
        vec![
            "spin angle".into(),
            format!(
                "{:.1} deg asked; the hubs turned to {:.1} .. {:.1} deg to close the joints \
                 (frame.json units[].spin)",
                frame.params.spin_angle.to_degrees(),
                lo.to_degrees(),
                hi.to_degrees()
            ),
        ]
    })
}

/// A link as the summary names it: its two units' ids, `A01-02 - A03-02`.
fn link_name(frame: &sv_frame::FrameFile, units: [usize; 2]) -> String {
    let id = |u: usize| frame.units.get(u).map_or("?", |r| r.id.as_str());
    format!("{} - {}", id(units[0]), id(units[1]))
}

/// The summary's row of the joints outside their limits: how many of each kind, the worst
/// three by their excess over the limit (naming the units), and what would help.
fn open_joints_row(frame: &sv_frame::FrameFile, tried_both: bool, laps: HeldLaps) -> Vec<String> {
    let limits = frame.params.joint_limits.unwrap_or_default();
    let mut open: Vec<(f64, String)> = Vec::new();
    let (mut bridges, mut welds) = (0, 0);
    // open welds whose plates turn in their plane more than a bridge may: edge to edge at
    // an angle, one end opens while the other runs into its neighbour
    let mut turned = (0, 0.0, String::new());
    let mut cut = Vec::new();
    for l in &frame.links {
        let Some(j) = l.joint else { continue };
        let strip = |u: usize| frame.units.get(u).map(|r| r.strip.as_str());
        if j.kind == sv_frame::JointKind::Bridge && strip(l.units[0]) != strip(l.units[1]) {
            cut.push(link_name(frame, l.units));
        }
        if limits.holds(&j) {
            continue;
        }
        let name = link_name(frame, l.units);
        match j.kind {
            sv_frame::JointKind::Bridge => bridges += 1,
            sv_frame::JointKind::Weld => welds += 1,
        }
        if j.kind == sv_frame::JointKind::Weld && j.bend.abs() > limits.bend {
            turned.0 += 1;
            if j.bend.abs() > turned.1 {
                turned = (turned.0, j.bend.abs(), name.clone());
            }
        }
        let (excess, measure) = limits.worst(&j);
        let what = match measure {
            sv_frame::JointMeasure::Gap => format!("apart {} mm", number(j.gap)),
            sv_frame::JointMeasure::Bend => format!("bent {:.1} deg", j.bend.abs().to_degrees()),
            sv_frame::JointMeasure::Twist => {
                format!("twisted {:.1} deg", j.twist.abs().to_degrees())
            }
            sv_frame::JointMeasure::Collision => {
                let across = if j.kind == sv_frame::JointKind::Bridge {
                    " across the slot"
                } else {
                    ""
                };
                format!("{} mm into each other{across}", number(j.collision))
            }
        };
        open.push((excess, format!("{name} {what}")));
    }
    open.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut text = if open.is_empty() {
        "none: every bridge and weld within its limits".to_string()
    } else {
        let worst: Vec<&str> = open.iter().take(3).map(|(_, s)| s.as_str()).collect();
        format!(
            "{bridges} bridges, {welds} welds of {} (worst: {}); {}",
            frame.links.len(),
            worst.join("; "),
            open_joint_levers(tried_both, laps)
        )
    };
    if turned.0 > 0 {
        text.push_str(&format!(
            "; at {} open welds the plates meet at an angle in their plane of more than {:.1} deg \
             (up to {:.1} deg at {}): edge to edge at such an angle one end opens while the \
             other runs into its neighbour",
            turned.0,
            limits.bend.to_degrees(),
            turned.1.to_degrees(),
            turned.2
        ));
    }
    if !cut.is_empty() {
        // the tiles the solve stretched made a piece longer than the sheet: the strips
        // stage cut it at a joint closed as a bridge, welded on site instead
        text.push_str(&format!(
            "; {} bridges cut for the sheet length, welded on site at their fold ({})",
            cut.len(),
            cut.join(", ")
        ));
    }
    vec!["joints outside limits".into(), text]
}

/// How the hub laps were held while the joints closed (`[frame] overlap`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum HeldLaps {
    /// Free.
    Free,
    /// Held to one length the solve chose (`"constant"`).
    Constant,
    /// Held to the length asked (mm).
    Asked,
}

impl HeldLaps {
    fn of(overlap: Overlap) -> Self {
        match overlap {
            Overlap::Rule(OverlapRule::Free) => HeldLaps::Free,
            Overlap::Rule(OverlapRule::Constant) => HeldLaps::Constant,
            Overlap::Length(_) => HeldLaps::Asked,
        }
    }
}

/// What may close the joints a build left open: more iterations, the other strip direction
/// where only one was tried and, where every hub lap was held to one length, laps left free
/// or a wider band (at 300 mm the built-in pavilion, dome and vault close every joint with
/// free laps and leave 1 / 1 / 5 welds open with the laps held within 1 mm). A larger unit
/// size only where the lap was asked in mm (the pavilion with 60 mm laps: 59 welds open at
/// 300 mm, none at 330 mm); with laps free or chosen by the solve it opened more welds, as
/// did another spin angle (docs/geometry.md 6.9).
fn open_joint_levers(tried_both: bool, laps: HeldLaps) -> String {
    let mut levers = vec!["more [joints] max_iterations"];
    if !tried_both {
        levers.push("the other --strip-direction");
    }
    if laps == HeldLaps::Asked {
        levers.push("a larger unit size (the lap asked a smaller share of it)");
    }
    if laps != HeldLaps::Free {
        levers.push("[frame] overlap = \"free\" or a wider overlap_tolerance");
    }
    let held_laps = laps != HeldLaps::Free;
    let last = levers.pop().unwrap_or_default();
    let mut text = if levers.is_empty() {
        format!("{last} may close them")
    } else {
        format!("{} or {last} may close them", levers.join(", "))
    };
    if held_laps {
        text.push_str(" (the hub laps held to one length cost closure)");
    }
    if tried_both {
        text.push_str(" (both strip directions were tried, the one that held better is kept)");
    }
    text
}

fn finish(bar: &ProgressBar) {
    bar.finish_and_clear();
}

/// The summary's hub laps: their range, and with one lap asked for every link
/// (`params.hub_lap`) whether every lap is within its tolerance, else how many are not, the
/// farthest three and the levers. A larger unit size is one only for a lap asked in mm (a
/// fixed length, a smaller share of a larger unit: the pavilion with 75 mm laps had 419 of
/// 487 outside the band at 300 mm, none at 360 mm); the lap the solve chooses grows with
/// the unit.
fn hub_overlap_text(frame: &sv_frame::FrameFile, held: HeldLaps) -> String {
    let laps = frame.links.iter().map(|l| l.hub_overlap);
    let min = laps.clone().fold(f64::INFINITY, f64::min);
    let max = laps.fold(f64::NEG_INFINITY, f64::max);
    let mm = |x: f64| format!("{} mm", number(x));
    let mut text = format!("{} .. {} (spread {})", mm(min), mm(max), mm(max - min));
    let Some(goal) = frame.params.hub_lap else {
        return text;
    };
    let mut off: Vec<(f64, String)> = frame
        .links
        .iter()
        .map(|l| (l.hub_overlap - goal.length, link_name(frame, l.units)))
        .filter(|(d, _)| d.is_nan() || d.abs() > goal.tolerance)
        .collect();
    off.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    let asked = format!("{} +- {}", number(goal.length), mm(goal.tolerance));
    if off.is_empty() {
        text.push_str(&format!(
            "; every lap within {asked}: one gauge block checks them all"
        ));
    } else {
        let worst: Vec<String> = off
            .iter()
            .take(3)
            .map(|(d, name)| format!("{name} {:+.2} mm", d))
            .collect();
        let levers = if held == HeldLaps::Asked {
            "a wider [frame] overlap_tolerance or a larger unit size"
        } else {
            "a wider [frame] overlap_tolerance"
        };
        text.push_str(&format!(
            "; {} of {} laps outside {asked} ({}): {levers} may bring them in",
            off.len(),
            frame.links.len(),
            worst.join(", ")
        ));
    }
    text
}

fn summary_rows(
    cfg: &BuildConfig,
    s: &SecondaryReport,
    sheet: &str,
    p: &sv_frame::SolveReport,
    overlap: &str,
    t: &Timings,
) -> Vec<Vec<String>> {
    let mm = |x: f64| format!("{} mm", number(x));
    let unit = s.mean_edge;
    let rows: Vec<[String; 2]> = vec![
        ["target".into(), cfg.target.clone()],
        ["units".into(), s.faces.to_string()],
        ["layout".into(), s.layout.clone()],
        ["mean edge".into(), mm(unit)],
        ["sheet".into(), sheet.into()],
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
        ["hub overlap".into(), overlap.into()],
        [
            "time secondary / primary / joints / strips / nest / report".into(),
            format!(
                "{:.3} s / {:.3} s / {:.3} s / {:.3} s / {:.3} s / {:.3} s",
                t.secondary, t.primary, t.joints, t.strips, t.nest, t.report
            ),
        ],
        [
            "time total".into(),
            seconds(std::time::Duration::from_secs_f64(t.total)),
        ],
    ];
    rows.into_iter().map(|r| r.to_vec()).collect()
}

#[cfg(test)]
mod tests {
    use super::{hub_overlap_text, open_joint_levers, shallower_hub, HeldLaps};
    use sv_strips::ProfileParams;

    /// The value after `key = ` in `text`.
    fn value(text: &str, key: &str) -> f64 {
        let at = text.find(&format!("{key} = ")).unwrap() + key.len() + 3;
        text[at..]
            .split([',', ')', ' '])
            .next()
            .unwrap()
            .parse()
            .unwrap()
    }

    #[test]
    fn a_hub_too_deep_names_narrower_legs_or_the_sheet_that_allows_them() {
        // legs wider than the sheet needs: narrower legs
        let wide = ProfileParams {
            leg_width: 20.0,
            ..ProfileParams::default()
        };
        assert!(shallower_hub(&wide, 1.0).contains("profile.leg_width 20"));
        // the default's legs and rim are the least 2.5 mm sheet allows: a thinner sheet,
        // whose widths (the fillets too: as copied from the message) are valid and put the
        // hub at least 1.3 mm less deep
        let d = ProfileParams::default();
        let text = shallower_hub(&d, 1.3);
        let named = ProfileParams {
            thickness: value(&text, "profile.thickness"),
            leg_width: value(&text, "leg_width"),
            neck_width: value(&text, "neck_width"),
            rim_width: value(&text, "rim_width"),
            slot_width: value(&text, "slot_width"),
            neck_length: value(&text, "neck_length"),
            fillet_radius: value(&text, "fillet_radius"),
            ..d.clone()
        };
        assert_eq!(named.thickness, 2.0, "{text}");
        named.validate().unwrap();
        // half the joint slot, the rim, two slots and the leg
        let inset =
            named.neck_length / 2.0 + named.rim_width + 2.0 * named.slot_width + named.leg_width;
        assert!(inset <= 28.125 - 1.3, "{inset}: {text}");
        // more than any sheet gives: said so
        assert!(
            shallower_hub(&d, 20.0).contains("no sheet"),
            "{}",
            shallower_hub(&d, 20.0)
        );
    }

    #[test]
    fn open_joints_name_the_laps_held_to_one_length_and_the_direction_not_tried() {
        let both = open_joint_levers(true, HeldLaps::Free);
        assert!(both.contains("both strip directions were tried"), "{both}");
        assert!(!both.contains("--strip-direction"), "{both}");
        assert!(!both.contains("overlap"), "{both}");
        let held = open_joint_levers(false, HeldLaps::Constant);
        assert!(held.contains("the other --strip-direction"), "{held}");
        assert!(held.contains("[frame] overlap = \"free\""), "{held}");
        assert!(held.contains("cost closure"), "{held}");
        assert!(held.ends_with("may close them (the hub laps held to one length cost closure)"));
        // measured to open more welds, not fewer: not offered
        for text in [&both, &held] {
            assert!(
                !text.contains("unit size") && !text.contains("spin"),
                "{text}"
            );
        }
        // with the lap asked in mm, a larger unit closed them (the pavilion, 60 mm laps)
        let asked = open_joint_levers(true, HeldLaps::Asked);
        assert!(asked.contains("a larger unit size"), "{asked}");
        assert!(asked.contains("[frame] overlap = \"free\""), "{asked}");
        assert!(!asked.contains("spin"), "{asked}");
        assert_eq!(
            open_joint_levers(false, HeldLaps::Free),
            "more [joints] max_iterations or the other --strip-direction may close them"
        );
    }

    #[test]
    fn laps_outside_the_band_name_a_larger_unit_only_for_a_lap_asked_in_mm() {
        let mesh = sv_frame::QuadMesh::sphere_cap(4, 4, 3000.0, 300.0);
        let mut frame = sv_frame::solve(&mesh, &sv_frame::SolveOptions::default(), &mut |_| {})
            .unwrap()
            .to_frame_file(&mesh);
        let laps: Vec<f64> = frame.links.iter().map(|l| l.hub_overlap).collect();
        let (min, max) = laps
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &l| {
                (a.min(l), b.max(l))
            });
        // free laps: the range only
        frame.params.hub_lap = None;
        let free = hub_overlap_text(&frame, HeldLaps::Free);
        assert!(
            !free.contains("outside") && !free.contains("gauge"),
            "{free}"
        );
        // every lap within the band
        frame.params.hub_lap = Some(sv_frame::LapGoal {
            length: 0.5 * (min + max),
            tolerance: 0.5 * (max - min) + 0.01,
        });
        let within = hub_overlap_text(&frame, HeldLaps::Constant);
        assert!(
            within.contains("one gauge block checks them all"),
            "{within}"
        );
        // a lap longer than any: every link outside, the lever by how the lap was held
        frame.params.hub_lap = Some(sv_frame::LapGoal {
            length: max + 20.0,
            tolerance: 1.0,
        });
        let outside = format!("{} of {} laps outside", laps.len(), laps.len());
        let asked = hub_overlap_text(&frame, HeldLaps::Asked);
        assert!(asked.contains(&outside), "{asked}");
        assert!(
            asked.contains("or a larger unit size may bring them in"),
            "{asked}"
        );
        let chosen = hub_overlap_text(&frame, HeldLaps::Constant);
        assert!(chosen.contains(&outside), "{chosen}");
        assert!(
            chosen.contains("overlap_tolerance may bring them in"),
            "{chosen}"
        );
        assert!(!chosen.contains("unit size"), "{chosen}");
    }
}
