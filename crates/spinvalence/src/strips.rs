//! The strip stage of `build`: unroll the deployed frame into strips, label every unit,
//! profile the cut contours, check the design rules, and render DXF + SVG per strip.
//! Pure computation; `build` writes the results atomically.

use anyhow::{anyhow, bail, Result};
use rayon::prelude::*;
use sv_frame::FrameFile;
use sv_strips::{
    FlatStrip, ProfileParams, StripOptions, StripProfile, StripsError, StripsFile, Violation,
};

/// Everything the strip stage produces, ready to write.
pub struct StripsStage {
    /// `strips.json`.
    pub file: StripsFile,
    /// Unrolled strips, in file order.
    pub strips: Vec<FlatStrip>,
    /// Cut profile of each strip.
    pub profiles: Vec<StripProfile>,
    /// `(file name, text)` of every strip's DXF and SVG, for `DIR/strips/`.
    pub drawings: Vec<(String, String)>,
    /// Largest bend and twist any pin takes up (rad).
    pub worst_pin: (f64, f64),
    /// Consecutive units whose facing sides overlap too little for a bridge: their strip
    /// ends there, and they are welded on site.
    pub breaks: Vec<[usize; 2]>,
}

/// At most this many rounds of strips ended where a bridge cannot be cut.
const BREAK_ROUNDS: usize = 10;

/// At most this many design-rule violations are listed in the error.
const SHOWN_VIOLATIONS: usize = 3;

/// Unroll, label and profile `frame`; writes the labels into `frame.units[].id`/`strip`.
/// A design-rule violation on any part is an error that names the strip, unit and rule:
/// a part that would crack or not cut is never written. Where the frame's joints were not
/// closed, two units whose facing sides overlap too little for a bridge end their strip
/// instead (welded on site, [`StripsStage::breaks`]); a closed frame decided its bridges,
/// and there it stays an error.
pub fn run(
    frame: &mut FrameFile,
    options: &StripOptions,
    params: &ProfileParams,
) -> Result<StripsStage> {
    params.validate().map_err(|e| anyhow!("profile: {e}"))?;
    if let Some(cut) = frame.params.cut {
        if cut != params.cut_widths() {
            bail!(
                "profile: the frame was deployed with the cut {cut:?} but the profile cuts \
                 {:?}: its parts would not fold to the solved poses",
                params.cut_widths()
            );
        }
    }
    let open = !frame.joints_closed();
    let mut options = options.clone();
    let mut round = 0;
    let (strips, profiled) = loop {
        let strips = sv_strips::unroll(frame, &options).map_err(|e| anyhow!("strips: {e}"))?;
        sv_strips::apply_labels(frame, &strips);
        let profiled = profile_all(frame, &strips, params);
        let breaks: Vec<[usize; 2]> = profiled
            .iter()
            .filter_map(|p| match p {
                Err(StripsError::NoBridge { units, .. }) => Some(*units),
                _ => None,
            })
            .collect();
        if !open || breaks.is_empty() || round == BREAK_ROUNDS {
            break (strips, profiled);
        }
        options.breaks.extend(breaks);
        round += 1;
    };
    let mut profiles: Vec<StripProfile> = Vec::with_capacity(strips.len());
    let mut violations: Vec<Violation> = Vec::new();
    for p in profiled {
        let (profile, v) = p.map_err(|e| anyhow!("profile: {e}"))?;
        violations.extend(v);
        profiles.push(profile);
    }
    if !violations.is_empty() {
        let shown: Vec<String> = violations
            .iter()
            .take(SHOWN_VIOLATIONS)
            .map(|v| v.to_string())
            .collect();
        bail!(
            "design-rule check: {} violation(s): {}{}",
            violations.len(),
            shown.join("; "),
            if violations.len() > SHOWN_VIOLATIONS {
                "; ..."
            } else {
                ""
            }
        );
    }
    let drawings: Vec<(String, String)> = strips
        .par_iter()
        .zip(&profiles)
        .flat_map_iter(|(strip, profile)| {
            [
                (
                    format!("{}.dxf", strip.id),
                    sv_export::strip_dxf(strip, profile),
                ),
                (
                    format!("{}.svg", strip.id),
                    sv_export::strip_svg(strip, profile, params),
                ),
            ]
        })
        .collect();
    let worst_pin = strips
        .iter()
        .flat_map(|s| &s.pins)
        .fold((0.0f64, 0.0f64), |(b, t), p| {
            (b.max(p.bend.abs()), t.max(p.twist.abs()))
        });
    let file = StripsFile::new(&strips, &profiles, params, frame.params.expansion, &options);
    Ok(StripsStage {
        file,
        strips,
        profiles,
        drawings,
        worst_pin,
        breaks: options.breaks,
    })
}

/// The cut profile of every strip and its design-rule violations, each strip on its own
/// core (in strip order, whichever finishes first).
fn profile_all(
    frame: &FrameFile,
    strips: &[FlatStrip],
    params: &ProfileParams,
) -> Vec<Result<(StripProfile, Vec<Violation>), StripsError>> {
    strips
        .par_iter()
        .map(|strip| {
            let names: Vec<String> = strip
                .units
                .iter()
                .map(|&u| frame.units.get(u).map(|r| r.id.clone()).unwrap_or_default())
                .collect();
            let profile = sv_strips::profile_strip(strip, &names, params)?;
            let violations = sv_strips::check_profile(strip, &profile, params);
            Ok((profile, violations))
        })
        .collect()
}
