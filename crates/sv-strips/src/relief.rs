//! Reliefs for the legs at the hub laps.
//!
//! Each leg leaves its hub at a corner, and the corners are where neighbouring hub plates
//! lap, one lying on the other. So at every lap one leg of the upper unit runs down through
//! the lower hub plate (docs/geometry.md 5.5). The lower plate gets a **relief** there: a
//! notch open to its edge (a closed hole would thread the plate onto the other unit), cut
//! as one with the hook slot it runs into. It covers the leg's section through the plate
//! (the leg as a plate, [`crate::leg_plate`], at its least-twist roll and turned through
//! [`ROLLS_DEG`]) plus [`CLEARANCE`] each side, and runs straight from there into the slot
//! the shortest way that stays out from under the upper plate (the lap is not cut), clear
//! of the hub's necks ([`neck_room`]) and with a web of [`relief_web`] to every other cut.

use std::collections::HashMap;

use sv_frame::FrameFile;
use sv_geom::planar::{point_segment_distance, segment_distance};
use sv_geom::{Point2, Point3, Real, Vector2};
use sv_unit::CutWidths;

use crate::leg_plate::{area, clip_convex, place, posed_leg, section_in_plate, Placed};
use crate::plane::convex_hull;
use crate::{FlatStrip, StripsError};

/// The leg's roll about its pin line is the one that twists its necks least; the relief
/// also clears it turned this far either way (degrees).
pub const ROLLS_DEG: [Real; 5] = [-20.0, -10.0, 0.0, 10.0, 20.0];
/// The directions a relief may run in from the leg's section (evenly spread): the
/// shortest that stays out from under the upper plate and clear of the necks and the other
/// cuts is taken.
const DIRECTIONS: usize = 180;
/// A bent relief's lead run covers the leg's section and goes on up to this many steps of
/// [`BEND_STEP`] (mm) before it turns.
const BEND_RUNS: usize = 12;
const BEND_STEP: Real = 3.0;
/// Room between the leg's section and the relief's sides (mm).
pub const CLEARANCE: Real = 1.0;
/// Where no relief stays out from under the upper plate (at most 1 mm² under it, round-off),
/// one may reach under its edge by this much (mm): the lap loses a sliver at most this deep
/// where the relief passes (the lap weld along that edge stops for the relief's width, as it
/// does wherever a relief meets that edge), about 3 % of a 49 mm lap. With the hub laps held
/// to one length (docs/config.md `[frame] overlap`) the dome at 300 mm has a leg whose every
/// relief crosses the upper plate's corner: 1 mm frees none, 1.25 mm it (measured on every
/// point of the relief, its round end too; both fold checks report the deepest as cut).
pub const UNDER_EDGE: Real = 1.5;
/// What a relief's web keeps beyond halfway between a neck and a leg ([`relief_web`]) (mm),
/// and, where no relief keeps that even under the upper plate's edge, in the search's last
/// tier: a web narrower than halfway is taken for a neck by both fold checks, and at 2.5 mm
/// sheet 11.5 mm is still half again as wide as a neck (7.5). Measured: on the saddle at
/// 300 mm with the tips of its laps kept in line (docs/geometry.md 5.5) four legs missed
/// the first margin by 0.1-0.7 mm.
pub const WEB_MARGINS: [Real; 2] = [1.0, 0.25];

/// A relief in a unit's hub plate, in the strip's flat frame: a straight notch `width`
/// across, from its round closed end (past the leg's section) to its open end (in the hook
/// slot beyond the hub's outline).
#[derive(Clone, Debug, PartialEq)]
pub struct Relief {
    /// Its outline, clockwise: the closed end's two corners are `outline[3]` and
    /// `outline[0]`, joined by a half circle round the back; `outline[1]` and `outline[2]`
    /// are where its sides cross the centre line of the hook slot it runs into (the open
    /// end lies in that slot).
    pub outline: [Point2; 4],
    /// Across (mm).
    pub width: Real,
    /// Where no straight notch keeps the rules, the relief bends once: it starts with a
    /// run round the leg's section from `lead[0]` to `lead[1]` (its centre line, `width`
    /// across; square at `lead[0]`, [`CLEARANCE`] behind the section, its corners rounded
    /// as the slots'), and `outline` runs on from `lead[1]`, the centre of its closed end,
    /// to the slot. `None` for a straight relief.
    pub lead: Option<[Point2; 2]>,
    /// The unit whose leg passes through.
    pub leg_of: usize,
    /// Which of its legs.
    pub leg: usize,
}

