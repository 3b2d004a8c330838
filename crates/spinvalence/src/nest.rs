//! `spinvalence nest`: nest closed-contour DXF parts onto sheets, or run a strip-packing
//! benchmark instance (jagua-rs JSON), on its own.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Result};
use serde::Serialize;
use sv_export::{CutDirection, EtchOrder, SheetPart, ShopConvention};
use sv_nest::LeftOut;
use sv_nest::{NestOptions, Part, RotationMode, StockSheet, StripInstance, StripOptions};

use crate::cli::NestArgs;
use crate::output::{self, number, AtomicDir, AtomicFiles};
use crate::solve::{progress_bar, seconds};

/// Parse `3000x1500` (mm); several sizes separated by commas are stock sizes in order.
pub fn parse_sheets(text: &str) -> Result<Vec<StockSheet>> {
    text.split(',')
        .map(|one| {
            let (w, h) = one.trim().split_once(['x', 'X']).ok_or_else(|| {
                anyhow!("invalid --sheet {one:?}: expected WIDTHxHEIGHT in mm, e.g. 3000x1500")
            })?;
            let parse = |s: &str| {
                s.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0)
            };
            match (parse(w), parse(h)) {
                (Some(width), Some(height)) => Ok(StockSheet { width, height }),
                _ => bail!(
                    "invalid --sheet {one:?}: width and height must be positive lengths in mm"
                ),
            }
        })
        .collect()
}

/// The reader's options from the flags; one line naming a bad flag.
fn read_options(args: &NestArgs) -> Result<sv_dxf::ReadOptions> {
    let units = args
        .units
        .as_deref()
        .map(|u| {
            u.parse::<sv_dxf::Units>()
                .map_err(|e| anyhow!("invalid --units: {e}"))
        })
        .transpose()?;
    for (flag, v) in [
        ("--join-tolerance", args.join_tolerance),
        ("--arc-tolerance", args.arc_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("invalid {flag} {v}: must be a positive length in mm");
        }
    }
    let user = args
        .layers
        .iter()
        .map(|r| r.parse().map_err(|e| anyhow!("invalid --layer {e}")))
        .collect::<Result<Vec<_>>>()?;
    Ok(sv_dxf::ReadOptions {
        units,
        join_tolerance: args.join_tolerance,
        arc_tolerance: args.arc_tolerance,
        layers: sv_dxf::LayerRules { user },
        islands: args.islands,
    })
}

/// The shop convention of the sheets from the flags.
fn convention(args: &NestArgs) -> Result<ShopConvention> {
    let direction = match args.cut_direction.as_str() {
        "outside-cw" => CutDirection::OutsideClockwise,
        "outside-ccw" => CutDirection::OutsideCounterClockwise,
        other => bail!("invalid --cut-direction {other:?}: outside-cw or outside-ccw"),
    };
    let etch = match args.etch.as_str() {
        "first" => EtchOrder::BeforeCuts,
        "last" => EtchOrder::AfterCuts,
        other => bail!("invalid --etch {other:?}: first or last"),
    };
    Ok(ShopConvention { direction, etch })
}

/// Check the numeric options; one line naming the flag.
fn check(args: &NestArgs) -> Result<()> {
    for (flag, v) in [
        ("--margin", args.margin),
        ("--kerf", args.kerf),
        ("--clearance", args.clearance),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            bail!("invalid {flag} {v}: must be a finite length >= 0 mm");
        }
    }
    crate::config::nest_seconds_ok(args.nest_seconds)
        .map_err(|why| anyhow!("invalid --nest-seconds {why}"))?;
    if args.parts.is_empty() {
        bail!("no parts given: name DXF files (or one jagua-rs JSON instance)");
    }
    Ok(())
}

/// `DIR/timings.json` of `nest`: wall seconds and how far the search went (a record of
/// the run, so not in `nest.json`, which the work budget makes the same on every run).
#[derive(Serialize)]
struct NestTimings<'a> {
    /// The nesting stage: set-up, construction, search, drawing the sheets.
    nest: f64,
    /// The whole command, reading the parts and writing the files included.
    total: f64,
    /// The search's work budget, the work done and whether the clock cut it.
    nest_search: &'a sv_nest::SearchReport,
}

