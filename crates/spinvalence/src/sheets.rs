//! The nesting stage, shared by `build` (the strips of the frame) and `nest` (DXF parts):
//! nest the parts onto sheets with a progress bar, then draw every sheet as DXF (the shop
//! file) and SVG (the preview). Pure computation; the callers write the files atomically.

use std::collections::HashMap;
use std::time::Duration;

use anyhow::{anyhow, Result};
use rayon::prelude::*;
use sv_export::{SheetCaption, SheetPart, ShopConvention};
use sv_nest::{ById, LeftOut, NestOptions, NestReport, Part};

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

/// Wall seconds to draw a part on its sheet (DXF with pierce points, SVG) on a quiet 2-core
/// machine, per part and per vertex of its contours and etching, measured on the 673 strips
/// of the 20 x 12 m dome at 150 mm (1.5 M vertices, 0.78 s) and the 2,000 small plates of
/// `many_parts.dxf` (0.059 s) (docs/nesting.md).
const DRAW_SECONDS_PER_PART: f64 = 30e-6;
/// See [`DRAW_SECONDS_PER_PART`].
const DRAW_SECONDS_PER_VERTEX: f64 = 0.5e-6;
/// Margin on that rate, for a machine a little slower than the one it was measured on.
const DRAW_MARGIN: f64 = 1.5;

/// Share of the time box the nesting keeps whatever the drawing is expected to take.
const NEST_SHARE_MIN: f64 = 0.5;

/// Expected wall seconds to draw `parts` on their sheets on a quiet machine, with
/// [`DRAW_MARGIN`].
fn drawing_seconds(parts: &[SheetPart]) -> f64 {
    let vertices: usize = parts
        .iter()
        .map(|p| {
            p.part.outer.vertices.len()
                + p.part.holes.iter().map(|h| h.vertices.len()).sum::<usize>()
                + p.etch.iter().map(Vec::len).sum::<usize>()
        })
        .sum();
    let quiet =
        DRAW_SECONDS_PER_PART * parts.len() as f64 + DRAW_SECONDS_PER_VERTEX * vertices as f64;
    quiet * DRAW_MARGIN
}

/// How much slower than when quiet this machine runs now: the runnable processes of the
/// last minute per core (`/proc/loadavg`), at least 1; 1 where that cannot be read. The
/// drawing is not capped by the clock, so the nesting leaves it room in proportion.
fn machine_slowdown() -> f64 {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|text| slowdown_from_loadavg(&text, cores))
        .unwrap_or(1.0)
}

/// The slowdown a `/proc/loadavg` text gives on `cores` cores (see [`machine_slowdown`]).
fn slowdown_from_loadavg(text: &str, cores: f64) -> Option<f64> {
    let load: f64 = text.split_whitespace().next()?.parse().ok()?;
    (load.is_finite() && load >= 0.0).then(|| (load / cores.max(1.0)).max(1.0))
}