/// Fill `strips[..].reliefs` from the poses in `frame`. Nothing where the frame has no
/// cut or its joints were not closed (its hub plates do not lie one on the other); no
/// relief where none can clear a leg (the fold check names that leg).
pub fn add_reliefs(frame: &FrameFile, strips: &mut [FlatStrip]) -> Result<(), StripsError> {
    for s in strips.iter_mut() {
        s.reliefs = vec![Vec::new(); s.units.len()];
    }
    let (Some(widths), Some(thickness)) = (frame.params.cut, frame.params.thickness) else {
        return Ok(());
    };
    if !frame.joints_closed() {
        return Ok(());
    }
    let webs = WEB_MARGINS.map(|m| relief_web(&widths, m).max(crate::params::min_web(thickness)));
    // every unit placed, and its legs posed at every roll, once
    let mut at: HashMap<usize, (usize, usize)> = HashMap::new();
    let mut placed: HashMap<usize, (Placed, Vec<[Point3; 4]>)> = HashMap::new();
    for (si, s) in strips.iter().enumerate() {
        for (j, (&u, tile)) in s.units.iter().zip(&s.tiles).enumerate() {
            let p = place(frame, u, tile, &widths).map_err(|why| StripsError::Unit {
                strip: s.id.clone(),
                unit: u,
                why,
            })?;
            let pins = p.layout.pins();
            // leg k at roll r is legs[k * ROLLS_DEG.len() + r] (none where it cannot be posed)
            let legs = (0..4)
                .flat_map(|k| ROLLS_DEG.iter().map(move |r| (k, r.to_radians())))
                .map(|(k, r)| posed_leg(&p, &widths, k, [pins.hub[k], pins.rim[k]], r))
                .collect::<Option<Vec<_>>>()
                .unwrap_or_default();
            at.insert(u, (si, j));
            placed.insert(u, (p, legs));
        }
    }
    for link in &frame.links {
        let [a, b] = link.units;
        for (f, g) in [(a, b), (b, a)] {
            let (Some((pf, legs)), Some((pg, _))) = (placed.get(&f), placed.get(&g)) else {
                continue;
            };
            for (k, rolls) in legs.chunks(ROLLS_DEG.len()).enumerate() {
                let sections: Vec<Point2> = rolls
                    .iter()
                    .flat_map(|leg| section_in_plate(leg, pg, thickness))
                    .collect();
                if sections.len() < 3 {
                    continue;
                }
                let (si, j) = at[&g];
                let existing = &strips[si].reliefs[j];
                // where no notch can clear the leg, none is cut: the fold check names the
                // leg that runs through the plate there
                let Some((outline, width, lead)) =
                    relief_for(&convex_hull(&sections), pf, pg, &widths, webs, existing)
                else {
                    continue;
                };
                strips[si].reliefs[j].push(Relief {
                    outline,
                    width,
                    lead,
                    leg_of: f,
                    leg: k,
                });
            }
        }
    }
    Ok(())
}

/// A relief as the search tries it: the run that opens into the slot (`outline`, as
/// [`Relief::outline`], its closed end round about the middle of `outline[3]` and
/// `outline[0]`), `half` its half width, and the lead run before a bend ([`Relief::lead`]).
struct Notch {
    outline: [Point2; 4],
    half: Real,
    lead: Option<[Point2; 2]>,
}

impl Notch {
    /// The centre of the open run's closed end.
    fn back(&self) -> Point2 {
        Point2::from((self.outline[0].coords + self.outline[3].coords) / 2.0)
    }

    /// The centre of its open end, in the slot.
    fn end(&self) -> Point2 {
        Point2::from((self.outline[1].coords + self.outline[2].coords) / 2.0)
    }

    /// Its length along its centre line.
    fn length(&self) -> Real {
        let lead = self.lead.map_or(0.0, |[p, q]| (q - p).norm());
        lead + (self.end() - self.back()).norm()
    }

