//! Draws one unit of a build as it is cut, from the build's `strips.json`, with its parts
//! named (docs/figures/fab-unit.svg): the part and its cuts, the hub plate, the legs, the
//! necks and their pins, the fold marks and the nominal tile (the joint line).
//!
//! `cargo run -p sv-export --example unit_figure -- BUILD_DIR [STRIP UNIT] > unit.svg`
//! (default strip `A17`, its 5th unit: `A17-05` of the default pavilion).

use std::fmt::Write;

use sv_export::svg_path_data as path_data;
use sv_geom::{Point2, Vector2};
use sv_strips::StripsFile;
use sv_unit::UnitLayout;

/// Pixels per millimetre.
const SCALE: f64 = 1.6;
/// Room round the tile (mm).
const MARGIN: f64 = 20.0;
/// Width of the column of names right of the unit (px).
const NAMES: f64 = 330.0;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: unit_figure BUILD_DIR [STRIP UNIT]";
    let dir = args.get(1).expect(usage);
    let strip_id = args.get(2).map_or("A17", String::as_str);
    let index: usize = args.get(3).map_or(Ok(5), |a| a.parse()).expect(usage);
    let path = format!("{dir}/strips.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let file: StripsFile = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
    let strip = file
        .strips
        .iter()
        .find(|s| s.id == strip_id)
        .unwrap_or_else(|| panic!("{path} has no strip {strip_id}"));
    let tile = strip
        .flat
        .get(index - 1)
        .unwrap_or_else(|| panic!("strip {strip_id} has no unit {index}"));
    let params = &file.params.profile;
    let widths = params.cut_widths();
    let corners = tile.primary.map(|p| Point2::new(p[0], p[1]));
    let layout = UnitLayout::new(&corners, &widths).expect("the unit's cut");
    print!("{}", draw(strip, tile.unit, &corners, &layout, params));
}

