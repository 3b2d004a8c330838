//! `report.html`: one self-contained page. Styles, plots, data and scripts are inline; the
//! viewer's ES modules (three.js included, once) sit in inert `<script type="text/plain">`
//! blocks that a short script turns into `blob:` URLs named by an import map. A
//! content-security policy forbids every network load, so the page works from `file://`,
//! offline, sent by mail.

use std::fmt::Write;

use serde_json::{json, Value};
use sv_frame::QuadMesh;
use sv_geom::Point3;

use crate::plot::{escape, histogram, short, top_view, Histogram, TopView, COLOUR_MAP};
use crate::sheets::sheet_svg;
use crate::summary::{strip_cut_length, strip_hub_face, strip_pierces, Summary, STEEL_DENSITY};
use crate::{ReportError, ReportInput};

const CSS: &str = include_str!("report.css");
const APP_JS: &str = include_str!("report.js");

/// Background of the 3D view (also what a test compares the canvas against).
pub const VIEW_BACKGROUND: &str = "#101317";

/// The page's content-security policy: inline scripts and styles, `blob:` modules,
/// `data:`/`blob:` images, and nothing from any network.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'none'; script-src 'unsafe-inline' blob:; \
     style-src 'unsafe-inline'; img-src data: blob:";

/// The whole report page.
pub fn report_html(input: &ReportInput<'_>) -> Result<String, ReportError> {
    input.validate()?;
    let summary = Summary::of(input);
    let mut page = String::with_capacity(sv_viewer::THREE_JS.len() + 600_000);
    let title = format!("Spin-Valence build report: {}", input.target);
    let _ = write!(
        page,
        r#"<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="{}">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="{}">
<title>{}</title>
<link rel="icon" href="data:,">
<style>
{CSS}</style>
</head>
<body data-ready="no">
"#,
        CONTENT_SECURITY_POLICY,
        escape(input.generator),
        escape(&title)
    );
    let _ = write!(
        page,
        r#"<header><h1>Spin-Valence build report</h1><p class="subtitle">{} &middot; {} units &middot; {} strips{} &middot; {}</p></header>
<main>
"#,
        escape(input.target),
        summary.units,
        summary.strips,
        summary
            .sheets
            .map_or(String::new(), |n| format!(" &middot; {n} sheets")),
        escape(input.generator)
    );
    page.push_str(&summary_section(input, &summary));
    // per unit, the goals not met there: the 3D view's colours, and whether it offers them
    let goals = goal_flags(input);
    page.push_str(&frame_section(input, &goals));
    page.push_str(&plots_section(input));
    page.push_str(&sheets_section(input));
    page.push_str(&strips_section(input)?);
    page.push_str("</main>\n");
    let _ = writeln!(
        page,
        "<footer>Made by {} from <code>frame.json</code>, <code>strips.json</code>{} beside this file; \
         the figures are defined in <code>docs/report.md</code>. This page needs no network: \
         three.js r170 (MIT licence, &copy; three.js authors) is inside it.</footer>",
        escape(input.generator),
        if input.nest.is_some() {
            " and <code>nest.json</code>"
        } else {
            ""
        }
    );
    page.push_str(&scripts(input, &goals));
    page.push_str("</body>\n</html>\n");
    Ok(page)
}

/// A row of the summary table: key (for tests), label, shown value, exact value,
/// definition.
struct Row {
    key: &'static str,
    label: &'static str,
    shown: String,
    value: String,
    definition: String,
}

