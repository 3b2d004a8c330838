//! Remake `report.html` and `bom.csv` of a build directory from its files:
//! `cargo run -p sv-report --example report_from_dir -- out` (reads frame.json, strips.json,
//! report.json and, when present, nest.json with sheets/*.dxf). Prints the summary.

use std::path::Path;

fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

fn main() -> Result<(), String> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "out".into());
    let dir = Path::new(&dir);
    let frame: sv_frame::FrameFile = read(&dir.join("frame.json"))?;
    let strips: sv_strips::StripsFile = read(&dir.join("strips.json"))?;
    let hub_mesh: Option<sv_surface::SecondaryReport> = read(&dir.join("report.json")).ok();
    let nest: Option<sv_nest::NestReport> = read(&dir.join("nest.json")).ok();
    let mut sheet_files: Vec<String> = std::fs::read_dir(dir.join("sheets"))
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| format!("sheets/{}", e.file_name().to_string_lossy()))
                .filter(|n| n.ends_with(".dxf"))
                .collect()
        })
        .unwrap_or_default();
    sheet_files.sort();
    let input = sv_report::ReportInput {
        target: &dir.display().to_string(),
        generator: "sv-report example",
        frame: &frame,
        strips: &strips,
        nest: nest.as_ref().map(|report| sv_report::NestInput {
            report,
            sheet_files: &sheet_files,
        }),
        hub_mesh: hub_mesh.as_ref(),
        fold_check: None,
    };
    let started = std::time::Instant::now();
    let html = sv_report::report_html(&input).map_err(|e| e.to_string())?;
    let bom = sv_report::bom_csv(&input).map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    std::fs::write(dir.join("report.html"), &html).map_err(|e| e.to_string())?;
    std::fs::write(dir.join("bom.csv"), &bom).map_err(|e| e.to_string())?;
    println!(
        "{}: {} bytes in {seconds:.3} s\n{:#?}",
        dir.join("report.html").display(),
        html.len(),
        sv_report::Summary::of(&input)
    );
    Ok(())
}
