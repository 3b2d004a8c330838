//! The parts as cut fold to the frame: our own fold check (`fold_check.py`: numpy and ezdxf,
//! nothing from the project) finds every neck in the strip DXFs, pins the legs there, moves
//! the pins with the hub and primary plates of `frame.json` and measures every leg and hub lap.

use std::fs;
use std::process::Command;

use serde_json::Value;

use crate::build::{default_build, saddle_build};
use crate::ezdxf::venv_python;
use crate::util::{diagonals_cross, dot3, read_json, unmet_goals, Dir};

/// Run the fold check on `dir/out`; `(exit code, stdout, figures)`.
fn fold_check(dir: &Dir) -> (i32, String, Value) {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/e2e/fold_check.py");
    let json = dir.join("fold.json");
    let out = Command::new(venv_python())
        .arg(script)
        .arg(dir.join("out"))
        .arg("--json")
        .arg(&json)
        .output()
        .expect("run fold_check.py");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let code = out.status.code().unwrap_or(-1);
    assert!(
        json.exists(),
        "fold_check.py wrote no figures (exit {code}): {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (code, stdout, read_json(&json))
}

/// A copy of the default build's `out/` (frame, strips and their DXFs) in a fresh directory.
fn copy_of_default_build() -> Dir {
    let (built, out) = default_build();
    out.expect_code(0);
    let dir = Dir::new();
    fs::create_dir_all(dir.join("out/strips")).unwrap();
    for f in ["frame.json", "strips.json"] {
        fs::copy(
            built.join(&format!("out/{f}")),
            dir.join(&format!("out/{f}")),
        )
        .unwrap();
    }
    for f in built.entries("out/strips") {
        fs::copy(
            built.join(&format!("out/strips/{f}")),
            dir.join(&format!("out/strips/{f}")),
        )
        .unwrap();
    }
    dir
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

#[test]
fn the_default_build_folds_from_its_dxf_as_our_own_code_measures_it() {
    let dir = copy_of_default_build();
    let frame = read_json(&dir.join("out/frame.json"));
    let units = frame["units"].as_array().unwrap().len();
    let links = frame["links"].as_array().unwrap().len();
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 0, "{stdout}");
    // every leg of every unit, every hub lap
    assert_eq!(fig["legs_checked"], 4 * units, "{fig}");
    assert_eq!(fig["laps_checked"], links, "{fig}");
    // the legs as cut reach the solved poses
    assert!(f(&fig, "leg_error_max") <= 0.5, "{fig}");
    // every hub lap can be welded (the default minimum, max(5 t, 25 mm) at t = 2.5)
    assert!(f(&fig, "lap_min") >= 25.0, "{fig}");
    // and frame.json reports the laps the parts show
    assert!(f(&fig, "lap_claim_error_max") <= 0.1, "{fig}");
    // the joints as our own code measures them on the plates the outline cuts
    joints_hold("default build", &fig);
    // `spinvalence check DIR` folds the same parts and agrees on what holds: on the default
    // build every row, the joints too (plates of neighbouring strips neither apart nor into
    // each other, bridges within their span, bend and twist)
    let checked = dir.run(&["check", "out"]);
    checked.expect_code(0);
    for row in [
        "neck as cut at its pin in frame.json",
        "leg between its necks, folded into the pose",
        "hub lap as cut",
        "hub lap = frame.json hub_overlap",
        "weld: plates of neighbouring strips apart",
        "plates of neighbouring strips reach into each other",
        "bridge length folded - flat",
        "bridge bent in its plane",
        "bridge twisted",
        "bridge: plates into each other across the slot",
        "units that cannot be rebuilt from their cut",
        "hub plates at a lap into each other",
        "leg through the neighbour's hub plate, outside its relief",
        "leg through a neighbour's rim",
        "relief under the hub plate lying on its own",
    ] {
        let line = checked
            .stdout
            .lines()
            .find(|l| l.starts_with(row))
            .unwrap_or_else(|| panic!("no row {row}: {checked:?}"));
        assert!(line.ends_with("ok"), "{line}");
    }
    // its smallest lap, widest weld and deepest reach are ours within the claim tolerance
    agrees_with_check(&checked, &fig);
}

/// The first number of `check`'s row that starts with `name`.
fn worst(out: &crate::util::Output, name: &str) -> f64 {
    row(out, name)
        .split_whitespace()
        .find_map(|w| w.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no figure in row {name}: {out:?}"))
}

/// Rows of `spinvalence check` and our figure for each: the hub lap, weld gap, reach
/// (between strips and across a bridge's slot), hub plates into each other, widest and
/// closest gap between lapping hub plates, a lap's overlap along the line of centres, a
/// leg into the neighbour's hub plate or rim.
const CHECK_ROWS: [(&str, &str); 10] = [
    ("hub lap as cut", "lap_min"),
    ("weld: plates of neighbouring strips apart", "weld_gap_max"),
    (
        "plates of neighbouring strips reach into each other",
        "reach_max",
    ),
    (
        "bridge: plates into each other across the slot",
        "bridge_reach_max",
    ),
    ("hub plates at a lap into each other", "hub_stack_lift_max"),
    (
        "hub plates at a lap, widest gap between them",
        "hub_stack_gap_max",
    ),
    (
        "hub plates at a lap, closest gap between them",
        "hub_stack_closest_max",
    ),
    (
        "hub lap, the plates' overlap along the line of centres",
        "lap_overlap_along_min",
    ),
    (
        "leg through the neighbour's hub plate, outside its relief",
        "leg_through_hub_plate_max",
    ),
    ("leg through a neighbour's rim", "leg_into_rim_max"),
];

/// `spinvalence check`'s worst hub lap, weld gap, reach (between strips and across a
/// bridge's slot), hub plates into each other, a leg into the neighbour's hub plate or rim
/// and widest gap between lapping hub plates are the fold check's, 0.1 mm; how deep a
/// relief reaches under the plate on it, 0.25 mm.
fn agrees_with_check(checked: &crate::util::Output, fig: &Value) {
    for (name, ours) in CHECK_ROWS {
        let theirs = worst(checked, name);
        assert!(
            (theirs - f(fig, ours)).abs() <= 0.1,
            "{name}: {theirs} vs {fig}"
        );
    }
    // how deep a relief reaches under the plate lying on it: each samples its own
    // quarter-millimetre grid and its own reading of the cuts' outlines
    let name = "relief under the hub plate lying on its own";
    let theirs = worst(checked, name);
    assert!(
        (theirs - f(fig, "relief_under_upper_max")).abs() <= 0.25,
        "{name}: {theirs} vs {fig}"
    );
    // and about as many legs run through the neighbours' hub plates and into their rims (a
    // leg at the limit may fall either side)
    for (name, ours) in [
        (
            "leg through the neighbour's hub plate, outside its relief",
            "legs_through_hub_plates",
        ),
        ("leg through a neighbour's rim", "legs_into_rims"),
    ] {
        let line = row(checked, name);
        let theirs: f64 = line
            .rsplit("; ")
            .next()
            .and_then(|t| t.split_whitespace().next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no count of legs in {line}"));
        let ours = f(fig, ours);
        assert!((theirs - ours).abs() <= 2.0, "{line} vs {ours} legs");
    }
}

/// Issue 14's and 15's joints by our own measure: every bridge of every strip found in the
/// outline, within 0.5 mm of its flat span and its bend and twist limits (the bend within a
/// few degrees); every weld between strips found, its plates at most 1.5 mm apart and as
/// frame.json says; no plate 0.1 mm into its neighbour.
fn joints_hold(what: &str, fig: &Value) {
    bridges_hold(what, fig);
    assert!(f(fig, "welds_checked") > 0.0, "{what}: {fig}");
    assert!(f(fig, "weld_gap_max") <= 1.5, "{what}: {fig}");
    assert!(f(fig, "weld_claim_error_max") <= 0.1, "{what}: {fig}");
    assert!(f(fig, "reach_max") <= 0.1, "{what}: {fig}");
    // the hub plates lie one on the other at every lap, never through it
    assert!(f(fig, "hub_stack_lift_max") <= 0.1, "{what}: {fig}");
    // and the leg that runs down through the lower plate at a lap passes through the relief
    // cut for it: the leg as a plate, its section through the plate, clear of its steel
    assert!(f(fig, "leg_through_hub_plate_max") <= 0.1, "{what}: {fig}");
    assert_eq!(fig["legs_through_hub_plates"], 0, "{what}: {fig}");
    // and that relief reaches at most 1.5 mm under the plate lying on it (the lap is kept)
    relief_stays_out(what, fig);
    // nor does a leg leaving its plate at the rim neck run through a neighbour's rim there
    // (that neighbour's plate lying under the corner, docs/geometry.md 5.5)
    assert!(f(fig, "leg_into_rim_max") <= 0.1, "{what}: {fig}");
    assert_eq!(fig["legs_into_rims"], 0, "{what}: {fig}");
}

/// The cuts of a hub plate reach at most 1.5 mm (`sv_strips::relief::UNDER_EDGE`) under the
/// hub plate lying on it at a lap, on our quarter-millimetre grid.
fn relief_stays_out(what: &str, fig: &Value) {
    assert!(f(fig, "relief_under_upper_max") <= 1.6, "{what}: {fig}");
}

/// Every bridge in the strips, found by our code in the DXF outlines, spans its joint,
/// bends and twists within its limits, and its two plates stay clear of each other across
/// the joint slot.
fn bridges_hold(what: &str, fig: &Value) {
    assert!(f(fig, "bridges_checked") > 0.0, "{what}: {fig}");
    assert_eq!(
        fig["bridges_checked"], fig["bridges_in_strips"],
        "{what}: {fig}"
    );
    assert!(f(fig, "bridge_span_max") <= 0.5, "{what}: {fig}");
    // turned in their plane, the plates would meet across the slot away from the bridge
    assert!(f(fig, "bridge_reach_max") <= 0.1, "{what}: {fig}");
    assert!(f(fig, "bridge_bend_limit_deg") <= 5.0, "{what}: {fig}");
    assert!(
        f(fig, "bridge_bend_max_deg") <= f(fig, "bridge_bend_limit_deg"),
        "{what}: {fig}"
    );
    assert!(
        f(fig, "bridge_twist_max_deg") <= f(fig, "bridge_twist_limit_deg"),
        "{what}: {fig}"
    );
}

/// Issue 14's acceptance on the other targets at 300 mm with the default parameters, by our
/// own fold code: every leg within 0.5 mm of its length, every hub lap of at least the weld
/// minimum and reported within 0.1 mm of what the parts show, and the slots as the profile
/// rules draw them; every joint within its limits, and every leg clear of the steel it
/// passes (the saddle since the tenth session: its welds closed by more rounds, and where
/// no straight relief keeps the rules a bent one, docs/geometry.md 5.5, 6.6, 6.9). `check`
/// agrees.
#[test]
fn the_dome_the_vault_the_saddle_and_a_hypar_fold_from_their_dxf_too() {
    let hypar = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/targets/hypar_square.obj"
    );
    for target in ["builtin:dome", "builtin:vault", "builtin:saddle", hypar] {
        let saddle = target == "builtin:saddle";
        let own;
        let (dir, built) = if saddle {
            let (dir, built) = saddle_build();
            (dir, built)
        } else {
            let dir = Dir::new();
            let mut args = vec!["build", "--target", target, "--quiet"];
            args.extend(crate::build::NEST_WORK);
            let built = dir.run(&args);
            own = (dir, built);
            (&own.0, &own.1)
        };
        built.expect_code(0);
        let frame = read_json(&dir.join("out/frame.json"));
        let units = frame["units"].as_array().unwrap().len();
        let (code, stdout, fig) = fold_check(dir);
        assert_eq!(fig["legs_checked"], 4 * units, "{target}: {fig}");
        assert!(f(&fig, "leg_error_max") <= 0.5, "{target}: {fig}");
        assert!(f(&fig, "lap_min") >= 25.0, "{target}: {fig}");
        assert!(f(&fig, "lap_claim_error_max") <= 0.1, "{target}: {fig}");
        assert!(f(&fig, "weld_claim_error_max") <= 0.1, "{target}: {fig}");
        // by our own clipping the plates of every lap overlap by the weld minimum along the
        // line of centres: the tips pass each other in line, not offset sideways (the
        // default saddle had 6 laps whose plates did not overlap at all, the vault 1,
        // until the joint solve held them; docs/geometry.md 5.5)
        assert!(f(&fig, "lap_overlap_along_min") >= 25.0, "{target}: {fig}");
        assert_eq!(fig["laps_overlap_along_none"], 0, "{target}: {fig}");
        let checked = dir.run(&["check", "out"]);
        agrees_with_check(&checked, &fig);
        assert_eq!(code, 0, "{target}: {stdout}");
        checked.expect_code(0);
        joints_hold(target, &fig);
    }
}

/// Issue 14's acceptance at 200 mm ([`holds_at_200_mm`]) on the saddle, the target that
/// takes the most rounds at 300 mm, in one strip direction (the one the build keeps when
/// it tries both) to keep the test short; every target, both directions: below.
#[test]
fn at_200_mm_the_saddle_folds_and_closes_every_joint() {
    holds_at_200_mm(
        "builtin:saddle",
        &["--target", "builtin:saddle", "--strip-direction", "v"],
    );
}

/// Issue 14's acceptance at 200 mm on every target it names, with the parameters the build
/// picks for that size (1.5 mm sheet at its least widths), both strip directions tried as
/// by default. About ten minutes on two cores, so `make test` runs only the saddle's
/// (above) and this one runs with `make acceptance`.
#[test]
#[ignore = "ten minutes: make acceptance"]
fn at_200_mm_every_target_folds_and_closes_every_joint() {
    let hypar = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/targets/hypar_square.obj"
    );
    holds_at_200_mm("pavilion", &[]);
    for target in ["builtin:dome", "builtin:vault", hypar, "builtin:saddle"] {
        holds_at_200_mm(target, &["--target", target]);
    }
}

/// Issue 15's constant overlap on the targets it names (pavilion, dome, vault) at 300 mm,
/// `[frame] overlap = "constant"`: by our own fold code every hub lap as cut within 1 mm of
/// the one lap frame.json asks (a spread of at most 2 mm), at least the weld minimum and as
/// reported; every leg within 0.5 mm and clear of the hub plate it passes (a relief cut
/// for it); every joint closed, with the lap length the build kept of those it tried
/// (docs/geometry.md 6.9: 3-11 welds stayed open at the median lap); every hub mesh goal
/// met (exit 0); `check` agrees with our figures. About fifteen minutes: `make acceptance`.
#[test]
#[ignore = "ten minutes: make acceptance"]
fn a_constant_overlap_holds_every_lap_within_1_mm_at_300_mm() {
    for target in ["pavilion", "builtin:dome", "builtin:vault"] {
        let dir = Dir::new();
        dir.write("constant.toml", "[frame]\noverlap = \"constant\"\n");
        let mut args = vec!["build", "--config", "constant.toml"];
        if target != "pavilion" {
            args.extend(["--target", target]);
        }
        args.extend(crate::build::NEST_WORK);
        // every goal met, every joint closed at one of the lengths tried, the one kept the
        // one frame.json asks
        let built = dir.run(&args);
        built.expect_code(0);
        let frame = read_json(&dir.join("out/frame.json"));
        let asked = &frame["params"]["hub_lap"];
        assert_eq!(asked["tolerance"], 1.0, "{target}: {asked}");
        let lengths = row(&built, "hub lap lengths");
        assert!(
            lengths.ends_with(&format!("kept {:.3} mm", f(asked, "length"))),
            "{target}: {lengths} / {asked}"
        );
        let units = frame["units"].as_array().unwrap().len();
        let (_, stdout, fig) = fold_check(&dir);
        assert_eq!(fig["legs_checked"], 4 * units, "{target}: {fig}");
        assert!(
            f(&fig, "lap_off_one_length_max") <= 1.0,
            "{target}: {stdout}"
        );
        assert!(
            f(&fig, "lap_max") - f(&fig, "lap_min") <= 2.0,
            "{target}: {fig}"
        );
        assert!(f(&fig, "lap_min") >= 25.0, "{target}: {fig}");
        assert!(f(&fig, "lap_claim_error_max") <= 0.1, "{target}: {fig}");
        assert!(f(&fig, "leg_error_max") <= 0.5, "{target}: {fig}");
        assert_eq!(fig["legs_through_hub_plates"], 0, "{target}: {stdout}");
        relief_stays_out(target, &fig);
        assert_eq!(fig["legs_into_rims"], 0, "{target}: {stdout}");
        joints_hold(target, &fig);
        let checked = dir.run(&["check", "out"]);
        checked.expect_code(0);
        agrees_with_check(&checked, &fig);
        assert!(
            row(&checked, "hub lap off the one lap asked").ends_with("ok"),
            "{target}: {checked:?}"
        );
    }
}

/// Joints left just outside their limits get a longer solve (`[joints] longer_solve`): the
/// torus patch at 300 mm keeps 6 welds open (2.77 mm) after the default 250 iterations, and
/// with twice as many (both strip directions again) closes every joint. The build says so and exits 0; our own fold code
/// finds every joint within its limits on the parts as cut, and `check` agrees.
#[test]
fn a_frame_whose_welds_end_just_open_is_solved_again_with_twice_the_iterations() {
    let dir = Dir::new();
    let target = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/targets/torus_patch.obj"
    );
    let mut args = vec!["build", "--target", target, "--unit-size", "300"];
    args.extend(crate::build::NEST_WORK);
    let built = dir.run(&args);
    built.expect_code(0);
    let longer = row(&built, "longer solve");
    assert!(
        longer.contains("solved again with max_iterations 500: 0 joints outside their limits")
            && longer.ends_with(", kept"),
        "{longer}"
    );
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 0, "{stdout}");
    joints_hold("torus patch", &fig);
    let checked = dir.run(&["check", "out"]);
    checked.expect_code(0);
    agrees_with_check(&checked, &fig);
}