/// The summary rows: key, label, value as shown and as an exact number, definition.
fn summary_rows(input: &ReportInput<'_>, s: &Summary) -> Vec<Row> {
    let t = s.thickness_mm;
    let mut rows = vec![
        Row {
            key: "units",
            label: "Units",
            shown: s.units.to_string(),
            value: s.units.to_string(),
            definition: "units of the frame (frame.json): one hub, four legs and one primary tile each".into(),
        },
        Row {
            key: "strips",
            label: "Strips",
            shown: s.strips.to_string(),
            value: s.strips.to_string(),
            definition: "parts to cut: units joined by necks into one piece (strips.json, strips/*.dxf)".into(),
        },
        Row {
            key: "sheets",
            label: "Sheets",
            shown: s.sheets.map_or("not nested".into(), |n| n.to_string()),
            value: s.sheets.map_or(String::new(), |n| n.to_string()),
            definition: match input.nest {
                Some(n) => format!(
                    "plasma sheets of {} x {} mm used by the nesting (nest.json), lower bound {}",
                    n.report.sheet.width, n.report.sheet.height, n.report.lower_bound_sheets
                ),
                None => "this build did not nest the strips onto sheets".into(),
            },
        },
        Row {
            key: "steel_area_mm2",
            label: "Steel area",
            shown: format!("{:.2} m\u{00b2}", s.steel_area_mm2 * 1e-6),
            value: s.steel_area_mm2.to_string(),
            definition: "net area of all parts: outlines minus slots, arcs exact (sum of strips.json area_mm2)".into(),
        },
        Row {
            key: "steel_mass_kg",
            label: "Steel weight",
            shown: format!("{:.1} kg", s.steel_mass_kg),
            value: s.steel_mass_kg.to_string(),
            definition: format!(
                "steel area x {t} mm thickness x {STEEL_DENSITY} kg/m\u{00b3}: the parts, without offcuts"
            ),
        },
    ];
    if let Some(n) = input.nest {
        let sheet_area: f64 = n.report.sheets.iter().map(|x| x.width * x.height).sum();
        let mass = sheet_area * t * 1e-9 * STEEL_DENSITY;
        rows.push(Row {
            key: "sheet_mass_kg",
            label: "Sheet steel to buy",
            shown: format!("{mass:.1} kg"),
            value: mass.to_string(),
            definition: format!(
                "the sheets' area ({:.2} m\u{00b2}) x {t} mm x {STEEL_DENSITY} kg/m\u{00b3}; parts / sheets = {:.1} %",
                sheet_area * 1e-6,
                if sheet_area > 0.0 { 100.0 * s.steel_area_mm2 / sheet_area } else { 0.0 }
            ),
        });
    }
    rows.extend([
        Row {
            key: "cut_length_mm",
            label: "Cut length",
            shown: format!("{:.1} m", s.cut_length_mm * 1e-3),
            value: s.cut_length_mm.to_string(),
            definition: "every outline and slot (DXF layers OUTSIDE and INSIDE), arcs at their true length; plasma time = cut length / cutting speed + pierces x pierce time".into(),
        },
        Row {
            key: "pierces",
            label: "Pierces",
            shown: s.pierces.to_string(),
            value: s.pierces.to_string(),
            definition: "one per closed cut contour: every outline and every slot".into(),
        },
        Row {
            key: "welds",
            label: "Welds to make",
            shown: s.welds.to_string(),
            value: s.welds.to_string(),
            definition: "hub welds + primary welds, below".into(),
        },
        Row {
            key: "hub_welds",
            label: "&nbsp;&nbsp;at hub overlaps",
            shown: s.hub_welds.to_string(),
            value: s.hub_welds.to_string(),
            definition: "one per link (interior mesh edge): the hubs of the two units overlap there and are welded".into(),
        },
        Row {
            key: "primary_welds",
            label: "&nbsp;&nbsp;at primary joints",
            shown: s.primary_welds.to_string(),
            value: s.primary_welds.to_string(),
            definition: "one per link whose primary tiles are not cut as one piece (no neck between them): neighbouring strips meet there on site".into(),
        },
    ]);
    rows
}

fn summary_section(input: &ReportInput<'_>, s: &Summary) -> String {
    let mut h = String::from("<section id=\"summary\"><h2>Summary</h2><table>\n");
    for r in summary_rows(input, s) {
        let _ = writeln!(
            h,
            r#"<tr data-key="{}" data-value="{}"><th>{}</th><td class="value">{}</td><td class="definition">{}</td></tr>"#,
            r.key,
            r.value,
            r.label,
            escape(&r.shown),
            escape(&r.definition)
        );
    }
    h.push_str("</table>\n");
    h.push_str(&quality_table(input));
    if let Some(fold) = input.fold_check {
        h.push_str(&fold_table(fold));
    }
    h.push_str("</section>\n");
    h
}

/// Per link the gap a person reads: on a frame whose joints were closed the joint's, on the
/// plates as cut (a bridge's sides from its fold line, a weld's plates apart, thickness
/// included), else the primary gap of the expanded tiles; and what it is called.
fn link_gaps(frame: &sv_frame::FrameFile) -> (Vec<f64>, &'static str) {
    if frame.joints_closed() {
        let gaps = frame
            .links
            .iter()
            .map(|l| l.joint.map_or(l.primary_gap, |j| j.gap))
            .collect();
        (gaps, "joint gap")
    } else {
        (
            frame.links.iter().map(|l| l.primary_gap).collect(),
            "primary gap",
        )
    }
}

