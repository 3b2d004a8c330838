//! Writes the DXF and SVG of every strip of a sphere cap and of the default pavilion build
//! and checks them, the DXF with
//! ezdxf's auditor (an independent reader). The test creates the Python venv with ezdxf
//! under `target/ezdxf-venv` when it is missing; it never skips.

use std::path::{Path, PathBuf};
use std::process::Command;

use sv_frame::{solve, QuadMesh, SolveOptions};
use sv_strips::{profile_strip, unit_labels, unroll, ProfileParams, StripOptions, StripProfile};

/// The strips of a sphere cap and of the default build (the built-in pavilion through the
/// library stages `spinvalence build` runs, default options).
fn strips() -> Vec<(sv_strips::FlatStrip, StripProfile)> {
    let cap = QuadMesh::sphere_cap(6, 6, 3000.0, 300.0);
    let pavilion = sv_surface::builtin_target("pavilion").unwrap();
    let (pavilion, _) = sv_surface::build_secondary(
        &pavilion,
        &sv_surface::SecondaryOptions::default(),
        &mut |_, _| {},
    )
    .unwrap();
    let mut out = strips_of(&cap, "cap-");
    out.extend(strips_of(&pavilion, "pavilion-"));
    out
}

fn strips_of(mesh: &QuadMesh, prefix: &str) -> Vec<(sv_strips::FlatStrip, StripProfile)> {
    let frame = solve(mesh, &SolveOptions::default(), &mut |_| {})
        .unwrap()
        .to_frame_file(mesh);
    let mut strips = unroll(&frame, &StripOptions::default()).unwrap();
    let labels = unit_labels(&strips, frame.units.len());
    let params = ProfileParams::default();
    for s in &mut strips {
        s.id = format!("{prefix}{}", s.id);
    }
    strips
        .into_iter()
        .map(|s| {
            let names: Vec<String> = s.units.iter().map(|&u| labels[u].id.clone()).collect();
            let p = profile_strip(&s, &names, &params).unwrap();
            (s, p)
        })
        .collect()
}

fn out_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sv-export-strips");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn venv_python() -> PathBuf {
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target");
    let venv = target.join("ezdxf-venv");
    let python = venv.join("bin/python3");
    let has_ezdxf = |p: &Path| {
        Command::new(p)
            .args(["-c", "import ezdxf"])
            .status()
            .map(|s| s.success())
            .unwrap_or(false)
    };
    if !has_ezdxf(&python) {
        let ok = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .expect("python3 is needed to audit DXF files with ezdxf")
            .success();
        assert!(ok, "could not create {}", venv.display());
        let ok = Command::new(venv.join("bin/pip"))
            .args(["install", "-q", "ezdxf"])
            .status()
            .expect("pip")
            .success();
        assert!(ok, "could not install ezdxf into {}", venv.display());
    }
    assert!(has_ezdxf(&python));
    python
}

#[test]
fn every_strip_dxf_passes_the_ezdxf_audit() {
    let dir = out_dir();
    let mut files = Vec::new();
    for (s, p) in strips() {
        let dxf = sv_export::strip_dxf(&s, &p);
        // structure we rely on, independent of ezdxf
        assert!(dxf.contains("$ACADVER\n  1\nAC1015"));
        assert!(dxf.contains("$INSUNITS\n 70\n4"));
        assert!(dxf.matches("\nLWPOLYLINE\n").count() > p.cuts.len());
        assert!(dxf.ends_with("  0\nEOF\n"));
        let path = dir.join(format!("{}.dxf", s.id));
        std::fs::write(&path, dxf).unwrap();
        files.push(path);
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/audit_dxf.py");
    let out = Command::new(venv_python())
        .arg(script)
        .args(&files)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains(&format!("audited {} file(s)", files.len())),
        "{text}"
    );
}

#[test]
fn every_strip_svg_has_title_labels_folds_and_scale_bar() {
    let dir = out_dir();
    let params = ProfileParams::default();
    for (s, p) in strips() {
        let svg = sv_export::strip_svg(&s, &p, &params);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains(&format!("Strip {}", s.id)));
        assert!(svg.contains(" mm</text>"), "scale bar");
        assert!(svg.matches("stroke=\"#d22\"").count() >= p.fold_marks.len());
        assert!(svg.matches("stroke=\"#2a7\"").count() >= p.labels.len());
        for l in &p.labels {
            assert!(
                svg.contains(&format!("<title>{}</title>", l.text)),
                "{}: label {} is named in the drawing",
                s.id,
                l.text
            );
        }
        // one path holds the outline and all cuts
        assert_eq!(svg.matches('Z').count(), 1 + p.cuts.len());
        std::fs::write(dir.join(format!("{}.svg", s.id)), svg).unwrap();
    }
}
