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
use sv_geom::{rigid_fit, Isometry3, Point2, Point3, Real, Vector2, Vector3};
use sv_unit::{CutWidths, UnitLayout};

use crate::leg_plate::{area, clip_convex, frame, hull, leg_outline, leg_pose, section_in_slab};
use crate::{FlatStrip, StripsError};

/// The leg's roll about its pin line is the one that twists its necks least; the relief
/// also clears it turned this far either way (degrees).
pub const ROLLS_DEG: [Real; 5] = [-20.0, -10.0, 0.0, 10.0, 20.0];
/// The directions a relief may run in from the leg's section (evenly spread): the
/// shortest that stays out from under the upper plate and clear of the necks and the other
/// cuts is taken.
const DIRECTIONS: usize = 72;
/// Room between the leg's section and the relief's sides (mm).
pub const CLEARANCE: Real = 1.0;

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
    /// The unit whose leg passes through.
    pub leg_of: usize,
    /// Which of its legs.
    pub leg: usize,
}

/// One unit, flat (in its strip's frame) and in the world.
pub(crate) struct Placed {
    pub layout: UnitLayout,
    /// Flat to world, for the hub plate and for the primary plate.
    pub hub: Isometry3,
    pub primary: Isometry3,
    /// The hub plate as cut, in the world.
    pub hub_plate: [Point3; 4],
}

pub(crate) fn lift(p: &Point2) -> Point3 {
    Point3::new(p.x, p.y, 0.0)
}

/// `q` scaled by `e` about its centroid.
pub(crate) fn expanded(q: &[[Real; 3]; 4], e: Real) -> [Point3; 4] {
    let p3 = |a: &[Real; 3]| Vector3::new(a[0], a[1], a[2]);
    let c = q.iter().fold(Vector3::zeros(), |a, p| a + p3(p)) / 4.0;
    q.map(|p| Point3::from(c + (p3(&p) - c) * e))
}

/// Unit `u`'s flat tile `tile` put where frame.json has it.
pub(crate) fn place(
    frame: &FrameFile,
    u: usize,
    tile: &[Point2; 4],
    widths: &CutWidths,
) -> Result<Placed, String> {
    let unit = frame
        .units
        .get(u)
        .ok_or_else(|| format!("frame.json has no unit {u}"))?;
    let e = frame.params.expansion;
    let layout = UnitLayout::new(tile, widths).map_err(|e| e.0)?;
    let flat3 = tile.map(|p| lift(&p));
    let (primary, res_p) =
        rigid_fit(&flat3, &expanded(&unit.primary, e)).ok_or("the primary tile is degenerate")?;
    let (hub, res_h) = rigid_fit(&flat3, &expanded(&unit.hub, e)).ok_or("the hub is degenerate")?;
    if res_p.max(res_h) > 0.01 {
        return Err(format!(
            "its flat tile is not congruent to frame.json's tiles ({:.3} mm off)",
            res_p.max(res_h)
        ));
    }
    let hub_plate = layout.hub.map(|p| hub * lift(&p));
    Ok(Placed {
        layout,
        hub,
        primary,
        hub_plate,
    })
}

/// Leg `k` of a placed unit as a plate (its body's mid-plane quad in the world) with its
/// pins at `pins` (flat hub pin, flat rim pin), turned `roll` (radians) from its least
/// twist roll.
pub(crate) fn leg_plate(
    p: &Placed,
    widths: &CutWidths,
    k: usize,
    pins: [Point2; 2],
    roll: Real,
) -> Option<[Point3; 4]> {
    let flat_dir = |n: &[Point2; 2]| {
        let d = (n[1] - n[0]).normalize();
        Vector3::new(d.x, d.y, 0.0)
    };
    // turned about its pin line so that its two necks' fold lines, as the leg carries them,
    // lie as near as they can to the same lines as the hub and the rim carry them (the hub
    // neck's fold line runs along the leg in the flat, so it alone cannot set the roll)
    let fh = flat_dir(&p.layout.hub_necks[k]);
    let fr = flat_dir(&p.layout.rim_necks[k]);
    let (hw, rw) = (p.hub * lift(&pins[0]), p.primary * lift(&pins[1]));
    let (pose, _) = leg_pose(
        pins[0],
        pins[1],
        hw,
        rw,
        &[(fh, p.hub * fh), (fr, p.primary * fr)],
    )?;
    let axis = nalgebra::Unit::new_normalize(rw - hw);
    let turn = nalgebra::UnitQuaternion::from_axis_angle(&axis, roll);
    let about = Isometry3::from_parts((hw.coords - turn * hw.coords).into(), turn);
    let outline = leg_outline(&p.layout, widths, k)?;
    Some(outline.map(|q| about * (pose * lift(&q))))
}

