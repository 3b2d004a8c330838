//! `DIR/report.html` and `DIR/bom.csv` of the default build: every summary figure
//! recomputed here from the other output files (frame.json, strips.json, strips/*.dxf,
//! nest.json), by other means than the report uses; the bill of materials row by row; and
//! the page itself in headless Chromium: opened from disk, no network request, a 3D view
//! that drew something, a unit picked with the mouse.

use std::collections::{HashMap, HashSet};
use std::fs;
use std::path::Path;
use std::time::Duration;

use serde_json::Value;

use crate::build::default_build;
use crate::util::{dxf_entities, num, read_json, DxfEntity};

/// The summary rows of report.html: `data-key` -> (`data-value`, shown text).
fn summary(html: &str) -> HashMap<String, (String, String)> {
    let mut rows = HashMap::new();
    for part in html.split("<tr data-key=\"").skip(1) {
        let key = part.split('"').next().unwrap().to_string();
        let value = part
            .split("data-value=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .to_string();
        let shown = part
            .split("<td class=\"value\">")
            .nth(1)
            .unwrap()
            .split("</td>")
            .next()
            .unwrap()
            .to_string();
        rows.insert(key, (value, shown));
    }
    rows
}

/// Perimeter of a closed polyline with bulges: an arc of bulge b over chord c has radius
/// r = c (1 + b^2) / (4 |b|) and sweep 4 atan |b|.
fn perimeter(v: &[[f64; 3]]) -> f64 {
    (0..v.len())
        .map(|i| {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let c = (b[0] - a[0]).hypot(b[1] - a[1]);
            if a[2] == 0.0 {
                c
            } else {
                let r = c * (1.0 + a[2] * a[2]) / (4.0 * a[2].abs());
                r * 4.0 * a[2].abs().atan()
            }
        })
        .sum()
}

/// Extent along x and y of a closed polyline with bulges, arcs included: each arc adds
/// the points where it crosses its circle's axis directions. An arc from a to b of bulge
/// k (sweep 4 atan k, counter-clockwise when positive) has its centre at the chord's
/// middle plus (1 - k^2) / (4 k) times the chord turned a quarter left.
fn extent(v: &[[f64; 3]]) -> [f64; 2] {
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    let mut take = |x: f64, y: f64| {
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    };
    for i in 0..v.len() {
        let (a, b, k) = (v[i], v[(i + 1) % v.len()], v[i][2]);
        take(a[0], a[1]);
        if k == 0.0 {
            continue;
        }
        let f = (1.0 - k * k) / (4.0 * k);
        let (cx, cy) = (
            0.5 * (a[0] + b[0]) - f * (b[1] - a[1]),
            0.5 * (a[1] + b[1]) + f * (b[0] - a[0]),
        );
        let r = (a[0] - cx).hypot(a[1] - cy);
        let start = (a[1] - cy).atan2(a[0] - cx);
        let sweep = 4.0 * k.atan();
        let tau = std::f64::consts::TAU;
        for quarter in 0..4 {
            let angle = quarter as f64 * tau / 4.0;
            let along = if sweep > 0.0 {
                (angle - start).rem_euclid(tau)
            } else {
                (start - angle).rem_euclid(tau)
            };
            if along <= sweep.abs() {
                take(cx + r * angle.cos(), cy + r * angle.sin());
            }
        }
    }
    [hi[0] - lo[0], hi[1] - lo[1]]
}

/// Area enclosed by a closed contour `[[x, y, bulge], ...]` (absolute): the polygon of its
/// vertices (shoelace) plus, per arc, the signed circular segment between chord and arc.
fn area(v: &[Value]) -> f64 {
    let p: Vec<[f64; 3]> = v
        .iter()
        .map(|x| {
            let a = x.as_array().unwrap();
            [
                num(&a[0], "x"),
                num(&a[1], "y"),
                a.get(2).map_or(0.0, |b| num(b, "bulge")),
            ]
        })
        .collect();
    let mut twice = 0.0;
    let mut segments = 0.0;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        twice += a[0] * b[1] - b[0] * a[1];
        if a[2] != 0.0 {
            let c = (b[0] - a[0]).hypot(b[1] - a[1]);
            let theta = 4.0 * a[2].atan(); // signed sweep
            let r = c / (2.0 * (theta / 2.0).sin().abs());
            // segment area r^2 / 2 (theta - sin theta), on the left for a positive sweep
            segments += 0.5 * r * r * (theta - theta.sin());
        }
    }
    (0.5 * twice + segments).abs()
}

