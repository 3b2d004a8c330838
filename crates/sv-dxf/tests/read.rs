//! The DXF reader on small hand-written files: LWPOLYLINE with bulges, CIRCLE holes,
//! LINE/ARC chains, POLYLINE/VERTEX, the shop layers and what is never cut, units, the join
//! tolerance and islands. Files written by other CAD libraries are the end-to-end tests'
//! (`tests/e2e/dxf_inputs.rs`, written by ezdxf).

use sv_dxf::{parse_parts, read_dxf, DxfParts, ReadOptions, Units};
use sv_geom::planar::polygon_area;

const DXF_LW: &str = "0\nSECTION\n2\nENTITIES\n0\nLWPOLYLINE\n8\nOUTSIDE\n90\n4\n70\n1\n10\n0\n20\n0\n42\n0\n10\n100\n20\n0\n42\n1\n10\n100\n20\n50\n42\n0\n10\n0\n20\n50\n0\nCIRCLE\n8\nINSIDE\n10\n40\n20\n25\n40\n10\n0\nLWPOLYLINE\n70\n0\n10\n500\n20\n500\n10\n600\n20\n500\n0\nENDSEC\n0\nEOF\n";

#[test]
fn dxf_lwpolyline_with_bulge_and_circle_hole() {
    let read = parse_parts(DXF_LW, "bracket").unwrap();
    assert_eq!(read.parts.len(), 1);
    let p = &read.parts[0];
    assert_eq!(p.id, "bracket");
    assert_eq!(p.outer.vertices.len(), 4);
    assert_eq!(p.outer.vertices[1].bulge, 1.0);
    assert_eq!(p.holes.len(), 1);
    // the half-circle end reaches x = 125
    let (_, hi) = p.outer.bounds().unwrap();
    assert!((hi[0] - 125.0).abs() < 1e-6);
    // the open polyline is rejected with a name
    assert_eq!(read.rejected.len(), 1);
    assert!(read.rejected[0].to_string().contains("open contour"));
    assert!(read.rejected[0].to_string().contains("bracket"));
}

#[test]
fn dxf_line_arc_chain_and_polyline() {
    // a 40x20 slot: two lines and two half arcs, plus a POLYLINE square elsewhere
    let text = "0\nSECTION\n2\nENTITIES\n\
0\nLINE\n10\n0\n20\n0\n11\n40\n21\n0\n\
0\nARC\n10\n40\n20\n10\n40\n10\n50\n270\n51\n90\n\
0\nLINE\n10\n40\n20\n20\n11\n0\n21\n20\n\
0\nARC\n10\n0\n20\n10\n40\n10\n50\n90\n51\n270\n\
0\nPOLYLINE\n66\n1\n70\n1\n0\nVERTEX\n10\n100\n20\n0\n0\nVERTEX\n10\n130\n20\n0\n0\nVERTEX\n10\n130\n20\n30\n0\nVERTEX\n10\n100\n20\n30\n0\nSEQEND\n\
0\nENDSEC\n0\nEOF\n";
    let read = parse_parts(text, "mix").unwrap();
    assert!(read.rejected.is_empty(), "{:?}", read.rejected);
    assert_eq!(read.parts.len(), 2);
    let areas = outline_areas(&read);
    let slot = 40.0 * 20.0 + std::f64::consts::PI * 100.0;
    assert!(areas.iter().any(|a| (a - slot).abs() < 0.5), "{areas:?}");
    assert!(areas.iter().any(|a| (a - 900.0).abs() < 1e-6), "{areas:?}");
    assert!(parse_parts("garbage\n", "bad").is_err());
}

/// A closed LWPOLYLINE of straight edges on `layer`.
/// The area inside each part's outline (mm^2, arcs exact).
fn outline_areas(read: &DxfParts) -> Vec<f64> {
    read.parts.iter().map(|p| p.outer.area()).collect()
}

