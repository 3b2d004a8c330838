//! `spinvalence build --config FILE`: every parameter of the build in one TOML file.
//!
//! ```toml
//! target = "builtin:pavilion"   # or a path to an OBJ/STL triangle mesh in mm
//! out = "out"
//!
//! [surface]                     # the layout of the hub mesh
//! layout = "coarse.obj"         # a designer's coarse quad mesh (optional)
//!
//! [secondary]                   # the hub mesh (sv_surface::SecondaryOptions)
//! unit_size = 300.0
//! planarity_weight = 1.0
//!
//! [primary]                     # the deployment (sv_frame::SolveOptions)
//! spin_angle_deg = 45.0
//! expansion = 1.0
//! side = "auto"
//!
//! [joints]                      # closing the joints (sv_frame::close_joints)
//! close = true
//!
//! [frame]                       # what the closed frame holds
//! overlap = "free"              # or "constant", or a hub lap in mm
//!
//! [strips]                      # strips and unrolling (sv_strips::StripOptions)
//! direction = "u"
//!
//! [profile]                     # cut profile (sv_strips::ProfileParams), mm
//! thickness = 3.0
//! kerf = 1.3
//!
//! [nest]                        # the strips on plasma sheets (sv_nest::NestOptions)
//! sheets = ["3000x1500"]
//! seconds = 5.0
//! ```
//!
//! Unknown keys are errors (a typo must not silently fall back to a default). Command-line
//! flags override the file.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};
use serde::{Deserialize, Serialize};
use sv_frame::{LapGoal, SidePolicy, SolveOptions};
use sv_strips::{ProfileParams, StripOptions};
use sv_surface::SecondaryOptions;

/// Default output directory of `build`.
pub const DEFAULT_OUT: &str = "out";

/// The whole build configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BuildConfig {
    /// `builtin:NAME` or a path to an OBJ/STL triangle mesh (mm, Z up).
    pub target: String,
    /// Output directory.
    pub out: PathBuf,
    /// The layout of the hub mesh (not printed while it holds no layout: it has no default
    /// to show).
    #[serde(skip_serializing_if = "SurfaceConfig::is_default")]
    pub surface: SurfaceConfig,
    /// Secondary (hub) mesh options.
    pub secondary: SecondaryOptions,
    /// Primary-surface solve options.
    pub primary: PrimaryConfig,
    /// Closing the joints: the hub mesh and the plates moved together.
    pub joints: JointsConfig,
    /// What the closed frame holds.
    pub frame: FrameConfig,
    /// Strip partition and unrolling.
    pub strips: StripsConfig,
    /// Cut profile of every part (mm).
    pub profile: ProfileParams,
    /// Nesting of the strips onto sheets.
    pub nest: NestConfig,
}

/// `[surface]`: where the hub mesh's layout comes from.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceConfig {
    /// A designer's coarse quad mesh (OBJ, mm) with the irregular vertices where they
    /// should be; subdivided to the unit size and laid onto the target. Without it the
    /// layout is automatic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<PathBuf>,
}

impl SurfaceConfig {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// `[nest]`: the strips on plasma sheets. The part spacing is the profile's kerf plus
/// `clearance`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NestConfig {
    /// Stock sheet sizes `WIDTHxHEIGHT` (mm), in order of preference.
    pub sheets: Vec<String>,
    /// Clear border along every sheet edge (mm).
    pub margin: f64,
    /// Distance between parts beyond the kerf (mm).
    pub clearance: f64,
    /// Any rotation instead of 0 and 180 degrees.
    pub free_rotation: bool,
    /// Time budget of the nesting (s): caps the stage and, without `evaluations`, sets the
    /// work budget that decides the sheets.
    pub seconds: f64,
    /// Work budget of the nesting (collision evaluations): the same sheets on every
    /// machine, `seconds` only caps the time. Default: derived from `seconds` and the parts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub evaluations: Option<u64>,
    /// Random seed (same seed and work budget, same sheets on every machine).
    pub seed: u64,
}

/// Default time budget of the nesting stage of `build` (s).
pub const DEFAULT_NEST_SECONDS: f64 = 5.0;

impl Default for NestConfig {
    fn default() -> Self {
        let d = sv_nest::NestOptions::default();
        Self {
            sheets: d
                .sheets
                .iter()
                .map(|s| format!("{}x{}", s.width, s.height))
                .collect(),
            margin: d.margin,
            clearance: 4.7,
            free_rotation: false,
            seconds: DEFAULT_NEST_SECONDS,
            evaluations: None,
            seed: 0,
        }
    }
}