/// What the output files say, recomputed.
struct Expected {
    units: usize,
    strips: usize,
    sheets: Option<usize>,
    steel_area_mm2: f64,
    thickness: f64,
    cut_length_mm: f64,
    pierces: usize,
    hub_welds: usize,
    primary_welds: usize,
    /// per strip id: (cut length from its DXF, pierces, area from its contours, the
    /// extent of its DXF outline along x and y)
    per_strip: HashMap<String, (f64, usize, f64, [f64; 2])>,
}

fn expected(out: &Path) -> Expected {
    let frame = read_json(&out.join("frame.json"));
    let strips = read_json(&out.join("strips.json"));
    let units = frame["units"].as_array().unwrap();
    let strip_list = strips["strips"].as_array().unwrap();
    // areas from the contours of strips.json (outline minus slots)
    let mut per_strip = HashMap::new();
    let mut steel = 0.0;
    for s in strip_list {
        let id = s["id"].as_str().unwrap().to_string();
        let outline = area(s["outline"].as_array().unwrap());
        let holes: f64 = s["cuts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| area(c.as_array().unwrap()))
            .sum();
        steel += outline - holes;
        // cut length and pierces from the DXF the plasma shop gets
        let dxf = fs::read_to_string(out.join(format!("strips/{id}.dxf"))).unwrap();
        let cut: Vec<DxfEntity> = dxf_entities(&dxf)
            .into_iter()
            .filter(|p| p.kind == "LWPOLYLINE" && (p.layer == "OUTSIDE" || p.layer == "INSIDE"))
            .collect();
        assert!(cut.iter().all(|p| p.closed), "{id}: open cut contour");
        assert_eq!(
            cut.iter().filter(|p| p.layer == "OUTSIDE").count(),
            1,
            "{id}"
        );
        let length: f64 = cut.iter().map(|p| perimeter(&p.vertices)).sum();
        let size = cut
            .iter()
            .find(|p| p.layer == "OUTSIDE")
            .map(|p| extent(&p.vertices))
            .unwrap();
        per_strip.insert(id, (length, cut.len(), outline - holes, size));
    }
    // welds: every link a hub weld; a primary weld where the two units are in different
    // strips (labels in frame.json)
    let links = frame["links"].as_array().unwrap();
    let strip_of = |u: &Value| units[u.as_u64().unwrap() as usize]["strip"].clone();
    let primary_welds = links
        .iter()
        .filter(|l| strip_of(&l["units"][0]) != strip_of(&l["units"][1]))
        .count();
    let nest = out.join("nest.json");
    Expected {
        units: units.len(),
        strips: fs::read_dir(out.join("strips"))
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == "dxf")
            })
            .count(),
        sheets: nest
            .exists()
            .then(|| read_json(&nest)["sheets"].as_array().unwrap().len()),
        steel_area_mm2: steel,
        thickness: num(&strips["params"]["thickness"], "thickness"),
        cut_length_mm: per_strip.values().map(|v| v.0).sum(),
        pierces: per_strip.values().map(|v| v.1).sum(),
        hub_welds: links.len(),
        primary_welds,
        per_strip,
    }
}

fn close(got: f64, want: f64, relative: f64) -> bool {
    (got - want).abs() <= relative * want.abs().max(1.0)
}