/// `[frame] laps_touch = true` on the dome at 300 mm: by our own fold code the two hub
/// plates of every lap come within 1.5 mm of each other somewhere over it (a lap weld
/// needs no filler; without the option 117 of its 364 laps stand further apart everywhere,
/// up to 6.2 mm) and never pass through each other; every leg, lap and joint holds as in
/// the default build, and `check` holds the closest gap to the weld gap limit and agrees.
#[test]
fn with_laps_touch_the_hub_plates_of_every_lap_touch_somewhere() {
    let dir = Dir::new();
    dir.write("touch.toml", "[frame]\nlaps_touch = true\n");
    let mut args = vec![
        "build",
        "--config",
        "touch.toml",
        "--target",
        "builtin:dome",
        "--quiet",
    ];
    args.extend(crate::build::NEST_WORK);
    dir.run(&args).expect_code(0);
    let frame = read_json(&dir.join("out/frame.json"));
    assert_eq!(
        frame["params"]["hub_laps_touch"], true,
        "{}",
        frame["params"]
    );
    let units = frame["units"].as_array().unwrap().len();
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 0, "{stdout}");
    assert_eq!(fig["legs_checked"], 4 * units, "{fig}");
    assert!(f(&fig, "hub_stack_closest_max") <= 1.5, "{stdout}");
    assert!(f(&fig, "leg_error_max") <= 0.5, "{fig}");
    assert!(f(&fig, "lap_min") >= 25.0, "{fig}");
    assert!(f(&fig, "lap_claim_error_max") <= 0.1, "{fig}");
    joints_hold("dome with laps_touch", &fig);
    let checked = dir.run(&["check", "out"]);
    checked.expect_code(0);
    let closest = row(&checked, "hub plates at a lap, closest gap between them");
    assert!(
        closest.contains("(mm)") && closest.ends_with("ok"),
        "{closest}"
    );
    agrees_with_check(&checked, &fig);
}

