//! Strip and cut-profile parameters with documented defaults for 3 mm mild steel cut on an
//! air plasma (kerf about 1.3 mm). All lengths in mm.

use serde::{Deserialize, Serialize};

use crate::StripsError;

/// Default sheet length (mm): the common 3000 x 1500 mm plate.
pub const DEFAULT_SHEET_LENGTH: f64 = 3000.0;
/// Default margin between the sheet edge and a part (mm), also the room for the outline's lead-in.
pub const DEFAULT_SHEET_MARGIN: f64 = 10.0;

/// Which mesh direction the strips follow.
///
/// Directions are propagated over the mesh from unit 0: a strip crosses opposite sides `k`
/// and `k + 2` of each unit. `U` strips cross sides 1 and 3 of unit 0, i.e. they run along
/// side 0 of unit 0 (increasing `i` on a [`sv_frame::QuadMesh::from_fn`] grid); `V` strips
/// cross the other pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StripDirection {
    /// Along side 0 of unit 0.
    #[default]
    U,
    /// Across side 0 of unit 0.
    V,
}

/// The largest strain a bridge may take bending in its plane or twisting (5 %: well
/// inside mild steel's elongation, where the fold itself, a plastic hinge like a neck, takes
/// far more).
pub const BRIDGE_STRAIN: f64 = 0.05;

/// How a chain too long for one sheet is cut into pieces (the piece count is the same
/// either way: the fewest the sheet length and the overlap guard allow).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplitRule {
    /// Pieces as long as the sheet allows, in chain order, the remainder last (a 20-unit
    /// row of the pavilion: 9 + 9 + 2). Full-length pieces fill a sheet row each and the
    /// short remainders share rows: 8 sheets for the pavilion against 10 balanced. A one-unit
    /// remainder is avoided by taking one unit less per piece when that needs no more pieces.
    #[default]
    Fill,
    /// Pieces of nearly equal length (20 units: 7 + 7 + 6): one piece per sheet row, each
    /// row partly empty.
    Balanced,
}

/// Options of the strip partition and unrolling.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StripOptions {
    /// Mesh direction of the strips.
    pub direction: StripDirection,
    /// Longest flat pattern (mm): the sheet length minus both margins. A strip whose flat
    /// pattern (longer side of its minimum-area bounding rectangle) would exceed it is split.
    pub max_length: f64,
    /// How a chain longer than `max_length` is cut into pieces.
    #[serde(default)]
    pub split: SplitRule,
    /// Two flat tiles count as overlapping when their intersection exceeds this area
    /// (mm^2). Consecutive tiles touch along their joint line (area 0); 1e-3 mm^2 is far below
    /// anything a cutter resolves and far above rounding noise.
    pub overlap_area_tolerance: f64,
    /// Consecutive units (frame unit indices, either order) between which a strip ends
    /// although a bridge could join them: where the profile found their facing sides too
    /// short for one ([`StripsError::NoBridge`]), they are welded on site instead.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub breaks: Vec<[usize; 2]>,
}

impl Default for StripOptions {
    fn default() -> Self {
        Self {
            direction: StripDirection::U,
            max_length: DEFAULT_SHEET_LENGTH - 2.0 * DEFAULT_SHEET_MARGIN,
            split: SplitRule::Fill,
            overlap_area_tolerance: 1e-3,
            breaks: Vec::new(),
        }
    }
}

impl StripOptions {
    /// Whether a strip must end between units `a` and `b` ([`StripOptions::breaks`]).
    pub fn breaks_between(&self, a: usize, b: usize) -> bool {
        self.breaks
            .iter()
            .any(|&[x, y]| [x, y] == [a, b] || [x, y] == [b, a])
    }

    /// Check the options; the error names the bad option.
    pub fn validate(&self) -> Result<(), StripsError> {
        if !(self.max_length.is_finite() && self.max_length > 0.0) {
            return Err(StripsError::Parameter {
                name: "max_length",
                value: self.max_length,
                why: "must be a finite length > 0".into(),
            });
        }
        if !(self.overlap_area_tolerance.is_finite() && self.overlap_area_tolerance >= 0.0) {
            return Err(StripsError::Parameter {
                name: "overlap_area_tolerance",
                value: self.overlap_area_tolerance,
                why: "must be a finite area >= 0".into(),
            });
        }
        Ok(())
    }
}