impl NestConfig {
    /// The nesting options for parts cut with `kerf` (mm), checked (one line naming the key).
    pub fn to_options(&self, kerf: f64) -> Result<sv_nest::NestOptions> {
        if self.sheets.is_empty() {
            bail!("invalid nest.sheets: name at least one sheet size, e.g. [\"3000x1500\"]");
        }
        let sheets = crate::nest::parse_sheets(&self.sheets.join(","))
            .map_err(|e| anyhow!("nest.sheets: {e}"))?;
        for (key, v) in [("margin", self.margin), ("clearance", self.clearance)] {
            if !(v.is_finite() && v >= 0.0) {
                bail!("invalid nest.{key} {v}: must be a finite length >= 0 mm");
            }
        }
        sv_nest::margin_leaves_room(&sheets, self.margin)
            .map_err(|why| anyhow!("invalid nest.margin {}: {why}", self.margin))?;
        nest_seconds_ok(self.seconds).map_err(|why| anyhow!("invalid nest.seconds {why}"))?;
        Ok(sv_nest::NestOptions {
            sheets,
            margin: self.margin,
            spacing: kerf + self.clearance,
            rotations: sv_nest::RotationMode::free_or_default(self.free_rotation),
            seed: self.seed,
            time_limit: std::time::Duration::from_secs_f64(self.seconds),
            max_evaluations: self.evaluations,
            ..sv_nest::NestOptions::default()
        })
    }
}

/// `[strips]`: how the units are partitioned into strips.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StripsConfig {
    /// `u` (along side 0 of unit 0) or `v` (across it).
    pub direction: sv_strips::StripDirection,
    /// Longest flat pattern (mm): the sheet length minus both margins.
    pub max_length: f64,
    /// `fill` (pieces as long as the sheet allows) or `balanced` (nearly equal pieces).
    pub split: sv_strips::SplitRule,
}

impl Default for StripsConfig {
    fn default() -> Self {
        let d = StripOptions::default();
        Self {
            direction: d.direction,
            max_length: d.max_length,
            split: d.split,
        }
    }
}

impl StripsConfig {
    /// The unrolling options, checked (one line naming the key).
    pub fn to_options(&self) -> Result<StripOptions> {
        let options = StripOptions {
            direction: self.direction,
            max_length: self.max_length,
            split: self.split,
            ..StripOptions::default()
        };
        options.validate().map_err(|e| anyhow!("strips: {e}"))?;
        Ok(options)
    }
}

impl Default for BuildConfig {
    fn default() -> Self {
        Self {
            target: format!("builtin:{}", sv_surface::DEFAULT_BUILTIN),
            out: PathBuf::from(DEFAULT_OUT),
            surface: SurfaceConfig::default(),
            secondary: SecondaryOptions::default(),
            primary: PrimaryConfig::default(),
            joints: JointsConfig::default(),
            frame: FrameConfig::default(),
            strips: StripsConfig::default(),
            profile: ProfileParams::default(),
            nest: NestConfig::default(),
        }
    }
}

/// `[frame]`: what the closed frame holds (docs/geometry.md 6.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrameConfig {
    /// The hub laps: `"free"` (any length above the weld minimum), `"constant"` (one length
    /// for every link, chosen by the build: one gauge block checks every hub joint on site;
    /// [`FrameConfig::overlap_targets`]) or that length in mm.
    pub overlap: Overlap,
    /// How far a hub lap may be from that one length, either way (mm).
    pub overlap_tolerance: f64,
    /// Pull the two hub plates of every lap together until they touch somewhere, within
    /// the weld gap limit: a lap weld then needs no filler. Costs time and, on some
    /// frames, closure (docs/config.md).
    pub laps_touch: bool,
}

impl Default for FrameConfig {
    fn default() -> Self {
        Self {
            overlap: Overlap::Rule(OverlapRule::Free),
            overlap_tolerance: 1.0,
            laps_touch: false,
        }
    }
}

/// `[frame] overlap`: a rule or a length (mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, try_from = "OverlapText")]
pub enum Overlap {
    /// `"free"` or `"constant"`.
    Rule(OverlapRule),
    /// One hub lap for every link (mm).
    Length(f64),
}