    /// The distance from the segment `p q` to the notch.
    fn apart(&self, p: &Point2, q: &Point2) -> Real {
        let open = relief_apart(&self.back(), self.half, &self.outline, p, q);
        open.min(self.lead_apart(p, q))
    }

    /// The lead run's band (its square end's corners not rounded), or nothing.
    fn lead_band(&self) -> Option<[Point2; 4]> {
        lead_band(self.lead?, self.half)
    }

    /// The distance from the segment `p q` to the lead run's band (infinite without one;
    /// its round end is the open run's closed end).
    fn lead_apart(&self, p: &Point2, q: &Point2) -> Real {
        self.lead_band()
            .map_or(Real::INFINITY, |band| band_apart(&band, p, q))
    }

    /// The convex pieces it is made of, clockwise or counter-clockwise: the open run, its
    /// round closed end (a polygon round the half circle) and the lead run.
    fn bands(&self) -> Vec<Vec<Point2>> {
        let mut bands = vec![self.outline.to_vec()];
        bands.extend(self.round_end());
        bands.extend(self.lead_band().map(|b| b.to_vec()));
        bands
    }

    /// The open run's closed end: the half circle round `back()` from `outline[0]` to
    /// `outline[3]`, as a polygon round it (its sides touch the circle).
    fn round_end(&self) -> Option<Vec<Point2>> {
        const SIDES: usize = 8;
        let back = self.back();
        let across = (self.outline[0] - back).try_normalize(1e-12)?;
        let mut away = Vector2::new(-across.y, across.x);
        if away.dot(&(back - self.end())) < 0.0 {
            away = -away;
        }
        let step = std::f64::consts::PI / SIDES as Real;
        let reach = self.half / (step / 2.0).cos();
        let mut ring = vec![self.outline[0]];
        ring.extend((0..SIDES).map(|i| {
            let t = (i as Real + 0.5) * step;
            back + (across * t.cos() + away * t.sin()) * reach
        }));
        ring.push(self.outline[3]);
        Some(ring)
    }
}

impl Relief {
    fn notch(&self) -> Notch {
        Notch {
            outline: self.outline,
            half: self.width / 2.0,
            lead: self.lead,
        }
    }
}

/// What a relief must keep clear of in one lower hub plate.
struct Rules<'a> {
    /// The upper hub plate's outline, counter-clockwise, in the lower plate's frame.
    upper_ccw: &'a [Point2],
    /// How deep under the upper plate's edge a relief may reach (mm); `None`: not at all
    /// (1 mm² of round-off).
    under_edge: Option<Real>,
    lower: &'a Placed,
    widths: &'a CutWidths,
    min_web: Real,
    existing: &'a [Relief],
    /// The centre line of the hook slots round the hub (the open run ends on it).
    track: [Point2; 4],
}

impl Rules<'_> {
    /// Whether the convex `band` (either orientation) lies under the upper plate beyond
    /// what the rules allow.
    fn under_upper(&self, band: &[Point2]) -> bool {
        let mut band = band.to_vec();
        if area(&band) < 0.0 {
            band.reverse();
        }
        let Some(allowed) = self.under_edge else {
            return area(&clip_convex(&band, self.upper_ccw)).abs() > 1.0;
        };
        // the band keeps out of the upper plate shrunk by `allowed` (a corner of the band
        // may lie on the outline while its middle cuts deep across the plate's corner)
        let upper: [Point2; 4] = std::array::from_fn(|i| self.upper_ccw[i]);
        sv_unit::inset(&upper, allowed)
            .is_none_or(|inner| area(&clip_convex(&band, &inner)).abs() > 1e-9)
    }

    /// The run along `dir` whose centre line passes `mid` to the left of `origin`, `half`
    /// either side, from `base` out to the slot's centre line (its sides must both leave
    /// the track further than `beyond` from `origin`).
    fn run(
        &self,
        [origin, base]: [Point2; 2],
        mid: Real,
        dir: Vector2,
        half: Real,
        beyond: Real,
    ) -> Option<[Point2; 4]> {
        let left = Vector2::new(-dir.y, dir.x);
        let side = |w: Real| {
            let p = origin + left * (mid + w);
            leaves(&self.track, &p, &dir)
                .filter(|&t| t > beyond)
                .map(|t| p + dir * t)
        };
        let (b, c) = (side(half)?, side(-half)?);
        Some([base + left * half, b, c, base - left * half])
    }
}