/// The section of `leg` through the hub plate of `lower` where it lies inside that plate,
/// in `lower`'s flat frame (empty when it does not).
pub(crate) fn section_in_plate(leg: &[Point3; 4], lower: &Placed, thickness: Real) -> Vec<Point2> {
    let Some((c, _, u, v)) = frame(&lower.hub_plate) else {
        return Vec::new();
    };
    let sec = section_in_slab(leg, &lower.hub_plate, thickness);
    if sec.len() < 3 {
        return Vec::new();
    }
    let mut outline: Vec<Point2> = lower
        .hub_plate
        .iter()
        .map(|p| Point2::new((p - c).dot(&u), (p - c).dot(&v)))
        .collect();
    if area(&outline) < 0.0 {
        outline.reverse();
    }
    let inside = clip_convex(&sec, &outline);
    if inside.len() < 3 || area(&inside) < 1e-3 {
        return Vec::new();
    }
    let inverse = lower.hub.inverse();
    inside
        .iter()
        .map(|p| {
            let q = inverse * (c + u * p.x + v * p.y);
            Point2::new(q.x, q.y)
        })
        .collect()
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
    if frame.links.iter().all(|l| l.joint.is_none()) {
        return Ok(());
    }
    let mut at: HashMap<usize, (usize, usize)> = HashMap::new();
    let mut placed: HashMap<usize, Placed> = HashMap::new();
    for (si, s) in strips.iter().enumerate() {
        for (j, (&u, tile)) in s.units.iter().zip(&s.tiles).enumerate() {
            let p = place(frame, u, tile, &widths).map_err(|why| StripsError::Unit {
                strip: s.id.clone(),
                unit: u,
                why,
            })?;
            at.insert(u, (si, j));
            placed.insert(u, p);
        }
    }
    for link in &frame.links {
        let [a, b] = link.units;
        for (f, g) in [(a, b), (b, a)] {
            let (Some(pf), Some(pg)) = (placed.get(&f), placed.get(&g)) else {
                continue;
            };
            for k in 0..4 {
                let pins = pf.layout.pins();
                let sections: Vec<Point2> = ROLLS_DEG
                    .iter()
                    .filter_map(|r| {
                        leg_plate(pf, &widths, k, [pins.hub[k], pins.rim[k]], r.to_radians())
                    })
                    .flat_map(|leg| section_in_plate(&leg, pg, thickness))
                    .collect();
                if sections.len() < 3 {
                    continue;
                }
                let (si, j) = at[&g];
                let found = relief_for(
                    &hull(sections),
                    pf,
                    pg,
                    &widths,
                    relief_web(&widths).max(crate::params::min_web(thickness)),
                    &strips[si].reliefs[j],
                );
                // where no notch can clear the leg, none is cut: the fold check names the
                // leg that runs through the plate there
                let Some(relief) = found else {
                    continue;
                };
                strips[si].reliefs[j].push(Relief {
                    leg_of: f,
                    leg: k,
                    ..relief
                });
            }
        }
    }
    Ok(())
}

