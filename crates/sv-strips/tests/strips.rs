//! Strip invariants on solved frames: congruent flat tiles, collinear pinned joints, no
//! overlaps, labels, and profiles that pass the design-rule check.

use std::f64::consts::FRAC_PI_2;

use sv_frame::{solve, FrameFile, QuadMesh, SolveOptions};
use sv_geom::{Point2, Point3};
use sv_strips::{
    check_profile, convex_intersection_area, hub_face, profile_strip, unit_labels, unroll,
    FlatStrip, HubFace, ProfileParams, SplitRule, StripDirection, StripOptions, StripsError,
    StripsFile, TileSet,
};

fn frame(mesh: &QuadMesh) -> FrameFile {
    solve(mesh, &SolveOptions::default(), &mut |_| {})
        .unwrap()
        .to_frame_file(mesh)
}

fn cap() -> FrameFile {
    frame(&QuadMesh::sphere_cap(6, 6, 3000.0, 300.0))
}

fn saddle() -> FrameFile {
    frame(&QuadMesh::translational(
        6,
        6,
        300.0,
        |x| x * x / 6000.0,
        |y| -y * y / 6000.0,
    ))
}

fn dist3(a: &Point3, b: &Point3) -> f64 {
    (a - b).norm()
}

fn dist2(a: &Point2, b: &Point2) -> f64 {
    (a - b).norm()
}

fn cross(a: sv_geom::Vector2, b: sv_geom::Vector2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Every invariant of an unrolled frame.
fn check_unrolled(f: &FrameFile, options: &StripOptions) {
    let tiles = TileSet::from_frame(f).unwrap();
    let strips = unroll(f, options).unwrap();
    // a partition of the units
    let mut seen = vec![0; f.units.len()];
    for s in &strips {
        for &u in &s.units {
            seen[u] += 1;
        }
        assert_eq!(s.tiles.len(), s.units.len());
        assert_eq!(s.pins.len() + 1, s.units.len());
        assert!(
            s.size[0] <= options.max_length + 1e-9,
            "{} {:?}",
            s.id,
            s.size
        );
    }
    assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    // labels
    let labels = unit_labels(&strips, f.units.len());
    let mut ids: Vec<&str> = labels.iter().map(|l| l.id.as_str()).collect();
    for l in &labels {
        let b = l.id.as_bytes();
        assert_eq!(b.len(), 6, "{}", l.id);
        assert!(b[0].is_ascii_uppercase() && b[1..3].iter().all(u8::is_ascii_digit));
        assert_eq!(b[3], b'-');
        assert!(b[4..].iter().all(u8::is_ascii_digit));
        assert!(l.id.starts_with(&l.strip));
    }
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), f.units.len());
    for s in &strips {
        // congruence: all six corner distances
        for (&u, flat) in s.units.iter().zip(&s.tiles) {
            let t = &tiles.tiles[u];
            for i in 0..4 {
                for j in (i + 1)..4 {
                    let e = (dist3(&t[i], &t[j]) - dist2(&flat[i], &flat[j])).abs();
                    assert!(
                        e < 1e-6,
                        "strip {} unit {u}: corner {i}-{j} off by {e}",
                        s.id
                    );
                }
            }
            // counter-clockwise (not mirrored)
            assert!(cross(flat[1] - flat[0], flat[2] - flat[0]) > 0.0);
        }
        for (j, pin) in s.pins.iter().enumerate() {
            let (tf, tg) = (&s.tiles[j], &s.tiles[j + 1]);
            let [k, m] = pin.sides;
            let (a, b) = (tf[k], tf[(k + 1) % 4]);
            let (c, d) = (tg[m], tg[(m + 1) % 4]);
            let u = (b - a).normalize();
            // collinear facing sides
            assert!(cross(u, c - a).abs() < 1e-6 && cross(u, d - a).abs() < 1e-6);
            // pin points coincide
            let pf = a + (b - a) * pin.along[0];
            let pg = c + (d - c) * pin.along[1];
            assert!(dist2(&pf, &pg) < 1e-6 && dist2(&pf, &pin.point) < 1e-6);
            // tiles on opposite sides of the line
            let cf = tf
                .iter()
                .fold(sv_geom::Vector2::zeros(), |s, p| s + p.coords)
                / 4.0;
            let cg = tg
                .iter()
                .fold(sv_geom::Vector2::zeros(), |s, p| s + p.coords)
                / 4.0;
            assert!(cross(u, cf - a.coords) > 1.0 && cross(u, cg - a.coords) < -1.0);
            assert!(pin.twist >= 0.0 && pin.twist < 0.5, "{pin:?}");
            assert!(pin.bend.abs() < 0.5 && pin.gap >= 0.0, "{pin:?}");
        }
        // no two tiles overlap
        for i in 0..s.tiles.len() {
            for j in (i + 1)..s.tiles.len() {
                let a = convex_intersection_area(&s.tiles[i], &s.tiles[j]);
                assert!(a <= options.overlap_area_tolerance, "{} {i} {j}: {a}", s.id);
            }
        }
    }
}