#[test]
fn every_summary_figure_is_recomputed_from_the_output_files() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let html = fs::read_to_string(dir.join("out/report.html")).unwrap();
    let rows = summary(&html);
    let want = expected(&dir.join("out"));
    let value = |key: &str| -> f64 {
        let (v, _) = rows
            .get(key)
            .unwrap_or_else(|| panic!("summary has no {key}: {rows:?}"));
        v.parse()
            .unwrap_or_else(|_| panic!("{key}: {v:?} is not a number"))
    };
    let shown = |key: &str| rows[key].1.clone();
    assert_eq!(value("units"), want.units as f64);
    assert_eq!(value("strips"), want.strips as f64);
    assert!(want.strips > 10, "the pavilion has {} strips", want.strips);
    match want.sheets {
        Some(n) => assert_eq!(value("sheets"), n as f64),
        None => {
            assert_eq!(rows["sheets"], (String::new(), "not nested".to_string()));
            assert!(html.contains("id=\"no-nesting\""));
        }
    }
    // steel: contours of strips.json with exact arc segments; weight at 7850 kg/m^3
    assert!(
        close(value("steel_area_mm2"), want.steel_area_mm2, 1e-9),
        "{} vs {}",
        value("steel_area_mm2"),
        want.steel_area_mm2
    );
    let mass = want.steel_area_mm2 * 1e-6 * want.thickness * 1e-3 * 7850.0;
    assert!(close(value("steel_mass_kg"), mass, 1e-9));
    assert_eq!(shown("steel_mass_kg"), format!("{mass:.1} kg"));
    assert_eq!(
        shown("steel_area_mm2"),
        format!("{:.2} m\u{00b2}", want.steel_area_mm2 * 1e-6)
    );
    // cutting: the DXF files' OUTSIDE and INSIDE polylines (9 decimals in the file)
    assert!(
        close(value("cut_length_mm"), want.cut_length_mm, 1e-7),
        "{} vs {}",
        value("cut_length_mm"),
        want.cut_length_mm
    );
    assert_eq!(
        shown("cut_length_mm"),
        format!("{:.1} m", want.cut_length_mm * 1e-3)
    );
    assert_eq!(value("pierces"), want.pierces as f64);
    // welding
    assert_eq!(value("hub_welds"), want.hub_welds as f64);
    assert_eq!(value("primary_welds"), want.primary_welds as f64);
    assert!(want.primary_welds > 0 && want.primary_welds < want.hub_welds);
    assert_eq!(value("welds"), (want.hub_welds + want.primary_welds) as f64);
    // every row was checked
    let mut keys: Vec<&str> = rows.keys().map(String::as_str).collect();
    keys.sort();
    let mut checked = vec![
        "cut_length_mm",
        "hub_welds",
        "pierces",
        "primary_welds",
        "sheets",
        "steel_area_mm2",
        "steel_mass_kg",
        "strips",
        "units",
        "welds",
    ];
    if want.sheets.is_some() {
        let nest = read_json(&dir.join("out/nest.json"));
        let sheet_area: f64 = nest["sheets"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| num(&s["width"], "width") * num(&s["height"], "height"))
            .sum();
        let mass = sheet_area * 1e-6 * want.thickness * 1e-3 * 7850.0;
        assert!(close(value("sheet_mass_kg"), mass, 1e-9));
        checked.push("sheet_mass_kg");
        checked.sort();
    }
    assert_eq!(keys, checked);
}

/// Split CSV text (RFC 4180) into rows of fields.
pub(crate) fn parse_csv(text: &str) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    let mut row = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => row.push(std::mem::take(&mut field)),
            (false, '\r') => {}
            (false, '\n') => {
                row.push(std::mem::take(&mut field));
                rows.push(std::mem::take(&mut row));
            }
            (false, c) => field.push(c),
        }
    }
    assert!(!quoted, "unterminated quoted field");
    assert!(
        field.is_empty() && row.is_empty(),
        "last line not terminated"
    );
    rows
}