/// `[frame] overlap` as written: a word or a number.
#[derive(Deserialize)]
#[serde(untagged)]
enum OverlapText {
    Word(String),
    Number(f64),
}

impl TryFrom<OverlapText> for Overlap {
    type Error = String;

    fn try_from(text: OverlapText) -> Result<Self, String> {
        match text {
            OverlapText::Word(w) if w == "free" => Ok(Overlap::Rule(OverlapRule::Free)),
            OverlapText::Word(w) if w == "constant" => Ok(Overlap::Rule(OverlapRule::Constant)),
            OverlapText::Number(mm) => Ok(Overlap::Length(mm)),
            OverlapText::Word(w) => Err(format!(
                "overlap = \"{w}\": expected \"free\", \"constant\" or a hub lap in mm"
            )),
        }
    }
}

/// How the hub laps may vary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OverlapRule {
    /// Any length above the weld minimum.
    Free,
    /// One length for every link, chosen by the build.
    Constant,
}

/// With `[frame] overlap = "constant"`, how many lengths the joint solve tries in turn
/// until every joint holds ([`FrameConfig::overlap_targets`]).
pub const LAP_LENGTHS: usize = 4;

impl FrameConfig {
    /// The hub laps the joint solve tries in turn, the first whose joints all hold kept:
    /// none where the laps are free, the length asked for, or with `"constant"` the
    /// primary solve's median lap (at least the weld minimum and the tolerance) and then
    /// [`LAP_LENGTHS`] - 1 longer ones, each two bands (4 x `overlap_tolerance`) past the
    /// last. Which length lets every joint close is not the median's to say, nor any one
    /// rule's: measured 2026-12-08 at 300 mm (docs/geometry.md 6.9), the pavilion closes at
    /// its median + 4 mm (53.1 mm) and not at its median or at 56 mm, the vault at its
    /// median + 8 mm (56.0 mm), the dome at its median + 12 mm (56.7 mm) but not at + 4 or
    /// + 8 mm.
    pub fn overlap_targets(&self, laps: &[f64], min_overlap: f64) -> Result<Vec<LapGoal>> {
        let Some(first) = self.overlap_target(laps, min_overlap)? else {
            return Ok(Vec::new());
        };
        let tries = match self.overlap {
            Overlap::Rule(OverlapRule::Constant) => LAP_LENGTHS,
            _ => 1,
        };
        Ok((0..tries)
            .map(|k| LapGoal {
                length: first.length + 4.0 * first.tolerance * k as f64,
                ..first
            })
            .collect())
    }

    /// The one hub lap every link must have, if any: `laps` are the primary solve's. Errors
    /// when the tolerance is not a positive length or the band reaches below the weld minimum.
    fn overlap_target(&self, laps: &[f64], min_overlap: f64) -> Result<Option<LapGoal>> {
        let tolerance = self.overlap_tolerance;
        if !(tolerance.is_finite() && tolerance > 0.0) {
            bail!(
                "frame: parameter overlap_tolerance = {tolerance}: expected a length in mm above 0"
            );
        }
        let lowest = min_overlap + tolerance;
        let length = match self.overlap {
            Overlap::Rule(OverlapRule::Free) => return Ok(None),
            Overlap::Rule(OverlapRule::Constant) => {
                let mut sorted: Vec<f64> = laps.iter().copied().filter(|v| v.is_finite()).collect();
                sorted.sort_by(f64::total_cmp);
                let median = sorted.get(sorted.len() / 2).copied().unwrap_or(lowest);
                median.max(lowest)
            }
            Overlap::Length(mm) if mm.is_finite() && mm >= lowest => mm,
            Overlap::Length(mm) => bail!(
                "frame: parameter overlap = {mm}: a hub lap must be a length of at least the \
                 weld minimum {min_overlap} mm plus overlap_tolerance {tolerance} mm"
            ),
        };
        Ok(Some(LapGoal { length, tolerance }))
    }
}