/// The cut profile of a unit (see `docs/fabrication.md` for the drawn layout).
///
/// From the part outline inward every unit has: the rim (primary-tile material that carries
/// the bridges to the neighbours), an outer slot, the leg, an inner slot and the hub. Each
/// of the four hook ("roughly L-shaped") slots separates the hub from leg `i`, the end of
/// leg `i` from leg `i + 1`, and leg `i + 1` from the rim, leaving a neck of width
/// `neck_width` where leg `i + 1` joins the hub and where it joins the rim. Consecutive
/// units of a strip are separated by a joint slot `neck_length` wide, crossed by one
/// bridge (`neck_width` x `neck_length`) at their pin.
///
/// Defaults (2.5 mm mild steel, air plasma; every width the least its rule allows, so the hub
/// plates as cut lap by the weld minimum at 300 mm units): t = 2.5, kerf 1.3, leg 15,
/// rim 3.75, neck 7.5 x 3.75, slot 3.75 (1.5 t, ends full rounds of diameter 3.75 >=
/// max(kerf + 0.5, t)), fillet 1.5, lead-in room 2.6 (2 kerf).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ProfileParams {
    /// Material thickness t (mm).
    pub thickness: f64,
    /// Kerf width of the cutter (mm). The contours are nominal: the CAM compensates it.
    pub kerf: f64,
    /// Width of a leg between its two slots (mm).
    pub leg_width: f64,
    /// Width of the rim between the outer slot and the part outline (mm).
    pub rim_width: f64,
    /// Width of a neck, the reduced cross-section where the part folds (mm):
    /// at most half the leg width, at least 3 t.
    pub neck_width: f64,
    /// Length of a neck along the fold (mm), 1-2 t: the joint slot between the units of a
    /// strip and so the length of a bridge. Leg necks are as long as the slot is wide.
    pub neck_length: f64,
    /// Width of every slot (mm); each end is a full round of this diameter.
    pub slot_width: f64,
    /// Radius of the fillets on the outline's corners (mm), >= 1.
    pub fillet_radius: f64,
    /// Diameter of the circle that must fit inside every cut for its pierce and lead-in (mm).
    pub lead_in_room: f64,
}

impl Default for ProfileParams {
    fn default() -> Self {
        Self {
            thickness: 2.5,
            kerf: 1.3,
            leg_width: 15.0,
            rim_width: 3.75,
            neck_width: 7.5,
            neck_length: 3.75,
            slot_width: 3.75,
            fillet_radius: 1.5,
            lead_in_room: 2.6,
        }
    }
}

/// Smallest inside radius a plasma-cut part may have (mm).
pub const MIN_INSIDE_RADIUS: f64 = 1.0;

/// The minimum web between cuts in sheet `thickness` (mm): max(1.5 t, 3 mm).
pub(crate) fn min_web(thickness: f64) -> f64 {
    (1.5 * thickness).max(3.0)
}

impl ProfileParams {
    /// The minimum web between cuts and the minimum slot width: max(1.5 t, 3 mm).
    pub fn min_web(&self) -> f64 {
        min_web(self.thickness)
    }

    /// The profile of sheet `thickness` with every width the least its rules allow
    /// (docs/fabrication.md), the kerf and lead-in room of `self` and its fillet where the
    /// joint slot takes it (else the least inside radius): the hub as far out in its tile
    /// as that sheet lets it lie. `None` where those rules leave no valid
    /// profile (below 1.5 mm the joint slot cannot be both 1-2 t long and 3 mm wide).
    pub fn least_for(&self, thickness: f64) -> Option<Self> {
        let t = thickness;
        let web = (1.5 * t).max(3.0);
        let p = Self {
            thickness: t,
            slot_width: web.max(self.kerf + 0.5).max(t),
            rim_width: web,
            neck_width: 3.0 * t,
            leg_width: (6.0 * t).max(web),
            neck_length: web,
            fillet_radius: if 2.0 * self.fillet_radius < web {
                self.fillet_radius
            } else {
                MIN_INSIDE_RADIUS
            },
            ..self.clone()
        };
        p.validate().ok().map(|()| p)
    }