/// The id of each DXF file's parts (docs/dxf.md, "Part ids"): its stem (`A01` for
/// `strips/A01.dxf`); where files share a stem, each of them is named by its stem and
/// as many of its parent directories as tell it from every other file of that stem
/// (`a/part` and `b/part` for `x/a/part.dxf` and `b/part.dxf`), with `/` between them on
/// every system, so that the id does not depend on the order of the files. Files whose
/// paths tell them from none (the same file given twice) are told apart by
/// [`make_unique`].
fn file_ids(paths: &[std::path::PathBuf]) -> Vec<String> {
    // the path's names from the stem up: ["part", "a", "x"] for `x/a/part.dxf`
    let names = |path: &Path| -> Vec<String> {
        let Some(stem) = path.file_stem().filter(|s| !s.is_empty()) else {
            return vec![path.display().to_string()];
        };
        let stem = stem.to_string_lossy().into_owned();
        let parents = path.parent().into_iter().flat_map(|p| {
            p.components().rev().filter_map(|c| match c {
                std::path::Component::Normal(n) => Some(n.to_string_lossy().into_owned()),
                _ => None,
            })
        });
        std::iter::once(stem).chain(parents).collect()
    };
    let all: Vec<Vec<String>> = paths.iter().map(|p| names(p)).collect();
    all.iter()
        .map(|mine| {
            // the fewest names that no other file of the stem ends with as well
            let others: Vec<&Vec<String>> = all
                .iter()
                .filter(|o| *o != mine && o[0] == mine[0])
                .collect();
            let depth = (1..=mine.len())
                .find(|&d| others.iter().all(|o| o.get(..d) != mine.get(..d)))
                .unwrap_or(mine.len());
            let mut id: Vec<&str> = mine[..depth].iter().map(String::as_str).collect();
            id.reverse();
            id.join("/")
        })
        .collect()
}

/// Makes the ids unique: an id that an earlier one has already gets `~2`, `~3`, ... (in
/// the order given), so that no two parts share one: the same file given twice, or a file
/// whose stem is another file's part id (`part#1.dxf` beside a `part.dxf` of two parts).
fn make_unique<'a>(ids: impl Iterator<Item = &'a mut String>) {
    let mut seen: std::collections::HashSet<String> = std::collections::HashSet::new();
    for id in ids {
        if !seen.contains(id.as_str()) {
            seen.insert(id.clone());
            continue;
        }
        let unique = (2..)
            .map(|k| format!("{id}~{k}"))
            .find(|c| !seen.contains(c))
            .expect("a free suffix");
        seen.insert(unique.clone());
        *id = unique;
    }
}