/// `[joints]`: the joint solve (docs/geometry.md, "Closing the joints").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct JointsConfig {
    /// Move the hub mesh and every unit's plates together so that the parts as cut meet:
    /// bridges fold without stretching, plates of neighbouring strips touch where they are
    /// welded. `false` keeps the hub mesh and the primary solve as they are (the joints
    /// then stay open: a study option).
    pub close: bool,
    /// Largest number of solver iterations.
    pub max_iterations: usize,
    /// Iterations after the bridges the solve could not make are split (welded on site
    /// instead), only when there are such bridges; 0 leaves them as they are.
    pub split_iterations: usize,
    /// Close the joints with the strips along both mesh directions and keep the one whose
    /// joints hold better (`[strips] direction` is tried first); `--strip-direction` on the
    /// command line tries only the direction it names.
    pub both_directions: bool,
    /// Where the kept direction ends with joints just outside their limits (none by more
    /// than twice them), solve every direction tried once more with twice `max_iterations`
    /// and keep the best, where it holds better.
    pub longer_solve: bool,
}

impl Default for JointsConfig {
    fn default() -> Self {
        Self {
            close: true,
            max_iterations: sv_frame::JointOptions::default().max_iterations,
            split_iterations: sv_frame::JointOptions::default().split_iterations,
            both_directions: true,
            longer_solve: true,
        }
    }
}

/// The nesting's time cap, in seconds: more than 0 and at most a day (`build`'s
/// `nest.seconds` and `--nest-seconds` of `build` and `nest`; a cap of 1e20 s overflowed the
/// clock and panicked). The error is the value and why.
pub fn nest_seconds_ok(seconds: f64) -> std::result::Result<(), String> {
    if seconds.is_finite() && seconds > 0.0 && seconds <= 86_400.0 {
        Ok(())
    } else {
        Err(format!("{seconds}: must be > 0 and at most a day (86400)"))
    }
}

/// `[primary]`: the deployment, in user units (degrees).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PrimaryConfig {
    /// Spin angle of the hubs (degrees, strictly between 0 and 90).
    pub spin_angle_deg: f64,
    /// Expansion factor e >= 1 of the physical primary tiles.
    pub expansion: f64,
    /// `auto`, `normal` or `opposite`.
    pub side: SidePolicy,
    /// `max` (the largest link gap) or `sum` (the sum of gaps, the paper's objective).
    pub objective: sv_frame::GapObjective,
    /// Largest number of solver iterations.
    pub max_iterations: usize,
    /// Stall tolerance of the solver (relative decrease over a few iterations).
    pub tolerance: f64,
    /// Largest face non-planarity accepted from the hub mesh (diagonal distance / mean edge).
    pub planarity_tolerance: f64,
    /// Shortest hub lap (mm) a weld may have, measured on the hub plates as cut along the
    /// line between their centres. Default: max(5 t, 25 mm) (AWS D1.1 lap joints). A
    /// negative value lets hubs miss each other (studies and benchmarks only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_overlap: Option<f64>,
}

impl Default for PrimaryConfig {
    fn default() -> Self {
        let d = SolveOptions::default();
        Self {
            spin_angle_deg: d.spin_angle.to_degrees(),
            expansion: d.expansion,
            side: d.side,
            objective: d.objective,
            max_iterations: d.max_iterations,
            tolerance: d.tolerance,
            planarity_tolerance: d.planarity_tolerance,
            min_overlap: None,
        }
    }
}

impl PrimaryConfig {
    /// The shortest weldable hub lap (mm) for the sheet of `profile`.
    pub fn min_overlap(&self, profile: &sv_strips::ProfileParams) -> Result<f64> {
        match self.min_overlap {
            None => Ok(profile.min_overlap()),
            // below zero the hubs may miss each other: for studies and benchmarks only
            Some(m) if m.is_finite() => Ok(m),
            Some(m) => bail!("invalid primary.min_overlap {m}: must be a finite length in mm"),
        }
    }

    /// The solver options, with the parameters checked (one line each, naming the key).
    pub fn to_solve_options(&self) -> Result<SolveOptions> {
        let spin = self.spin_angle_deg;
        if !(spin > 0.0 && spin < 90.0) {
            bail!("invalid primary.spin_angle_deg (--spin-angle) {spin}: must be strictly between 0 and 90 degrees");
        }
        let e = self.expansion;
        if !(e.is_finite() && e >= 1.0) {
            bail!("invalid primary.expansion (--expansion) {e}: must be a finite number >= 1");
        }
        let tol = self.planarity_tolerance;
        if !(tol.is_finite() && tol > 0.0) {
            bail!("invalid primary.planarity_tolerance {tol}: must be a finite number > 0");
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            bail!(
                "invalid primary.tolerance {}: must be a finite number >= 0",
                self.tolerance
            );
        }
        Ok(SolveOptions {
            spin_angle: spin.to_radians(),
            expansion: e,
            side: self.side,
            objective: self.objective,
            max_iterations: self.max_iterations,
            tolerance: self.tolerance,
            planarity_tolerance: tol,
            ..SolveOptions::default()
        })
    }
}

