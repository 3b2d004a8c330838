//! The command line: clap types only, no work.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use sv_frame::{MeshChecks, SidePolicy, SolveOptions};

const MAIN_EXAMPLES: &str = "\
Examples:
  spinvalence solve --mesh fixtures/sphere_cap.obj --out out/cap
  spinvalence check out/cap/frame.json

Lengths are millimetres, Z is up, angles on the command line are degrees.
Exit codes: 0 success, 1 `check` found a violation, 2 bad input or usage (or, with
`build --strict`, goals not met), 3 `build` wrote what it could make but some goals are
not met (the summary names them).";

const SOLVE_EXAMPLES: &str = "\
Examples:
  # a flat 4 x 3 grid of 300 mm squares, default spin angle 45 degrees
  spinvalence solve --mesh fixtures/grid_small.obj --out out/small

  # a sphere cap, tiles 2 % larger than the model tiles, for a script
  spinvalence solve --mesh fixtures/sphere_cap.obj --expansion 1.02 --out out/cap --quiet

  # a saddle with every hub on the side its face normal points to
  spinvalence solve --mesh fixtures/saddle.obj --side normal --out out/saddle

Writes DIR/frame.json and DIR/frame.obj, both or neither.";

const CHECK_EXAMPLES: &str = "\
Examples:
  spinvalence check out/cap/frame.json
  spinvalence check out/cap/frame.json && echo frame ok
  # a build directory: the frame, then every unit rebuilt from the cut in strips.json and
  # folded at its necks into its pose (legs, hub laps, primary plates, bridges)
  spinvalence check out

Exit code 0 when every check passes, 1 when one fails, 2 when the file cannot be read.";

/// Spin-Valence kirigami space frames: from a quad mesh of hubs to a deployed frame.
#[derive(Debug, Parser)]
#[command(name = "spinvalence", version, after_help = MAIN_EXAMPLES, arg_required_else_help = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Deploy a quad mesh of hubs: solve every unit's (theta, phi) so the primary tiles meet.
    #[command(after_help = SOLVE_EXAMPLES)]
    Solve(SolveArgs),
    /// Re-verify a frame.json, or a build directory folded from its cut, and print a table.
    #[command(after_help = CHECK_EXAMPLES)]
    Check(CheckArgs),
    /// Nest closed-contour DXF parts onto plasma sheets (or run a strip-packing instance).
    #[command(after_help = NEST_EXAMPLES)]
    Nest(NestArgs),
    /// Target surface to deployed frame: hub mesh, primary solve, files in DIR (default ./out).
    #[command(after_help = BUILD_EXAMPLES)]
    Build(BuildArgs),
    /// Serve a frame to AR clients: target poses and tolerance checks over a websocket, the page at /.
    Serve(crate::serve::ServeArgs),
}

const BUILD_EXAMPLES: &str = "\
Examples:
  # the built-in pavilion (about 6 x 4 m) with 300 mm units into ./out
  spinvalence build

  # your own surface (OBJ or STL triangle mesh in mm), 250 mm units
  spinvalence build --target roof.stl --unit-size 250 --out out/roof

  # every parameter from a file, the unit size overridden on the command line
  spinvalence build --config build.toml --unit-size 200

  # your own layout: a coarse quad mesh with the irregular vertices where you want them
  spinvalence build --target roof.obj --layout roof_layout.obj --out out/roof

Built-in targets: builtin:flat, builtin:vault, builtin:dome, builtin:saddle, builtin:pavilion.
Writes DIR/mesh.obj (hub mesh), frame.json, frame.obj, strips.json, strips/ (one DXF and one
SVG per strip), nest.json and sheets/ (the strips nested on plasma sheets: one DXF and one
SVG per sheet), report.html (the build report: open it in a browser, it needs no network),
bom.csv (one row per strip), report.json and timings.json, all or nothing (where the strips
cannot be cut: the hub mesh, frame and report only, exit code 3).
`spinvalence build --print-config` prints a config file with every default.

