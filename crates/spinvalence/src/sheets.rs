//! The nesting stage, shared by `build` (the strips of the frame) and `nest` (DXF parts):
//! nest the parts onto sheets with a progress bar, then draw every sheet as DXF (the shop
//! file) and SVG (the preview). Pure computation; the callers write the files atomically.

use anyhow::{anyhow, Result};
use sv_export::{SheetCaption, SheetPart, ShopConvention};
use sv_nest::{NestOptions, NestReport, Part};

use crate::solve::progress_bar;

/// What the nesting stage produces.
pub struct NestStage {
    /// `nest.json`.
    pub report: NestReport,
    /// `(file name, text)` of every sheet's DXF and SVG, for `DIR/sheets/`.
    pub drawings: Vec<(String, String)>,
    /// The DXF file of each sheet, relative to the output directory
    /// (`sheets/sheet-01_3000x1500mm_t3mm.dxf`), in sheet order.
    pub sheet_files: Vec<String>,
}

/// Nest `parts` with `options` and draw the sheets in `convention`; `thickness` (mm) goes
/// into the file names and titles when known.
pub fn run(
    parts: &[SheetPart],
    options: &NestOptions,
    thickness: Option<f64>,
    convention: &ShopConvention,
    quiet: bool,
) -> Result<NestStage> {
    let plain: Vec<Part> = parts.iter().map(|p| p.part.clone()).collect();
    let seconds = options.time_limit.as_secs_f64();
    let bar = progress_bar(quiet, (seconds * 10.0).ceil() as usize, "nesting");
    let report = sv_nest::nest_sheets(&plain, options, &mut |p| {
        bar.set_position((p.elapsed_s * 10.0) as u64);
        bar.set_message(format!(
            "{} sheet(s), {:.1} % used",
            p.best,
            100.0 * p.density
        ));
    });
    bar.finish_and_clear();
    let report = report.map_err(|e| anyhow!("nesting: {e}"))?;
    let caption = SheetCaption {
        thickness,
        generator: format!("spinvalence {}", env!("CARGO_PKG_VERSION")),
    };
    let mut drawings = Vec::with_capacity(2 * report.sheets.len());
    let mut sheet_files = Vec::with_capacity(report.sheets.len());
    for (i, sheet) in report.sheets.iter().enumerate() {
        let stem = sv_export::sheet_file_stem(i, sheet.width, sheet.height, thickness);
        let dxf = sv_export::sheet_dxf(&report, i, parts, &caption, convention)
            .map_err(|e| anyhow!("nesting: {e}"))?;
        let svg = sv_export::sheet_svg(&report, &plain, i);
        sheet_files.push(format!("sheets/{stem}.dxf"));
        drawings.push((format!("{stem}.dxf"), dxf));
        drawings.push((format!("{stem}.svg"), svg));
    }
    Ok(NestStage {
        report,
        drawings,
        sheet_files,
    })
}

/// Rows of a summary table: sheets against the lower bound, utilisation, offcut and what
/// was left out.
pub fn summary_rows(report: &NestReport) -> Vec<Vec<String>> {
    let used: Vec<String> = report
        .sheets
        .iter()
        .map(|s| format!("{:.1}", 100.0 * s.utilisation))
        .collect();
    let mut rows = vec![vec![
        "sheets".into(),
        format!(
            "{} of {} x {} mm (lower bound {}), {} % used",
            report.sheets.len(),
            report.sheet.width,
            report.sheet.height,
            report.lower_bound_sheets,
            used.join(" / ")
        ),
    ]];
    if let Some(o) = &report.offcut {
        rows.push(vec![
            "offcut".into(),
            format!(
                "{:.0} x {:.0} mm on sheet {}",
                o.width,
                o.height,
                o.sheet + 1
            ),
        ]);
    }
    for l in &report.left_out {
        rows.push(vec!["left out".into(), format!("{}: {}", l.part, l.reason)]);
    }
    rows
}