/// A config file as read: its parameters, and whether it names the sheet.
pub struct ConfigFile {
    pub config: BuildConfig,
    /// The file has a `[profile]` (without one the sheet follows the unit size).
    pub sets_profile: bool,
}

/// Read a config file's text; errors are one line naming `name:line:column`.
pub fn read(text: &str, name: &str) -> Result<ConfigFile> {
    let located = |e: toml::de::Error| {
        let (line, column) = e
            .span()
            .map(|span| line_column(text, span.start))
            .unwrap_or((1, 1));
        let message = e.message().replace(['\n', '\r'], " ");
        anyhow!("{name}:{line}:{column}: {}", message.trim_end_matches('.'))
    };
    let config: BuildConfig = toml::from_str(text).map_err(located)?;
    // valid as a BuildConfig, and valid TOML but for an integer past i64 (`seed =
    // 18446744073709551615` is a u64 but no TOML integer)
    let table: toml::Table = toml::from_str(text).map_err(located)?;
    let sets_profile = match table.get("profile") {
        Some(toml::Value::Table(profile)) => {
            check_profile_keys(profile, text, name)?;
            true
        }
        _ => false,
    };
    Ok(ConfigFile {
        config,
        sets_profile,
    })
}

/// `[profile]` is `sv_strips::ProfileParams`, which `strips.json` flattens and so cannot
/// deny unknown fields itself: compare its keys with the known ones here.
fn check_profile_keys(profile: &toml::Table, text: &str, name: &str) -> Result<()> {
    let known = toml::Table::try_from(ProfileParams::default())
        .map_err(|e| anyhow!("profile defaults: {e}"))?;
    if let Some(key) = profile.keys().find(|k| !known.contains_key(*k)) {
        let at = text
            .find(&format!("\n{key}"))
            .map(|i| line_column(text, i + 1))
            .unwrap_or((1, 1));
        let expected: Vec<&str> = known.keys().map(String::as_str).collect();
        bail!(
            "{name}:{}:{}: unknown field `{key}` in [profile], expected one of {}",
            at.0,
            at.1,
            expected.join(", ")
        );
    }
    Ok(())
}

/// 1-based line and column of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text.as_bytes()[..offset.min(text.len())];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let column = 1 + before.iter().rev().take_while(|&&b| b != b'\n').count();
    (line, column)
}