/// The fold check of the parts as cut (`spinvalence check DIR`): a line saying whether every
/// row holds, then every row, the failing ones marked.
fn fold_table(fold: &sv_frame::CheckReport) -> String {
    let failing = fold.rows.iter().filter(|r| !r.ok).count();
    let verdict = if failing == 0 {
        "Every row holds: the parts as cut fold into the frame.".to_string()
    } else {
        format!(
            "{failing} of {} rows fail: the steel as cut does not fold into the frame there \
             (the build exits 0 with a warning; spinvalence check exits 1).",
            fold.rows.len()
        )
    };
    let mut h = format!(
        "<h3 style=\"margin-top:16px\">Fold check of the parts as cut</h3>\n<p class=\"fold-verdict{}\">{}</p>\n<table class=\"quality fold\"><tr><th>check</th><th>worst</th><th>limit</th><th>where</th><th></th></tr>",
        if failing == 0 { "" } else { " fail" },
        escape(&verdict)
    );
    for r in &fold.rows {
        let limit = if r.limit.is_finite() {
            short(r.limit)
        } else {
            "-".into()
        };
        let _ = write!(
            h,
            "<tr class=\"{}\"><th>{}</th><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            if r.ok { "" } else { "fail" },
            escape(&r.name),
            escape(&short(r.worst)),
            escape(&limit),
            escape(&r.at),
            r.verdict()
        );
    }
    h.push_str("</table>\n");
    h
}

/// Frame and hub mesh quality, from the files' own figures.
fn quality_table(input: &ReportInput<'_>) -> String {
    let links = &input.frame.links;
    let (gaps, gap_name) = link_gaps(input.frame);
    let overlaps: Vec<f64> = links.iter().map(|l| l.hub_overlap).collect();
    let mut rows: Vec<(String, String)> = Vec::new();
    if let Some((_, lo, median, hi)) = crate::plot::stats(&gaps) {
        rows.push((
            gap_name.into(),
            format!(
                "{} / {} / {} mm (min / median / max), sum {} mm",
                short(lo),
                short(median),
                short(hi),
                short(gaps.iter().sum())
            ),
        ));
    }
    if let Some((_, lo, median, hi)) = crate::plot::stats(&overlaps) {
        rows.push((
            "hub overlap".into(),
            format!(
                "{} / {} / {} mm (min / median / max)",
                short(lo),
                short(median),
                short(hi)
            ),
        ));
    }
    let pins = input.strips.strips.iter().flat_map(|s| &s.pins);
    let (bend, twist) = pins.fold((0.0f64, 0.0f64), |(b, t), p| {
        (b.max(p.bend.abs()), t.max(p.twist.abs()))
    });
    rows.push((
        "necks".into(),
        format!(
            "largest bend {:.1} deg, largest twist {:.1} deg",
            bend.to_degrees(),
            twist.to_degrees()
        ),
    ));
    if let Some(m) = input.hub_mesh {
        rows.push((
            "hub mesh".into(),
            format!(
                "planarity max {}, conical residual max {} deg, distance to target max {} mm, target covered {:.1} %",
                short(m.planarity_max),
                short(m.conical_max_deg),
                short(m.closeness_max * m.mean_edge),
                100.0 * m.coverage
            ),
        ));
        if !m.layout.is_empty() {
            rows.push(("layout".into(), m.layout.clone()));
        }
        if !m.unmet.is_empty() {
            rows.push(("goals not met".into(), m.unmet.join("; ")));
        }
    }
    let mut h =
        String::from("<h3 style=\"margin-top:16px\">Frame quality</h3><table class=\"quality\">");
    for (k, v) in rows {
        let _ = write!(h, "<tr><th>{}</th><td>{}</td></tr>", escape(&k), escape(&v));
    }
    h.push_str("</table>\n");
    h
}