/// `spinvalence build --unit-size 200` with `args`: the 1.5 mm sheet at its least widths,
/// and by our own fold code every leg within 0.5 mm, every hub lap at least 25 mm and as
/// reported, every joint within its limits, no plate or leg into another; `check` agrees
/// and passes.
fn holds_at_200_mm(what: &str, args: &[&str]) {
    let dir = Dir::new();
    let mut all = vec!["build", "--unit-size", "200", "--quiet"];
    all.extend(args);
    all.extend(crate::build::NEST_WORK);
    dir.run(&all).expect_code(0);
    let frame = read_json(&dir.join("out/frame.json"));
    let params = &frame["params"];
    assert_eq!(params["thickness"], 1.5, "{what}: {params}");
    let units = frame["units"].as_array().unwrap().len();
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 0, "{what}: {stdout}");
    assert_eq!(fig["legs_checked"], 4 * units, "{what}: {fig}");
    assert!(f(&fig, "leg_error_max") <= 0.5, "{what}: {fig}");
    assert!(f(&fig, "lap_min") >= 25.0, "{what}: {fig}");
    assert!(f(&fig, "lap_claim_error_max") <= 0.1, "{what}: {fig}");
    joints_hold(what, &fig);
    let checked = dir.run(&["check", "out"]);
    agrees_with_check(&checked, &fig);
    checked.expect_code(0);
}