/// The relief of `section` (the leg's section, flat, in `lower`'s frame) out to `lower`'s
/// hook slots beside `upper`'s hub plate ([`Relief`]): its outline, width and lead run;
/// `None` where no notch keeps to the rules. A straight notch where one does, the
/// shortest; else one bent once, the shortest of those; where neither stays out from under
/// the upper plate, the same search again with [`UNDER_EDGE`] under its edge allowed; where
/// none keeps the web `webs[0]` even so, the same once more with `webs[1]` (the narrower
/// of [`WEB_MARGINS`]).
fn relief_for(
    section: &[Point2],
    upper: &Placed,
    lower: &Placed,
    widths: &CutWidths,
    webs: [Real; 2],
    existing: &[Relief],
) -> Option<([Point2; 4], Real, Option<[Point2; 2]>)> {
    let inverse = lower.hub.inverse();
    let up: Vec<Point2> = upper
        .hub_plate
        .iter()
        .map(|p| {
            let q = inverse * p;
            Point2::new(q.x, q.y)
        })
        .collect();
    let mut upper_ccw = up.clone();
    if area(&upper_ccw) < 0.0 {
        upper_ccw.reverse();
    }
    let n = section.len() as Real;
    let centre = Point2::from(section.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / n);
    // the directions are counted from along the upper plate's side nearest the section,
    // turning away from that plate
    let side = (0..4).min_by(|&i, &j| {
        let d = |i: usize| {
            let (p, q) = (up[i], up[(i + 1) % 4]);
            (q - p).normalize().perp(&(centre - p)).abs()
        };
        d(i).total_cmp(&d(j))
    })?;
    let along = (up[(side + 1) % 4] - up[side]).try_normalize(1e-12)?;
    let up_centre = Point2::from(up.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / 4.0);
    let mut away = Vector2::new(-along.y, along.x);
    if away.dot(&(centre - up_centre)) < 0.0 {
        away = -away;
    }
    let direction = |step: usize| {
        let turn = std::f64::consts::TAU * step as Real / DIRECTIONS as Real;
        along * turn.cos() + away * turn.sin()
    };
    let track = sv_unit::inset(&lower.layout.hub, -widths.slot / 2.0)?;
    // the run round the section along `dir`: the offset of its centre line, its base (the
    // centre of its closed end), its half width, and how far along it the section reaches
    let round_section = |dir: &Vector2| {
        let left = Vector2::new(-dir.y, dir.x);
        let (w0, w1) = extent(section, &centre, &left);
        let (t0, t1) = extent(section, &centre, dir);
        let mid = (w0 + w1) / 2.0;
        (
            mid,
            centre + left * mid + dir * t0,
            (w1 - w0) / 2.0 + CLEARANCE,
            t1,
        )
    };
    // out from under the upper plate where any relief can be, else under its edge by at
    // most UNDER_EDGE
    let tiers = [
        (None, webs[0]),
        (Some(UNDER_EDGE), webs[0]),
        (Some(UNDER_EDGE), webs[1]),
    ];
    for (under_edge, min_web) in tiers {
        let rules = Rules {
            upper_ccw: &upper_ccw,
            under_edge,
            lower,
            widths,
            min_web,
            existing,
            track,
        };
        let mut best: Option<Notch> = None;
        let keep = |notch: Notch, best: &mut Option<Notch>| {
            if best.as_ref().is_none_or(|b| notch.length() < b.length()) && fits(&notch, &rules) {
                *best = Some(notch);
            }
        };
        for step in 0..DIRECTIONS {
            let dir = direction(step);
            let (mid, base, half, reach) = round_section(&dir);
            if let Some(outline) = rules.run([centre, base], mid, dir, half, reach) {
                keep(
                    Notch {
                        outline,
                        half,
                        lead: None,
                    },
                    &mut best,
                );
            }
        }
        if best.is_none() {
            // bent once: a lead run round the section, as long as it covers it and up to
            // BEND_RUNS steps longer, then on from its end in any direction
            for step in 0..DIRECTIONS {
                let dir = direction(step);
                let (mid, base, half, reach) = round_section(&dir);
                let left = Vector2::new(-dir.y, dir.x);
                // square behind the section
                let back = base - dir * CLEARANCE;
                for k in 0..BEND_RUNS {
                    let elbow = centre + left * mid + dir * (reach + k as Real * BEND_STEP);
                    // no run after this lead is shorter than the best, or none keeps the
                    // rules: the turns need not be tried
                    let lead = [back, elbow];
                    let no_shorter = best
                        .as_ref()
                        .is_some_and(|b| (elbow - back).norm() >= b.length());
                    if no_shorter || lead_breaks_rules(lead, half, &rules) {
                        continue;
                    }
                    for turn in 0..DIRECTIONS {
                        let run = rules.run([elbow, elbow], 0.0, direction(turn), half, 0.0);
                        if let Some(outline) = run {
                            keep(
                                Notch {
                                    outline,
                                    half,
                                    lead: Some([back, elbow]),
                                },
                                &mut best,
                            );
                        }
                    }
                }
            }
        }
        if let Some(b) = best {
            return Some((b.outline, 2.0 * b.half, b.lead));
        }
    }
    None
}