fn frame_section(input: &ReportInput<'_>, goals: &[Vec<String>]) -> String {
    let e = input.frame.params.expansion;
    let goals_radio = if goals.iter().any(|g| !g.is_empty()) {
        "\n<label><input type=\"radio\" name=\"colour\" value=\"goals\"> unmet goals</label>"
    } else {
        ""
    };
    format!(
        r#"<section id="frame"><h2>The frame</h2>
<div class="frame"><div id="view" aria-label="3D view of the frame"></div>
<aside class="side">
<fieldset><legend>Colour by</legend>
<label><input type="radio" name="colour" value="gap" checked> gap</label>
<label><input type="radio" name="colour" value="overlap"> hub overlap</label>
<label><input type="radio" name="colour" value="strip"> strip</label>{goals_radio}</fieldset>
<div id="legend"></div>
<fieldset style="margin-top:10px"><legend>Show</legend>
<label><input type="checkbox" data-layer="hubs" checked> hubs</label>
<label><input type="checkbox" data-layer="primaries" checked> primary tiles</label>
<label><input type="checkbox" data-layer="legs" checked> legs</label></fieldset>
<button id="reset-view" type="button">Reset view</button>
<div id="info" data-unit=""></div>
</aside></div>
<p class="muted">Drag to orbit, scroll to zoom, right-drag to pan; click a unit for its label, angles, gaps and overlaps. Hubs are opaque, primary tiles translucent{}; legs join hub corner i to primary corner i + 1.</p>
</section>
"#,
        if (e - 1.0).abs() > 1e-12 {
            format!(" (drawn expanded by e = {})", short(e))
        } else {
            String::new()
        }
    )
}

fn plots_section(input: &ReportInput<'_>) -> String {
    let frame = input.frame;
    let (gaps, gap_name) = link_gaps(frame);
    let overlaps: Vec<f64> = frame.links.iter().map(|l| l.hub_overlap).collect();
    let mesh = QuadMesh {
        vertices: frame
            .mesh
            .vertices
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect(),
        faces: frame.mesh.faces.clone(),
    };
    let planarity = mesh.planarity_residuals();
    let conical: Vec<f64> = mesh
        .conical_residuals()
        .into_iter()
        .map(|(_, r)| r.to_degrees())
        .collect();
    // the hub plates as cut where the frame has them
    let quads: Vec<[[f64; 3]; 4]> = frame
        .units
        .iter()
        .map(|u| u.hub_plate.unwrap_or(u.hub))
        .collect();
    let labels: Vec<&str> = frame.units.iter().map(|u| u.id.as_str()).collect();
    let theta: Vec<f64> = frame.units.iter().map(|u| u.theta.to_degrees()).collect();
    let depth: Vec<f64> = frame
        .units
        .iter()
        .map(|u| u.depth.unwrap_or(f64::NAN))
        .collect();
    let figure = |svg: String, caption: &str| {
        format!(
            "<figure>{svg}<figcaption>{}</figcaption></figure>\n",
            escape(caption)
        )
    };
    let mut h = String::from("<section id=\"plots\"><h2>Plots</h2><div class=\"plots\">\n");
    h.push_str(&figure(
        histogram(&gaps, &Histogram {
            id: "hist-gap",
            title: if gap_name == "joint gap" { "Joint gaps" } else { "Primary gaps" },
            quantity: if gap_name == "joint gap" {
                "gap at the joint, on the plates as cut"
            } else {
                "gap between facing expanded primary sides"
            },
            unit: "mm",
            items: "links",
        }),
        if gap_name == "joint gap" {
            "Per link, on the plates as cut: at a bridge how far the facing sides are from its fold line, at a weld the gap the welder closes, thickness included (frame.json links[].joint.gap)."
        } else {
            "The distance the welder has to bridge between neighbouring primary tiles, per link (frame.json primary_gap)."
        },
    ));
    h.push_str(&figure(
        histogram(&overlaps, &Histogram {
            id: "hist-overlap",
            title: "Hub overlaps",
            quantity: "hub overlap",
            unit: "mm",
            items: "links",
        }),
        "How far the two hub tips pass each other along the line between the hub centres, per link (frame.json hub_overlap); negative: they do not reach.",
    ));
    h.push_str(&figure(
        histogram(
            &planarity,
            &Histogram {
                id: "hist-planarity",
                title: "Planarity of the hub mesh faces",
                quantity: "diagonal distance / mean edge",
                unit: "",
                items: "faces",
            },
        ),
        "Distance between the two diagonals of each face over its mean edge: 0 for a planar face.",
    ));
    h.push_str(&figure(
        histogram(&conical, &Histogram {
            id: "hist-conical",
            title: "Conical residuals of the hub mesh",
            quantity: "|w1 - w2 + w3 - w4|",
            unit: "deg",
            items: "vertices",
        }),
        "Angle balance at every interior vertex with four faces: 0 when the four face planes touch one cone.",
    ));
    h.push_str(&figure(
        top_view(
            &quads,
            &theta,
            &labels,
            &TopView {
                id: "map-theta",
                title: "Rotation angle theta across the surface",
                quantity: "theta",
                unit: "deg",
            },
        ),
        "Each hub seen from above, coloured by its unit's rotation angle theta.",
    ));
    h.push_str(&figure(
        top_view(&quads, &depth, &labels, &TopView {
            id: "map-depth",
            title: "Frame depth across the surface",
            quantity: "depth |P|",
            unit: "mm",
        }),
        "Each hub seen from above, coloured by the frame depth at its unit (distance hub to primary tile).",
    ));
    h.push_str("</div></section>\n");
    h
}