/// A config file with every key at its default, for `docs/` and `--print-config`.
pub fn default_toml() -> String {
    toml::to_string_pretty(&BuildConfig::default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`read`]'s parameters alone.
    fn parse(text: &str, name: &str) -> Result<BuildConfig> {
        read(text, name).map(|file| file.config)
    }

    /// Free laps: no length; a length asked: that one; `"constant"`: the median lap (at
    /// least the weld minimum and the tolerance) and three more, each two bands longer.
    #[test]
    fn the_lap_lengths_tried_follow_the_overlap_asked() {
        let laps = [40.0, 52.0, 47.0, 61.0, 30.0];
        let frame = |overlap: &str| parse(&format!("[frame]\noverlap = {overlap}\n"), "c.toml");
        let free = frame("\"free\"").unwrap().frame;
        assert!(free.overlap_targets(&laps, 25.0).unwrap().is_empty());
        let asked = frame("50.0")
            .unwrap()
            .frame
            .overlap_targets(&laps, 25.0)
            .unwrap();
        assert_eq!(asked.iter().map(|g| g.length).collect::<Vec<_>>(), [50.0]);
        let constant = frame("\"constant\"").unwrap().frame;
        let lengths = |laps: &[f64]| -> Vec<f64> {
            let goals = constant.overlap_targets(laps, 25.0).unwrap();
            assert!(goals.iter().all(|g| g.tolerance == 1.0));
            goals.iter().map(|g| g.length).collect()
        };
        assert_eq!(lengths(&laps), [47.0, 51.0, 55.0, 59.0]);
        // laps shorter than the weld minimum and its band start from there
        assert_eq!(lengths(&[10.0, 12.0]), [26.0, 30.0, 34.0, 38.0]);
    }

    #[test]
    fn a_file_names_the_sheet_only_with_a_profile() {
        assert!(
            !read("[secondary]\nunit_size = 200.0\n", "c.toml")
                .unwrap()
                .sets_profile
        );
        assert!(
            read("[profile]\nthickness = 2.0\n", "c.toml")
                .unwrap()
                .sets_profile
        );
    }

    #[test]
    fn empty_file_is_all_defaults() {
        assert_eq!(parse("", "c.toml").unwrap(), BuildConfig::default());
    }

    #[test]
    fn default_file_round_trips() {
        let text = default_toml();
        assert!(
            text.contains("[secondary]") && text.contains("[primary]"),
            "{text}"
        );
        assert_eq!(parse(&text, "c.toml").unwrap(), BuildConfig::default());
    }

    #[test]
    fn keys_override_defaults() {
        let c = parse(
            "target = \"builtin:dome\"\n[secondary]\nunit_size = 250.0\n[primary]\nspin_angle_deg = 40\nside = \"normal\"\n",
            "c.toml",
        )
        .unwrap();
        assert_eq!(c.target, "builtin:dome");
        assert_eq!(c.secondary.unit_size, 250.0);
        assert_eq!(c.primary.spin_angle_deg, 40.0);
        assert_eq!(c.primary.side, SidePolicy::Normal);
        assert_eq!(c.primary.expansion, 1.0);
    }

    #[test]
    fn typos_and_bad_values_name_the_place() {
        let e = parse("[secondary]\nunit_sise = 250.0\n", "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("c.toml:2:"), "{e}");
        assert!(e.contains("unit_sise"), "{e}");
        let e = parse("[primary]\nspin_angle_deg = \"x\"\n", "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("c.toml:2:"), "{e}");
        let e = parse("target = \n", "c.toml").unwrap_err().to_string();
        assert!(e.starts_with("c.toml:1:"), "{e}");
        assert!(!e.contains('\n'));
        let e = parse("[profile]\nthickness = 2.0\nneck_widht = 9.0\n", "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("c.toml:3:1:"), "{e}");
        assert!(e.contains("neck_widht") && e.contains("neck_width"), "{e}");
        let c = parse(
            "[profile]\nthickness = 2.0\n[strips]\ndirection = \"v\"\n",
            "c.toml",
        )
        .unwrap();
        assert_eq!(c.profile.thickness, 2.0);
        assert_eq!(c.profile.kerf, ProfileParams::default().kerf);
        assert_eq!(c.strips.direction, sv_strips::StripDirection::V);
        assert_eq!(c.strips.split, sv_strips::SplitRule::Fill);
        // the benchmark config of docs/benchmarks.md parses and its profile is valid
        let b = parse(include_str!("../../../bench/b110.toml"), "bench/b110.toml").unwrap();
        assert_eq!(b.target, "builtin:saddle");
        assert_eq!(b.secondary.unit_size, 110.0);
        b.profile.validate().unwrap();
        let c = parse("[strips]\nsplit = \"balanced\"\n", "c.toml").unwrap();
        assert_eq!(
            c.strips.to_options().unwrap().split,
            sv_strips::SplitRule::Balanced
        );
        let e = parse("[strips]\nsplit = \"even\"\n", "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("c.toml:2:") && e.contains("fill"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        assert!(parse("[strips]\nmax_length = -1.0\n", "c.toml")
            .unwrap()
            .strips
            .to_options()
            .is_err());
        for (key, value) in [
            ("spin_angle_deg", "90.0"),
            ("spin_angle_deg", "0.0"),
            ("expansion", "0.9"),
            ("expansion", "nan"),
        ] {
            let c = parse(&format!("[primary]\n{key} = {value}\n"), "c.toml").unwrap();
            let e = c.primary.to_solve_options().unwrap_err().to_string();
            assert!(
                e.contains(&format!("primary.{key}")),
                "{key} = {value}: {e}"
            );
        }
    }

    /// An integer past i64 reads as a u64 seed or an f64 but is no TOML integer: the
    /// second read (as a table) failed with toml's multi-line report (source line, caret).
    #[test]
    fn an_integer_past_i64_is_a_one_line_error() {
        for (key, at) in [("seed", "c.toml:3:8"), ("margin", "c.toml:3:10")] {
            let text = format!("[nest]\nsheets = [\"3000x1500\"]\n{key} = 18446744073709551615\n");
            let e = parse(&text, "c.toml").unwrap_err().to_string();
            assert_eq!(e, format!("{at}: u64 value was too large"));
        }
    }
}