fn draw(
    strip: &sv_strips::StripRecord,
    unit: usize,
    tile: &[Point2; 4],
    layout: &UnitLayout,
    params: &sv_strips::ProfileParams,
) -> String {
    // the unit's frame: its tile's bounding box, y up as in the DXF
    let (lo, hi) = tile.iter().fold(
        (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let (x0, y1) = (lo.x - MARGIN, hi.y + MARGIN);
    let width = (hi.x - lo.x + 2.0 * MARGIN) * SCALE;
    let height = (hi.y - lo.y + 2.0 * MARGIN) * SCALE;
    let px = |p: Point2| ((p.x - x0) * SCALE, (y1 - p.y) * SCALE);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" font-family="sans-serif" font-size="13">"#,
        width + NAMES,
        height + 30.0
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    // the part in mm, y up, clipped to the unit's window
    let _ = writeln!(
        s,
        r#"<clipPath id="unit"><rect width="{width:.1}" height="{height:.1}"/></clipPath><g clip-path="url(#unit)"><g transform="scale({SCALE} {}) translate({:.3} {:.3})">"#,
        -SCALE, -x0, -y1
    );
    let mut part = path_data(&strip.outline, 2);
    for c in &strip.cuts {
        part.push_str(&path_data(c, 2));
    }
    let hub: Vec<String> = layout
        .hub
        .iter()
        .map(|p| format!("{:.2},{:.2}", p.x, p.y))
        .collect();
    let thin = 1.0 / SCALE;
    // the part grey, its hub plate green (within the part: the reliefs stay open)
    let _ = writeln!(
        s,
        r##"<clipPath id="part"><path d="{part}" clip-rule="evenodd"/></clipPath><path d="{part}" fill="#dfe5ec" fill-rule="evenodd"/><polygon points="{}" fill="#c9e8d6" clip-path="url(#part)"/><path d="{part}" fill="none" stroke="black" stroke-width="{thin:.3}"/>"##,
        hub.join(" ")
    );
    let tile_pts: Vec<String> = tile
        .iter()
        .map(|p| format!("{:.2},{:.2}", p.x, p.y))
        .collect();
    let _ = writeln!(
        s,
        r##"<polygon points="{}" fill="none" stroke="#888" stroke-width="{thin:.3}" stroke-dasharray="{:.2} {:.2}"/>"##,
        tile_pts.join(" "),
        4.0 * thin,
        3.0 * thin
    );
    for m in &strip.fold_marks {
        let _ = writeln!(
            s,
            r##"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#d22" stroke-width="{:.3}"/>"##,
            m[0][0],
            m[0][1],
            m[1][0],
            m[1][1],
            2.0 * thin
        );
    }
    let pins = layout.pins();
    for p in pins.hub.iter().chain(&pins.rim) {
        let _ = writeln!(
            s,
            r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="#d22"/>"##,
            p.x,
            p.y,
            2.5 * thin
        );
    }
    let _ = writeln!(s, "</g></g>");
    // the names, each with a leader to a point of the part
    let centre = Point2::from(tile.iter().fold(Vector2::zeros(), |a, p| a + p.coords) / 4.0);
    let leg = 1;
    let on_rim = {
        // the middle of side 2, half the rim inside the plate
        let (a, b) = (layout.plate[2], layout.plate[3]);
        let m = Point2::from((a.coords + b.coords) / 2.0);
        m + (centre - m).normalize() * (params.rim_width / 2.0)
    };
    let slot = {
        let p = layout.slot_paths[2];
        Point2::from((p[1].coords + p[2].coords) / 2.0)
    };
    let names = [
        (
            pins.rim[leg],
            format!("rim neck of leg {leg} ({} mm)", params.neck_width),
        ),
        (
            Point2::from((pins.hub[leg].coords + pins.rim[leg].coords) / 2.0),
            format!("leg {leg} ({} mm)", params.leg_width),
        ),
        (
            pins.hub[leg],
            format!("hub neck of leg {leg} ({} mm)", params.neck_width),
        ),
        (
            on_rim,
            format!("rim, the primary plate ({} mm)", params.rim_width),
        ),
        (
            slot,
            format!("hook slot ({} mm, round ends)", params.slot_width),
        ),
        (centre, "hub plate (label etched here)".to_string()),
        (tile[3], "nominal tile: the joint line".to_string()),
    ];
    // the bridge to the next unit of the strip (the pin at the middle of its joint)
    let bridge = strip.pins.iter().find(|p| p.units[0] == unit).map(|p| {
        (
            Point2::new(p.at[0], p.at[1]),
            format!(
                "bridge to the next unit ({} x {} mm)",
                params.neck_width, params.neck_length
            ),
        )
    });
    let names = names.into_iter().chain(bridge);
    // top to bottom as their points are, so that the leaders do not cross
    let mut names: Vec<((f64, f64), String)> =
        names.into_iter().map(|(at, name)| (px(at), name)).collect();
    names.sort_by(|a, b| a.0 .1.total_cmp(&b.0 .1));
    let step = height / (names.len() + 1) as f64;
    for (i, ((ax, ay), name)) in names.iter().enumerate() {
        let ty = step * (i + 1) as f64;
        let tx = width + 20.0;
        let _ = writeln!(
            s,
            r##"<line x1="{ax:.1}" y1="{ay:.1}" x2="{:.1}" y2="{ty:.1}" stroke="#333" stroke-width="0.7"/><circle cx="{ax:.1}" cy="{ay:.1}" r="2" fill="#333"/><text x="{tx:.1}" y="{:.1}">{name}</text>"##,
            tx - 4.0,
            ty + 4.0
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="10" y="{:.0}">One unit as cut ({}; t = {} mm): grey the part, green its hub plate, red dots the pins, red lines the fold marks; the notches into the hub plate are reliefs.</text>"#,
        height + 20.0,
        unit_label(strip, unit),
        params.thickness
    );
    s.push_str("</svg>\n");
    s
}

/// The unit's label in its strip, as etched (`A17-05`).
fn unit_label(strip: &sv_strips::StripRecord, unit: usize) -> String {
    let at = strip.units.iter().position(|&u| u == unit).unwrap_or(0);
    format!("{}-{:02}", strip.id, at + 1)
}