fn sheets_section(input: &ReportInput<'_>) -> String {
    let mut h = String::from("<section id=\"sheets\"><h2>Sheets</h2>\n");
    let Some(nest) = input.nest else {
        h.push_str(
            "<p class=\"note\" id=\"no-nesting\">No nesting data: this build did not nest the strips onto sheets. \
             The strips' DXF files are in <code>strips/</code>; <code>spinvalence nest strips/*.dxf</code> nests them.</p></section>\n",
        );
        return h;
    };
    let r = nest.report;
    let _ = writeln!(
        h,
        "<p class=\"muted\">{} sheets of {} x {} mm, margin {} mm, spacing {} mm between parts; lower bound {} sheets. \
         Drawn from strips.json moved by the placements of nest.json.</p><div class=\"sheets\">",
        r.sheets.len(),
        r.sheet.width,
        r.sheet.height,
        r.sheet.margin,
        r.sheet.spacing,
        r.lower_bound_sheets
    );
    let strips = input.strips_by_id();
    for (i, sheet) in r.sheets.iter().enumerate() {
        let _ = writeln!(
            h,
            "<figure>{}<figcaption>Sheet {}{}: {} x {} mm, {} strips, utilisation {:.1} %</figcaption></figure>",
            sheet_svg(input, &strips, sheet, i),
            i + 1,
            nest.sheet_files
                .get(i)
                .map_or(String::new(), |f| format!(" (<code>{}</code>)", escape(f))),
            sheet.width,
            sheet.height,
            sheet.placements.len(),
            100.0 * sheet.utilisation
        );
    }
    h.push_str("</div>");
    if !r.left_out.is_empty() {
        h.push_str("<p class=\"note\">Not nested: ");
        let parts: Vec<String> = r
            .left_out
            .iter()
            .map(|l| format!("{} ({})", escape(&l.part), escape(&l.reason)))
            .collect();
        h.push_str(&parts.join("; "));
        h.push_str("</p>");
    }
    h.push_str("</section>\n");
    h
}

fn strips_section(input: &ReportInput<'_>) -> Result<String, ReportError> {
    let placements = input.placements()?;
    let mut h = String::from(
        "<section id=\"strips\"><h2>Strips</h2><p class=\"muted\">The same rows as <code>bom.csv</code>.</p><table>\
         <tr><th>strip</th><th class=\"num\">units</th><th>first - last unit</th><th class=\"num\">length x width (mm)</th>\
         <th class=\"num\">area (m\u{00b2})</th><th class=\"num\">cut length (m)</th><th class=\"num\">pierces</th>\
         <th class=\"num\">largest bend / twist (deg)</th><th>sheet</th>\
         <th title=\"the face of the part the hubs come out of: etched (the face the marks are on; \
         each hub carries a circle with a dot) or back (a circle with a cross)\">hub face</th></tr>\n",
    );
    for s in &input.strips.strips {
        let first = s
            .units
            .first()
            .map_or("", |&u| input.frame.units[u].id.as_str());
        let last = s
            .units
            .last()
            .map_or("", |&u| input.frame.units[u].id.as_str());
        let (bend, twist) = s.pins.iter().fold((0.0f64, 0.0f64), |(b, t), p| {
            (b.max(p.bend.abs()), t.max(p.twist.abs()))
        });
        let sheet = placements
            .get(s.id.as_str())
            .map_or("-".to_string(), |p| p.sheet.to_string());
        let _ = writeln!(
            h,
            "<tr data-strip=\"{}\"><td>{}</td><td class=\"num\">{}</td><td>{} - {}</td><td class=\"num\">{:.0} x {:.0}</td>\
             <td class=\"num\">{:.3}</td><td class=\"num\">{:.2}</td><td class=\"num\">{}</td><td class=\"num\">{:.1} / {:.1}</td><td>{}</td><td class=\"hub-face\">{}</td></tr>",
            escape(&s.id),
            escape(&s.id),
            s.units.len(),
            escape(first),
            escape(last),
            s.size_mm[0],
            s.size_mm[1],
            s.area_mm2 * 1e-6,
            strip_cut_length(s) * 1e-3,
            strip_pierces(s),
            bend.to_degrees(),
            twist.to_degrees(),
            sheet,
            escape(&strip_hub_face(s, |u| input.frame.units[u].id.clone()))
        );
    }
    h.push_str("</table></section>\n");
    Ok(h)
}