/// Every row an unmet goal `fold check: ...` names as failing (`NAME (UNIT) WORST (limit
/// LIMIT) at PLACE`) is one our own fold code measures past its limit too, within 0.1 mm;
/// at least one is named.
fn failures_are_ours(goal: &str, fig: &Value) {
    let mut named = 0;
    for (name, ours) in CHECK_ROWS {
        let Some(at) = goal.find(&format!("{name} (")) else {
            continue;
        };
        let figures: Vec<f64> = goal[at + name.len()..]
            .split(|c: char| c.is_whitespace() || c == '(' || c == ')')
            .filter_map(|w| w.parse().ok())
            .take(2)
            .collect();
        let [worst, limit] = figures[..] else {
            panic!("no worst and limit for {name} in {goal}")
        };
        let ours = f(fig, ours);
        assert!(
            (ours - worst).abs() <= 0.1,
            "{name}: {worst} vs ours {ours}"
        );
        // a smallest (the lap) fails below its limit, the others above it
        let past = if name.starts_with("hub lap") {
            ours < limit
        } else {
            ours > limit
        };
        assert!(past, "{name}: ours {ours} within the limit {limit}: {goal}");
        named += 1;
    }
    assert!(named > 0, "no row we measure is named: {goal}");
}

/// Each row of `out/report.json`'s fold check that fails lists the units where it does
/// (the report's 3D view marks them), and where our own fold code (`fig`) names the worst
/// link of that row, both its units are among them.
fn failing_rows_list_our_worst(dir: &Dir, out: &str, fig: &Value) {
    let report = read_json(&dir.join(&format!("{out}/report.json")));
    let frame = read_json(&dir.join(&format!("{out}/frame.json")));
    let ids: Vec<&str> = frame["units"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["id"].as_str().unwrap())
        .collect();
    // the rows whose worst link fold_check.py names, and its key for it
    let worst_of = [
        ("hub lap as cut", "lap_min"),
        ("weld: plates of neighbouring strips apart", "weld_gap"),
        (
            "plates of neighbouring strips reach into each other",
            "reach",
        ),
    ];
    let rows = report["fold_check"]["rows"].as_array().expect("fold rows");
    let mut compared = 0;
    for row in rows.iter().filter(|r| r["ok"] == false) {
        let listed: Vec<&str> = row["units"]
            .as_array()
            .unwrap_or_else(|| panic!("a failing row lists no units: {row}"))
            .iter()
            .map(|u| ids[u.as_u64().unwrap() as usize])
            .collect();
        assert!(!listed.is_empty(), "{row}");
        let name = row["name"].as_str().unwrap();
        for (_, key) in worst_of.iter().filter(|(p, _)| name.starts_with(p)) {
            let worst = fig["worst"][key].as_str().expect("our worst link");
            for id in worst.split('~') {
                assert!(listed.contains(&id), "{name}: {worst} not in {listed:?}");
            }
            compared += 1;
        }
    }
    assert!(compared > 0, "no failing row of ours to compare: {rows:?}");
}