#[test]
fn bill_of_materials_has_one_row_per_strip() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let out_dir = dir.join("out");
    let text = fs::read_to_string(out_dir.join("bom.csv")).unwrap();
    assert!(text.ends_with("\r\n") && !text.replace("\r\n", "").contains('\n'));
    let rows = parse_csv(&text);
    assert_eq!(
        rows[0],
        [
            "strip",
            "sheet",
            "sheet_file",
            "x_mm",
            "y_mm",
            "rotation_deg",
            "length_mm",
            "width_mm",
            "area_mm2",
            "cut_length_mm",
            "pierces",
            "units",
            "unit_labels",
            "hub_face"
        ]
    );
    let frame = read_json(&out_dir.join("frame.json"));
    let strips = read_json(&out_dir.join("strips.json"));
    let nest = out_dir
        .join("nest.json")
        .exists()
        .then(|| read_json(&out_dir.join("nest.json")));
    let want = expected(&out_dir);
    let list = strips["strips"].as_array().unwrap();
    assert_eq!(rows.len(), 1 + list.len());
    let mut seen = HashSet::new();
    for (row, strip) in rows[1..].iter().zip(list) {
        assert_eq!(row.len(), 14, "{row:?}");
        let id = strip["id"].as_str().unwrap();
        assert_eq!(row[0], id);
        assert!(seen.insert(id.to_string()));
        let f = |k: usize| -> f64 { row[k].parse().unwrap_or_else(|_| panic!("{row:?}")) };
        let (cut, pierces, area, size_as_cut) = want.per_strip[id];
        assert!((f(8) - area).abs() <= 0.05 + 1e-9 * area, "{id} area");
        assert!((f(9) - cut).abs() <= 0.05 + 1e-9 * cut, "{id} cut length");
        assert_eq!(f(10), pierces as f64, "{id} pierces");
        // the size of the part as cut: its outline in strips/ID.dxf, arcs included (it
        // was the nominal tiles' rectangle, up to 0.71 mm larger); strips.json says the same
        assert!(
            (f(6) - size_as_cut[0]).abs() <= 0.05 + 1e-9
                && (f(7) - size_as_cut[1]).abs() <= 0.05 + 1e-9,
            "{id}: bom.csv {} x {}, the DXF outline {size_as_cut:?}",
            row[6],
            row[7]
        );
        let size = strip["size_mm"].as_array().unwrap();
        assert!((f(6) - num(&size[0], "l")).abs() <= 0.05);
        assert!((f(7) - num(&size[1], "w")).abs() <= 0.05);
        let labels: Vec<&str> = strip["units"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| {
                frame["units"][u.as_u64().unwrap() as usize]["id"]
                    .as_str()
                    .unwrap()
            })
            .collect();
        assert_eq!(f(11), labels.len() as f64);
        assert_eq!(row[12], labels.join(" "));
        match &nest {
            None => assert!(row[1..6].iter().all(String::is_empty), "{row:?}"),
            Some(nest) => {
                let (sheet, placement) = nest["sheets"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .enumerate()
                    .find_map(|(i, s)| {
                        s["placements"]
                            .as_array()
                            .unwrap()
                            .iter()
                            .find(|p| p["strip"] == id)
                            .map(|p| (i + 1, p.clone()))
                    })
                    .unwrap_or_else(|| panic!("{id} is not on a sheet"));
                assert_eq!(f(1), sheet as f64, "{id}");
                assert!(!row[2].is_empty(), "{id}: sheet file");
                assert!((f(3) - num(&placement["translation"][0], "x")).abs() <= 0.005);
                assert!((f(4) - num(&placement["translation"][1], "y")).abs() <= 0.005);
                assert!((f(5) - num(&placement["rotation_deg"], "r")).abs() <= 0.0005);
                // the placement maps the strip's own drawing into the sheet's margin
                let sheet_json = &nest["sheets"][sheet - 1];
                let (w, h) = (
                    num(&sheet_json["width"], "w"),
                    num(&sheet_json["height"], "h"),
                );
                let margin = num(&nest["sheet"]["margin"], "margin");
                let (sin, cos) = num(&placement["rotation_deg"], "r").to_radians().sin_cos();
                let t = [
                    num(&placement["translation"][0], "x"),
                    num(&placement["translation"][1], "y"),
                ];
                for v in strip["outline"].as_array().unwrap() {
                    let (x, y) = (num(&v[0], "x"), num(&v[1], "y"));
                    let p = [cos * x - sin * y + t[0], sin * x + cos * y + t[1]];
                    let slack = 0.5;
                    assert!(
                        p[0] >= margin - slack
                            && p[0] <= w - margin + slack
                            && p[1] >= margin - slack
                            && p[1] <= h - margin + slack,
                        "{id}: outline vertex at {p:?} is off sheet {sheet} ({w} x {h}, margin {margin})"
                    );
                }
            }
        }
    }
}