fn round(x: f64, unit: f64) -> Value {
    if x.is_finite() {
        json!((x / unit).round() * unit)
    } else {
        Value::Null
    }
}

fn finite(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// The data of the 3D view: units (corners in mm to 0.01, drawing only), links
/// `[i, j, gap, overlap]` and per unit the goals not met there ([`goal_flags`]); the
/// figures the unit panel shows keep their full precision.
fn view_data(input: &ReportInput<'_>, goals: &[Vec<String>]) -> Value {
    let pts = |q: &[[f64; 3]; 4]| -> Value {
        Value::Array(
            q.iter()
                .map(|p| Value::Array(p.iter().map(|&x| round(x, 0.01)).collect()))
                .collect(),
        )
    };
    let units: Vec<Value> = input
        .frame
        .units
        .iter()
        .map(|u| {
            json!({
                "id": u.id, "strip": u.strip,
                "theta": finite(u.theta), "phi": finite(u.phi),
                "depth": u.depth.map_or(Value::Null, |d| round(d, 0.01)),
                "hub": pts(&u.hub_plate.unwrap_or(u.hub)), "primary": pts(&u.primary),
            })
        })
        .collect();
    let (gaps, gap_name) = link_gaps(input.frame);
    let links: Vec<Value> = input
        .frame
        .links
        .iter()
        .zip(&gaps)
        .map(|(l, &gap)| json!([l.units[0], l.units[1], finite(gap), finite(l.hub_overlap)]))
        .collect();
    json!({
        "units": units,
        "links": links,
        "goals": goals,
        "expansion": input.frame.params.expansion,
        "background": VIEW_BACKGROUND,
        "colour_map": COLOUR_MAP,
        "gap_name": gap_name,
    })
}

/// Per unit, the goals not met there (empty lists when all hold): the hub mesh's
/// ([`hub_mesh_flags`]) and, for each row of the fold check that fails on the parts as
/// cut, every unit where it found a value outside its limit (`CheckRow::units`: both units
/// of a link). Empty when the build met every goal.
fn goal_flags(input: &ReportInput<'_>) -> Vec<Vec<String>> {
    let frame = input.frame;
    let mut flags = hub_mesh_flags(input);
    let failing = input
        .fold_check
        .iter()
        .flat_map(|fold| &fold.rows)
        .filter(|r| !r.ok);
    for row in failing {
        for &u in row.units.iter().filter(|&&u| u < frame.units.len()) {
            if flags.is_empty() {
                flags = vec![Vec::new(); frame.units.len()];
            }
            flags[u].push(format!("fold check: {}", row.name));
        }
    }
    flags
}

/// Per unit, the hub mesh goals not met there (empty lists when all hold): faces whose
/// planarity, sides or edge ratio miss the goal, the faces around vertices whose conical
/// residual does, and the faces at the worst vertex of the distance goals the report
/// names. Empty when the hub mesh met every goal.
fn hub_mesh_flags(input: &ReportInput<'_>) -> Vec<Vec<String>> {
    let Some(m) = input.hub_mesh.filter(|m| !m.unmet.is_empty()) else {
        return Vec::new();
    };
    let frame = input.frame;
    let mesh = QuadMesh {
        vertices: frame
            .mesh
            .vertices
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect(),
        faces: frame.mesh.faces.clone(),
    };
    let goals = sv_surface::Goals::default();
    let unmet = |prefix: &str| m.unmet.iter().any(|l| l.starts_with(prefix));
    let mut flags: Vec<Vec<&str>> = vec![Vec::new(); mesh.faces.len()];
    let planarity = mesh.planarity_residuals();
    for f in 0..mesh.faces.len() {
        if unmet("planarity") && planarity[f] > goals.planarity {
            flags[f].push("planarity");
        }
        let p = mesh.face_points(f);
        let e = [0, 1, 2, 3].map(|k| (p[(k + 1) % 4] - p[k]).norm());
        let (lo, hi) = e
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
        if unmet("faces with edge ratio") && hi > sv_surface::EDGE_RATIO_LIMIT * lo {
            flags[f].push("edge ratio");
        }
        let unit = m.unit_size;
        let (a, b) = goals.side_range;
        if unmet("face sides") && (lo < a * unit || hi > b * unit) {
            flags[f].push("face sides");
        }
    }
    let mut at_vertex = |v: usize, goal: &'static str| {
        for (f, face) in mesh.faces.iter().enumerate() {
            if face.contains(&v) && !flags[f].contains(&goal) {
                flags[f].push(goal);
            }
        }
    };
    if unmet("conical") {
        for (v, r) in mesh.conical_residuals() {
            if r.to_degrees() > goals.conical_deg {
                at_vertex(v, "conical");
            }
        }
    }
    if unmet("distance to target") {
        at_vertex(m.closeness_worst_vertex, "distance to target");
    }
    if unmet("distance to boundary") {
        at_vertex(m.boundary_worst_vertex, "distance to boundary");
    }
    frame
        .units
        .iter()
        .map(|u| {
            let at = flags.get(u.face).map_or(&[][..], |v| &v[..]);
            at.iter().map(|g| g.to_string()).collect()
        })
        .collect()
}