/// Nest `parts` with `options` and draw the sheets in `convention`; `thickness` (mm) goes
/// into the file names and titles when known. `options.time_limit` bounds both (the nesting
/// is given what the drawing is expected to leave).
pub fn run(
    parts: &[SheetPart],
    options: &NestOptions,
    thickness: Option<f64>,
    convention: &ShopConvention,
    quiet: bool,
) -> Result<NestStage> {
    let plain: Vec<Part> = parts.iter().map(|p| p.part.clone()).collect();
    // the time box holds the drawing too: the nesting's clock gets what drawing these
    // parts leaves on this machine as loaded now (at least half of it); its work budget,
    // which decides the sheets, what drawing leaves on a quiet one
    let leave = |seconds: f64| {
        options
            .time_limit
            .saturating_sub(Duration::from_secs_f64(seconds))
            .max(options.time_limit.mul_f64(NEST_SHARE_MIN))
    };
    let drawing = drawing_seconds(parts);
    let nesting = NestOptions {
        time_limit: leave(drawing * machine_slowdown()),
        budget_time: Some(leave(drawing)),
        ..options.clone()
    };
    let bar = progress_bar(quiet, 1000, "nesting");
    let report = sv_nest::nest_sheets(&plain, &nesting, &mut |p| {
        bar.set_position((p.work_fraction * 1000.0) as u64);
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
    let by_id = ById::new(parts, |p| &p.part.id);
    // every sheet drawn on its own core (in sheet order, whichever finishes first)
    let drawn: Vec<Result<(String, String, String)>> = (0..report.sheets.len())
        .into_par_iter()
        .map(|i| {
            let sheet = &report.sheets[i];
            let stem = sv_export::sheet_file_stem(i, sheet.width, sheet.height, thickness);
            let dxf = sv_export::sheet_dxf(&report, i, &by_id, &caption, convention)
                .map_err(|e| anyhow!("nesting: {e}"))?;
            let svg = sv_export::sheet_svg(&report, &by_id, i);
            Ok((stem, dxf, svg))
        })
        .collect();
    let mut drawings = Vec::with_capacity(2 * report.sheets.len());
    let mut sheet_files = Vec::with_capacity(report.sheets.len());
    for d in drawn {
        let (stem, dxf, svg) = d?;
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

/// The `search` row of a summary: the search's evaluations against its work budget (the
/// construction's are counted apart: the budget is the search's alone, and never overrun),
/// and whether the time cap cut it (then the layout may differ on a faster or less busy
/// machine). `searched` is false when the time cap stopped the construction and no search
/// followed.
pub fn search_row(
    evaluations: u64,
    budget: u64,
    construction: u64,
    cut: bool,
    searched: bool,
    seconds: f64,
) -> String {
    let m = evaluations_text;
    if !searched {
        format!(
            "none: the {seconds} s time cap stopped the construction first (after {} \
             evaluations; work budget {})",
            m(construction),
            m(budget)
        )
    } else if cut {
        format!(
            "cut by the {seconds} s time cap at {:.0} % of its work budget ({} of {} evaluations, \
             the construction's {} apart): the layout may differ on a faster or less busy machine",
            100.0 * evaluations as f64 / budget.max(1) as f64,
            m(evaluations),
            m(budget),
            m(construction)
        )
    } else {
        format!(
            "{} evaluations (work budget {}, the construction's {} apart; the same layout on \
             every machine)",
            m(evaluations),
            m(budget),
            m(construction)
        )
    }
}

/// A count of evaluations as the summary says it: in millions from 100,000 up (`0.33 M`),
/// below that whole, its thousands grouped (`2,000`: a small budget read as `0.00 M`).
fn evaluations_text(n: u64) -> String {
    if n >= 100_000 {
        return format!("{:.2} M", n as f64 / 1e6);
    }
    let digits = n.to_string();
    let mut grouped = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            grouped.push(',');
        }
        grouped.push(c);
    }
    grouped
}

/// The `construction` row of a summary when the time cap stopped the construction: how
/// many parts it left to rows of bounding boxes.
pub fn construction_row(report: &NestReport, seconds: f64) -> Option<String> {
    let s = &report.search;
    let parts: usize = report.sheets.iter().map(|x| x.placements.len()).sum();
    s.construction_cut.then(|| {
        format!(
            "cut by the {seconds} s time cap: {} of {parts} parts went onto sheets of their \
             own in rows of bounding boxes, and there was no search",
            s.parts_in_rows
        )
    })
}

/// The warning line for a search the time cap cut short (printed even with `--quiet`).
pub fn cut_warning(report: &NestReport, seconds: f64) -> Option<String> {
    let s = &report.search;
    if s.construction_cut {
        return Some(format!(
            "warning: nesting: the {seconds} s time cap stopped the construction before every \
             part was placed: {} part(s) went onto sheets of their own in rows of bounding \
             boxes, and there was no search, so these sheets depend on this machine's speed; \
             give more --nest-seconds for the full layout",
            s.parts_in_rows
        ));
    }
    s.cut_by_time.then(|| {
        format!(
            "warning: nesting: the {seconds} s time cap cut the search at {:.0} % of its work \
             budget, so these sheets depend on this machine's speed; for the sheets a less \
             busy machine finds, give --nest-evaluations {} and more --nest-seconds",
            100.0 * s.done_fraction(),
            s.work_budget
        )
    })
}

/// Rows of a summary table: sheets against the lower bound, utilisation, offcut, the search
/// and what was left out.
pub fn summary_rows(report: &NestReport, seconds: f64) -> Vec<Vec<String>> {
    let used: Vec<String> = report
        .sheets
        .iter()
        .map(|s| format!("{:.1}", 100.0 * s.utilisation))
        .collect();
    let sheets = if report.sheets.is_empty() {
        "none".to_string()
    } else {
        format!(
            "{} of {} x {} mm (lower bound {}), {} % used",
            report.sheets.len(),
            report.sheet.width,
            report.sheet.height,
            report.lower_bound_sheets,
            used.join(" / ")
        )
    };
    let mut rows = vec![vec!["sheets".into(), sheets]];
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
    if let Some(c) = construction_row(report, seconds) {
        rows.push(vec!["construction".into(), c]);
    }
    rows.push(vec![
        "search".into(),
        search_row(
            report.search.evaluations,
            report.search.work_budget,
            report.search.construction_evaluations,
            report.search.cut_by_time,
            !report.search.construction_cut,
            seconds,
        ),
    ]);
    for (who, reason) in left_out_groups(&report.left_out) {
        rows.push(vec!["left out".into(), format!("{who}: {reason}")]);
    }
    rows
}

/// Parts named in a line of parts left out for one reason (the rest counted; `nest.json`
/// names every one).
const PARTS_NAMED: usize = 3;

/// The parts left out by reason, in the order of their first part: (who, reason), who
/// being the part, or for more than [`PARTS_NAMED`] parts their count, the first ones and
/// the last (`70000 parts (a#1, a#2, a#3, ..., a#70000)`).
pub fn left_out_groups(left_out: &[LeftOut]) -> Vec<(String, &str)> {
    let mut groups: Vec<(&str, Vec<&str>)> = Vec::new();
    let mut group_of: HashMap<&str, usize> = HashMap::new();
    for l in left_out {
        let g = *group_of.entry(&l.reason).or_insert_with(|| {
            groups.push((&l.reason, Vec::new()));
            groups.len() - 1
        });
        groups[g].1.push(&l.part);
    }
    groups
        .into_iter()
        .flat_map(|(reason, parts)| {
            if parts.len() <= PARTS_NAMED {
                parts
                    .into_iter()
                    .map(|p| (p.to_string(), reason))
                    .collect::<Vec<_>>()
            } else {
                let first = parts[..PARTS_NAMED].join(", ");
                let last = parts[parts.len() - 1];
                let who = format!("{} parts ({first}, ..., {last})", parts.len());
                vec![(who, reason)]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{evaluations_text, search_row, slowdown_from_loadavg};

    /// Small counts are said whole (a budget of 2,000 read "0.00 M"), large ones in millions.
    #[test]
    fn small_counts_of_evaluations_are_said_whole() {
        assert_eq!(evaluations_text(0), "0");
        assert_eq!(evaluations_text(999), "999");
        assert_eq!(evaluations_text(2_000), "2,000");
        assert_eq!(evaluations_text(56_337), "56,337");
        assert_eq!(evaluations_text(100_000), "0.10 M");
        assert_eq!(evaluations_text(1_700_000), "1.70 M");
        assert_eq!(
            search_row(2_000, 2_000, 56_337, false, true, 5.0),
            "2,000 evaluations (work budget 2,000, the construction's 56,337 apart; the same \
             layout on every machine)"
        );
    }

    /// The search row never puts the construction's evaluations against the search's
    /// budget: after a construction the clock stopped there was no search, and the row
    /// says so instead of a share of the budget (it read "at 100 % of its work budget
    /// (0.65 M of 0.33 M)").
    #[test]
    fn the_search_row_counts_the_construction_apart() {
        let none = search_row(0, 330_000, 650_000, true, false, 5.0);
        assert_eq!(
            none,
            "none: the 5 s time cap stopped the construction first (after 0.65 M \
             evaluations; work budget 0.33 M)"
        );
        let cut = search_row(165_000, 330_000, 650_000, true, true, 5.0);
        assert!(
            cut.starts_with(
                "cut by the 5 s time cap at 50 % of its work budget (0.17 M of 0.33 M \
                 evaluations, the construction's 0.65 M apart)"
            ),
            "{cut}"
        );
        let full = search_row(330_000, 330_000, 650_000, false, true, 5.0);
        assert_eq!(
            full,
            "0.33 M evaluations (work budget 0.33 M, the construction's 0.65 M apart; the \
             same layout on every machine)"
        );
    }

    #[test]
    fn the_load_per_core_slows_the_machine_and_a_quiet_one_is_not_faster() {
        let quiet = "0.52 0.60 0.70 1/234 5678\n";
        assert_eq!(slowdown_from_loadavg(quiet, 2.0), Some(1.0));
        let busy = "5.00 3.10 2.00 6/300 9999\n";
        assert_eq!(slowdown_from_loadavg(busy, 2.0), Some(2.5));
        assert_eq!(slowdown_from_loadavg(busy, 8.0), Some(1.0));
        for bad in ["", "load", "NaN 1 1", "-1 0 0", "inf 0 0"] {
            assert_eq!(slowdown_from_loadavg(bad, 2.0), None, "{bad:?}");
        }
    }
}