/// The row of `check`'s table that starts with `name`.
fn row<'a>(out: &'a crate::util::Output, name: &str) -> &'a str {
    out.stdout
        .lines()
        .find(|l| l.starts_with(name))
        .unwrap_or_else(|| panic!("no row {name}: {out:?}"))
}

#[test]
fn a_pose_moved_2_mm_or_a_neck_moved_2_mm_fails_both_checks_naming_the_unit() {
    // the primary plate of one unit moved 2 mm along its normal
    let dir = copy_of_default_build();
    let path = dir.join("out/frame.json");
    let mut frame: Value = read_json(&path);
    let unit = &mut frame["units"][40];
    let id = unit["id"].as_str().unwrap().to_string();
    let p: Vec<[f64; 3]> = (0..4)
        .map(|i| std::array::from_fn(|k| unit["primary"][i][k].as_f64().unwrap()))
        .collect();
    let n = diagonals_cross(&p);
    let len = dot3(n, n).sqrt();
    for (i, c) in p.iter().enumerate() {
        for k in 0..3 {
            unit["primary"][i][k] = (c[k] + 2.0 * n[k] / len).into();
        }
    }
    fs::write(&path, serde_json::to_string_pretty(&frame).unwrap()).unwrap();
    let (code, stdout, _) = fold_check(&dir);
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains(&id), "{id}: {stdout}");
    let checked = dir.run(&["check", "out/frame.json"]);
    checked.expect_code(1);
    assert!(checked.stdout.contains(&id), "{id}: {checked:?}");
    let checked = dir.run(&["check", "out"]);
    checked.expect_code(1);
    let legs = row(&checked, "leg between its necks, folded into the pose");
    assert!(legs.ends_with("FAIL") && legs.contains(&id), "{id}: {legs}");

    // one hook slot of a unit moved 2 mm in its strip's DXF: its necks move with it
    let dir = copy_of_default_build();
    let strips = read_json(&dir.join("out/strips.json"));
    let strip = strips["strips"][3]["id"].as_str().unwrap().to_string();
    let dxf = dir.join(&format!("out/strips/{strip}.dxf"));
    let moved = Command::new(venv_python())
        .arg("-c")
        .arg(
            "import ezdxf, sys\n\
             d = ezdxf.readfile(sys.argv[1])\n\
             e = [e for e in d.modelspace() if e.dxf.layer == 'INSIDE'][0]\n\
             e.set_points([(x + 2.0, y, s, t, b) for x, y, s, t, b in e.get_points()])\n\
             d.saveas(sys.argv[1])\n",
        )
        .arg(&dxf)
        .status()
        .unwrap();
    assert!(moved.success());
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 1, "{stdout}");
    // the necks moved with the slot: their legs change length, or (where the move runs
    // across the legs) the necks leave their pins
    assert!(
        f(&fig, "leg_error_max") > 0.5 || f(&fig, "pin_offset_max") > 0.5,
        "{fig}"
    );
    assert!(stdout.contains(&format!("{strip}-")), "{strip}: {stdout}");
    // `spinvalence check DIR` reads the cut from the DXF too
    let checked = dir.run(&["check", "out"]);
    checked.expect_code(1);
    let necks = row(&checked, "neck as cut at its pin in frame.json");
    assert!(
        necks.ends_with("FAIL") && necks.contains(&format!("{strip}-")),
        "{strip}: {necks}"
    );
}