#[test]
fn report_is_one_reasonable_file_with_three_js_once() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let html = fs::read_to_string(dir.join("out/report.html")).unwrap();
    assert!(html.len() < 3_000_000, "{} bytes", html.len());
    assert_eq!(html.matches("const REVISION = '170'").count(), 1);
    assert_eq!(html.matches("function createFrameView(").count(), 1);
    // nothing that would load from elsewhere
    for needle in ["http://", "https://", "src=\"", "href=\"http", "@import"] {
        let outside = html
            .match_indices(needle)
            .filter(|(i, _)| !html[..*i].ends_with("xmlns=\""))
            .count();
        let in_three = sv_viewer::THREE_JS.matches(needle).count()
            + sv_viewer::ORBIT_CONTROLS_JS.matches(needle).count();
        assert!(
            outside <= in_three,
            "{needle}: {outside} in the page, {in_three} in three.js comments"
        );
    }
    assert!(html.contains("Content-Security-Policy"));
    assert!(out.stdout.contains(&format!(
        "{}",
        Path::new("out").join("report.html").display()
    )));
}

/// The page in headless Chromium, from `file://`: it renders, requests nothing, and a click
/// on a unit shows that unit.
#[test]
fn report_opens_offline_in_chromium_and_shows_a_clicked_unit() {
    let (dir, out) = default_build();
    out.expect_code(0);
    let path = fs::canonicalize(dir.join("out/report.html")).unwrap();
    let url = format!("file://{}", path.display());
    let frame = read_json(&dir.join("out/frame.json"));
    let browser = sv_browser::Browser::launch().unwrap();
    let mut page = browser.open(&url).unwrap();
    page.wait_for(
        "document.body.dataset.ready !== 'no'",
        Duration::from_secs(60),
        "the report to start",
    )
    .unwrap();
    assert_eq!(
        page.eval("document.body.dataset.ready").unwrap(),
        "yes",
        "3D view failed: {:?}",
        page.eval("document.getElementById('view').textContent")
    );

    // the 3D view drew the frame: many colours, not just the background
    let image = page.screenshot("#view canvas").unwrap();
    assert!(
        image.width > 300 && image.height > 300,
        "{}x{}",
        image.width,
        image.height
    );
    let drawn = image.fraction_unlike([0x10, 0x13, 0x17], 6);
    assert!(
        drawn > 0.05 && image.distinct_colours() > 20,
        "blank 3D view: {:.3} drawn, {} colours",
        drawn,
        image.distinct_colours()
    );

    // plots: every histogram counts every link, face and unit
    let links = frame["links"].as_array().unwrap().len();
    let units = frame["units"].as_array().unwrap();
    let mut n = |id: &str| page_eval_n(&mut page, id);
    assert_eq!(n("hist-gap"), links);
    assert_eq!(n("hist-overlap"), links);
    assert_eq!(
        n("hist-planarity"),
        frame["mesh"]["faces"].as_array().unwrap().len()
    );
    assert_eq!(n("map-theta"), units.len());
    assert_eq!(n("map-depth"), units.len());
    assert!(n("hist-conical") > 0);

    // one picture per sheet, with its utilisation
    let nest = dir.join("out/nest.json");
    if nest.exists() {
        let nest = read_json(&nest);
        let sheets = nest["sheets"].as_array().unwrap();
        let pictures = page
            .eval("[...document.querySelectorAll('svg.sheet')].map((s) => [s.dataset.parts, s.closest('figure').textContent])")
            .unwrap();
        let pictures = pictures.as_array().unwrap();
        assert_eq!(pictures.len(), sheets.len());
        for (p, s) in pictures.iter().zip(sheets) {
            let parts = s["placements"].as_array().unwrap().len();
            assert_eq!(p[0], parts.to_string());
            let u = format!("utilisation {:.1} %", 100.0 * num(&s["utilisation"], "u"));
            assert!(p[1].as_str().unwrap().contains(&u), "{p:?}: {u}");
        }
    } else {
        assert_eq!(
            page.eval("document.querySelectorAll('svg.sheet').length")
                .unwrap(),
            0
        );
        assert!(
            page.eval("document.getElementById('no-nesting') !== null")
                .unwrap()
                == true
        );
    }

    // click a unit in the middle of the frame, hubs only so that nothing is in front
    page.eval("document.querySelector('input[data-layer=\"primaries\"]').click()")
        .unwrap();
    page.eval("document.querySelector('input[data-layer=\"legs\"]').click()")
        .unwrap();
    let mut picked = None;
    for k in [units.len() / 2, units.len() / 3, 2 * units.len() / 3, 17] {
        let id = units[k]["id"].as_str().unwrap();
        let at = page
            .eval(&format!("window.__report.view.project('{id}')"))
            .unwrap();
        let (x, y) = (num(&at["x"], "x"), num(&at["y"], "y"));
        page.click(x, y).unwrap();
        page.pump(Duration::from_millis(200)).unwrap();
        if page
            .eval("document.getElementById('info').dataset.unit")
            .unwrap()
            == id
        {
            picked = Some(k);
            break;
        }
    }
    let k = picked.expect("a click on a unit's hub selects it");
    let unit = &units[k];
    let info = page
        .eval("document.getElementById('info').innerText")
        .unwrap()
        .as_str()
        .unwrap()
        .to_string();
    let theta = format!("{:.2} deg", num(&unit["theta"], "theta").to_degrees());
    let phi = format!("{:.2} deg", num(&unit["phi"], "phi").to_degrees());
    assert!(info.contains(&theta) && info.contains(&phi), "{info}");
    // one row per link of the unit, with the link's gap and overlap
    let mine: Vec<&Value> = frame["links"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|l| l["units"][0] == k || l["units"][1] == k)
        .collect();
    let rows = page
        .eval("[...document.querySelectorAll('#info tr[data-neighbour]')].map((r) => [r.dataset.neighbour, r.cells[1].textContent, r.cells[2].textContent])")
        .unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), mine.len(), "{rows:?}");
    for l in mine {
        let other = if l["units"][0] == k {
            &l["units"][1]
        } else {
            &l["units"][0]
        };
        let label = &units[other.as_u64().unwrap() as usize]["id"];
        let row = rows
            .iter()
            .find(|r| &r[0] == label)
            .unwrap_or_else(|| panic!("no row for {label}: {rows:?}"));
        // the gap on the plates as cut where the joint is recorded, else the primary gap
        let gap = if l["joint"].is_object() {
            num(&l["joint"]["gap"], "joint gap")
        } else {
            num(&l["primary_gap"], "gap")
        };
        assert_eq!(row[1], format!("{gap:.2}"));
        assert_eq!(row[2], format!("{:.2}", num(&l["hub_overlap"], "overlap")));
    }

    // colour by strip: the view changes
    page.eval("document.querySelector('input[name=\"colour\"][value=\"strip\"]').click()")
        .unwrap();
    assert_eq!(page.eval("document.body.dataset.mode").unwrap(), "strip");
    page.pump(Duration::from_millis(300)).unwrap();
    let by_strip = page.screenshot("#view canvas").unwrap();
    assert_ne!(by_strip.rgba, image.rgba);

    // nothing but the file itself (and the blob: modules made from it) was requested
    page.pump(Duration::from_millis(300)).unwrap();
    let requests = page.requests();
    assert!(
        requests.iter().any(|r| r.url == url),
        "the network log saw the page itself: {requests:?}"
    );
    // data: and blob: URLs are the page's own bytes; here the viewer's modules, one each
    let outside: Vec<_> = requests
        .iter()
        .filter(|r| r.url != url && !r.url.starts_with("blob:") && !r.url.starts_with("data:"))
        .collect();
    assert!(outside.is_empty(), "requests: {outside:?}");
    let modules = requests
        .iter()
        .filter(|r| r.url.starts_with("blob:") && r.kind == "Script")
        .count();
    assert_eq!(modules, sv_viewer::MODULES.len(), "{requests:?}");
    assert!(page.errors().is_empty(), "page errors: {:?}", page.errors());
}

fn page_eval_n(page: &mut sv_browser::Page, id: &str) -> usize {
    let v = page
        .eval(&format!("document.getElementById('{id}').dataset.n"))
        .unwrap();
    v.as_str()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{id}: data-n {v}"))
}
