//! A leg as a plate: its cut outline, posed between its two pins with the roll that twists
//! its necks least, and where it passes through another plate.
//!
//! The pin model (a rigid bar between the two neck centres) fixes the leg's line but not its
//! roll about that line. A neck is a short web across a slot: it folds easily about its fold
//! line (across the web, in the sheet) and twists less easily. So the leg's plate is turned
//! about its pin line until each neck's fold line, as the leg carries it, lies as near as it
//! can to the same fold line as the plate at the other side of the neck carries it.

use sv_geom::{Isometry3, Point2, Point3, Real, Vector3};
use sv_unit::{inset, CutWidths, UnitLayout};

/// The body of leg `k` in the flat: the band between the slots along side `k`, from its hub
/// neck to where slot `k` crosses its end (counter-clockwise quad). The necks' webs and the
/// slots' round ends are left out.
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

/// Where leg `k` lies: the motion from the flat to the world that puts its hub pin
/// `hub_pin` on `hub_world` and its rim pin on the line to `rim_world`, turned about that
/// line to twist its necks least; and each neck's twist (radians, hub then rim).
pub fn leg_pose(
    hub_pin: Point2,
    rim_pin: Point2,
    hub_world: Point3,
    rim_world: Point3,
    folds: &[(Vector3, Vector3)],
) -> Option<(Isometry3, Vec<Real>)> {
    let e1 = (rim_pin - hub_pin).try_normalize(1e-12)?;
    let e1 = Vector3::new(e1.x, e1.y, 0.0);
    let e2 = Vector3::z().cross(&e1);
    let a = (rim_world - hub_world).try_normalize(1e-12)?;
    let b0 = a
        .cross(&Vector3::z())
        .try_normalize(1e-6)
        .unwrap_or_else(|| {
            a.cross(&Vector3::x())
                .try_normalize(1e-12)
                .unwrap_or(Vector3::y())
        });
    let c0 = a.cross(&b0);
    // the leg takes a flat vector f to (f.e1) a + (f.e2) b; the roll of b maximises the
    // agreement of each fold line as the leg carries it with the same as its plate does
    let (mut sc, mut ss) = (0.0, 0.0);
    for (flat, world) in folds {
        let f2 = flat.dot(&e2);
        sc += f2 * b0.dot(world);
        ss += f2 * c0.dot(world);
    }
    let psi = ss.atan2(sc);
    let b = b0 * psi.cos() + c0 * psi.sin();
    let rotation = nalgebra::Rotation3::from_basis_unchecked(&[a, b, a.cross(&b)])
        * nalgebra::Rotation3::from_basis_unchecked(&[e1, e2, Vector3::z()]).transpose();
    let rotation = nalgebra::UnitQuaternion::from_rotation_matrix(&rotation);
    let translation = hub_world.coords - rotation * Vector3::new(hub_pin.x, hub_pin.y, 0.0);
    let motion = Isometry3::from_parts(translation.into(), rotation);
    let twist = folds
        .iter()
        .map(|(flat, world)| (rotation * flat).angle(world))
        .collect();
    Some((motion, twist))
}

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
    hull(flat)
}

/// The plate's centre, unit normal and in-plane axes.
pub fn frame(q: &[Point3; 4]) -> Option<(Point3, Vector3, Vector3, Vector3)> {
    let c = Point3::from(q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0);
    let n = (q[2] - q[0]).cross(&(q[3] - q[1])).try_normalize(1e-12)?;
    let u = (q[1] - q[0]) - n * (q[1] - q[0]).dot(&n);
    let u = u.try_normalize(1e-12)?;
    Some((c, n, u, n.cross(&u)))
}

/// Convex hull, counter-clockwise (Andrew's monotone chain).
pub fn hull(mut p: Vec<Point2>) -> Vec<Point2> {
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup_by(|a, b| (*a - *b).norm() < 1e-12);
    if p.len() < 3 {
        return p;
    }
    let turn = |o: &Point2, a: &Point2, b: &Point2| (a - o).perp(&(b - o));
    let chain = |pts: &mut dyn Iterator<Item = Point2>| {
        let mut c: Vec<Point2> = Vec::new();
        for q in pts {
            while c.len() >= 2 && turn(&c[c.len() - 2], &c[c.len() - 1], &q) <= 0.0 {
                c.pop();
            }
            c.push(q);
        }
        c.pop();
        c
    };
    let mut lower = chain(&mut p.iter().copied());
    let upper = chain(&mut p.iter().rev().copied());
    lower.extend(upper);
    lower
}

/// The part of convex polygon `p` inside convex counter-clockwise polygon `clip`.
pub fn clip_convex(p: &[Point2], clip: &[Point2]) -> Vec<Point2> {
    let mut out = p.to_vec();
    for i in 0..clip.len() {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[i], clip[(i + 1) % clip.len()]);
        let side = |q: &Point2| (b - a).perp(&(q - a));
        let input = std::mem::take(&mut out);
        for j in 0..input.len() {
            let (p0, p1) = (input[j], input[(j + 1) % input.len()]);
            let (s0, s1) = (side(&p0), side(&p1));
            if s0 >= 0.0 {
                out.push(p0);
            }
            if (s0 >= 0.0) != (s1 >= 0.0) {
                out.push(p0 + (p1 - p0) * (s0 / (s0 - s1)));
            }
        }
    }
    out
}

/// Area of a polygon (positive counter-clockwise).
pub fn area(p: &[Point2]) -> Real {
    (0..p.len())
        .map(|i| p[i].coords.perp(&p[(i + 1) % p.len()].coords))
        .sum::<Real>()
        / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leg posed between two world pins puts its hub pin on the first exactly, its rim pin
    /// on the line to the second, and a fold line that the plate carries the same way as
    /// the leg can lie in the leg: no twist.
    #[test]
    fn a_leg_lies_on_its_pins_and_takes_a_fold_line_it_can_hold() {
        let (hp, rp) = (Point2::new(10.0, 5.0), Point2::new(210.0, 5.0));
        let (hw, rw) = (
            Point3::new(0.0, 0.0, 100.0),
            Point3::new(120.0, 80.0, -40.0),
        );
        // a fold line across the leg in the flat; in the world, across the pin line
        let axis = (rw - hw).normalize();
        let across = axis.cross(&Vector3::z()).normalize();
        let flat_fold = Vector3::y();
        let (pose, twist) =
            leg_pose(hp, rp, hw, rw, &[(flat_fold, across), (flat_fold, across)]).unwrap();
        assert!((pose * Point3::new(hp.x, hp.y, 0.0) - hw).norm() < 1e-9);
        let r = pose * Point3::new(rp.x, rp.y, 0.0);
        assert!((r - hw).normalize().cross(&axis).norm() < 1e-9);
        assert!(twist.iter().all(|t| t.abs() < 1e-9), "{twist:?}");
    }

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
