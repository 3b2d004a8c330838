//! `spinvalence check`: re-verify a frame.json and print a table.

use anyhow::Result;
use sv_frame::{CheckOptions, CheckReport};

use crate::cli::CheckArgs;
use crate::output::{self, number};

/// Run `check`; `Ok(true)` when every check passes. The reader checks the header
/// (`format`, `version`, `length_unit`), shapes, finiteness and indices.
pub fn run(args: &CheckArgs) -> Result<bool> {
    let name = args.frame.display().to_string();
    let text = output::read_text(&args.frame)?;
    let frame = sv_io::frame_from_json(&text, &name)?;
    let report = sv_frame::check_frame(&frame, &CheckOptions::default());
    output::print_out(&render(&report))?;
    if report.ok() {
        Ok(true)
    } else {
        let failed: Vec<&str> = report
            .rows
            .iter()
            .filter(|r| !r.ok)
            .map(|r| r.name.as_str())
            .collect();
        eprintln!(
            "error: {name}: {} of {} checks failed: {}",
            failed.len(),
            report.rows.len(),
            failed.join(", ")
        );
        Ok(false)
    }
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
            number(row.limit),
            row.at.clone(),
            if row.ok { "ok" } else { "FAIL" }.to_string(),
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
                },
                CheckRow {
                    name: "congruence".into(),
                    worst: 5.0,
                    limit: 1e-6,
                    at: "unit B7".into(),
                    ok: false,
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