/// Text for a raw-text `<script>` element: `</script` and `<!--` cannot occur in it.
fn script_text(source: &str) -> String {
    source
        .replace("</script", "<\\/script")
        .replace("</SCRIPT", "<\\/SCRIPT")
        .replace("<!--", "<\\!--")
}

/// A viewer module with its relative imports renamed to the bare names of the import map.
fn module_text(module: &sv_viewer::Module) -> String {
    let mut source = module.source.to_string();
    for (spec, path) in module.imports {
        for q in ['\'', '"'] {
            source = source.replace(&format!("{q}{spec}{q}"), &format!("{q}{path}{q}"));
        }
    }
    script_text(&source)
}

const BOOTSTRAP: &str = "(() => {
  const imports = {};
  for (const s of document.querySelectorAll('script[type=\"text/plain\"][data-module]')) {
    imports[s.dataset.module] = URL.createObjectURL(new Blob([s.textContent], { type: 'text/javascript' }));
  }
  const map = document.createElement('script');
  map.type = 'importmap';
  map.textContent = JSON.stringify({ imports });
  document.currentScript.after(map);
})();
";

fn scripts(input: &ReportInput<'_>, goals: &[Vec<String>]) -> String {
    let data = view_data(input, goals).to_string().replace('<', "\\u003c");
    let mut h = format!("<script type=\"application/json\" id=\"sv-data\">{data}</script>\n");
    for m in &sv_viewer::MODULES {
        let _ = writeln!(
            h,
            "<script type=\"text/plain\" data-module=\"{}\">{}</script>",
            m.path,
            module_text(m)
        );
    }
    let _ = writeln!(h, "<script>\n{BOOTSTRAP}</script>");
    let _ = writeln!(
        h,
        "<script type=\"module\">\n{}</script>",
        script_text(APP_JS)
    );
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_cannot_close_their_element() {
        assert_eq!(
            script_text("a = '</script>'; // <!-- x"),
            "a = '<\\/script>'; // <\\!-- x"
        );
    }

    #[test]
    fn modules_import_each_other_by_bare_names() {
        for m in &sv_viewer::MODULES {
            let text = module_text(m);
            for (spec, path) in m.imports {
                assert!(!text.contains(&format!("'{spec}'")), "{}: {spec}", m.path);
                assert!(
                    text.contains(&format!("from '{path}'")),
                    "{}: {path}",
                    m.path
                );
            }
            assert!(!text.to_lowercase().contains("</script"));
        }
        assert!(APP_JS.contains("from 'viewer.js'"));
    }
}
