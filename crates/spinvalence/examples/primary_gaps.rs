//! The primary solve on the issue-3 targets: largest and summed link gaps per target and
//! unit size, with the solve time (docs/geometry.md, 3.5).
//!
//! ```text
//! cargo run --release -p spinvalence --example primary_gaps -- [--cache DIR] [--worst N] \
//!     UNIT:TARGET ...        # e.g. 300:builtin:pavilion 150:fixtures/targets/dome_lens.obj
//! ```
//!
//! The hub mesh of each case comes from `sv_surface::build_secondary` with default options
//! (the `spinvalence build` chain). With `--cache DIR` it is written there as OBJ on the
//! first run and read back afterwards, so that the primary solve can be compared on the same
//! meshes without re-running the secondary stage. `--worst N` prints the N largest links.

use std::path::PathBuf;
use std::time::Instant;

use sv_frame::{solve, QuadMesh, SolveOptions};
use sv_surface::{build_secondary, SecondaryOptions};

fn hub_mesh(unit: f64, spec: &str, cache: Option<&PathBuf>) -> Result<QuadMesh, String> {
    let key: String = format!("{unit}_{spec}")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let path = cache.map(|d| d.join(format!("{key}.obj")));
    if let Some(p) = path.as_ref().filter(|p| p.exists()) {
        let text = std::fs::read_to_string(p).map_err(|e| e.to_string())?;
        return sv_io::read_quad_obj(&text, &p.display().to_string()).map_err(|e| e.to_string());
    }
    let target = if spec.starts_with("builtin:") {
        sv_surface::builtin_target(spec).map_err(|e| e.to_string())?
    } else {
        let bytes = std::fs::read(spec).map_err(|e| format!("{spec}: {e}"))?;
        let m = sv_io::read_tri_mesh(&bytes, spec).map_err(|e| e.to_string())?;
        sv_surface::TargetMesh {
            vertices: m.vertices,
            triangles: m.triangles,
        }
    };
    let opts = SecondaryOptions {
        unit_size: unit,
        ..Default::default()
    };
    let (mesh, _) = build_secondary(&target, &opts, &mut |_, _| {}).map_err(|e| e.to_string())?;
    if let Some(p) = &path {
        let text = sv_io::write_quad_obj(&mesh, &format!("hub mesh of {spec} at {unit} mm"));
        std::fs::write(p, text).map_err(|e| e.to_string())?;
    }
    Ok(mesh)
}

