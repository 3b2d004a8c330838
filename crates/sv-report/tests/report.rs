//! The report of a small solved frame (a 4 x 3 sphere cap, strips of 4 units), with and
//! without nesting: bill of materials columns, sheets, summary, and inputs that do not
//! belong together.

use serde_json::json;
use sv_frame::{solve, FrameFile, QuadMesh, SolveOptions};
use sv_nest::NestReport;
use sv_report::{bom_csv, report_html, NestInput, ReportError, ReportInput, Summary};
use sv_strips::{apply_labels, profile_strip, unroll, ProfileParams, StripOptions, StripsFile};

fn build() -> (FrameFile, StripsFile) {
    let mesh = QuadMesh::sphere_cap(4, 3, 3000.0, 300.0);
    let mut frame = solve(&mesh, &SolveOptions::default(), &mut |_| {})
        .unwrap()
        .to_frame_file(&mesh);
    let strips = unroll(&frame, &StripOptions::default()).unwrap();
    apply_labels(&mut frame, &strips);
    let params = ProfileParams::default();
    let profiles: Vec<_> = strips
        .iter()
        .map(|s| {
            let names: Vec<String> = s.units.iter().map(|&u| frame.units[u].id.clone()).collect();
            profile_strip(s, &names, &params).unwrap()
        })
        .collect();
    let file = StripsFile::new(&strips, &profiles, &params, 1.0, &StripOptions::default());
    (frame, file)
}

/// Strips A01 and A02 on sheet 1, A03 turned half round on sheet 2.
fn nest() -> NestReport {
    serde_json::from_value(json!({
        "sheet": {"width": 3000.0, "height": 1500.0, "margin": 10.0, "spacing": 6.0},
        "sheets": [
            {"width": 3000.0, "height": 1500.0, "utilisation": 0.31, "placements": [
                {"strip": "A01", "translation": [20.0, 15.0], "rotation_deg": 0.0},
                {"strip": "A02", "translation": [20.0, 500.0], "rotation_deg": 0.0}]},
            {"width": 3000.0, "height": 1500.0, "utilisation": 0.15, "placements": [
                {"strip": "A03", "translation": [1300.5, 420.25], "rotation_deg": 180.0}]}
        ],
        "lower_bound_sheets": 1,
        "lower_bounds": {"area": 1, "martello_toth": 1},
        "left_out": [],
        "offcut": {"sheet": 1, "x": 1400.0, "y": 0.0, "width": 1600.0, "height": 1500.0}
    }))
    .unwrap()
}

fn input<'a>(
    frame: &'a FrameFile,
    strips: &'a StripsFile,
    nest: Option<NestInput<'a>>,
) -> ReportInput<'a> {
    ReportInput {
        target: "sphere cap <4 x 3>",
        generator: "test",
        frame,
        strips,
        nest,
        hub_mesh: None,
        fold_check: None,
    }
}