/// At 200 mm units the default 2.5 mm sheet's hub laps cannot be welded (about 3 mm on a
/// flat grid), so without a `[profile]` the build cuts the thickest sheet whose laps can
/// (1.5 mm at its least widths, docs/config.md) and its summary says so; our own fold check
/// finds every lap in the DXFs at least 25 mm. A config that names a profile is cut as it
/// stands: its short laps are an unmet goal naming the levers (exit 3), and what it makes
/// is written for the user to look at, the short laps shown by `spinvalence check`. At a
/// unit size where no sheet's laps can be welded the joints are left open and the same
/// holds (`--strict`: an error). (40 joint iterations in one strip direction, and none for
/// the named profile: this is about the sheet and the laps, and the full solve takes a
/// minute.)
#[test]
fn at_200_mm_the_sheet_follows_the_unit_size_and_every_lap_can_be_welded() {
    let dir = Dir::new();
    let quick = "[joints]\nmax_iterations = 40\nboth_directions = false\n";
    fs::write(dir.join("quick.toml"), quick).unwrap();
    let args = ["--target", "builtin:flat", "--unit-size", "200"];
    let built = dir.run(&[&["build", "--config", "quick.toml"][..], &args].concat());
    // 40 iterations leave the parts as cut short of closing: the fold check's failing rows
    // are the one goal not met (exit 3), each as our own fold code measures it (below)
    built.expect_code(3);
    let unmet = unmet_goals(&dir, "out");
    assert!(
        unmet.len() == 1 && unmet[0].starts_with("fold check: "),
        "{unmet:?}"
    );
    let sheet = row(&built, "sheet");
    assert!(sheet.contains("1.500 mm at its least widths"), "{sheet}");
    assert!(
        sheet.contains("short of the weld minimum 25.000 mm"),
        "{sheet}"
    );
    let frame = read_json(&dir.join("out/frame.json"));
    assert_eq!(frame["params"]["thickness"], 1.5, "{}", frame["params"]);
    // the least widths of 1.5 mm sheet: legs 6 t, necks 3 t, rim and slots 3 mm
    let cut = &frame["params"]["cut"];
    assert_eq!(
        (f(cut, "leg"), f(cut, "neck"), f(cut, "rim")),
        (9.0, 4.5, 3.0),
        "{cut}"
    );
    let units = frame["units"].as_array().unwrap().len();
    let (_, stdout, fig) = fold_check(&dir);
    assert_eq!(fig["legs_checked"], 4 * units, "{stdout}");
    assert!(f(&fig, "leg_error_max") <= 0.5, "{fig}");
    assert!(f(&fig, "lap_min") >= 25.0, "{fig}");
    failures_are_ours(&unmet[0], &fig);
    failing_rows_list_our_worst(&dir, "out", &fig);

    fs::write(
        dir.join("given.toml"),
        "[joints]\nclose = false\n[profile]\nthickness = 2.5\n",
    )
    .unwrap();
    let given = dir.run(
        &[
            &["build", "--config", "given.toml", "--out", "given"][..],
            &args,
        ]
        .concat(),
    );
    given.expect_code(3);
    assert!(
        given.stderr.contains("hub laps too short to weld")
            && given.stderr.contains("profile.thickness = 1.500"),
        "{}",
        given.stderr
    );
    // at 45 degrees the spin is not a lever; at 80 it is named (the hubs lap most at 45);
    // (at 78 and 80 degrees the legs as cut used to stay 2-7e-6 mm off their lengths after
    // the projection's 60 iterations, and the build stopped with exit 2)
    assert!(!given.stderr.contains("spin angle"), "{}", given.stderr);
    let spun = dir.run(
        &[
            &[
                "build",
                "--config",
                "given.toml",
                "--spin-angle",
                "80",
                "--out",
                "spun",
            ][..],
            &args,
        ]
        .concat(),
    );
    spun.expect_code(3);
    assert!(
        spun.stderr
            .contains("or a spin angle nearer 45 degrees (asked 80.000: the hubs lap most at 45)"),
        "{}",
        spun.stderr
    );
    let report = read_json(&dir.join("given/report.json"));
    assert!(
        report["unmet"].as_array().unwrap().iter().any(|u| u
            .as_str()
            .unwrap()
            .starts_with("hub laps too short to weld")),
        "{report}"
    );
    // the laps as cut, read from the DXFs, fail the weld minimum
    let checked = dir.run(&["check", "given"]);
    checked.expect_code(1);
    let laps = row(&checked, "hub lap as cut (mm, smallest)");
    assert!(laps.ends_with("FAIL"), "{laps}");
    // the build's report says so too, not only its stderr: report.json's fold check has
    // the row failing, report.html marks it
    let fold = report["fold_check"]["rows"]
        .as_array()
        .expect("fold_check rows");
    let lap_row = fold
        .iter()
        .find(|r| r["name"] == "hub lap as cut (mm, smallest)")
        .expect("lap row");
    assert_eq!(lap_row["ok"], false, "{lap_row}");
    assert!(f(lap_row, "worst") < f(lap_row, "limit"), "{lap_row}");
    let html = fs::read_to_string(dir.join("given/report.html")).unwrap();
    let failing = fold.iter().filter(|r| r["ok"] == false).count();
    assert!(
        html.contains(&format!("{failing} of {} rows fail", fold.len()))
            && html.contains("<tr class=\"fail\"><th>hub lap as cut (mm, smallest)</th>"),
        "report.html does not show the failing fold check"
    );

    // At 150 mm no sheet the profile's rules allow laps 25 mm: 1.5 mm sheet at its least
    // widths puts the hub 1.5 + 3 + 2 x 3 + 9 = 19.5 mm inside its tile, and a flat grid's
    // lap (sqrt 2 - 1) L - 2 sqrt 2 inset reaches 25 mm from this unit size on. The build
    // cuts that sheet, leaves the joints open (no solve lifts a lap that far) and says why
    // among the unmet goals; with --strict that is an error.
    // (the nesting's fixed work: on a busy machine the time cap would cut the search and
    // say so on stderr, which the --strict run below must not have)
    let small_args = [
        &[
            "build",
            "--target",
            "builtin:flat",
            "--unit-size",
            "150",
            "--out",
            "small",
        ][..],
        &crate::build::NEST_WORK,
    ]
    .concat();
    let small = dir.run(&small_args);
    small.expect_code(3);
    let root2 = 2f64.sqrt();
    let least_unit = ((25.0 + 2.0 * root2 * 19.5) / (root2 - 1.0)).ceil();
    let said = |text: &str| {
        text.contains("secondary.unit_size 150")
            && text.contains(&format!("unit_size to at least {least_unit} mm"))
            && text.contains("primary.min_overlap")
    };
    assert!(said(&small.stderr), "{}", small.stderr);
    assert!(
        row(&small, "joints").contains("left open"),
        "{}",
        small.stdout
    );
    assert!(
        row(&small, "sheet").contains("1.500 mm at its least widths"),
        "{}",
        small.stdout
    );
    let frame = read_json(&dir.join("small/frame.json"));
    let cut = &frame["params"]["cut"];
    assert_eq!(
        (f(cut, "leg"), f(cut, "neck"), f(cut, "rim")),
        (9.0, 4.5, 3.0),
        "{cut}"
    );
    // every lap as cut is short of the minimum: the flat grid's lap at 150 mm
    let flat_lap = (root2 - 1.0) * 150.0 - 2.0 * root2 * 19.5;
    let checked = dir.run(&["check", "small"]);
    checked.expect_code(1);
    let laps = row(&checked, "hub lap as cut (mm, smallest)");
    let smallest: f64 = laps.split_whitespace().nth(6).unwrap().parse().unwrap();
    assert!(smallest < 25.0 && smallest <= flat_lap + 1.0, "{laps}");
    let strict = dir.run(&[&small_args[..], &["--strict"]].concat());
    strict.expect_code(2);
    assert!(said(strict.one_error_line()), "{}", strict.stderr);
}

