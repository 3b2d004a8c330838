//! A leg as a plate: its cut outline, posed between its two pins with the roll that twists
//! its necks least, and where it passes through another plate.
//!
//! The pin model (a rigid bar between the two neck centres) fixes the leg's line but not its
//! roll about that line. A neck is a short web across a slot: it folds easily about its fold
//! line (across the web, in the sheet) and twists less easily. So the leg's plate is turned
//! about its pin line until each neck's fold line, as the leg carries it, lies as near as it
//! can to the same fold line as the plate at the other side of the neck carries it.

use sv_frame::plates::leg_pose;
use sv_frame::FrameFile;
use sv_geom::{planar, rigid_fit, Isometry3, Point2, Point3, Real, Vector3};
use sv_unit::{leg_outline, CutWidths, UnitLayout};

use crate::plane::convex_hull;

/// The outline, seen along `plate`'s normal, of the part of the slab `leg` (a flat quad in
/// the world, `thickness` through) that lies within the slab of `plate` (its mid-plane
/// quad, `thickness` through): the leg's section at the plate, in the plate's frame `(c, u,
/// v)` (convex, counter-clockwise; empty when the leg does not reach the plate's slab).
pub fn section_in_slab(leg: &[Point3; 4], plate: &[Point3; 4], thickness: Real) -> Vec<Point2> {
    let Some((c, n, u, v)) = frame(plate) else {
        return Vec::new();
    };
    let Some(nl) = (leg[2] - leg[0])
        .cross(&(leg[3] - leg[1]))
        .try_normalize(1e-12)
    else {
        return Vec::new();
    };
    let half = thickness / 2.0;
    let corners: Vec<Point3> = [-half, half]
        .iter()
        .flat_map(|&o| leg.iter().map(move |p| p + nl * o))
        .collect();
    let edges = [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 0),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 4),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    let h = |p: &Point3| (p - c).dot(&n);
    let mut pts: Vec<Point3> = corners
        .iter()
        .filter(|p| h(p).abs() <= half)
        .copied()
        .collect();
    for (i, j) in edges {
        let (p, q) = (corners[i], corners[j]);
        let (hp, hq) = (h(&p), h(&q));
        for level in [-half, half] {
            if (hp - level) * (hq - level) < 0.0 {
                let s = (level - hp) / (hq - hp);
                pts.push(p + (q - p) * s);
            }
        }
    }
    let flat: Vec<Point2> = pts
        .iter()
        .map(|p| Point2::new((p - c).dot(&u), (p - c).dot(&v)))
        .collect();
    convex_hull(&flat)
}

/// A plate's centre, unit normal and in-plane axes.
pub type PlateFrame = (Point3, Vector3, Vector3, Vector3);

/// The plate's centre, unit normal and in-plane axes.
pub fn frame(q: &[Point3; 4]) -> Option<PlateFrame> {
    let c = Point3::from(q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0);
    let n = (q[2] - q[0]).cross(&(q[3] - q[1])).try_normalize(1e-12)?;
    let u = (q[1] - q[0]) - n * (q[1] - q[0]).dot(&n);
    let u = u.try_normalize(1e-12)?;
    Some((c, n, u, n.cross(&u)))
}

/// Signed area of a polygon (positive counter-clockwise; [`sv_geom::planar::polygon_area`]).
pub(crate) fn area(p: &[Point2]) -> Real {
    planar::polygon_area(&flat(p))
}

/// The part of convex polygon `p` inside convex counter-clockwise polygon `clip`
/// ([`sv_geom::planar::convex_clip`]).
pub(crate) fn clip_convex(p: &[Point2], clip: &[Point2]) -> Vec<Point2> {
    planar::convex_clip(&flat(p), &flat(clip))
        .into_iter()
        .map(|q| Point2::new(q[0], q[1]))
        .collect()
}

pub(crate) fn flat(p: &[Point2]) -> Vec<[Real; 2]> {
    p.iter().map(|q| [q.x, q.y]).collect()
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
pub(crate) fn posed_leg(
    p: &Placed,
    widths: &CutWidths,
    k: usize,
    pins: [Point2; 2],
    roll: Real,
) -> Option<[Point3; 4]> {
    // turned about its pin line so that its two necks' fold lines, as the leg carries them,
    // lie as near as they can to the same lines as the hub and the rim carry them (the hub
    // neck's fold line runs along the leg in the flat, so it alone cannot set the roll)
    let [fh, fr] = p.layout.fold_lines(k);
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

/// The part of the leg's section through `plate`'s slab ([`section_in_slab`]) that lies
/// inside the plate's outline, with that outline, both in the plate's frame `(c, u, v)`
/// (counter-clockwise); `None` when nothing of it does.
pub(crate) fn section_inside(
    leg: &[Point3; 4],
    plate: &[Point3; 4],
    thickness: Real,
) -> Option<(PlateFrame, [Point2; 4], Vec<Point2>)> {
    let f = frame(plate)?;
    let (c, _, u, v) = f;
    let section = section_in_slab(leg, plate, thickness);
    if section.len() < 3 {
        return None;
    }
    let mut outline = plate.map(|p| Point2::new((p - c).dot(&u), (p - c).dot(&v)));
    if area(&outline) < 0.0 {
        outline.reverse();
    }
    let inside = clip_convex(&section, &outline);
    (inside.len() >= 3 && area(&inside) >= 1e-3).then_some((f, outline, inside))
}

/// The section of `leg` through the hub plate of `lower` where it lies inside that plate,
/// in `lower`'s flat frame (empty when it does not).
pub(crate) fn section_in_plate(leg: &[Point3; 4], lower: &Placed, thickness: Real) -> Vec<Point2> {
    let Some(((c, _, u, v), _, inside)) = section_inside(leg, &lower.hub_plate, thickness) else {
        return Vec::new();
    };
    let inverse = lower.hub.inverse();
    inside
        .iter()
        .map(|p| {
            let q = inverse * (c + u * p.x + v * p.y);
            Point2::new(q.x, q.y)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leg 15 mm wide standing square through a plate's 2.5 mm slab: its section is the
    /// leg's 15 x 2.5 mm cross-section.
    #[test]
    fn a_leg_square_through_a_plate_cuts_its_own_cross_section() {
        let plate = [
            Point3::new(-100.0, -100.0, 0.0),
            Point3::new(100.0, -100.0, 0.0),
            Point3::new(100.0, 100.0, 0.0),
            Point3::new(-100.0, 100.0, 0.0),
        ];
        let leg = [
            Point3::new(0.0, 0.0, -50.0),
            Point3::new(15.0, 0.0, -50.0),
            Point3::new(15.0, 0.0, 50.0),
            Point3::new(0.0, 0.0, 50.0),
        ];
        let section = section_in_slab(&leg, &plate, 2.5);
        assert!(
            (area(&section).abs() - 15.0 * 2.5).abs() < 1e-9,
            "{section:?}"
        );
        // clear of the plate's slab, nothing
        let high = leg.map(|p| p + Vector3::new(0.0, 0.0, 60.0));
        assert!(section_in_slab(&high, &plate, 2.5).is_empty());
    }
}