#[test]
fn sphere_cap_and_saddle_unroll_in_both_directions() {
    for f in [cap(), saddle()] {
        for direction in [StripDirection::U, StripDirection::V] {
            let options = StripOptions {
                direction,
                ..Default::default()
            };
            check_unrolled(&f, &options);
            let strips = unroll(&f, &options).unwrap();
            assert_eq!(strips.len(), 6, "one strip per row of a 6 x 6 grid");
            // the curved strips are not flat: joints bend
            assert!(strips
                .iter()
                .flat_map(|s| &s.pins)
                .any(|p| p.bend.abs() > 1e-3));
        }
    }
}

#[test]
fn strips_follow_the_grid_rows_and_columns() {
    let f = cap();
    let u = unroll(&f, &StripOptions::default()).unwrap();
    assert_eq!(u[0].units, vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(u[1].id, "A02");
    let v = unroll(
        &f,
        &StripOptions {
            direction: StripDirection::V,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(v[0].units, vec![0, 6, 12, 18, 24, 30]);
}

/// Unit counts of the pieces of each chain, checking that the pieces follow the chains.
fn piece_sizes(chains: &[Vec<usize>], strips: &[FlatStrip]) -> Vec<Vec<usize>> {
    let mut next = 0;
    let mut out = Vec::new();
    for chain in chains {
        let mut covered = 0;
        let mut sizes = Vec::new();
        while covered < chain.len() {
            let s = &strips[next];
            assert_eq!(s.units[0], chain[covered], "pieces follow the chain");
            covered += s.units.len();
            sizes.push(s.units.len());
            next += 1;
        }
        assert_eq!(covered, chain.len());
        out.push(sizes);
    }
    assert_eq!(next, strips.len());
    out
}

#[test]
fn long_strips_are_split_at_the_sheet_length() {
    let f = cap();
    let tiles = TileSet::from_frame(&f).unwrap();
    let mut counts = Vec::new();
    for split in [SplitRule::Fill, SplitRule::Balanced] {
        let options = StripOptions {
            max_length: 1300.0,
            split,
            ..Default::default()
        };
        check_unrolled(&f, &options);
        let strips = unroll(&f, &options).unwrap();
        assert!(strips.len() > 6);
        assert!(strips.iter().all(|s| s.size[0] <= 1300.0));
        let chains = sv_strips::chains(&tiles, options.direction);
        let sizes = piece_sizes(&chains, &strips);
        for (chain, sizes) in chains.iter().zip(&sizes) {
            let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            if sizes.len() > 1 {
                assert!(*lo > 1, "a one-unit stub in {sizes:?} ({split:?})");
            }
            // balanced: nearly equal pieces, not a long run and a short rest
            if split == SplitRule::Balanced {
                assert!(
                    hi - lo <= 1,
                    "unbalanced pieces {sizes:?} of a {}-unit chain",
                    chain.len()
                );
            }
        }
        counts.push(sizes);
    }
    // both rules need the same number of pieces per chain (the same welds on site); fill
    // puts at least as many units into the first piece of a chain, and more somewhere
    let (fill, balanced) = (&counts[0], &counts[1]);
    for (f, b) in fill.iter().zip(balanced) {
        assert_eq!(f.len(), b.len(), "fill {f:?}, balanced {b:?}");
        assert!(f[0] >= b[0], "fill {f:?}, balanced {b:?}");
    }
    assert!(
        fill.iter().zip(balanced).any(|(f, b)| f[0] > b[0]),
        "fill {fill:?}, balanced {balanced:?}"
    );
    // a tile longer than the sheet cannot be cut
    let e = unroll(
        &f,
        &StripOptions {
            max_length: 100.0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, StripsError::Unit { unit: 0, .. }), "{e}");
}

#[test]
fn a_strip_that_would_overlap_itself_is_split() {
    // Rhombic tiles have parallel opposite sides, so a chain of them unrolls straight; the
    // overlap guard matters for other tiles. Here: the trapezoids of a flat annulus, 1.5
    // turns, which unroll into a ring that runs over itself after one turn.
    let n = 24;
    let corner = |i: usize, j: usize| {
        let a = i as f64 / 16.0 * std::f64::consts::TAU;
        let r = 600.0 + 300.0 * j as f64;
        Point3::new(r * a.cos(), r * a.sin(), 0.0)
    };
    let tiles = TileSet {
        hub_faces: vec![HubFace::Back; n],
        joints: vec![[None; 4]; n],
        tiles: (0..n)
            .map(|i| {
                [
                    corner(i, 0),
                    corner(i + 1, 0),
                    corner(i + 1, 1),
                    corner(i, 1),
                ]
            })
            .collect(),
        across: (0..n)
            .map(|i| {
                let mut a = [None; 4];
                if i > 0 {
                    a[3] = Some((i - 1, 1));
                }
                if i + 1 < n {
                    a[1] = Some((i + 1, 3));
                }
                a
            })
            .collect(),
    };
    // one full turn (16 tiles) fits and the 17th would overlap, so the 24 tiles need two
    // pieces: 16 + 8 filled, 12 + 12 balanced
    for (split, expected) in [(SplitRule::Fill, [16, 8]), (SplitRule::Balanced, [12, 12])] {
        let options = StripOptions {
            max_length: 1e6,
            split,
            ..Default::default()
        };
        let strips = sv_strips::unroll_tiles(&tiles, &options).unwrap();
        assert_eq!(
            strips.iter().map(|s| s.units.len()).collect::<Vec<_>>(),
            expected,
            "{split:?}"
        );
        for s in &strips {
            for i in 0..s.tiles.len() {
                for j in (i + 1)..s.tiles.len() {
                    assert!(convex_intersection_area(&s.tiles[i], &s.tiles[j]) <= 1e-3);
                }
            }
        }
    }
}

#[test]
fn profiles_pass_the_design_rules() {
    let params = ProfileParams::default();
    for f in [cap(), saddle()] {
        let options = StripOptions::default();
        let strips = unroll(&f, &options).unwrap();
        let labels = unit_labels(&strips, f.units.len());
        let mut profiles = Vec::new();
        for s in &strips {
            let names: Vec<String> = s.units.iter().map(|&u| labels[u].id.clone()).collect();
            let p = profile_strip(s, &names, &params).unwrap();
            assert_eq!(p.cuts.len(), 4 * s.units.len());
            assert!(p.outline.signed_area() > 0.0);
            assert!(p.cuts.iter().all(|c| c.signed_area() < 0.0));
            assert!(p.area > 0.0 && p.area < p.outline.signed_area());
            assert_eq!(p.labels.len(), s.units.len());
            assert_eq!(p.labels[0].text, names[0]);
            assert_eq!(p.fold_marks.len(), 8 * s.units.len() + s.pins.len());
            // one face mark per unit, saying what the frame's poses say, upright labels
            assert_eq!(p.face_marks.len(), s.units.len());
            for ((m, &u), l) in p.face_marks.iter().zip(&s.units).zip(&p.labels) {
                let q = |c: [[f64; 3]; 4]| c.map(|c| Point3::new(c[0], c[1], c[2]));
                let want = hub_face(&q(f.units[u].primary), &q(f.units[u].hub));
                assert_eq!(Some(m.face), want, "unit {u}");
                assert!(l.angle > -FRAC_PI_2 && l.angle <= FRAC_PI_2, "{l:?}");
            }
            assert_eq!(
                s.hub_faces,
                p.face_marks.iter().map(|m| m.face).collect::<Vec<_>>()
            );
            let v = check_profile(s, &p, &params);
            assert!(
                v.is_empty(),
                "{}",
                v.iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join("\n")
            );
            profiles.push(p);
        }
        let file = StripsFile::new(&strips, &profiles, &params, f.params.expansion, &options);
        let json = serde_json::to_value(&file).unwrap();
        assert_eq!(json["format"], "spin-valence/strips");
        assert_eq!(json["version"], 1);
        assert_eq!(json["length_unit"], "mm");
        assert_eq!(json["params"]["thickness"], params.thickness);
        assert_eq!(json["params"]["min_web"], params.min_web());
        let s0 = &json["strips"][0];
        assert_eq!(s0["id"], "A01");
        assert_eq!(s0["flat"][0]["primary"].as_array().unwrap().len(), 4);
        assert!(["etched", "back"].contains(&s0["flat"][0]["hub_face"].as_str().unwrap()));
        assert_eq!(
            s0["face_marks"].as_array().unwrap().len(),
            s0["units"].as_array().unwrap().len()
        );
        assert_eq!(s0["outline"][0].as_array().unwrap().len(), 3);
        assert_eq!(s0["cuts"][0][0].as_array().unwrap().len(), 3);
        assert!(s0["area_mm2"].as_f64().unwrap() > 0.0);
        let back: StripsFile = serde_json::from_value(json).unwrap();
        assert_eq!(back, file);
    }
}

#[test]
fn the_design_rule_check_catches_a_thin_web() {
    let params = ProfileParams::default();
    let f = cap();
    let strips = unroll(&f, &StripOptions::default()).unwrap();
    let names = vec![String::from("A01-01"); strips[0].units.len()];
    let mut p = profile_strip(&strips[0], &names, &params).unwrap();
    // move the first cut toward the second one by most of the web between them
    let shift = {
        let a = &p.cuts[0].vertices[0];
        let b = &p.cuts[1].vertices[0];
        [b.x - a.x, b.y - a.y]
    };
    for v in &mut p.cuts[0].vertices {
        v.x += shift[0] * 0.97;
        v.y += shift[1] * 0.97;
    }
    let v = check_profile(&strips[0], &p, &params);
    assert!(
        v.iter()
            .any(|v| v.rule == sv_strips::DrcRule::MinWeb && v.unit == Some(strips[0].units[0])),
        "{v:?}"
    );
    // a slot end made square is caught
    let mut p = profile_strip(&strips[0], &names, &params).unwrap();
    for v in &mut p.cuts[2].vertices {
        v.bulge = 0.0;
    }
    let v = check_profile(&strips[0], &p, &params);
    assert!(
        v.iter().any(|v| v.rule == sv_strips::DrcRule::SlotEnd),
        "{v:?}"
    );
}

#[test]
fn bad_parameters_name_the_parameter() {
    let f = cap();
    let strips = unroll(&f, &StripOptions::default()).unwrap();
    let bad = ProfileParams {
        neck_width: 30.0,
        ..Default::default()
    };
    let e = profile_strip(&strips[0], &[], &bad).unwrap_err();
    assert!(
        matches!(
            e,
            StripsError::Parameter {
                name: "neck_width",
                ..
            }
        ),
        "{e}"
    );
    let e = unroll(
        &f,
        &StripOptions {
            max_length: f64::NAN,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("max_length"), "{e}");
}

/// A flat 6 x 6 grid of 300 mm squares in which the edge between the faces of column 2,
/// rows 1 and 2 is turned: two interior vertices get three faces, one five. Returns the
/// mesh and the interior vertices of odd valence.
fn irregular_grid() -> (QuadMesh, Vec<usize>) {
    let n = 6;
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut m = QuadMesh::grid(n, n, 300.0);
    let (a, b, c, d, e, f) = (id(2, 1), id(3, 1), id(3, 2), id(3, 3), id(2, 3), id(2, 2));
    m.vertices[f].x -= 60.0;
    m.vertices[c].x += 60.0;
    let cell = |i: usize, j: usize| j * n + i;
    let (lower, upper) = (cell(2, 1), cell(2, 2));
    m.faces[lower] = [a, b, e, f];
    m.faces[upper] = [b, c, d, e];
    (m, vec![c, e, f])
}

#[test]
fn strips_end_at_vertices_of_odd_valence_on_an_irregular_mesh() {
    let (mesh, odd) = irregular_grid();
    let f = frame(&mesh);
    let tiles = TileSet::from_frame(&f).unwrap();
    for direction in [StripDirection::U, StripDirection::V] {
        let chains = sv_strips::chains(&tiles, direction);
        // every unit in exactly one chain
        let mut count = vec![0; tiles.len()];
        for c in &chains {
            for &u in c {
                count[u] += 1;
            }
        }
        assert!(count.iter().all(|&c| c == 1), "{direction:?}: {count:?}");
        // each step enters through one side and leaves through the opposite one
        for c in &chains {
            for w in c.windows(3) {
                let into = (0..4).find(|&k| tiles.across[w[1]][k].map(|x| x.0) == Some(w[0]));
                let out = (0..4).find(|&k| tiles.across[w[1]][k].map(|x| x.0) == Some(w[2]));
                let (Some(i), Some(o)) = (into, out) else {
                    panic!("{direction:?}: chain step without a link: {w:?}")
                };
                assert_eq!(
                    (i + 2) % 4,
                    o,
                    "{direction:?}: chain {c:?} turns at unit {}",
                    w[1]
                );
            }
        }
        // at each odd vertex a chain ends in one of the faces around it
        for &v in &odd {
            let around: Vec<usize> = (0..mesh.faces.len())
                .filter(|&g| mesh.faces[g].contains(&v))
                .collect();
            let ends = chains
                .iter()
                .any(|c| around.contains(&c[0]) || around.contains(&c[c.len() - 1]));
            assert!(
                ends,
                "{direction:?}: no strip ends at vertex {v}: {chains:?}"
            );
        }
        // and the whole frame unrolls, every unit in one strip
        let options = StripOptions {
            direction,
            ..Default::default()
        };
        let strips = unroll(&f, &options).unwrap();
        let mut placed: Vec<usize> = strips.iter().flat_map(|s| s.units.clone()).collect();
        placed.sort_unstable();
        assert_eq!(
            placed,
            (0..tiles.len()).collect::<Vec<_>>(),
            "{direction:?}"
        );
    }
}

/// A sphere cap solved as cut for the default profile, unrolled and profiled: its file.
fn cap_as_cut() -> (FrameFile, StripsFile) {
    let params = ProfileParams::default();
    let mesh = QuadMesh::sphere_cap(6, 6, 3000.0, 300.0);
    let options = SolveOptions {
        cut: Some(params.cut_widths()),
        ..SolveOptions::default()
    };
    let mut f = solve(&mesh, &options, &mut |_| {})
        .unwrap()
        .to_frame_file(&mesh);
    let strip_options = StripOptions::default();
    let strips = unroll(&f, &strip_options).unwrap();
    sv_strips::apply_labels(&mut f, &strips);
    let labels = unit_labels(&strips, f.units.len());
    let profiles: Vec<_> = strips
        .iter()
        .map(|s| {
            let names: Vec<String> = s.units.iter().map(|&u| labels[u].id.clone()).collect();
            profile_strip(s, &names, &params).unwrap()
        })
        .collect();
    let file = StripsFile::new(
        &strips,
        &profiles,
        &params,
        f.params.expansion,
        &strip_options,
    );
    (f, file)
}

fn fold_row<'a>(r: &'a sv_frame::CheckReport, name: &str) -> &'a sv_frame::CheckRow {
    r.rows
        .iter()
        .find(|r| r.name.starts_with(name))
        .unwrap_or_else(|| panic!("no row {name}: {r:#?}"))
}

#[test]
fn parts_as_cut_fold_into_their_poses_and_a_slot_moved_2_mm_is_caught_at_its_unit() {
    let (f, file) = cap_as_cut();
    let limits = sv_strips::FoldLimits::for_profile(&file.params.profile);
    let r = sv_strips::fold_check(&f, &file, &limits);
    for name in [
        "neck as cut",
        "leg between its necks",
        "hub plate as cut",
        "hub lap = frame.json",
        "units that cannot be rebuilt",
    ] {
        assert!(fold_row(&r, name).ok, "{:#?}", fold_row(&r, name));
    }
    // the necks are found where the layout pins the legs, to far below a kerf
    assert!(fold_row(&r, "neck as cut").worst < 0.5);
    // one slot of the fifth unit of the first strip moved 2 mm across its strip
    let mut moved = file.clone();
    let s = &mut moved.strips[0];
    let unit = s.units[4];
    let k = s.cut_units.iter().position(|&u| u == unit).unwrap();
    s.cuts[k] = s.cuts[k].transformed(0.0, [0.0, 2.0]);
    let r = sv_strips::fold_check(&f, &moved, &limits);
    let necks = fold_row(&r, "neck as cut");
    assert!(!necks.ok && necks.worst > 0.5, "{necks:?}");
    assert!(necks.at.contains(&f.units[unit].id), "{necks:?}");
}

/// A strips file that lost its strips, or lists one twice, passed the fold check: nothing
/// was measured of the units it left out, and the lap row said "inf ... ok".
#[test]
fn every_unit_in_exactly_one_strip_and_a_row_that_measured_nothing_fails() {
    let (f, file) = cap_as_cut();
    let limits = sv_strips::FoldLimits::for_profile(&file.params.profile);
    file.validate(f.units.len()).unwrap();
    let cover = "units in no strip or in more than one";
    assert!(fold_row(&sv_strips::fold_check(&f, &file, &limits), cover).ok);

    let mut empty = file.clone();
    empty.strips.clear();
    let r = sv_strips::fold_check(&f, &empty, &limits);
    let row = fold_row(&r, cover);
    assert!(!row.ok && row.worst == f.units.len() as f64, "{row:?}");
    assert!(
        row.at
            .starts_with(&format!("unit {} is in no strip", f.units[0].id)),
        "{row:?}"
    );
    let laps = fold_row(&r, "hub lap as cut");
    assert!(!laps.ok && laps.at == "nothing measured", "{laps:?}");

    let mut twice = file.clone();
    twice.strips.push(file.strips[0].clone());
    let row = fold_row(&sv_strips::fold_check(&f, &twice, &limits), cover).clone();
    let first = file.strips[0].units[0];
    let id = &file.strips[0].id;
    assert!(
        !row.ok && row.worst == file.strips[0].units.len() as f64,
        "{row:?}"
    );
    assert!(
        row.at.starts_with(&format!(
            "unit {} is in 2 strips: {id} (strips[0]), {id} (strips[{}])",
            f.units[first].id,
            file.strips.len()
        )),
        "{row:?}"
    );
}

/// What the fold check cannot read is refused by path: indices out of range, strips whose
/// units are not their tiles', a profile that cannot be cut.
#[test]
fn strips_files_the_fold_check_cannot_read_name_the_path() {
    let (f, file) = cap_as_cut();
    let n = f.units.len();
    let mut oob = file.clone();
    oob.strips[1].units[0] = 999;
    assert_eq!(
        oob.validate(n).unwrap_err(),
        format!("strips[1].units[0]: index 999 out of range (the frame has {n} units)")
    );
    let mut oob = file.clone();
    oob.strips[0].cut_units[2] = n;
    assert!(oob
        .validate(n)
        .unwrap_err()
        .starts_with("strips[0].cut_units[2]: index"));
    let mut other = file.clone();
    other.strips[1].units.swap(0, 1);
    assert!(
        other
            .validate(n)
            .unwrap_err()
            .starts_with("strips[1]: units ["),
        "{:?}",
        other.validate(n)
    );
    let mut thin = file.clone();
    thin.params.profile.thickness = 0.0;
    assert_eq!(
        thin.validate(n).unwrap_err(),
        "params.thickness = 0: must be a finite length > 0"
    );
}