/// With one hub lap asked of every link (`params.hub_lap`, `[frame] overlap = "constant"`),
/// both checks hold every lap as cut to it: our fold check measures the laps in the DXFs
/// and `spinvalence check DIR` must agree with it on the farthest lap, passing a band that
/// holds every lap and failing one 1 mm too narrow.
#[test]
fn a_lap_asked_of_every_link_is_held_by_both_checks() {
    let dir = copy_of_default_build();
    let (code, stdout, fig) = fold_check(&dir);
    assert_eq!(code, 0, "{stdout}");
    assert!(fig["lap_off_one_length_max"].is_null(), "{fig}");
    let (lo, hi) = (f(&fig, "lap_min"), f(&fig, "lap_max"));
    let mid = (lo + hi) / 2.0;
    let path = dir.join("out/frame.json");
    let frame: Value = read_json(&path);
    for (tolerance, holds) in [(hi - mid + 0.5, true), (hi - mid - 1.0, false)] {
        let mut asked = frame.clone();
        asked["params"]["hub_lap"] = serde_json::json!({"length": mid, "tolerance": tolerance});
        fs::write(&path, serde_json::to_string_pretty(&asked).unwrap()).unwrap();
        let (code, stdout, fig) = fold_check(&dir);
        assert_eq!(code == 0, holds, "tolerance {tolerance}: {stdout}");
        let farthest = f(&fig, "lap_off_one_length_max");
        assert!(
            (farthest - (hi - mid)).abs() < 1e-6,
            "{farthest} vs {}",
            hi - mid
        );
        let checked = dir.run(&["check", "out"]);
        checked.expect_code(if holds { 0 } else { 1 });
        let text = row(&checked, "hub lap off the one lap asked");
        let theirs = worst(&checked, "hub lap off the one lap asked");
        assert!(
            (theirs - farthest).abs() < 0.01,
            "check {theirs}, ours {farthest}: {text}"
        );
        assert_eq!(text.ends_with("FAIL"), !holds, "{text}");
    }
}