/// The distance from a notch to `other`, a relief already cut, by `apart` (the notch's
/// distance to a segment, or to a point where both ends are one): to the round of its
/// closed end, the sides of its open run and its lead run's band.
fn distance_to(other: &Relief, apart: impl Fn(&Point2, &Point2) -> Real) -> Real {
    let notch = other.notch();
    let [a0, b0, c0, d0] = notch.outline;
    let back = notch.back();
    let mut d = apart(&back, &back) - notch.half;
    for (p, q) in [(a0, b0), (b0, c0), (c0, d0)] {
        d = d.min(apart(&p, &q));
    }
    if let Some(band) = notch.lead_band() {
        for i in 0..4 {
            d = d.min(apart(&band[i], &band[(i + 1) % 4]));
        }
    }
    d
}

/// The band of a lead run from `lead[0]` to `lead[1]`, `half` either side of it (its square
/// end's corners not rounded); nothing for a run of no length.
fn lead_band(lead: [Point2; 2], half: Real) -> Option<[Point2; 4]> {
    let [a, b] = lead;
    let along = (b - a).try_normalize(1e-12)?;
    let left = Vector2::new(-along.y, along.x) * half;
    Some([b + left, a + left, a - left, b - left])
}

/// The distance from the segment `p q` to the outline of `band`.
fn band_apart(band: &[Point2; 4], p: &Point2, q: &Point2) -> Real {
    (0..4)
        .map(|i| segment_distance(xy(&band[i]), xy(&band[(i + 1) % 4]), xy(p), xy(q)))
        .fold(Real::INFINITY, Real::min)
}

/// Whether a bent notch's lead run alone breaks a rule that [`fits`] holds every notch to
/// (under the upper plate, a web to a slot or to a relief already cut, a hub neck's room):
/// then no run after it fits, whichever way it turns.
fn lead_breaks_rules(lead: [Point2; 2], half: Real, rules: &Rules) -> bool {
    let Some(band) = lead_band(lead, half) else {
        return false;
    };
    if rules.under_upper(&band) {
        return true;
    }
    let web = rules.widths.slot / 2.0 + rules.min_web;
    let near_slot = rules.lower.layout.slot_paths.iter().any(|path| {
        path.windows(2)
            .any(|w| band_apart(&band, &w[0], &w[1]) < web)
    });
    let near_relief = rules
        .existing
        .iter()
        .any(|r| distance_to(r, |p, q| band_apart(&band, p, q)) < rules.min_web);
    let near_neck = rules
        .lower
        .layout
        .pins()
        .hub
        .iter()
        .any(|p| band_apart(&band, p, p) <= neck_room(rules.widths));
    near_slot || near_relief || near_neck
}