    /// The shortest hub lap that can carry a stress-carrying lap weld: max(5 t, 25 mm)
    /// (AWS D1.1), the default of `[primary] min_overlap`.
    pub fn min_overlap(&self) -> f64 {
        (5.0 * self.thickness).max(25.0)
    }

    /// What the joints between primary plates must reach with this profile
    /// (docs/geometry.md, "What a bridge takes"). A bridge is a web `neck_width` wide and
    /// `neck_length` long across its joint slot, of sheet `t`. It folds about the joint
    /// freely (a plastic hinge, like a neck), but bending it in its plane strains its edges
    /// by `(w / 2) bend / l` and twisting it shears its faces by `t twist / l` (von Mises
    /// `/ sqrt 3`); both are held at [`BRIDGE_STRAIN`]. Bridges within 0.5 mm of their flat
    /// length, welds within 1.5 mm (a butt or fillet weld bridges that in 3 mm sheet without
    /// a filler), plates into each other by at most 0.1 mm.
    pub fn joint_limits(&self) -> sv_frame::JointLimits {
        let (w, l, t) = (self.neck_width, self.neck_length, self.thickness);
        sv_frame::JointLimits {
            bend: 2.0 * BRIDGE_STRAIN * l / w,
            twist: 3f64.sqrt() * BRIDGE_STRAIN * l / t,
            ..sv_frame::JointLimits::default()
        }
    }

    /// Smallest diameter of a slot's round end: max(kerf + 0.5 mm, t).
    pub fn min_slot_end_diameter(&self) -> f64 {
        (self.kerf + 0.5).max(self.thickness)
    }

    /// Where the cut goes inside a unit's tile: the widths the unit as cut is made of
    /// (sv_unit::UnitLayout), read by the frame solve and the cut profile alike.
    pub fn cut_widths(&self) -> sv_unit::CutWidths {
        sv_unit::CutWidths {
            rim: self.rim_width,
            slot: self.slot_width,
            leg: self.leg_width,
            neck: self.neck_width,
            joint: self.neck_length,
        }
    }

    /// How far the hub lies inside the expanded primary tile (mm): half the joint slot,
    /// rim, two slots and the leg.
    pub fn hub_inset(&self) -> f64 {
        self.cut_widths().hub_inset()
    }

    /// The hub lap as cut on a flat grid of square units of side `unit` at spin 45 degrees
    /// (docs/geometry.md 5.4): a hub corner passes the edge by `(sqrt 2 - 1) unit / 2`, and
    /// the plate as cut loses `sqrt 2 hub_inset` of it on each side.
    pub fn flat_lap(&self, unit: f64) -> f64 {
        (2f64.sqrt() - 1.0) * unit - 2.0 * 2f64.sqrt() * self.hub_inset()
    }

    /// The unit size whose [`flat_lap`](Self::flat_lap) is `lap`.
    pub fn unit_for_flat_lap(&self, lap: f64) -> f64 {
        (lap + 2.0 * 2f64.sqrt() * self.hub_inset()) / (2f64.sqrt() - 1.0)
    }

    /// Of this profile, its least widths and the least profiles of thinner sheets
    /// ([`thinner_least`](Self::thinner_least)), the one whose hub lies least deep in its
    /// tile (the first of equals): the longest laps any sheet gives at a unit size.
    pub fn shallowest_hub(&self) -> Self {
        (self.least_for(self.thickness).into_iter())
            .chain(self.thinner_least())
            .fold(self.clone(), |best, q| {
                if q.hub_inset() < best.hub_inset() {
                    q
                } else {
                    best
                }
            })
    }

    /// The sheet for units of side `unit` when the user names none: `self` where its
    /// [`flat_lap`](Self::flat_lap) reaches `min_overlap` of it, else the least profile
    /// ([`least_for`](Self::least_for)) of the thickest sheet, in 0.5 mm steps below
    /// `self`'s, whose flat lap does; `None` where no sheet's does.
    pub fn for_unit_size(&self, unit: f64, min_overlap: impl Fn(&Self) -> f64) -> Option<Self> {
        let welds = |p: &Self| p.flat_lap(unit) >= min_overlap(p);
        if welds(self) {
            return Some(self.clone());
        }
        self.thinner_least().find(welds)
    }

