//! The unit as cut: where the hook slots run, where the legs fold (necks) and where the
//! legs are pinned, on one flat unit plate (docs/geometry.md, "The unit as cut").
//!
//! From the plate outline inward: the rim, an outer slot track, the leg, an inner slot track
//! and the hub. Hook slot `i` starts on the inner track of side `i` a neck width past
//! inner corner `i`, runs along side `i`, crosses to the outer track at corner `i + 1`, runs
//! along side `i + 1`, turns corner `i + 2` and stops a neck width before slot `i + 1`
//! crosses there. So leg `j` (between the tracks along side `j`) joins the hub at the neck
//! near corner `j` and the rim at the neck near corner `j + 1`. In the limit of zero widths
//! those necks are the tile corners `j` and `j + 1`: the paper's leg from `s_j` to `r_{j+1}`.
//!
//! This is the one place that says where the cut goes: the cut profile (sv-strips) draws
//! its slots along [`UnitLayout::slot_paths`], the frame solve pins its legs at
//! [`UnitLayout::pins`].

use sv_geom::{Point2, Real, Vector2, Vector3};

/// The widths that place the cut inside a unit plate (mm).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CutWidths {
    /// Rim: between the outer slot and the plate outline.
    pub rim: Real,
    /// Slot width.
    pub slot: Real,
    /// Leg: between the two slots.
    pub leg: Real,
    /// Neck: the reduced section where a leg folds.
    pub neck: Real,
    /// The joint slot between consecutive units of a strip: every plate is its tile
    /// inset by half of it.
    pub joint: Real,
}

impl CutWidths {
    /// All widths zero: the paper's idealised unit (legs hinged at the tile corners).
    pub const ZERO: CutWidths = CutWidths {
        rim: 0.0,
        slot: 0.0,
        leg: 0.0,
        neck: 0.0,
        joint: 0.0,
    };

    /// 3 mm sheet at about the least widths the profile's rules allow (rim, slot and joint
    /// slot 1.5 t, neck 3 t, leg two necks; the rim 5 mm): hub 33.75 mm inside its tile.
    pub const STEEL_3MM: CutWidths = CutWidths {
        rim: 5.0,
        slot: 4.5,
        leg: 18.0,
        neck: 9.0,
        joint: 4.5,
    };

    /// How far a unit's plate lies inside its tile's side where the joint slot runs: half
    /// the slot (the next unit of the strip has the other half).
    pub fn plate_inset(&self) -> Real {
        self.joint / 2.0
    }

    /// How far the hub plate lies inside the tile on every side (mm).
    pub fn hub_inset(&self) -> Real {
        self.plate_inset() + self.rim + 2.0 * self.slot + self.leg
    }

    /// Every width multiplied by `k` (the zero-width limit is `k -> 0`).
    pub fn scaled(&self, k: Real) -> Self {
        Self {
            rim: self.rim * k,
            slot: self.slot * k,
            leg: self.leg * k,
            neck: self.neck * k,
            joint: self.joint * k,
        }
    }
}

/// The cut of one unit plate, in the plate's flat frame.
#[derive(Clone, Debug, PartialEq)]
pub struct UnitLayout {
    /// The plate: the tile inset by half the joint slot (counter-clockwise).
    pub plate: [Point2; 4],
    /// The hub plate, inside the inner slot track (counter-clockwise).
    pub hub: [Point2; 4],
    /// Centre line of hook slot `i`: start, the crossing at corner `i + 1`, corner `i + 2`,
    /// end.
    pub slot_paths: [[Point2; 4]; 4],
    /// Fold line across the neck where leg `j` joins the hub (slot edge to slot edge).
    pub hub_necks: [[Point2; 2]; 4],
    /// Fold line across the neck where leg `j` joins the rim.
    pub rim_necks: [[Point2; 2]; 4],
}

/// Why a tile cannot carry the cut.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CutError(pub String);

impl std::fmt::Display for CutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

fn cross(a: &Vector2, b: &Vector2) -> Real {
    a.x * b.y - a.y * b.x
}

