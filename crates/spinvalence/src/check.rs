//! `spinvalence check`: re-verify a frame.json, or a build directory folded from its cut,
//! and print a table.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use sv_frame::{CheckOptions, CheckReport, FrameFile};
use sv_strips::{FoldLimits, StripsFile, STRIPS_FORMAT};

use crate::cli::CheckArgs;
use crate::output::{self, number};

/// Run `check`; `Ok(true)` when every check passes. The readers check the headers
/// (`format`, `version`, `length_unit`), shapes, finiteness and indices.
pub fn run(args: &CheckArgs) -> Result<bool> {
    if let Some(m) = args.min_overlap {
        // a weld minimum at or below 0 would pass hub plates that do not lap
        if !(m.is_finite() && m > 0.0) {
            bail!("invalid --min-overlap {m}: must be a length > 0 in mm");
        }
    }
    let (name, report) = if args.frame.is_dir() {
        let dir = &args.frame;
        let frame = read_frame(&dir.join("frame.json"))?;
        let strips_json = dir.join("strips.json");
        if !strips_json.exists() {
            // a build whose strips could not be cut writes the frame alone
            bail!(
                "{}: no such file: that build cut no strips (its report.json says why); \
                 `spinvalence check {}` checks the frame alone",
                strips_json.display(),
                dir.join("frame.json").display()
            );
        }
        let mut strips = read_strips(&strips_json)?;
        strips
            .validate(frame.units.len())
            .map_err(|e| anyhow!("{}: {e}", strips_json.display()))?;
        for note in cuts_from_dxf(dir, &mut strips)? {
            eprintln!("note: {note}");
        }
        let mut limits = FoldLimits::for_profile(&strips.params.profile);
        if let Some(m) = args.min_overlap {
            limits.min_overlap = m;
        }
        (
            dir.display().to_string(),
            check_build(&frame, &strips, &limits),
        )
    } else {
        let frame = read_frame(&args.frame)?;
        let report = sv_frame::check_frame(&frame, &CheckOptions::default());
        (args.frame.display().to_string(), report)
    };
    output::print_out(&render(&report))?;
    if report.ok() {
        return Ok(true);
    }
    let failed = failures(&report);
    eprintln!(
        "error: {name}: {} of {} checks failed: {}",
        failed.len(),
        report.rows.len(),
        failed.join("; ")
    );
    Ok(false)
}

/// Every failing row, one phrase each: its name, worst, limit and place.
pub fn failures(report: &CheckReport) -> Vec<String> {
    report
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
        .collect()
}

/// The frame's rows, then the fold check of its strips.
pub fn check_build(frame: &FrameFile, strips: &StripsFile, limits: &FoldLimits) -> CheckReport {
    let mut report = sv_frame::check_frame(frame, &CheckOptions::default());
    report
        .rows
        .extend(sv_strips::fold_check(frame, strips, limits).rows);
    report
}

fn read_frame(path: &Path) -> Result<FrameFile> {
    let text = output::read_text(path)?;
    Ok(sv_io::frame_from_json(&text, &path.display().to_string())?)
}

/// strips.json, its header checked; errors name the file, line and column.
fn read_strips(path: &Path) -> Result<StripsFile> {
    let name = path.display();
    let text = output::read_text(path)?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| anyhow!("{name}:{}:{}: {e}", e.line(), e.column()))?;
    let format = value.get("format").and_then(|v| v.as_str());
    if format != Some(STRIPS_FORMAT) {
        bail!("{name}: not a strips file (format {format:?}, expected \"{STRIPS_FORMAT}\")");
    }
    match value.get("version").and_then(|v| v.as_u64()) {
        Some(1) => {}
        v => bail!("{name}: strips.json version {v:?}; this build reads version 1"),
    }
    if value.get("length_unit").and_then(|v| v.as_str()) != Some("mm") {
        bail!("{name}: length_unit must be \"mm\"");
    }
    serde_json::from_value(value).map_err(|e| anyhow!("{name}: {e}"))
}

/// The slots of every strip as its DXF (`DIR/strips/<id>.dxf`) cuts them, in place of
/// strips.json's: each hole goes to the unit whose slot in strips.json is nearest. A strip
/// without its DXF keeps strips.json's slots, with a note saying so.
fn cuts_from_dxf(dir: &Path, strips: &mut StripsFile) -> Result<Vec<String>> {
    let mut notes = Vec::new();
    for record in &mut strips.strips {
        let path = dir.join("strips").join(format!("{}.dxf", record.id));
        if !path.exists() {
            notes.push(format!(
                "{}: missing, strip {} checked from strips.json",
                path.display(),
                record.id
            ));
            continue;
        }
        let name = path.display().to_string();
        let bytes = output::read_bytes(&path)?;
        let read = sv_dxf::read_dxf(&bytes, &name, &sv_dxf::ReadOptions::default())
            .map_err(|e| anyhow!("{e}"))?;
        let [part] = read.parts.as_slice() else {
            bail!("{name}: {} parts, a strip is one part", read.parts.len());
        };
        let centre = |c: &sv_geom::Contour| {
            c.bounds().map_or([f64::NAN; 2], |(lo, hi)| {
                [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0]
            })
        };
        let designed: Vec<[f64; 2]> = record.cuts.iter().map(centre).collect();
        let mut units = Vec::with_capacity(part.holes.len());
        for hole in &part.holes {
            let c = centre(hole);
            let nearest = designed
                .iter()
                .map(|d| (d[0] - c[0]).hypot(d[1] - c[1]))
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .ok_or_else(|| {
                    anyhow!("{name}: strips.json has no slots for strip {}", record.id)
                })?;
            units.push(record.cut_units[nearest.0]);
        }
        record.cuts = part.holes.clone();
        record.cut_units = units;
    }
    Ok(notes)
}

/// The table: check, worst, limit, where, ok/FAIL.
pub fn render(report: &CheckReport) -> String {
    let mut rows = vec![["check", "worst", "limit", "where", ""]
        .map(String::from)
        .to_vec()];
    for row in &report.rows {
        rows.push(vec![
            row.name.clone(),
            number(row.worst),
            if row.limit.is_finite() {
                number(row.limit)
            } else {
                "-".into()
            },
            row.at.clone(),
            row.verdict().to_string(),
        ]);
    }
    output::table(&rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_frame::CheckRow;

    #[test]
    fn table_marks_failures() {
        let report = CheckReport {
            rows: vec![
                CheckRow {
                    name: "leg length".into(),
                    worst: 1e-12,
                    limit: 1e-9,
                    at: "unit A1".into(),
                    ok: true,
                    units: Vec::new(),
                },
                CheckRow {
                    name: "congruence".into(),
                    worst: 5.0,
                    limit: 1e-6,
                    at: "unit B7".into(),
                    ok: false,
                    units: vec![7],
                },
            ],
        };
        let text = render(&report);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[1].ends_with("ok") && lines[1].contains("unit A1"));
        assert!(lines[2].ends_with("FAIL") && lines[2].contains("unit B7"));
        // columns line up: "where" starts at the same offset in every row
        let at = lines[0].find("where").unwrap();
        assert_eq!(lines[2].find("unit B7"), Some(at));
    }
}
