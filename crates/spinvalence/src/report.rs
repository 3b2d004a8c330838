//! The report stage of `build`: `report.html` and `bom.csv` from the data of the earlier
//! stages (sv-report, pure). `build` writes them with the other files, all or nothing.

use anyhow::{anyhow, Result};
use sv_frame::{CheckReport, FrameFile};
use sv_report::{NestInput, ReportInput, Summary};
use sv_strips::StripsFile;
use sv_surface::SecondaryReport;

use crate::output::number;

/// What the report stage produces.
pub struct ReportStage {
    /// `report.html`.
    pub html: String,
    /// `bom.csv`.
    pub bom: String,
    /// The figures of the summary.
    pub summary: Summary,
}

/// Make the report of a build of `target`. `nest` is `nest.json` with the sheet file names
/// when the build nested the strips.
pub fn run(
    target: &str,
    frame: &FrameFile,
    strips: &StripsFile,
    nest: Option<NestInput<'_>>,
    hub_mesh: &SecondaryReport,
    fold_check: Option<&CheckReport>,
) -> Result<ReportStage> {
    let generator = format!("spinvalence {}", env!("CARGO_PKG_VERSION"));
    let input = ReportInput {
        target,
        generator: &generator,
        frame,
        strips,
        nest,
        hub_mesh: Some(hub_mesh),
        fold_check,
    };
    let html = sv_report::report_html(&input).map_err(|e| anyhow!("report: {e}"))?;
    let bom = sv_report::bom_csv(&input).map_err(|e| anyhow!("report: {e}"))?;
    Ok(ReportStage {
        html,
        bom,
        summary: Summary::of(&input),
    })
}

/// Rows of the build's summary table: steel, cutting, welding, and where the report is.
pub fn summary_rows(stage: &ReportStage, report_path: &str) -> Vec<Vec<String>> {
    let s = &stage.summary;
    vec![
        vec![
            "steel".into(),
            format!(
                "{} m2 net, {} kg at {} mm",
                number(s.steel_area_mm2 * 1e-6),
                number(s.steel_mass_kg),
                number(s.thickness_mm)
            ),
        ],
        vec![
            "cut length / pierces".into(),
            format!("{} m / {}", number(s.cut_length_mm * 1e-3), s.pierces),
        ],
        vec![
            "welds".into(),
            format!(
                "{} ({} at hub overlaps, {} at primary joints)",
                s.welds, s.hub_welds, s.primary_welds
            ),
        ],
        vec![
            "report".into(),
            format!(
                "{report_path} ({:.1} MB, opens offline in a browser)",
                stage.html.len() as f64 / 1e6
            ),
        ],
    ]
}