/// Intersection of the lines `p + s d` and `q + t e`.
fn meet(p: Point2, d: Vector2, q: Point2, e: Vector2) -> Option<Point2> {
    let den = cross(&d, &e);
    if den.abs() < 1e-12 {
        return None;
    }
    Some(p + d * (cross(&(q - p), &e) / den))
}

/// The point of the open polyline `path` closest to `p`.
fn closest_on_path(path: &[Point2], p: Point2) -> Point2 {
    path.windows(2)
        .map(|w| {
            let e = w[1] - w[0];
            let t = ((p - w[0]).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            w[0] + e * t
        })
        .min_by(|a, b| (a - p).norm().total_cmp(&(b - p).norm()))
        .expect("a path has a segment")
}

/// The counter-clockwise convex quad `q` with every side moved inward by `delta`; `None`
/// when that turns a side around.
pub fn inset(q: &[Point2; 4], delta: Real) -> Option<[Point2; 4]> {
    inset_sides(q, [delta; 4])
}

/// The counter-clockwise convex quad `q` with side `i` (from corner `i` to `i + 1`) moved
/// inward by `delta[i]`; `None` when that turns a side around.
pub fn inset_sides(q: &[Point2; 4], delta: [Real; 4]) -> Option<[Point2; 4]> {
    let d: [Vector2; 4] = std::array::from_fn(|i| (q[(i + 1) % 4] - q[i]).normalize());
    let base: [Point2; 4] =
        std::array::from_fn(|i| q[i] + Vector2::new(-d[i].y, d[i].x) * delta[i]);
    let mut out = [Point2::origin(); 4];
    for i in 0..4 {
        let h = (i + 3) % 4;
        out[i] = meet(base[h], d[h], base[i], d[i])?;
    }
    for i in 0..4 {
        if (out[(i + 1) % 4] - out[i]).dot(&d[i]) <= 1e-9 {
            return None;
        }
    }
    Some(out)
}

impl UnitLayout {
    /// The cut of the unit whose tile (counter-clockwise, convex) is `tile`.
    pub fn new(tile: &[Point2; 4], w: &CutWidths) -> Result<Self, CutError> {
        let err = |why: String| Err(CutError(why));
        let Some(q) = inset(tile, w.plate_inset()) else {
            return err("tile smaller than the joint slot".into());
        };
        let s = w.slot;
        let Some(oq) = inset(&q, w.rim + s / 2.0) else {
            return err("tile too small for the rim".into());
        };
        let Some(iq) = inset(&q, w.rim + 1.5 * s + w.leg) else {
            return err("tile too small for rim, legs and slots".into());
        };
        let Some(hub) = inset(&q, w.rim + 2.0 * s + w.leg) else {
            return err("tile too small: no hub left inside the legs".into());
        };
        let d: [Vector2; 4] = std::array::from_fn(|i| (q[(i + 1) % 4] - q[i]).normalize());
        let sin_at = |i: usize| cross(&d[(i + 3) % 4], &d[i % 4]).abs();
        let neck = w.neck + s;
        let mut slot_paths = [[Point2::origin(); 4]; 4];
        for i in 0..4 {
            let (i1, i2) = ((i + 1) % 4, (i + 2) % 4);
            let a = iq[i] + d[i] * (neck / sin_at(i));
            let parallel = || CutError("tile has parallel adjacent sides".into());
            let x = meet(iq[i], d[i], oq[i1], d[i1]).ok_or_else(parallel)?;
            let c = oq[i2];
            let x_next = meet(iq[i1], d[i1], oq[i2], d[i2]).ok_or_else(parallel)?;
            let run = (x_next - c).dot(&d[i2]) - neck / sin_at(i2);
            if (x - a).dot(&d[i]) < s || run < s / 2.0 {
                return err(format!(
                    "tile too small for hook slot {i} with neck width {}",
                    w.neck
                ));
            }
            slot_paths[i] = [a, x, c, c + d[i2] * run];
        }
        // A slot is its centre line grown by half its width (round ends, round outer
        // bends), so the web between two slots is narrowest where their centre lines are
        // closest, and it runs along the line joining those two points. Leg i joins the hub
        // between the start of slot i and slot i - 1, and the rim (its leg i + 1) between
        // the end of slot i and slot i + 1.
        let web = |end: Point2, other: &[Point2; 4]| {
            let near = closest_on_path(other, end);
            let u = (near - end).normalize();
            [end + u * (s / 2.0), near - u * (s / 2.0)]
        };
        let hub_necks = std::array::from_fn(|i| web(slot_paths[i][0], &slot_paths[(i + 3) % 4]));
        let rim_necks = std::array::from_fn(|j| {
            let i = (j + 3) % 4;
            web(slot_paths[i][3], &slot_paths[j])
        });
        Ok(Self {
            plate: q,
            hub,
            slot_paths,
            hub_necks,
            rim_necks,
        })
    }

    /// The fold lines of leg `j`'s hub neck and rim neck: unit directions in the sheet's
    /// plane (z = 0), as a leg's pose turns to them (`sv_frame::plates::leg_pose`).
    pub fn fold_lines(&self, j: usize) -> [Vector3; 2] {
        [&self.hub_necks[j], &self.rim_necks[j]].map(|n| {
            let d = (n[1] - n[0]).normalize();
            Vector3::new(d.x, d.y, 0.0)
        })
    }

    /// The pins of the four legs: leg `j` is a rigid bar from `hub[j]` (a point of the hub
    /// plate) to `rim[j]` (a point of the primary plate), each the centre of its neck's
    /// fold line, where the neck's section is narrowest.
    pub fn pins(&self) -> Pins {
        let mid = |n: &[Point2; 2]| Point2::from((n[0].coords + n[1].coords) / 2.0);
        Pins {
            hub: self.hub_necks.each_ref().map(mid),
            rim: self.rim_necks.each_ref().map(mid),
        }
    }
}

/// The body of leg `k` in the flat: the band between the slots along side `k`, from its hub
/// neck to where slot `k` crosses its end (counter-clockwise quad). The necks' webs and the
/// slots' round ends are left out. The fold check poses it as a plate, the joint solve keeps
/// its end near the rim out of the neighbouring plates.
pub fn leg_outline(layout: &UnitLayout, w: &CutWidths, k: usize) -> Option<[Point2; 4]> {
    let q = &layout.plate;
    let outer = inset(q, w.rim + w.slot)?;
    let inner = inset(q, w.rim + w.slot + w.leg)?;
    let k1 = (k + 1) % 4;
    let d = (q[k1] - q[k]).normalize();
    let along = |p: Point2| (p - outer[k]).dot(&d);
    let neck = &layout.hub_necks[k];
    let start = along(Point2::from((neck[0].coords + neck[1].coords) / 2.0));
    let end = along(layout.slot_paths[k][1]) - w.slot / 2.0;
    if end <= start {
        return None;
    }
    let on = |line: &[Point2; 4], t: Real| {
        let e = (line[k1] - line[k]).normalize();
        // the point of `line`'s side k at `t` along d from outer[k]
        let s = (t - (line[k] - outer[k]).dot(&d)) / e.dot(&d);
        line[k] + e * s
    };
    Some([
        on(&outer, start),
        on(&outer, end),
        on(&inner, end),
        on(&inner, start),
    ])
}

/// Where the legs are pinned, in the flat unit's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pins {
    /// Leg `j`'s pin on the hub plate.
    pub hub: [Point2; 4],
    /// Leg `j`'s pin on the primary plate (rim).
    pub rim: [Point2; 4],
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(h: Real) -> [Point2; 4] {
        [
            Point2::new(h, 0.0),
            Point2::new(0.0, h),
            Point2::new(-h, 0.0),
            Point2::new(0.0, -h),
        ]
    }

    const DEFAULT: CutWidths = CutWidths::STEEL_3MM;

    #[test]
    fn legs_pin_near_the_corners_they_replace_and_the_hub_is_inset() {
        let tile = square(212.0);
        let l = UnitLayout::new(&tile, &DEFAULT).unwrap();
        let p = l.pins();
        for j in 0..4 {
            // hub pin near corner j, rim pin near corner j + 1: closer to them than to any
            // other corner
            let near = |x: Point2| {
                (0..4).min_by(|&a, &b| (x - tile[a]).norm().total_cmp(&(x - tile[b]).norm()))
            };
            assert_eq!(near(p.hub[j]), Some(j));
            assert_eq!(near(p.rim[j]), Some((j + 1) % 4));
            // both inside the plate, the hub pin on the hub's side of the inner track
            assert!(p.hub[j].coords.norm() < p.rim[j].coords.norm());
        }
        // the hub plate lies hub_inset inside the tile on every side
        let inset_here = (tile[0].coords.norm() - l.hub[0].coords.norm()) / 2f64.sqrt();
        assert!((inset_here - DEFAULT.hub_inset()).abs() < 1e-9);
    }

    #[test]
    fn pins_tend_to_the_tile_corners_as_the_widths_vanish() {
        let tile = [
            Point2::new(230.0, 0.0),
            Point2::new(0.0, 190.0),
            Point2::new(-230.0, 0.0),
            Point2::new(0.0, -190.0),
        ];
        let mut last = Real::INFINITY;
        for k in [1.0, 0.1, 0.01, 0.001] {
            let p = UnitLayout::new(&tile, &DEFAULT.scaled(k)).unwrap().pins();
            let worst = (0..4)
                .map(|j| {
                    (p.hub[j] - tile[j])
                        .norm()
                        .max((p.rim[j] - tile[(j + 1) % 4]).norm())
                })
                .fold(0.0, Real::max);
            assert!(worst < last, "k = {k}: {worst} not below {last}");
            last = worst;
        }
        assert!(last < 0.2, "{last}");
    }

    /// Points every `step` along the open polyline `path`.
    fn sampled(path: &[Point2; 4], step: Real) -> Vec<Point2> {
        path.windows(2)
            .flat_map(|w| {
                let n = ((w[1] - w[0]).norm() / step).ceil() as usize;
                (0..=n).map(move |k| w[0] + (w[1] - w[0]) * (k as Real / n as Real))
            })
            .collect()
    }

    #[test]
    fn pins_sit_where_the_webs_between_slots_are_narrowest_on_a_skewed_tile() {
        // a kite with 70 and 110 degree corners: the neck rules of a square tile do not apply
        let tile = [
            Point2::new(0.0, 0.0),
            Point2::new(260.0, 0.0),
            Point2::new(260.0 + 280.0 * 0.342, 280.0 * 0.940),
            Point2::new(280.0 * 0.342, 280.0 * 0.940),
        ];
        let l = UnitLayout::new(&tile, &DEFAULT).unwrap();
        let p = l.pins();
        let samples: Vec<Vec<Point2>> = l.slot_paths.iter().map(|s| sampled(s, 0.01)).collect();
        // brute force: the closest pair of centre lines of slots `a` and `b` within 15 mm
        // of `pin`; the web is that distance less a slot width
        let check = |pin: Point2, a: usize, b: usize| {
            let near = |v: &Vec<Point2>| -> Vec<Point2> {
                v.iter()
                    .copied()
                    .filter(|q| (q - pin).norm() < 15.0)
                    .collect()
            };
            let (sa, sb) = (near(&samples[a]), near(&samples[b]));
            let mut best = (Real::INFINITY, Point2::origin());
            for x in &sa {
                for y in &sb {
                    let dist = (x - y).norm();
                    if dist < best.0 {
                        best = (dist, Point2::from((x.coords + y.coords) / 2.0));
                    }
                }
            }
            assert!(
                (best.1 - pin).norm() < 0.02,
                "pin {pin} vs web centre {}",
                best.1
            );
            assert!(
                best.0 - DEFAULT.slot >= DEFAULT.neck - 0.01,
                "web {}",
                best.0
            );
        };
        for j in 0..4 {
            check(p.hub[j], j, (j + 3) % 4);
            check(p.rim[j], (j + 3) % 4, j);
        }
    }

    #[test]
    fn a_tile_too_small_is_named() {
        let e = UnitLayout::new(&square(40.0), &DEFAULT).unwrap_err();
        assert!(e.0.contains("too small"), "{e}");
    }
}