/// The relief of `section` (the leg's section, flat, in `lower`'s frame), out to `lower`'s
/// hook slots beside `upper`'s hub plate; `None` where no direction keeps to the rules.
fn relief_for(
    section: &[Point2],
    upper: &Placed,
    lower: &Placed,
    widths: &CutWidths,
    min_web: Real,
    existing: &[Relief],
) -> Option<Relief> {
    let inverse = lower.hub.inverse();
    let to_flat = |p: &Point3| {
        let q = inverse * p;
        Point2::new(q.x, q.y)
    };
    let up: Vec<Point2> = upper.hub_plate.iter().map(to_flat).collect();
    let hub = &lower.layout.hub;
    let n = section.len() as Real;
    let centre = Point2::from(section.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / n);
    // the upper plate's side nearest the section
    let side = (0..4).min_by(|&i, &j| {
        let d = |i: usize| {
            let (p, q) = (up[i], up[(i + 1) % 4]);
            (q - p).normalize().perp(&(centre - p)).abs()
        };
        d(i).total_cmp(&d(j))
    })?;
    let along = (up[(side + 1) % 4] - up[side]).try_normalize(1e-12)?;
    // away from the upper plate (and the lap under it)
    let up_centre = Point2::from(up.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / 4.0);
    let mut away = Vector2::new(-along.y, along.x);
    if away.dot(&(centre - up_centre)) < 0.0 {
        away = -away;
    }
    // out to the centre line of the hook slots round the hub: along the side either way,
    // or turned away from the lap by up to TURNS; the shortest that keeps clear of the
    // hub's necks
    let track = sv_unit::inset(hub, -widths.slot / 2.0)?;
    let pins = lower.layout.pins();
    let mut candidates: Vec<(Real, [Point2; 4], Real)> = Vec::new();
    let mut upper_ccw = up.clone();
    if area(&upper_ccw) < 0.0 {
        upper_ccw.reverse();
    }
    for step in 0..DIRECTIONS {
        {
            let turn = std::f64::consts::TAU * step as Real / DIRECTIONS as Real;
            let dir = along * turn.cos() + away * turn.sin();
            let left = Vector2::new(-dir.y, dir.x);
            let (w0, w1) = extent(section, &centre, &left);
            let half = (w1 - w0) / 2.0 + CLEARANCE;
            let mid = (w0 + w1) / 2.0;
            let (t0, t1) = extent(section, &centre, &dir);
            let side = |w: Real| {
                let p = centre + left * (mid + w);
                leaves(&track, &p, &dir)
                    .filter(|&t| t > t1)
                    .map(|t| p + dir * t)
            };
            let base = centre + left * mid + dir * t0;
            let (Some(b), Some(c)) = (side(half), side(-half)) else {
                continue;
            };
            // both sides end on the straight run of one hook slot along the hub, and the
            // relief keeps a web of min_web from every other stretch of slot
            let end = Point2::from((b.coords + c.coords) / 2.0);
            // beside the lap, not under the upper plate
            let band = [base + left * half, b, c, base - left * half];
            let mut band_ccw = band.to_vec();
            if area(&band_ccw) < 0.0 {
                band_ccw.reverse();
            }
            if area(&clip_convex(&band_ccw, &upper_ccw)).abs() > 1.0 {
                continue;
            }
            let mut runs = 0;
            let mut webbed = true;
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
                    if ends_here {
                        runs += 1;
                    } else if relief_apart(&base, half, &band, &w[0], &w[1])
                        < widths.slot / 2.0 + min_web
                    {
                        webbed = false;
                    }
                }
            }
            // and from the reliefs already cut into this plate
            for r in existing {
                let [a0, b0, c0, d0] = r.outline;
                let back = Point2::from((a0.coords + d0.coords) / 2.0);
                let apart = [(a0, b0), (b0, c0), (c0, d0)]
                    .iter()
                    .map(|(p, q)| relief_apart(&base, half, &band, p, q))
                    .fold(
                        relief_apart(&base, half, &band, &back, &back) - r.width / 2.0,
                        Real::min,
                    );
                if apart < min_web {
                    webbed = false;
                }
            }
            if runs != 1 || !webbed {
                continue;
            }
            let clear = pins
                .hub
                .iter()
                .all(|p| distance_to_segment(p, &base, &end) - half > neck_room(widths));
            if clear {
                candidates.push((
                    (end - base).norm(),
                    [base + left * half, b, c, base - left * half],
                    2.0 * half,
                ));
            }
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (_, outline, width) = candidates.first()?;
    Some(Relief {
        outline: *outline,
        width: *width,
        leg_of: 0,
        leg: 0,
    })
}

/// The least web a relief leaves to any other cut: wider than any neck-like web, halfway
/// between a neck and a leg, and a millimetre more (a web as narrow as a neck would act as
/// one, and the fold check would take it for one).
pub(crate) fn relief_web(widths: &CutWidths) -> Real {
    (widths.neck + widths.leg) / 2.0 + 1.0
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
        .map(|(u, v)| segments_apart(u, v, p, q))
        .fold(distance_to_segment(back, p, q) - half, Real::min)
        .max(0.0)
}

/// The distance between the segments `a b` and `c d`.
fn segments_apart(a: &Point2, b: &Point2, c: &Point2, d: &Point2) -> Real {
    let crosses = {
        let s = |p: &Point2, q: &Point2, r: &Point2| (q - p).perp(&(r - p));
        s(a, b, c) * s(a, b, d) < 0.0 && s(c, d, a) * s(c, d, b) < 0.0
    };
    if crosses {
        return 0.0;
    }
    distance_to_segment(a, c, d)
        .min(distance_to_segment(b, c, d))
        .min(distance_to_segment(c, a, b))
        .min(distance_to_segment(d, a, b))
}

fn distance_to_segment(p: &Point2, a: &Point2, b: &Point2) -> Real {
    let e = b - a;
    let t = ((p - a).dot(&e) / e.norm_squared().max(1e-300)).clamp(0.0, 1.0);
    (a + e * t - p).norm()
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
