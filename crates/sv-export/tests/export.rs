//! Writes the DXF and SVG of every strip of a sphere cap and of the default pavilion build
//! and checks them, the DXF with the nesting's DXF reader and with
//! ezdxf's auditor (an independent reader, `tests/ezdxf/mod.rs`).

mod ezdxf;

use std::path::{Path, PathBuf};

use ezdxf::audit;

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
        // read back by the nesting's DXF reader: one part (the OUTSIDE outline) with every
        // INSIDE slot as a hole; the INFO tiles, pins and title and the ETCH text are skipped
        let back = sv_dxf::parse_parts(&dxf, &s.id).unwrap();
        assert!(back.rejected.is_empty(), "{}: {:?}", s.id, back.rejected);
        assert_eq!(back.parts.len(), 1, "{}: one part per outline", s.id);
        assert_eq!(back.parts[0].id, s.id);
        assert_eq!(back.parts[0].holes.len(), p.cuts.len(), "{}: holes", s.id);
        assert_eq!(
            back.parts[0].outer.vertices.len(),
            p.outline.vertices.len(),
            "{}: the outline as written",
            s.id
        );
        let path = dir.join(format!("{}.dxf", s.id));
        std::fs::write(&path, dxf).unwrap();
        files.push(path);
    }
    audit(&files, false);
}

/// The strips nested onto sheets (a fixed evaluation budget: the same layout every run),
/// each sheet written as DXF: ezdxf's audit is clean, and reading the sheet back as parts
/// (the sv-nest reader skips ETCH and INFO) gives every placed strip once, with its slots.
#[test]
fn every_sheet_dxf_passes_the_ezdxf_audit_and_reads_back_as_its_parts() {
    let dir = out_dir();
    let parts: Vec<sv_export::SheetPart> = strips()
        .iter()
        .map(|(s, p)| sv_export::strip_sheet_part(s, p))
        .collect();
    let plain: Vec<sv_nest::Part> = parts.iter().map(|p| p.part.clone()).collect();
    let options = sv_nest::NestOptions {
        time_limit: std::time::Duration::from_secs(600),
        max_evaluations: Some(20_000),
        ..sv_nest::NestOptions::default()
    };
    let report = sv_nest::nest_sheets(&plain, &options, &mut |_| {}).unwrap();
    assert!(report.left_out.is_empty(), "{:?}", report.left_out);
    let caption = sv_export::SheetCaption {
        thickness: Some(3.0),
        generator: "sv-export tests".into(),
    };
    let mut files = Vec::new();
    let mut seen = Vec::new();
    let by_id = sv_nest::ById::new(&parts, |p| &p.part.id);
    for (i, sheet) in report.sheets.iter().enumerate() {
        let dxf = sv_export::sheet_dxf(&report, i, &by_id, &caption, &Default::default()).unwrap();
        let back = sv_dxf::parse_parts(&dxf, "sheet").unwrap();
        assert!(back.rejected.is_empty(), "{:?}", back.rejected);
        assert_eq!(back.parts.len(), sheet.placements.len());
        for pl in &sheet.placements {
            let original = &parts.iter().find(|p| p.part.id == pl.strip).unwrap().part;
            let moved = original.transformed(pl.rotation_deg, pl.translation);
            // the part read back whose outline starts where the placed outline starts
            let v0 = moved.outer.vertices[0];
            let read = back
                .parts
                .iter()
                .find(|p| {
                    let w = p.outer.vertices[0];
                    (w.x - v0.x).abs() < 1e-6 && (w.y - v0.y).abs() < 1e-6
                })
                .unwrap_or_else(|| panic!("{} is not on sheet {}", pl.strip, i + 1));
            assert_eq!(read.outer.vertices.len(), moved.outer.vertices.len());
            assert_eq!(read.holes.len(), original.holes.len(), "{}", pl.strip);
            seen.push(pl.strip.clone());
        }
        let stem = sv_export::sheet_file_stem(i, sheet.width, sheet.height, Some(3.0));
        let path = dir.join(format!("{stem}.dxf"));
        std::fs::write(&path, dxf).unwrap();
        files.push(path);
    }
    seen.sort();
    let mut all: Vec<String> = parts.iter().map(|p| p.part.id.clone()).collect();
    all.sort();
    assert_eq!(seen, all, "every strip on exactly one sheet");
    audit(&files, true);
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