fn lw(layer: &str, pts: &[[f64; 2]]) -> String {
    let mut s = format!("0\nLWPOLYLINE\n8\n{layer}\n90\n{}\n70\n1\n", pts.len());
    for p in pts {
        s += &format!("10\n{}\n20\n{}\n", p[0], p[1]);
    }
    s
}

fn square(x: f64, y: f64, s: f64) -> [[f64; 2]; 4] {
    [[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
}

/// Shop layers: OUTSIDE contours are the outlines, INSIDE ones holes of the outline around
/// them; INFO (closed tiles, sheet outline, text) and ETCH are not parts. A part inside
/// another's hole (part in part on a sheet) is a part of its own.
#[test]
fn dxf_shop_layers_outlines_holes_and_what_is_not_cut() {
    let mut text = String::from("0\nSECTION\n2\nENTITIES\n");
    // a sheet outline and a nominal tile on INFO, etched lines, a label
    text += &lw("INFO", &square(-10.0, -10.0, 2000.0));
    text += &lw("INFO", &square(5.0, 5.0, 90.0));
    text += &lw("ETCH", &square(20.0, 20.0, 5.0));
    text += "0\nTEXT\n8\nINFO\n10\n0\n20\n0\n40\n5\n1\nA01\n";
    // part 1: a 100 mm square with two slots
    text += &lw("INSIDE", &square(10.0, 10.0, 20.0));
    text += &lw("INSIDE", &square(60.0, 60.0, 20.0));
    text += &lw("OUTSIDE", &square(0.0, 0.0, 100.0));
    // part 2: a 400 mm square with a 300 mm hole holding part 3 (40 mm, one slot)
    text += &lw("INSIDE", &square(550.0, 50.0, 300.0));
    text += &lw("OUTSIDE", &square(500.0, 0.0, 400.0));
    text += &lw("INSIDE", &square(610.0, 110.0, 10.0));
    text += &lw("OUTSIDE", &square(600.0, 100.0, 40.0));
    // a slot in no outline
    text += &lw("INSIDE", &square(1500.0, 1500.0, 10.0));
    text += "0\nENDSEC\n0\nEOF\n";
    let read = parse_parts(&text, "sheet").unwrap();
    let holes: Vec<(String, usize)> = read
        .parts
        .iter()
        .map(|p| (p.id.clone(), p.holes.len()))
        .collect();
    assert_eq!(
        holes,
        [
            ("sheet#1".to_string(), 2),
            ("sheet#2".to_string(), 1),
            ("sheet#3".to_string(), 1)
        ]
    );
    // the etched square goes with part 1 (closed: five points), nothing else etches
    assert_eq!(read.parts[0].etch.len(), 1);
    assert_eq!(read.parts[0].etch[0].len(), 5);
    assert!(read.parts[1].etch.is_empty() && read.parts[2].etch.is_empty());
    assert_eq!(read.rejected.len(), 1, "{:?}", read.rejected);
    let why = read.rejected[0].to_string();
    assert!(why.contains("sheet") && why.contains("OUTSIDE"), "{why}");
    // without shop layers the same contours nest by containment: the stray slot is a part
    // of its own, the square inside the hole of part 2 the slug that falls out of it
    // (noted, not nested) unless islands are asked for
    let generic = text
        .replace("\n8\nINSIDE\n", "\n8\n0\n")
        .replace("\n8\nOUTSIDE\n", "\n8\n0\n");
    let read = parse_parts(&generic, "sheet").unwrap();
    assert_eq!(read.parts.len(), 3, "{:?}", read.notes);
    assert!(
        read.notes.iter().any(|n| n.what.contains("inside a hole")),
        "{:?}",
        read.notes
    );
    let options = ReadOptions {
        islands: true,
        ..ReadOptions::default()
    };
    let read = read_dxf(generic.as_bytes(), "sheet", &options).unwrap();
    assert_eq!(read.parts.len(), 4);
}

/// A file with a header setting `$INSUNITS` and `entities`.
fn with_units(code: i32, entities: &str) -> String {
    format!("0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n{code}\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n{entities}0\nENDSEC\n0\nEOF\n")
}

#[test]
fn units_scale_to_mm_and_unknown_units_are_refused() {
    let square = lw("0", &square(0.0, 0.0, 2.0));
    let inches = read_dxf(
        with_units(1, &square).as_bytes(),
        "in",
        &ReadOptions::default(),
    )
    .unwrap();
    assert!((inches.parts[0].outer.area() - 4.0 * 25.4 * 25.4).abs() < 1e-6);
    assert!(inches
        .notes
        .iter()
        .any(|n| n.what.contains("scaled by 25.4")));
    // --units overrides the file
    let options = ReadOptions {
        units: Some("m".parse::<Units>().unwrap()),
        ..ReadOptions::default()
    };
    let metres = read_dxf(with_units(1, &square).as_bytes(), "m", &options).unwrap();
    assert!((metres.parts[0].outer.area() - 4e6).abs() < 1e-3);
    let err = read_dxf(
        with_units(99, &square).as_bytes(),
        "odd",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("odd: $INSUNITS 99"), "{err}");
    assert!(read_dxf(with_units(99, &square).as_bytes(), "odd", &options).is_ok());
}

#[test]
fn the_join_tolerance_is_settable_and_open_contours_say_how_far_apart() {
    // a 100 x 50 rectangle of lines with a 0.1 mm gap at one corner
    let lines = "0\nLINE\n10\n0\n20\n0\n11\n100\n21\n0\n0\nLINE\n10\n100\n20\n0\n11\n100\n21\n50\n\
0\nLINE\n10\n100\n20\n50\n11\n0\n21\n50\n0\nLINE\n10\n0\n20\n50\n11\n0\n21\n0.1\n";
    let text = with_units(4, lines);
    let read = read_dxf(text.as_bytes(), "gap", &ReadOptions::default()).unwrap();
    assert!(read.parts.is_empty());
    let why = read.rejected[0].to_string();
    assert!(
        why.contains("0.100 mm apart") && why.contains("gap"),
        "{why}"
    );
    let options = ReadOptions {
        join_tolerance: 0.2,
        ..ReadOptions::default()
    };
    let read = read_dxf(text.as_bytes(), "gap", &options).unwrap();
    assert_eq!(read.parts.len(), 1);
    assert!((read.parts[0].outer.area() - 5000.0).abs() < 10.0);
    assert!(
        read.notes
            .iter()
            .any(|n| n.what.contains("gap of 0.1000 mm closed")),
        "{:?}",
        read.notes
    );
}

/// The notes of reading `entities` (mm) with `options`, one string each.
fn notes_of(entities: &str, options: &ReadOptions) -> Vec<String> {
    let text = with_units(4, entities);
    let read = read_dxf(text.as_bytes(), "f.dxf", options).unwrap();
    read.notes.iter().map(|n| n.to_string()).collect()
}

/// An ARC or ELLIPSE whose start is 1e20 degrees was read by adding a turn at a time until
/// the end passed the start, which at 1e20 never happens: a hang. A NaN angle gave a part
/// with NaN corners.
#[test]
fn arcs_with_huge_or_non_finite_angles_are_skipped_not_a_hang() {
    let arc =
        |a0: &str, a1: &str| format!("0\nARC\n8\n0\n10\n0\n20\n0\n40\n10\n50\n{a0}\n51\n{a1}\n");
    let notes = notes_of(&arc("1e20", "0"), &ReadOptions::default());
    assert!(
        notes.contains(&"f.dxf: skipped: start and end angle 1e20, 0.0: not finite, or beyond a million turns: layer 0: ARC #1".to_string()),
        "{notes:?}"
    );
    let notes = notes_of(&arc("nan", "90"), &ReadOptions::default());
    assert!(
        notes.contains(&"f.dxf: skipped: start and end angle NaN, 90.0: not finite, or beyond a million turns: layer 0: ARC #1".to_string()),
        "{notes:?}"
    );
    // ordinary angles as before: 270 to 90 is the half on the right, 720 turns ahead are
    // the same angle
    let text = with_units(4, &format!("{}{}", arc("270", "90"), arc("90", "-360")));
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    assert_eq!(read.parts.len(), 1, "{:?}", read.rejected);
    let area = std::f64::consts::PI * 100.0;
    assert!((read.parts[0].outer.area() - area).abs() < 1e-6);
    let ellipse =
        "0\nELLIPSE\n8\n0\n10\n0\n20\n0\n30\n0\n11\n40\n21\n0\n31\n0\n40\n0.5\n41\n-1e300\n42\n1\n";
    let notes = notes_of(ellipse, &ReadOptions::default());
    assert!(
        notes.iter().any(|n| n.starts_with("f.dxf: skipped: start and end parameter -1e300, 1.0: not finite, or beyond a million turns: layer 0: ELLIPSE")),
        "{notes:?}"
    );
}

/// A coordinate of 1e300 overflowed the chaining grid (a panic in a debug build, lines
/// left unchained in a release build) or gave a part of infinite area; a NaN on the ETCH
/// layer was etched.
#[test]
fn coordinates_not_finite_or_far_out_are_skipped_with_a_note() {
    let far = lw(
        "0",
        &[[0.0, 0.0], [100.0, 0.0], [100.0, 1e300], [0.0, 100.0]],
    );
    let notes = notes_of(&far, &ReadOptions::default());
    assert!(
        notes.contains(&"f.dxf: skipped: farther than 1e9 mm from the origin (drawn in the wrong units, or a corrupt number?): layer 0: LWPOLYLINE #1".to_string()),
        "{notes:?}"
    );
    let line = "0\nLINE\n8\n0\n10\n0\n20\n0\n11\n1e300\n21\n0\n";
    let notes = notes_of(line, &ReadOptions::default());
    assert!(
        notes
            .iter()
            .any(|n| n.contains("farther than 1e9 mm") && n.ends_with("LINE #1")),
        "{notes:?}"
    );
    let etch = format!(
        "{}0\nLWPOLYLINE\n8\nETCH\n90\n2\n70\n0\n10\n10\n20\n10\n10\nnan\n20\n20\n",
        lw("OUTSIDE", &square(0.0, 0.0, 100.0))
    );
    let text = with_units(4, &etch);
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    assert!(read.parts[0].etch.is_empty(), "{:?}", read.parts[0].etch);
    let notes: Vec<String> = read.notes.iter().map(|n| n.to_string()).collect();
    assert!(
        notes.contains(
            &"f.dxf: skipped: a coordinate that is not a finite number: layer ETCH: LWPOLYLINE #2"
                .to_string()
        ),
        "{notes:?}"
    );
}

/// A 30000 x 30000 INSERT array is 900 million copies: the reader looped over them (and
/// overflowed `rows * cols` in a debug build); nested arrays multiply the same way.
#[test]
fn an_insert_array_past_the_entity_limit_is_skipped_with_a_note() {
    let blocks = "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n8\n0\n2\nC\n70\n0\n10\n0\n20\n0\n30\n0\n\
0\nCIRCLE\n8\n0\n10\n0\n20\n0\n40\n3\n0\nENDBLK\n0\nENDSEC\n";
    let text = format!(
        "{blocks}0\nSECTION\n2\nENTITIES\n0\nINSERT\n8\n0\n2\nC\n10\n0\n20\n0\n70\n30000\n71\n30000\n44\n10\n45\n10\n\
0\nINSERT\n8\n0\n2\nC\n10\n0\n20\n0\n70\n3\n71\n2\n44\n10\n45\n10\n0\nENDSEC\n0\nEOF\n"
    );
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    let notes: Vec<String> = read.notes.iter().map(|n| n.to_string()).collect();
    assert!(
        notes.contains(&"f.dxf: skipped: 30000 x 30000 copies of block \"C\" (1 entities) take the file past 200000 entities: layer 0: INSERT #1".to_string()),
        "{notes:?}"
    );
    // the small array is read
    assert_eq!(read.parts.len(), 6);
}

/// A curve that needs more samples than the reader takes (a picometre arc tolerance, a
/// 100 km ellipse) was sampled for minutes into gigabytes.
#[test]
fn a_curve_too_large_for_the_arc_tolerance_is_skipped_with_a_note() {
    let ellipse = "0\nELLIPSE\n8\n0\n10\n0\n20\n0\n30\n0\n11\n40\n21\n0\n31\n0\n40\n0.5\n41\n0\n42\n6.283185307179586\n";
    let options = ReadOptions {
        arc_tolerance: 1e-12,
        ..ReadOptions::default()
    };
    let notes = notes_of(ellipse, &options);
    assert!(
        notes.contains(&"f.dxf: skipped: too large for the arc tolerance 0.000000000001 mm (the file's curves need over 4194304 samples): drawn in the wrong units, or a corrupt number?: layer 0: ELLIPSE #1".to_string()),
        "{notes:?}"
    );
    // at the default tolerance it is a part
    let text = with_units(4, ellipse);
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    assert_eq!(read.parts.len(), 1);
}

/// The DXF parser's messages quote the file, line breaks and all, and it panics on a header
/// date it cannot hold: both are one-line errors.
#[test]
fn parser_failures_are_one_line_errors() {
    let date = "0\nSECTION\n2\nHEADER\n9\n$TDCREATE\n40\n1e300\n0\nENDSEC\n0\nEOF\n";
    let err = read_dxf(date.as_bytes(), "d.dxf", &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "d.dxf: not a readable DXF file: the parser failed on a value it cannot hold, such as a date out of range (TimeDelta::seconds out of bounds)"
    );
    // binary DXF, a line break inside the first section's name
    let broken = b"AutoCAD Binary DXF\r\n\x1a\x00\x00SEC\nTION\x00\x00EOF\x00";
    let err = read_dxf(broken, "b.dxf", &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(!err.contains(['\n', '\r']), "{err:?}");
    assert!(err.starts_with("b.dxf: not a readable DXF file: "), "{err}");
    let long = format!("0\n{}\n0\nEOF\n", "x".repeat(5000));
    let err = read_dxf(long.as_bytes(), "l.dxf", &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.len() < 300 && err.contains("xxx...xxx"), "{err}");
    assert!(err.ends_with("at line/offset 1"), "{err}");
}

/// The samples are the file's, not each curve's: 20 ellipses of 30 km (a million samples each
/// at the default tolerance) fit until the file's samples run out, the rest are skipped
/// (a block that inserts itself scaled by 2 gave thousands of such curves: hours).
#[test]
fn the_curve_samples_are_counted_for_the_whole_file() {
    let ellipses: String = (0..20)
        .map(|k| {
            format!(
                "0\nELLIPSE\n8\n0\n10\n{}\n20\n0\n30\n0\n11\n3e7\n21\n0\n31\n0\n40\n0.5\n41\n0\n42\n6.283185307179586\n",
                1e8 * k as f64
            )
        })
        .collect();
    let text = with_units(4, &ellipses);
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    let skipped = read
        .notes
        .iter()
        .find(|n| {
            n.what
                .contains("the file's curves need over 4194304 samples")
        })
        .unwrap_or_else(|| panic!("{:?}", read.notes));
    assert!(
        !read.parts.is_empty() && read.parts.len() + skipped.entities.len() == 20,
        "{} parts, {:?}",
        read.parts.len(),
        skipped
    );
}

/// A layer or line type name is the file's text: control characters in it (a binary DXF
/// string, a stray byte) were written into notes and rejections as they are.
#[test]
fn layer_names_with_control_characters_stay_on_one_line() {
    let open = "0\nLINE\n8\nA\x0bB\n10\n0\n20\n0\n11\n10\n21\n0\n";
    let text = with_units(4, open);
    let read = read_dxf(text.as_bytes(), "f.dxf", &ReadOptions::default()).unwrap();
    let why = read.rejected[0].to_string();
    assert!(
        why.starts_with("part f.dxf (layer A\\u{b}B: LINE #1): open contour"),
        "{why}"
    );
    let dashed = "0\nLINE\n8\n0\n6\nDASH\x07\n10\n0\n20\n0\n11\n10\n21\n0\n";
    let notes = notes_of(dashed, &ReadOptions::default());
    assert!(
        notes.contains(&"f.dxf: skipped: dashed line type DASH\\u{7}: a construction or bend line, not cut: layer 0: LINE #1".to_string()),
        "{notes:?}"
    );
}

/// LINE entities from `pts` to the next, closed.
fn lines(pts: &[[f64; 2]]) -> String {
    let mut s = String::new();
    for (k, a) in pts.iter().enumerate() {
        let b = pts[(k + 1) % pts.len()];
        s += &format!(
            "0\nLINE\n8\n0\n10\n{}\n20\n{}\n11\n{}\n21\n{}\n",
            a[0], a[1], b[0], b[1]
        );
    }
    s
}

#[test]
fn a_curve_drawn_as_lines_shorter_than_the_join_tolerance_stays_a_curve() {
    // a 50 mm circle of 20,000 lines 0.016 mm long (the join tolerance is 0.05 mm), and
    // beside it a square of lines with 0.03 mm gaps at its corners, which still close
    let n = 20_000;
    let circle: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            [50.0 * t.cos(), 50.0 * t.sin()]
        })
        .collect();
    let mut text = String::from("0\nSECTION\n2\nENTITIES\n") + &lines(&circle);
    for (a, b) in [
        ([100.0, 0.0], [140.0, 0.0]),
        ([140.0, 0.03], [140.0, 40.0]),
        ([139.97, 40.0], [100.0, 40.0]),
        ([100.0, 39.97], [100.0, 0.03]),
    ] {
        text += &format!(
            "0\nLINE\n8\n0\n10\n{}\n20\n{}\n11\n{}\n21\n{}\n",
            a[0], a[1], b[0], b[1]
        );
    }
    text += "0\nENDSEC\n0\nEOF\n";
    let read = read_dxf(text.as_bytes(), "fine", &ReadOptions::default()).unwrap();
    assert!(read.rejected.is_empty(), "{:?}", read.rejected);
    assert_eq!(read.parts.len(), 2);
    let areas = outline_areas(&read);
    // the polygon of 20,000 sides, and the square (its corners moved by the joins)
    let polygon = polygon_area(&circle);
    assert!(
        areas.iter().any(|a| (a - polygon).abs() < 1e-6 * polygon),
        "{areas:?}"
    );
    assert!(areas.iter().any(|a| (a - 1600.0).abs() < 2.0), "{areas:?}");
    // every vertex of the circle where it was drawn: no vertex joined a neighbour's
    let circle_part = read
        .parts
        .iter()
        .find(|p| p.outer.vertices.len() > 4)
        .unwrap();
    assert_eq!(circle_part.outer.vertices.len(), n);
    let gaps: Vec<&str> = read
        .notes
        .iter()
        .map(|n| n.what.as_str())
        .filter(|w| w.contains("gap of"))
        .collect();
    assert_eq!(gaps.len(), 4, "{gaps:?}");
    assert!(
        gaps.iter().all(|w| w.contains("gap of 0.0300 mm closed")),
        "{gaps:?}"
    );
}