/// Whether `notch` keeps the rules: not under the upper plate (or under its edge by at most
/// `rules.under_edge`); the open run's sides both
/// end on the straight run of one hook slot; a web of `min_web` to every other stretch of
/// slot and to the reliefs already cut; the neck finder's radius from every hub neck.
fn fits(notch: &Notch, rules: &Rules) -> bool {
    if notch.bands().iter().any(|band| rules.under_upper(band)) {
        return false;
    }
    let [_, b, c, _] = notch.outline;
    let (widths, lower) = (rules.widths, rules.lower);
    let mut runs = 0;
    for path in &lower.layout.slot_paths {
        for (i, w) in path.windows(2).enumerate() {
            let e = w[1] - w[0];
            let at = |p: &Point2| (p - w[0]).dot(&e) / e.norm_squared();
            let off = |p: &Point2| e.normalize().perp(&(p - w[0])).abs();
            let room = widths.slot / e.norm();
            let ends_here = i == 0
                && [b, c]
                    .iter()
                    .all(|p| off(p) < 1e-6 && at(p) > room && at(p) < 1.0 - room);
            let web = widths.slot / 2.0 + rules.min_web;
            if ends_here {
                runs += 1;
                // the lead keeps its web from the slot the notch opens into, too
                if notch.lead_apart(&w[0], &w[1]) < web {
                    return false;
                }
            } else if notch.apart(&w[0], &w[1]) < web {
                return false;
            }
        }
    }
    runs == 1
        && rules
            .existing
            .iter()
            .all(|r| distance_to(r, |p, q| notch.apart(p, q)) >= rules.min_web)
        && lower.layout.pins().hub.iter().all(|p| {
            let [s, e] = [notch.back(), notch.end()];
            point_segment_distance(xy(p), xy(&s), xy(&e)) - notch.half > neck_room(widths)
                && notch.lead_apart(p, p) > neck_room(widths)
        })
}

/// The least web a relief leaves to any other cut: wider than any neck-like web, halfway
/// between a neck and a leg, and `margin` more (a web as narrow as a neck would act as one,
/// and the fold check would take it for one).
pub(crate) fn relief_web(widths: &CutWidths, margin: Real) -> Real {
    (widths.neck + widths.leg) / 2.0 + margin
}

/// How far from a neck's centre the fold check looks for the neck (the narrowest web
/// between two slots): a relief stays beyond it, so that no web of its own is taken for
/// a neck, or acts as one.
pub(crate) fn neck_room(widths: &CutWidths) -> Real {
    widths.neck + 2.0 * widths.slot + 2.0
}

/// The distance from the segment `p q` to a relief: its sides and open end `band` (A, B,
/// C, D) and the half disc of radius `half` round `back`.
fn relief_apart(back: &Point2, half: Real, band: &[Point2; 4], p: &Point2, q: &Point2) -> Real {
    let [a, b, c, d] = band;
    [(a, b), (b, c), (c, d)]
        .iter()
        .map(|(u, v)| segment_distance(xy(u), xy(v), xy(p), xy(q)))
        .fold(
            point_segment_distance(xy(back), xy(p), xy(q)) - half,
            Real::min,
        )
        .max(0.0)
}

/// A point as `sv_geom::planar` takes it.
fn xy(p: &Point2) -> [Real; 2] {
    [p.x, p.y]
}

/// The least and largest of `(p - o) . d` over `pts`.
fn extent(pts: &[Point2], o: &Point2, d: &Vector2) -> (Real, Real) {
    pts.iter()
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), p| {
            let t = (p - o).dot(d);
            (a.min(t), b.max(t))
        })
}

/// Where the line `p + t d` leaves the convex quad `q` (the largest `t` on it), if it meets
/// it.
fn leaves(q: &[Point2; 4], p: &Point2, d: &Vector2) -> Option<Real> {
    let (mut lo, mut hi) = (Real::NEG_INFINITY, Real::INFINITY);
    let ccw = area(q) > 0.0;
    for i in 0..4 {
        let (a, b) = (q[i], q[(i + 1) % 4]);
        let e = b - a;
        let inward = if ccw {
            Vector2::new(-e.y, e.x)
        } else {
            Vector2::new(e.y, -e.x)
        };
        // inside: (p + t d - a) . inward >= 0
        let s0 = (p - a).dot(&inward);
        let s1 = d.dot(&inward);
        if s1.abs() < 1e-15 {
            if s0 < 0.0 {
                return None;
            }
            continue;
        }
        let t = -s0 / s1;
        if s1 > 0.0 {
            lo = lo.max(t);
        } else {
            hi = hi.min(t);
        }
    }
    (lo <= hi).then_some(hi)
}