Exit codes: 0 every goal met; 3 built and written, but some goals are not met (the hub
mesh's planarity, conical, distance to target or boundary, coverage, edge ratio, face
sides; hub laps long enough to weld; parts that can be cut; every row of the fold check of
the parts as cut, an open weld say): the summary and report.html
name each with its worst place, and where the strips could not be cut only the hub mesh,
the frame and the report are written; 2 bad input or usage, or with --strict unmet goals
(the files are still written, to look at).";

const NEST_EXAMPLES: &str = "\
Examples:
  # every closed contour in the DXF files is a part (contours inside others are holes)
  spinvalence nest parts/*.dxf --sheet 3000x1500 --out out/nest

  # two stock sizes, 8 mm margin, free rotation, one minute
  spinvalence nest a.dxf b.dxf --sheet 3000x1500,2500x1250 --margin 8 --free-rotation --nest-seconds 60 --out out/n

  # a flat pattern drawn in inches, bend lines on a layer called FOLD
  spinvalence nest bracket.dxf --units in --layer 'FOLD=skip' --out out/b

  # a strip-packing benchmark instance (jagua-rs JSON)
  spinvalence nest ../shared/datasets/nesting/spp/fu.json --nest-seconds 60 --out out/fu

Reads LINE, ARC, CIRCLE, LWPOLYLINE, POLYLINE, SPLINE and ELLIPSE (turned into arcs), blocks
through INSERTs, $INSUNITS and extrusion directions; bend, construction, dimension and
border layers and dashed lines are not cut (docs/dxf.md has the layer rules). Every entity
skipped or repaired is named on a `note:` line and in nest.json's notes.
Writes DIR/nest.json and, per sheet, DIR/sheets/sheet-NN_WxHmm[_tTmm].dxf (layers OUTSIDE,
INSIDE, ETCH, INFO; etching first, outside contours clockwise, inside ones counter-clockwise
and before their outline; pierce points and labels on INFO) and .svg (or DIR/strip.json for
an instance).
Parts that cannot be nested (open or self-intersecting contours, larger than every sheet,
unreadable files) are left out, named on `warning:` lines on stderr (one line per reason)
and each in nest.json's left_out; the others still nest (exit code 0; 2 when none could). The layout is decided by a
work budget (collision evaluations: --nest-evaluations, else derived from --nest-seconds
and the parts), so the same files, options and seed give the same sheets on every machine;
--nest-seconds caps the wall time of the whole stage, and when it cuts the search short the
summary, a warning line and DIR/timings.json's nest_search.cut_by_time say so.";

/// `spinvalence nest`.
#[derive(Debug, Args)]
pub struct NestArgs {
    /// DXF files with closed contours (mm), or one jagua-rs JSON strip-packing instance.
    #[arg(value_name = "PARTS", required = true)]
    pub parts: Vec<PathBuf>,
    /// Sheet size WIDTHxHEIGHT in mm; several comma-separated sizes are stock sizes in order.
    #[arg(long, default_value = "3000x1500", allow_hyphen_values = true)]
    pub sheet: String,
    /// Clear border along the sheet edges (mm).
    #[arg(long, value_name = "MM", default_value_t = sv_nest::sheets::DEFAULT_MARGIN, allow_negative_numbers = true)]
    pub margin: f64,
    /// Plasma kerf (mm); the part spacing is kerf + clearance.
    #[arg(
        long,
        value_name = "MM",
        default_value_t = 1.3,
        allow_negative_numbers = true
    )]
    pub kerf: f64,
    /// Extra clearance between parts (mm).
    #[arg(
        long,
        value_name = "MM",
        default_value_t = 4.7,
        allow_negative_numbers = true
    )]
    pub clearance: f64,
    /// Allow any rotation (default: 0 and 180 degrees).
    #[arg(long)]
    pub free_rotation: bool,
    /// Time budget in seconds: caps the whole stage and, without --nest-evaluations, sets
    /// the work budget that decides the layout.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 10.0,
        allow_negative_numbers = true
    )]
    pub nest_seconds: f64,
    /// Work budget (collision evaluations) that decides the layout, the same on every
    /// machine; --nest-seconds then only caps the time.
    #[arg(long, value_name = "N")]
    pub nest_evaluations: Option<u64>,
    /// Random seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Material thickness (mm), for the sheet file names and titles.
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub thickness: Option<f64>,
    /// Units of the DXF files, overriding their $INSUNITS (mm, cm, m, in, ft, ...).
    #[arg(long, value_name = "UNIT")]
    pub units: Option<String>,
    /// Ends of lines and arcs closer than this are joined (mm).
    #[arg(long, value_name = "MM", default_value_t = sv_dxf::DEFAULT_JOIN_TOLERANCE, allow_negative_numbers = true)]
    pub join_tolerance: f64,
    /// SPLINE and ELLIPSE become arcs within this distance (mm).
    #[arg(long, value_name = "MM", default_value_t = sv_dxf::DEFAULT_ARC_TOLERANCE, allow_negative_numbers = true)]
    pub arc_tolerance: f64,
    /// A layer rule PATTERN=ROLE (ROLE: outside, inside, cut, etch, skip; `*` and `?` in
    /// the pattern), before the defaults; repeat for several.
    #[arg(long = "layer", value_name = "PATTERN=ROLE")]
    pub layers: Vec<String>,
    /// Nest contours found inside holes (islands) as parts of their own.
    #[arg(long)]
    pub islands: bool,
    /// Cut direction on the sheets: outside-cw (outside contours clockwise, inside ones
    /// counter-clockwise) or outside-ccw.
    #[arg(long, value_name = "DIR", default_value = "outside-cw")]
    pub cut_direction: String,
    /// Where the etching goes in the sheet files: first (before every cut) or last.
    #[arg(long, value_name = "WHEN", default_value = "first")]
    pub etch: String,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `spinvalence build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// TOML file with every parameter (see `--print-config`); flags override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Target surface: an OBJ/STL triangle mesh in mm, or builtin:NAME.
    #[arg(long, value_name = "FILE|builtin:NAME")]
    pub target: Option<String>,
    /// Unit (face) side in mm (default 300).
    #[arg(long, value_name = "MM", allow_negative_numbers = true)]
    pub unit_size: Option<f64>,
    /// A coarse quad mesh (OBJ, mm) laid out as you want the hub mesh, irregular vertices
    /// included; it is subdivided to the unit size, laid onto the target and optimised.
    #[arg(long, value_name = "COARSE.obj")]
    pub layout: Option<PathBuf>,
    /// Unmet goals are an error (exit code 2) instead of exit code 3.
    #[arg(long)]
    pub strict: bool,
    /// Spin angle of the hubs in degrees (default 45).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub spin_angle: Option<f64>,
    /// Expansion factor e >= 1 of the physical primary tiles (default 1).
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    pub expansion: Option<f64>,
    /// Output directory (default ./out).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Mesh direction of the strips: u (along side 0 of unit 0) or v (default u).
    #[arg(long, value_name = "u|v", value_parser = parse_direction)]
    pub strip_direction: Option<sv_strips::StripDirection>,
    /// Time budget of the nesting in seconds (default 5): caps the stage and, without
    /// --nest-evaluations, sets the work budget that decides the sheets.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub nest_seconds: Option<f64>,
    /// Work budget of the nesting (collision evaluations), the same sheets on every
    /// machine; --nest-seconds then only caps the time.
    #[arg(long, value_name = "N")]
    pub nest_evaluations: Option<u64>,
    /// Print a config file with every default and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `spinvalence solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Quad mesh of hubs: OBJ in mm, planar quads listed counter-clockwise seen from the hub side.
    #[arg(long, value_name = "HUBS.obj")]
    pub mesh: PathBuf,
    /// Spin angle of the hubs in degrees, strictly between 0 and 90 (45 for a square grid).
    // 45 = sv_frame::DEFAULT_SPIN_ANGLE in degrees (a test keeps the two equal).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 45.0,
        allow_negative_numbers = true
    )]
    pub spin_angle: f64,
    /// Expansion factor e >= 1 of the physical primary tiles about their centroids.
    #[arg(
        long,
        value_name = "E",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub expansion: f64,
    /// Which side of its primary tile each hub goes to.
    #[arg(long, value_enum, default_value_t = SideArg::Auto)]
    pub side: SideArg,
    /// What to minimise: the largest link gap (max) or the sum of gaps (sum, the paper's).
    #[arg(long, value_enum, default_value_t = ObjectiveArg::Max)]
    pub objective: ObjectiveArg,
    /// Largest allowed face non-planarity: diagonal distance / mean edge of the face.
    #[arg(long, value_name = "X", default_value_t = MeshChecks::DEFAULT_PLANARITY_TOLERANCE,
          allow_negative_numbers = true)]
    pub planarity_tolerance: f64,
    /// Largest number of solver iterations.
    #[arg(long, value_name = "N", default_value_t = SolveOptions::default().max_iterations)]
    pub max_iterations: usize,
    /// Output directory (created if missing); receives frame.json and frame.obj.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print nothing but errors: no progress bar, no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--side`, the command-line face of [`SidePolicy`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SideArg {
    /// Per unit, hubs on the concave side (shorter distances); flat parts keep the mesh normal.
    Auto,
    /// Every hub on the side its face normal points to.
    Normal,
    /// Every hub on the side opposite to its face normal.
    Opposite,
}

/// `--objective`, the command-line face of [`sv_frame::GapObjective`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObjectiveArg {
    /// The largest link gap (min-max, after a least-squares start).
    Max,
    /// The sum of link gaps (the paper's objective).
    Sum,
}

impl From<ObjectiveArg> for sv_frame::GapObjective {
    fn from(o: ObjectiveArg) -> Self {
        match o {
            ObjectiveArg::Max => sv_frame::GapObjective::Max,
            ObjectiveArg::Sum => sv_frame::GapObjective::Sum,
        }
    }
}

impl From<SideArg> for SidePolicy {
    fn from(side: SideArg) -> Self {
        match side {
            SideArg::Auto => SidePolicy::Auto,
            SideArg::Normal => SidePolicy::Normal,
            SideArg::Opposite => SidePolicy::Opposite,
        }
    }
}

/// `spinvalence check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// A frame.json written by `spinvalence solve`, or a directory written by `spinvalence
    /// build` (its frame.json and strips.json).
    #[arg(value_name = "FRAME.json|DIR")]
    pub frame: PathBuf,
    /// Shortest hub lap a build directory must show (mm, above 0). Default: max(5 t, 25 mm)
    /// for the sheet thickness t of its strips.json.
    #[arg(long, value_name = "MM")]
    pub min_overlap: Option<f64>,
}

/// `u` or `v`, as in the config file.
fn parse_direction(text: &str) -> Result<sv_strips::StripDirection, String> {
    match text {
        "u" | "U" => Ok(sv_strips::StripDirection::U),
        "v" | "V" => Ok(sv_strips::StripDirection::V),
        _ => Err(format!("`{text}` is not a strip direction (u or v)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn default_spin_angle_matches_the_library() {
        let cli =
            Cli::try_parse_from(["spinvalence", "solve", "--mesh", "m.obj", "--out", "o"]).unwrap();
        let Command::Solve(args) = cli.command else {
            panic!("expected solve")
        };
        assert!((args.spin_angle.to_radians() - sv_frame::DEFAULT_SPIN_ANGLE).abs() < 1e-15);
        assert_eq!(SidePolicy::from(args.side), SolveOptions::default().side);
    }
}