fn main() {
    let mut cache = None;
    let mut worst = 0usize;
    let mut options = SolveOptions::default();
    let mut cases = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--cache" => cache = args.next().map(PathBuf::from),
            "--worst" => worst = args.next().and_then(|s| s.parse().ok()).unwrap_or(5),
            "--iterations" => {
                options.max_iterations = args.next().and_then(|s| s.parse().ok()).unwrap_or(60)
            }
            "--sum" => options.objective = sv_frame::GapObjective::Sum,
            "--side" => {
                options.side = match args.next().as_deref() {
                    Some("normal") => sv_frame::SidePolicy::Normal,
                    Some("opposite") => sv_frame::SidePolicy::Opposite,
                    _ => sv_frame::SidePolicy::Auto,
                }
            }
            "--per-unit-case" => options.axis_case = None,
            _ => cases.push(a),
        }
    }
    if let Some(d) = &cache {
        if let Err(e) = std::fs::create_dir_all(d) {
            eprintln!("error: {}: {e}", d.display());
            std::process::exit(2);
        }
    }
    println!("| target | unit (mm) | units | links | gap max (mm) | % unit | gap sum (mm) | start sum (mm) | iterations | primary s |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for case in cases {
        let Some((unit, spec)) = case
            .split_once(':')
            .and_then(|(u, s)| u.parse::<f64>().ok().map(|u| (u, s)))
        else {
            eprintln!("error: {case}: expected UNIT:TARGET");
            continue;
        };
        let mesh = match hub_mesh(unit, spec, cache.as_ref()) {
            Ok(m) => m,
            Err(e) => {
                println!("| {spec} | {unit} | hub mesh failed: {e} |");
                continue;
            }
        };
        // the rhombi themselves (spin 0, no depth): how far apart their facing sides are
        let fitted: Vec<[sv_geom::Point3; 4]> = (0..mesh.faces.len())
            .map(|f| {
                sv_frame::Hub::fit(&mesh.face_points(f), 0.0)
                    .map(|h| h.corners())
                    .unwrap_or([sv_geom::Point3::origin(); 4])
            })
            .collect();
        let mut mismatch = (0.0f64, [0usize; 2]);
        for l in mesh.links() {
            let [f, g] = l.faces;
            let [k, m] = l.slots;
            let d = sv_geom::segment_closest(
                &fitted[f][k],
                &fitted[f][(k + 1) % 4],
                &fitted[g][m],
                &fitted[g][(m + 1) % 4],
            )
            .distance;
            if d > mismatch.0 {
                mismatch = (d, l.faces);
            }
        }
        let t = Instant::now();
        let solved = solve(&mesh, &options, &mut |_| {});
        let secs = t.elapsed().as_secs_f64();
        let s = match solved {
            Ok(s) => s,
            Err(e) => {
                println!("| {spec} | {unit} | solve failed: {e} |");
                continue;
            }
        };
        let r = &s.report;
        println!(
            "| {spec} | {unit} | {} | {} | {:.1} | {:.1} % | {:.0} | {:.0} | {} | {:.3} |",
            s.hubs.len(),
            s.links.len(),
            r.gap_max,
            100.0 * r.gap_max / unit,
            r.gap_sum,
            r.gap_sum_start,
            r.iterations,
            secs
        );
        println!(
            "    rhombus mismatch max {:.1} mm ({:.1} %) at faces {:?}",
            mismatch.0,
            100.0 * mismatch.0 / unit,
            mismatch.1
        );
        let hi = s
            .deployments
            .iter()
            .filter(|d| d.theta > 1.45)
            .map(|d| d.theta.to_degrees());
        let hi: Vec<String> = hi.map(|t| format!("{t:.1}")).collect();
        let capped: Vec<usize> = s
            .deployments
            .iter()
            .zip(&s.hubs)
            .enumerate()
            .filter(|(_, (d, h))| {
                let (a, b) = (h.rhombus.a(), h.rhombus.b());
                let cap = 1.5f64.min(2.0 * (a.min(b) / a.max(b)).atan() - 0.02);
                d.theta > cap - 1e-6
            })
            .map(|(u, _)| u)
            .collect();
        println!("    units at their theta cap: {capped:?}");
        let lo = s.deployments.iter().filter(|d| d.theta < 0.06).count();
        let ph = s.deployments.iter().filter(|d| d.phi.abs() > 1.19).count();
        let thmax = s
            .deployments
            .iter()
            .map(|d| d.theta)
            .fold(0.0, f64::max)
            .to_degrees();
        let thmin = s
            .deployments
            .iter()
            .map(|d| d.theta)
            .fold(9.0, f64::min)
            .to_degrees();
        let phmax = s
            .deployments
            .iter()
            .map(|d| d.phi.abs())
            .fold(0.0, f64::max)
            .to_degrees();
        println!("    theta {thmin:.1}..{thmax:.1} deg, |phi| <= {phmax:.1} deg; theta > 83 deg: {hi:?}; at theta min: {lo}; at phi bound: {ph}");
        let file = s.to_frame_file(&mesh);
        let mut order: Vec<usize> = (0..s.links.len()).collect();
        order.sort_by(|&a, &b| s.evaluation.gaps[b].total_cmp(&s.evaluation.gaps[a]));
        for &l in order.iter().take(worst) {
            let link = s.links[l];
            let [f, g] = link.faces;
            let (df, dg) = (s.deployments[f], s.deployments[g]);
            let [k, m] = link.slots;
            let p = |u: usize, i: usize| {
                let c = file.units[u].primary[i % 4];
                sv_geom::Point3::new(c[0], c[1], c[2])
            };
            let c = sv_geom::segment_closest(&p(f, k), &p(f, k + 1), &p(g, m), &p(g, m + 1));
            let (df_, dg_) = (&file.units[f], &file.units[g]);
            let boundary = |u: &sv_frame::UnitRecord| {
                file.links
                    .iter()
                    .filter(|l| l.units.contains(&u.face))
                    .count()
            };
            println!(
                "    s {:.2} t {:.2} links {}/{}",
                c.s,
                c.t,
                boundary(df_),
                boundary(dg_)
            );
            println!(
                "    gap {:.1} mm  faces {f}-{g}  theta {:.1}/{:.1} deg  phi {:.1}/{:.1} deg  sides {:?}/{:?}",
                s.evaluation.gaps[l],
                df.theta.to_degrees(),
                dg.theta.to_degrees(),
                df.phi.to_degrees(),
                dg.phi.to_degrees(),
                df.side,
                dg.side
            );
        }
    }
}