    /// The least profiles ([`least_for`](Self::least_for)) of the sheets thinner than
    /// `self`'s, in 0.5 mm steps, thickest first (those that have one).
    pub fn thinner_least(&self) -> impl Iterator<Item = Self> + '_ {
        (1..)
            .map(|k| self.thickness - 0.5 * k as f64)
            .take_while(|&t| t > 0.0)
            .filter_map(|t| self.least_for(t))
    }

    /// Check every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<(), StripsError> {
        let bad = |name: &'static str, value: f64, why: String| {
            Err(StripsError::Parameter { name, value, why })
        };
        let fields = [
            ("thickness", self.thickness),
            ("kerf", self.kerf),
            ("leg_width", self.leg_width),
            ("rim_width", self.rim_width),
            ("neck_width", self.neck_width),
            ("neck_length", self.neck_length),
            ("slot_width", self.slot_width),
            ("fillet_radius", self.fillet_radius),
            ("lead_in_room", self.lead_in_room),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, v, "must be a finite length > 0".into());
            }
        }
        let t = self.thickness;
        let web = self.min_web();
        if self.slot_width <= self.kerf {
            return bad(
                "slot_width",
                self.slot_width,
                format!("narrower than the kerf {}", self.kerf),
            );
        }
        if self.slot_width < web {
            return bad(
                "slot_width",
                self.slot_width,
                format!("below the minimum slot width max(1.5 t, 3 mm) = {web}"),
            );
        }
        if self.slot_width < self.min_slot_end_diameter() {
            return bad(
                "slot_width",
                self.slot_width,
                format!(
                    "slot ends would be rounds below max(kerf + 0.5, t) = {}",
                    self.min_slot_end_diameter()
                ),
            );
        }
        if self.neck_width >= self.leg_width {
            return bad(
                "neck_width",
                self.neck_width,
                format!("not narrower than the leg ({})", self.leg_width),
            );
        }
        if self.neck_width > 0.5 * self.leg_width + 1e-9 {
            return bad(
                "neck_width",
                self.neck_width,
                format!(
                    "above half the leg width ({}): the fold would not stay at the neck",
                    0.5 * self.leg_width
                ),
            );
        }
        if self.neck_width < 3.0 * t - 1e-9 {
            return bad(
                "neck_width",
                self.neck_width,
                format!("below 3 t = {}", 3.0 * t),
            );
        }
        if self.neck_length < t - 1e-9 || self.neck_length > 2.0 * t + 1e-9 {
            return bad(
                "neck_length",
                self.neck_length,
                format!("outside 1-2 t = [{t}, {}]", 2.0 * t),
            );
        }
        if self.neck_length < web {
            return bad(
                "neck_length",
                self.neck_length,
                format!("the joint slot it makes is below the minimum slot width {web}"),
            );
        }
        if self.leg_width < web || self.rim_width < web {
            let (name, v) = if self.leg_width < web {
                ("leg_width", self.leg_width)
            } else {
                ("rim_width", self.rim_width)
            };
            return bad(name, v, format!("below the minimum web {web}"));
        }
        if self.fillet_radius < MIN_INSIDE_RADIUS {
            return bad(
                "fillet_radius",
                self.fillet_radius,
                format!("below the minimum inside radius {MIN_INSIDE_RADIUS}"),
            );
        }
        if self.fillet_radius >= self.leg_width / 2.0 {
            return bad(
                "fillet_radius",
                self.fillet_radius,
                format!(
                    "not smaller than half the leg width ({})",
                    self.leg_width / 2.0
                ),
            );
        }
        if 2.0 * self.fillet_radius >= self.neck_length {
            return bad(
                "fillet_radius",
                self.fillet_radius,
                format!(
                    "a fillet this large would close the joint slot (neck_length {})",
                    self.neck_length
                ),
            );
        }
        if self.lead_in_room >= self.slot_width {
            return bad(
                "lead_in_room",
                self.lead_in_room,
                format!("does not fit in a slot of width {}", self.slot_width),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name_of(p: ProfileParams) -> &'static str {
        match p.validate() {
            Err(StripsError::Parameter { name, .. }) => name,
            other => panic!("expected a parameter error, got {other:?}"),
        }
    }

    #[test]
    fn defaults_are_valid_and_match_the_rules() {
        let p = ProfileParams::default();
        p.validate().unwrap();
        assert_eq!(p.min_web(), 3.75);
        // every width the least its rule allows (docs/fabrication.md)
        assert_eq!(p.slot_width, p.min_web());
        assert_eq!(p.rim_width, p.min_web());
        assert_eq!(p.neck_length, p.min_web());
        assert_eq!(p.neck_width, 3.0 * p.thickness);
        assert_eq!(p.leg_width, 2.0 * p.neck_width);
        assert!(p.slot_width >= p.min_slot_end_diameter());
        assert!(p.neck_width <= p.leg_width / 2.0 && p.neck_width >= 3.0 * p.thickness);
        assert!(StripOptions::default().max_length == 2980.0);
    }

    #[test]
    fn the_least_profile_of_a_sheet_is_valid_and_puts_the_hub_where_its_rules_let_it() {
        let d = ProfileParams::default();
        // the default is the least profile of its own sheet
        assert_eq!(d.least_for(d.thickness), Some(d.clone()));
        let thin = d.least_for(1.5).unwrap();
        // hub inset: half the joint slot, rim, two slots, the leg: 1.5 + 3 + 6 + 9
        assert!(
            (thin.hub_inset() - 19.5).abs() < 1e-12,
            "{}",
            thin.hub_inset()
        );
        assert!(d.least_for(1.0).is_none());
    }

    #[test]
    fn the_sheet_follows_the_unit_size_where_the_default_cannot_weld() {
        let d = ProfileParams::default();
        let aws = |p: &ProfileParams| (5.0 * p.thickness).max(25.0);
        // 300 mm: the default's laps, 0.41421 x 300 - 2.82843 x 28.125 = 44.7 mm
        assert_eq!(d.for_unit_size(300.0, aws), Some(d.clone()));
        // 200 mm: 2.5 mm gives 3.3 mm, 2 mm sheet at its least (hub 22.5 mm in) 19.2 mm,
        // 1.5 mm (19.5 mm in) 27.7 mm
        let thin = d.for_unit_size(200.0, aws).unwrap();
        assert_eq!(thin, d.least_for(1.5).unwrap());
        assert!((thin.flat_lap(200.0) - (82.8427 - 55.1543)).abs() < 1e-3);
        // 180 mm: 1.5 mm gives 19.4 mm, and no thinner sheet has a profile
        assert_eq!(d.for_unit_size(180.0, aws), None);
        // a lower weld minimum keeps the default longer
        assert_eq!(d.for_unit_size(200.0, |_| 0.0), Some(d.clone()));
        // the longest laps any sheet gives: 1.5 mm at its least, the hub 19.5 mm in, 25 mm
        // from (25 + 2.82843 x 19.5) / 0.41421 = 193.51 mm on
        let best = d.shallowest_hub();
        assert_eq!(best, d.least_for(1.5).unwrap());
        assert!((best.hub_inset() - 19.5).abs() < 1e-12);
        assert!((best.unit_for_flat_lap(25.0) - 193.5097).abs() < 1e-3);
        assert!((best.flat_lap(best.unit_for_flat_lap(25.0)) - 25.0).abs() < 1e-9);
    }

    #[test]
    fn bad_parameters_are_named() {
        let d = ProfileParams::default;
        assert_eq!(
            name_of(ProfileParams {
                neck_width: 25.0,
                ..d()
            }),
            "neck_width"
        );
        assert_eq!(
            name_of(ProfileParams {
                slot_width: 1.0,
                ..d()
            }),
            "slot_width"
        );
        assert_eq!(
            name_of(ProfileParams {
                fillet_radius: 30.0,
                ..d()
            }),
            "fillet_radius"
        );
        assert_eq!(
            name_of(ProfileParams {
                thickness: 0.0,
                ..d()
            }),
            "thickness"
        );
        assert_eq!(
            name_of(ProfileParams {
                thickness: -3.0,
                ..d()
            }),
            "thickness"
        );
        assert_eq!(
            name_of(ProfileParams {
                kerf: f64::NAN,
                ..d()
            }),
            "kerf"
        );
        let e = ProfileParams {
            neck_width: 25.0,
            ..d()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("parameter neck_width = 25"), "{e}");
    }
}