/// Run `nest`.
pub fn run(args: &NestArgs) -> Result<()> {
    let started = Instant::now();
    check(args)?;
    let json: Vec<&Path> = args
        .parts
        .iter()
        .map(|p| p.as_path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    if !json.is_empty() {
        if args.parts.len() != 1 {
            bail!("a JSON strip-packing instance is nested on its own: give exactly one file");
        }
        return run_strip(args, json[0]);
    }
    let sheets = parse_sheets(&args.sheet)?;
    sv_nest::margin_leaves_room(&sheets, args.margin)
        .map_err(|why| anyhow!("invalid --margin {}: {why}", args.margin))?;
    let read_options = read_options(args)?;
    let convention = convention(args)?;
    let mut parts: Vec<SheetPart> = Vec::new();
    let mut left_out: Vec<LeftOut> = Vec::new();
    let mut notes: Vec<sv_dxf::Note> = Vec::new();
    let ids = file_ids(&args.parts);
    for (path, id) in args.parts.iter().zip(&ids) {
        let name = path.display().to_string();
        let bytes = match output::read_bytes(path) {
            Ok(bytes) => bytes,
            Err(e) => {
                left_out.push(LeftOut {
                    part: name,
                    reason: format!("{e:#}"),
                });
                continue;
            }
        };
        match sv_dxf::read_dxf(&bytes, id, &read_options) {
            Ok(read) => {
                // the parts with what they etch (labels and fold marks of a strip DXF)
                parts.extend(read.parts.into_iter().map(|p| SheetPart {
                    part: Part {
                        id: p.id,
                        outer: p.outer,
                        holes: p.holes,
                    },
                    etch: p.etch,
                    labels: Vec::new(),
                }));
                // a contour left out is named by its file and entities
                left_out.extend(read.rejected.into_iter().map(|e| match e {
                    sv_dxf::DxfError::BadPart {
                        entities, reason, ..
                    } => LeftOut {
                        part: format!("{name} ({entities})"),
                        reason,
                    },
                    sv_dxf::DxfError::Dxf { message, .. } => LeftOut {
                        part: name.clone(),
                        reason: message,
                    },
                }));
                notes.extend(read.notes.into_iter().map(|n| sv_dxf::Note {
                    file: name.clone(),
                    ..n
                }));
            }
            Err(e) => left_out.push(LeftOut {
                part: name,
                // the file is named by `part`
                reason: match e {
                    sv_dxf::DxfError::Dxf { message, .. } => message,
                    other => other.to_string(),
                },
            }),
        }
    }
    make_unique(parts.iter_mut().map(|p| &mut p.part.id));
    if parts.is_empty() {
        // the first reason, naming the file unless it does already
        let why = left_out
            .first()
            .map_or("no closed contours".to_string(), |l| {
                if l.reason.contains(&l.part) {
                    l.reason.clone()
                } else {
                    format!("{}: {}", l.part, l.reason)
                }
            });
        bail!("nothing to nest: {why}");
    }
    if let Some(t) = args.thickness {
        if !(t.is_finite() && t > 0.0) {
            bail!("invalid --thickness {t}: must be a positive length in mm");
        }
    }
    let files = AtomicFiles::create(&args.out, &["nest.json", "timings.json"])?;
    let sheet_dir = AtomicDir::create(&args.out, "sheets", output::DRAWINGS)?;
    let options = NestOptions {
        sheets,
        margin: args.margin,
        spacing: args.kerf + args.clearance,
        rotations: RotationMode::free_or_default(args.free_rotation),
        seed: args.seed,
        time_limit: Duration::from_secs_f64(args.nest_seconds),
        max_evaluations: args.nest_evaluations,
        ..NestOptions::default()
    };
    let stage_started = Instant::now();
    let mut stage = crate::sheets::run(&parts, &options, args.thickness, &convention, args.quiet)?;
    let stage_s = stage_started.elapsed().as_secs_f64();
    stage.report.left_out.extend(left_out);
    let report = &stage.report;
    // a line per reason parts were left out, even with --quiet: the others were nested
    // without them
    for (who, reason) in crate::sheets::left_out_groups(&report.left_out) {
        eprintln!("warning: {who} left out: {reason}");
    }
    if let Some(w) = crate::sheets::cut_warning(report, args.nest_seconds) {
        eprintln!("{w}");
    }
    for (name, text) in &stage.drawings {
        sheet_dir.write(name, text)?;
    }
    // nest.json with what the reader skipped and repaired
    let mut json = serde_json::to_value(report)?;
    json["notes"] = serde_json::to_value(&notes)?;
    let json = serde_json::to_string_pretty(&json)?;
    let timings = serde_json::to_string_pretty(&NestTimings {
        nest: stage_s,
        total: started.elapsed().as_secs_f64(),
        nest_search: &report.search,
    })?;
    sheet_dir.commit()?;
    files.commit(&[&json, &timings])?;
    if !args.quiet {
        let mut rows: Vec<Vec<String>> = vec![vec!["parts".into(), parts.len().to_string()]];
        rows.extend(crate::sheets::summary_rows(report, args.nest_seconds));
        for (i, s) in report.sheets.iter().enumerate() {
            rows.push(vec![
                format!("sheet {}", i + 1),
                format!(
                    "{} parts, {:.1} % used",
                    s.placements.len(),
                    100.0 * s.utilisation
                ),
            ]);
        }
        rows.push(vec!["wall time".into(), seconds(started.elapsed())]);
        let mut text = output::table(&rows);
        for n in &notes {
            text.push_str(&format!("note: {n}\n"));
        }
        output::print_out(&text)?;
    }
    if report.sheets.is_empty() {
        bail!(
            "nothing nested: all {} part(s) were left out (the warnings above; {} names each)",
            report.left_out.len(),
            args.out.join("nest.json").display()
        );
    }
    Ok(())
}

fn run_strip(args: &NestArgs, path: &Path) -> Result<()> {
    let text = output::read_text(path)?;
    let inst = StripInstance::from_json(&text).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let files = AtomicFiles::create(&args.out, &["strip.json"])?;
    let bar = progress_bar(args.quiet, 1000, "strip packing");
    let options = StripOptions {
        seed: args.seed,
        time_limit: Duration::from_secs_f64(args.nest_seconds),
        max_evaluations: args.nest_evaluations,
        ..StripOptions::default()
    };
    let result = sv_nest::nest_strip(&inst, &options, &mut |p| {
        bar.set_position((p.work_fraction * 1000.0) as u64);
        bar.set_message(format!(
            "length {}, density {:.2} %",
            number(p.best),
            100.0 * p.density
        ));
    });
    bar.finish_and_clear();
    if result.items_in_columns > 0 {
        eprintln!(
            "warning: strip packing: the {} s time cap cut the construction: {} of {} items \
             went in columns of their bounding boxes, without a search (--nest-seconds for more \
             time)",
            args.nest_seconds,
            result.items_in_columns,
            result.placements.len()
        );
    }
    if result.cut_by_time {
        eprintln!(
            "warning: strip packing: the {} s time cap cut the search short of its work \
             budget; the layout may differ on a faster or less busy machine",
            args.nest_seconds
        );
    }
    files.commit(&[&serde_json::to_string_pretty(&result)?])?;
    if !args.quiet {
        let mut rows = vec![
            vec!["instance".into(), result.name.clone()],
            vec![
                "strip".into(),
                format!("{} x {}", number(result.height), number(result.length)),
            ],
            vec!["density".into(), format!("{:.2} %", 100.0 * result.density)],
            vec!["items".into(), result.placements.len().to_string()],
        ];
        if result.items_in_columns > 0 {
            rows.push(vec![
                "construction".into(),
                format!(
                    "cut by the {} s cap: {} items in columns",
                    args.nest_seconds, result.items_in_columns
                ),
            ]);
        }
        rows.extend([
            vec![
                "search".into(),
                // (the construction cut or not, a search follows it in the time left)
                crate::sheets::search_row(
                    result.evaluations,
                    result.work_budget.unwrap_or(result.evaluations) * options.searches as u64,
                    result.construction_evaluations,
                    result.cut_by_time,
                    true,
                    args.nest_seconds,
                ),
            ],
            vec!["time".into(), format!("{:.1} s", result.elapsed_s)],
        ]);
        output::print_out(&output::table(&rows))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_that_share_a_stem_are_told_apart_by_their_directories() {
        let ids = |paths: &[&str]| {
            let paths: Vec<std::path::PathBuf> = paths.iter().map(Into::into).collect();
            let mut ids = file_ids(&paths);
            make_unique(ids.iter_mut());
            ids
        };
        assert_eq!(ids(&["strips/A01.dxf", "strips/A02.dxf"]), ["A01", "A02"]);
        assert_eq!(ids(&["a/part.dxf", "b/part.dxf"]), ["a/part", "b/part"]);
        // the order of the files does not change a file's id
        assert_eq!(ids(&["b/part.dxf", "a/part.dxf"]), ["b/part", "a/part"]);
        assert_eq!(
            ids(&["/x/a/part.dxf", "y/a/part.dxf", "b/part.DXF", "other.dxf"]),
            ["x/a/part", "y/a/part", "b/part", "other"]
        );
        assert_eq!(ids(&["part.dxf", "sub/part.dxf"]), ["part", "sub/part"]);
        // the same file twice: told apart by order
        assert_eq!(
            ids(&["a/part.dxf", "./a/part.dxf", "b/part.dxf"]),
            ["a/part", "a/part~2", "b/part"]
        );
        let mut taken = vec!["part#1".to_string(), "part#2".into(), "part#1".into()];
        make_unique(taken.iter_mut());
        assert_eq!(taken, ["part#1", "part#2", "part#1~2"]);
    }

    #[test]
    fn sheet_sizes_parse_and_bad_ones_name_the_flag() {
        let s = parse_sheets("3000x1500, 2500X1250").unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!((s[1].width, s[1].height), (2500.0, 1250.0));
        for bad in ["3000", "0x1500", "-3x2", "axb", "3000x", "nanx10"] {
            let e = parse_sheets(bad).unwrap_err().to_string();
            assert!(e.contains("--sheet"), "{bad}: {e}");
        }
    }
}