fn csv_rows(text: &str) -> Vec<Vec<String>> {
    text.split("\r\n")
        .filter(|l| !l.is_empty())
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn without_nesting_the_report_says_so_and_leaves_sheets_empty() {
    let (frame, strips) = build();
    assert_eq!(strips.strips.len(), 3);
    let input = input(&frame, &strips, None);
    let html = report_html(&input).unwrap();
    assert!(html.contains("id=\"no-nesting\""));
    assert!(html.contains("<title>Spin-Valence build report: sphere cap &lt;4 x 3&gt;</title>"));
    assert_eq!(html.matches("<svg class=\"sheet\"").count(), 0);
    assert_eq!(html.matches("class=\"plot\"").count(), 6);
    let rows = csv_rows(&bom_csv(&input).unwrap());
    assert_eq!(rows.len(), 4);
    for row in &rows[1..] {
        assert!(row[1..6].iter().all(String::is_empty), "{row:?}");
    }
    let s = Summary::of(&input);
    assert_eq!(s.sheets, None);
    // 4 x 3 units: 3 x 3 + 4 x 2 = 17 links, 3 x 3 of them necks inside the strips
    assert_eq!((s.hub_welds, s.primary_welds), (17, 8));
    assert_eq!(s.pierces, 3 + 4 * 12);
}

#[test]
fn with_nesting_every_strip_has_its_sheet_and_position() {
    let (frame, strips) = build();
    let nest = nest();
    let files = vec!["sheets/sheet-01.dxf".to_string()];
    let input = input(
        &frame,
        &strips,
        Some(NestInput {
            report: &nest,
            sheet_files: &files,
        }),
    );
    let rows = csv_rows(&bom_csv(&input).unwrap());
    assert_eq!(
        rows[1][..6],
        ["A01", "1", "sheets/sheet-01.dxf", "20.00", "15.00", "0.000"]
    );
    assert_eq!(
        rows[2][..6],
        [
            "A02",
            "1",
            "sheets/sheet-01.dxf",
            "20.00",
            "500.00",
            "0.000"
        ]
    );
    // no file name known for sheet 2: its number stands in
    assert_eq!(
        rows[3][..6],
        ["A03", "2", "2", "1300.50", "420.25", "180.000"]
    );
    let html = report_html(&input).unwrap();
    assert_eq!(html.matches("<svg class=\"sheet\"").count(), 2);
    assert!(html.contains("data-sheet=\"1\" data-parts=\"2\""));
    assert!(html.contains("data-sheet=\"2\" data-parts=\"1\""));
    assert!(html.contains("utilisation 31.0 %") && html.contains("utilisation 15.0 %"));
    assert!(html.contains("rotate(180.0000)"));
    assert!(html.contains("class=\"offcut\""));
    assert!(!html.contains("id=\"no-nesting\""));
    let s = Summary::of(&input);
    assert_eq!(s.sheets, Some(2));
    // the steel to buy: two 3000 x 1500 mm sheets of the profile's thickness at 7850 kg/m^3
    let t = ProfileParams::default().thickness / 1000.0;
    let mass = 2.0 * 3.0 * 1.5 * t * 7850.0;
    let value: f64 = html
        .split("data-key=\"sheet_mass_kg\" data-value=\"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .and_then(|t| t.parse().ok())
        .expect("a sheet steel row");
    assert!((value - mass).abs() < 1e-9, "{value} vs {mass}");
}

#[test]
fn parts_that_are_not_strips_or_placed_twice_are_errors() {
    let (frame, strips) = build();
    let mut stranger = nest();
    stranger.sheets[1].placements[0].strip = "Z99".into();
    let input_a = input(
        &frame,
        &strips,
        Some(NestInput {
            report: &stranger,
            sheet_files: &[],
        }),
    );
    assert_eq!(
        report_html(&input_a).unwrap_err(),
        ReportError::UnknownPart {
            sheet: 2,
            part: "Z99".into()
        }
    );
    let mut twice = nest();
    twice.sheets[1].placements[0].strip = "A01".into();
    let input_b = input(
        &frame,
        &strips,
        Some(NestInput {
            report: &twice,
            sheet_files: &[],
        }),
    );
    assert_eq!(
        bom_csv(&input_b).unwrap_err().to_string(),
        "strip A01 is placed twice (sheets 1 and 2)"
    );
    let mut broken = strips.clone();
    broken.strips[0].units[0] = 99;
    assert_eq!(
        report_html(&input(&frame, &broken, None))
            .unwrap_err()
            .to_string(),
        "strip A01: unit 99 is not in the frame (12 units)"
    );
}

#[test]
fn the_fold_check_is_shown_with_its_failing_rows_marked() {
    use sv_frame::{CheckReport, CheckRow};
    let (frame, strips) = build();
    let row = |name: &str, worst: f64, limit: f64, ok: bool| CheckRow {
        name: name.into(),
        worst,
        limit,
        at: format!("at {name}"),
        ok,
        units: Vec::new(),
    };
    let fold = CheckReport {
        rows: vec![
            row("leg between its necks", 0.08, 0.5, true),
            row("weld: plates apart (mm)", 2.75, 1.5, false),
            row("widest gap (not held)", 24.0, f64::INFINITY, true),
        ],
    };
    let without = report_html(&input(&frame, &strips, None)).unwrap();
    assert!(!without.contains("Fold check of the parts as cut"));
    assert!(!without.contains("value=\"goals\""));
    let mut shown = input(&frame, &strips, None);
    shown.fold_check = Some(&fold);
    let html = report_html(&shown).unwrap();
    assert!(html.contains("Fold check of the parts as cut"));
    // a failing row is a goal not met: the 3D view can show it at every unit where it
    // failed (here none)
    assert!(!html.contains("value=\"goals\""));
    let flag = "[\"fold check: weld: plates apart (mm)\"]";
    assert_eq!(
        html.matches(flag).count(),
        0,
        "a unit flagged by a row naming none"
    );
    let mut named = fold.clone();
    // two open welds (units 2 and 6, 6 and 7), a unit past the frame's units ignored
    named.rows[1].units = vec![2, 6, 7, frame.units.len()];
    // a row that holds marks nothing, whatever it lists
    named.rows[0].units = vec![3];
    shown.fold_check = Some(&named);
    let flagged = report_html(&shown).unwrap();
    assert_eq!(
        flagged.matches(flag).count(),
        3,
        "every unit of the open welds"
    );
    assert!(!flagged.contains("fold check: leg between its necks"));
    assert!(flagged.contains("value=\"goals\""), "no unmet-goals view");
    shown.fold_check = Some(&fold);
    assert!(html.contains("1 of 3 rows fail"), "verdict missing");
    assert_eq!(html.matches("<tr class=\"fail\">").count(), 1);
    assert!(html.contains(
        "<tr class=\"fail\"><th>weld: plates apart (mm)</th><td>2.750</td><td>1.500</td><td>at weld: plates apart (mm)</td><td>FAIL</td></tr>"
    ));
    assert!(html.contains("<td>24.00</td><td>-</td><td>at widest gap (not held)</td><td>info</td>"));
    let mut held = fold.clone();
    held.rows[1].ok = true;
    held.rows[1].worst = 1.0;
    shown.fold_check = Some(&held);
    let html = report_html(&shown).unwrap();
    assert!(html.contains("Every row holds") && !html.contains("<tr class=\"fail\">"));
    assert!(!html.contains("value=\"goals\""));
}
