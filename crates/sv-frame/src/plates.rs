//! Measures of two plates that meet: how far one passes through the other, and the fold,
//! bend and twist of a hinge between them. The solve aims at them and the fold check
//! measures them, on the same definitions.

use sv_geom::{
    segment_closest, Isometry3, Point2, Point3, Real, Rotation3, UnitQuaternion, Vector3,
};

/// Unit normal of a convex quad plate, `(q2 - q0) x (q3 - q1)`; `None` when degenerate.
pub fn plate_normal(q: &[Point3; 4]) -> Option<Vector3> {
    (q[2] - q[0]).cross(&(q[3] - q[1])).try_normalize(1e-12)
}

/// The point of plate `a` (a convex quad on its mid-plane, `thickness` thick) nearest `x`.
pub fn nearest_on_plate(a: &[Point3; 4], thickness: Real, x: &Point3) -> Point3 {
    let Some(n) = plate_normal(a) else {
        return a[0];
    };
    let h = n.dot(&(x - a[0]));
    let flat = x - n * h;
    // inside the outline, or the nearest point of its nearest side
    let inside = (0..4).all(|i| n.cross(&(a[(i + 1) % 4] - a[i])).dot(&(flat - a[i])) >= 0.0);
    let on = if inside {
        flat
    } else {
        (0..4)
            .map(|i| {
                let c = segment_closest(&a[i], &a[(i + 1) % 4], &flat, &flat);
                a[i] + (a[(i + 1) % 4] - a[i]) * c.s
            })
            .min_by(|p, q| (p - flat).norm().total_cmp(&(q - flat).norm()))
            .unwrap_or(flat)
    };
    on + n * h.clamp(-thickness / 2.0, thickness / 2.0)
}

/// From plate `a`'s edge at `w` (a point of its side on its mid-plane) to plate `b`: the
/// shortest move that brings the point within one thickness of `b`'s mid-plane, over `b`'s
/// outline. Zero where the two plates touch there, edge to edge (in one plane) or edge on
/// face (one lying on the other), or pass into each other.
pub fn edge_to_plate(_a: &[Point3; 4], w: &Point3, b: &[Point3; 4], thickness: Real) -> Vector3 {
    nearest_on_plate(b, 2.0 * thickness, w) - w
}

/// Points at which [`reach_profile`] samples a segment.
pub const REACH_SAMPLES: usize = 17;

/// Rows of [`reach_profile`]: the samples and the deepest point.
pub const REACH_ROWS: usize = REACH_SAMPLES + 1;

/// The weight of the excess depth of [`reach_profile`]'s deepest row: a slope for the solve
/// where plates pass through each other, weak, so that it does not take over (saddle: 37
/// welds left open without it, 9 / 3 / 7 / 12 at 0.01 / 0.03 / 0.1 / 0.3, and at 1 the hub
/// laps fell short; docs/geometry.md 6.5).
const EXCESS: Real = 0.03;

/// Along the segment `p q`, the six lines (value at `p`, change from `p` to `q`) whose
/// smallest is how deep a point lies in plate `a`: its depth inside each of `a`'s four
/// sides (seen along `a`'s normal) and its clearance `thickness -+ height` from `a`'s
/// mid-plane. `None` for a degenerate plate.
fn reach_lines(
    a: &[Point3; 4],
    p: &Point3,
    q: &Point3,
    thickness: Real,
) -> Option<[(Real, Real); 6]> {
    let n = plate_normal(a)?;
    let mut lines = [(0.0, 0.0); 6];
    for (i, line) in lines.iter_mut().take(4).enumerate() {
        let inward = n.cross(&(a[(i + 1) % 4] - a[i])).normalize();
        *line = (inward.dot(&(p - a[i])), inward.dot(&(q - p)));
    }
    let (h, dh) = (n.dot(&(p - a[0])), n.dot(&(q - p)));
    lines[4] = (thickness - h, -dh);
    lines[5] = (thickness + h, dh);
    Some(lines)
}

/// `(depth inside the outline, clearance inside the slab)` at `s` along the segment.
fn reach_at(lines: &[(Real, Real); 6], s: Real) -> (Real, Real) {
    let min = |l: &[(Real, Real)]| {
        l.iter()
            .map(|(v, d)| v + d * s)
            .fold(Real::INFINITY, Real::min)
    };
    (min(&lines[..4]), min(&lines[4..]))
}

/// Where along `p q` (0 to 1) the segment reaches deepest into plate `a`, and how deep
/// (see [`reach_into`]).
fn reach_peak(lines: &[(Real, Real); 6]) -> (Real, Real) {
    let value = |s: Real| {
        let (depth, clear) = reach_at(lines, s);
        depth.min(clear)
    };
    let mut best = (0.0, value(0.0));
    let mut consider = |s: Real| {
        let v = value(s);
        if v > best.1 {
            best = (s, v);
        }
    };
    consider(1.0);
    for i in 0..6 {
        for j in i + 1..6 {
            let slope = lines[i].1 - lines[j].1;
            if slope.abs() > 1e-15 {
                let s = (lines[j].0 - lines[i].0) / slope;
                if (0.0..=1.0).contains(&s) {
                    consider(s);
                }
            }
        }
    }
    (best.0, best.1.max(0.0))
}

/// How deep `p q` reaches into plate `a` (see [`reach_into`]) at [`REACH_SAMPLES`] points
/// and at its deepest: rows for the solve. Where the segment passes through `a`'s
/// mid-plane more than a thickness inside its outline, the reach stays at the thickness
/// however deep it goes (no slope): the deepest row then adds [`EXCESS`] times the depth
/// beyond the thickness there, so that the solve can pull it out.
pub fn reach_profile(
    a: &[Point3; 4],
    p: &Point3,
    q: &Point3,
    thickness: Real,
) -> [Real; REACH_ROWS] {
    let Some(lines) = reach_lines(a, p, q, thickness) else {
        return [0.0; REACH_ROWS];
    };
    let row = |s: Real| {
        let (depth, clear) = reach_at(&lines, s);
        depth.min(clear).max(0.0)
    };
    let peak = reach_peak(&lines).0;
    // where the segment passes through the plate's mid-plane deeper inside its outline than
    // a thickness, the reach is the thickness however deep: the excess gives it a slope
    let (h, dh) = (thickness - lines[4].0, -lines[4].1);
    let crossing = (dh.abs() > 1e-12)
        .then(|| -h / dh)
        .filter(|s| (0.0..=1.0).contains(s));
    let excess = crossing.map_or(0.0, |s| (reach_at(&lines, s).0 - thickness).max(0.0));
    std::array::from_fn(|i| {
        if i < REACH_SAMPLES {
            row(i as Real / (REACH_SAMPLES - 1) as Real)
        } else {
            row(peak) + EXCESS * excess
        }
    })
}

/// How far the segment `p q` reaches into plate `a` (a convex quad of thickness
/// `thickness` on its mid-plane): the largest, over points of the segment, of how deep the
/// point lies inside `a`'s outline (seen along `a`'s normal) while closer to `a`'s
/// mid-plane than `thickness` (mm, 0 when it stays clear). A segment whose plate touches
/// `a` edge to edge, or passes above or below it, reaches 0.
///
/// Exact: along the segment the depth below each of `a`'s four sides and the clearance
/// `thickness -+ height` are linear, so their smallest is concave and piecewise linear, and
/// its largest value lies at an end of the segment or where two of the six lines cross.
pub fn reach_into(a: &[Point3; 4], p: &Point3, q: &Point3, thickness: Real) -> Real {
    reach_lines(a, p, q, thickness).map_or(0.0, |l| reach_peak(&l).1)
}

/// How far two facing plates reach into each other: the deeper of `b`'s side `m` into `a`
/// and `a`'s side `k` into `b` ([`reach_into`]).
pub fn facing_reach(a: &[Point3; 4], k: usize, b: &[Point3; 4], m: usize, thickness: Real) -> Real {
    reach_into(a, &b[m], &b[(m + 1) % 4], thickness).max(reach_into(
        b,
        &a[k],
        &a[(k + 1) % 4],
        thickness,
    ))
}

/// A primary plate as cut from its (expanded) tile: side `k` moved into the tile's plane by
/// `inset[k]` (half the joint slot where a bridge joins the strip's next unit there, 0 where
/// the plate reaches the tile's side; `docs/fabrication.md` 3). The corner fillets are left
/// out (they take at most `fillet_radius (sqrt 2 - 1)` off a right corner). Each corner
/// moves from its own tile corner, so it follows that corner off the plane too: the solve
/// differentiates it that way (`sv_unit::inset_sides` on the flattened tile would put all
/// four in one plane and change those derivatives, and with them the solve's result).
pub fn plate_as_cut(tile: &[Point3; 4], inset: [Real; 4]) -> [Point3; 4] {
    let Some(n) = plate_normal(tile) else {
        return *tile;
    };
    if inset == [0.0; 4] {
        return *tile;
    }
    let inward: [Vector3; 4] =
        std::array::from_fn(|i| n.cross(&(tile[(i + 1) % 4] - tile[i])).normalize());
    std::array::from_fn(|k| {
        // corner k joins side k - 1 and side k: moved in by both insets
        let h = (k + 3) % 4;
        let (u, v) = (inward[h], inward[k]);
        let c = u.dot(&v);
        let det = 1.0 - c * c;
        if det < 1e-12 {
            return tile[k] + u * inset[h];
        }
        let along_u = (inset[h] - c * inset[k]) / det;
        let along_v = (inset[k] - c * inset[h]) / det;
        tile[k] + u * along_u + v * along_v
    })
}

/// Two plates that lap (hub plates): over their overlap seen along `b`'s normal, the lowest
/// and highest height of `a`'s mid-plane above `b`'s (mm); `None` when they do not overlap
/// or stand square to each other. The heights are linear over the overlap, a convex
/// polygon, so its corners give both. Lying one on the other (`thickness` apart, never
/// through each other) is `low >= thickness` or `high <= -thickness`.
pub fn lap_heights(a: &[Point3; 4], b: &[Point3; 4]) -> Option<(Real, Real)> {
    let view = LapView::of(a, b)?;
    let na = plate_normal(a)?;
    let height = |x: &[Real; 2]| {
        let on_b = view.point(x);
        na.dot(&(a[0] - on_b)) / na.dot(&view.normal)
    };
    Some(
        view.overlap
            .iter()
            .map(height)
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), h| {
                (lo.min(h), hi.max(h))
            }),
    )
}

/// How far two lapping hub plates overlap along the line of their centres (mm), seen along
/// `b`'s normal: the length of their common outline along that line, 0 where they do not
/// overlap. The hub lap (the tips passing each other along that line) is this where the
/// tips meet head on; where they pass each other offset sideways ([`tips_offset`]), less.
pub fn lap_overlap_length(a: &[Point3; 4], b: &[Point3; 4]) -> Real {
    let Some(view) = LapView::of(a, b) else {
        return 0.0;
    };
    let centre = |q: &[Point3; 4]| {
        view.flat(&Point3::from(
            q.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / 4.0,
        ))
    };
    let (ca, cb) = (centre(a), centre(b));
    let (dx, dy) = (cb[0] - ca[0], cb[1] - ca[1]);
    let len = dx.hypot(dy);
    if len < 1e-9 {
        return 0.0;
    }
    let (lo, hi) = view
        .overlap
        .iter()
        .map(|x| (x[0] * dx + x[1] * dy) / len)
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        });
    hi - lo
}

/// Plate `a` seen along plate `b`'s normal, on `b`'s plane (origin `b[0]`, axes `u` along
/// its side 0 and `v`): the convex overlap of the two outlines there.
struct LapView {
    origin: Point3,
    u: Vector3,
    v: Vector3,
    normal: Vector3,
    overlap: Vec<[Real; 2]>,
}

impl LapView {
    /// `None` when the plates do not overlap or stand square to each other.
    fn of(a: &[Point3; 4], b: &[Point3; 4]) -> Option<Self> {
        let normal = plate_normal(b)?;
        if plate_normal(a)?.dot(&normal).abs() < 1e-6 {
            return None;
        }
        let u = (b[1] - b[0]).normalize();
        let mut view = Self {
            origin: b[0],
            u,
            v: normal.cross(&u),
            normal,
            overlap: Vec::new(),
        };
        let fb: Vec<[Real; 2]> = b.iter().map(|p| view.flat(p)).collect();
        let mut fa: Vec<[Real; 2]> = a.iter().map(|p| view.flat(p)).collect();
        if sv_geom::planar::polygon_area(&fa) < 0.0 {
            fa.reverse();
        }
        view.overlap = sv_geom::planar::convex_clip(&fa, &fb);
        (view.overlap.len() >= 3).then_some(view)
    }

    fn flat(&self, p: &Point3) -> [Real; 2] {
        [
            (p - self.origin).dot(&self.u),
            (p - self.origin).dot(&self.v),
        ]
    }

    fn point(&self, x: &[Real; 2]) -> Point3 {
        self.origin + self.u * x[0] + self.v * x[1]
    }
}

/// How far apart across the line of centres the tips of two lapping hub plates pass (mm):
/// corner `k` of `a` and corner `m` of `b`, the offset between them square to the line of
/// their centres and to the plates' mean normal. Aligned tips (0) overlap in a square
/// whose diagonal is the lap; offset by `d`, two right-angled tips overlap along the line
/// of centres by the lap less `d` only, and not at all once `d` reaches the lap.
pub fn tips_offset(a: &[Point3; 4], k: usize, b: &[Point3; 4], m: usize) -> Real {
    let centre = |q: &[Point3; 4]| q.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / 4.0;
    let e = (centre(b) - centre(a)).normalize();
    let n = match (plate_normal(a), plate_normal(b)) {
        (Some(na), Some(nb)) => (na + nb).normalize(),
        _ => return Real::NAN,
    };
    match n.cross(&e).try_normalize(1e-12) {
        Some(across) => (a[k] - b[m]).dot(&across).abs(),
        None => Real::NAN,
    }
}

/// The turn of a hinge from plate `a`'s side `k` to plate `b`'s side `m` (the two facing
/// sides run opposite ways): `(bend, twist)` in radians. `bend` is the turn of `b`'s side in
/// `a`'s plane (about `a`'s normal), `twist` its turn out of it (about the line across the
/// joint); a pure fold about the joint line has both zero.
pub fn hinge_turn(a: &[Point3; 4], k: usize, b: &[Point3; 4], m: usize) -> (Real, Real) {
    let Some(n) = plate_normal(a) else {
        return (Real::NAN, Real::NAN);
    };
    let e = (a[(k + 1) % 4] - a[k]).normalize();
    let across = n.cross(&e);
    let g = (b[m] - b[(m + 1) % 4]).normalize();
    let bend = across.dot(&g).atan2(e.dot(&g));
    let twist = n.dot(&g).clamp(-1.0, 1.0).asin();
    (bend, twist)
}

/// Where leg `k` lies: the motion from the flat to the world that puts its hub pin
/// `hub_pin` on `hub_world` and its rim pin on the line to `rim_world`, turned about that
/// line to twist its necks least; and each neck's twist (radians, hub then rim). `folds`:
/// each neck's fold line in the flat and as the plate at its other side carries it in the
/// world. The fold check poses its leg plates so, the joint solve its legs' rim ends.
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
    let rotation = Rotation3::from_basis_unchecked(&[a, b, a.cross(&b)])
        * Rotation3::from_basis_unchecked(&[e1, e2, Vector3::z()]).transpose();
    let rotation = UnitQuaternion::from_rotation_matrix(&rotation);
    let translation = hub_world.coords - rotation * Vector3::new(hub_pin.x, hub_pin.y, 0.0);
    let motion = Isometry3::from_parts(translation.into(), rotation);
    let twist = folds
        .iter()
        .map(|(flat, world)| (rotation * flat).angle(world))
        .collect();
    Some((motion, twist))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: Real, x0: Real) -> [Point3; 4] {
        [
            Point3::new(x0, 0.0, z),
            Point3::new(x0 + 1.0, 0.0, z),
            Point3::new(x0 + 1.0, 1.0, z),
            Point3::new(x0, 1.0, z),
        ]
    }

    /// Two hub plates, diamonds of half-diagonal 100 mm whose tips face each other along x,
    /// `lap` past each other and `side` apart across: their overlap along the line of
    /// centres is the extent, along that line, of the points inside both (counted on a
    /// 0.05 mm grid); where the tips pass offset by more than the lap the plates do not
    /// overlap at all, though the tips still pass each other along the line of centres.
    #[test]
    fn the_overlap_along_the_line_of_centres_shrinks_as_the_tips_pass_offset() {
        let diamond = |cx: Real, cy: Real, z: Real| -> [Point3; 4] {
            [(100.0, 0.0), (0.0, 100.0), (-100.0, 0.0), (0.0, -100.0)]
                .map(|(x, y)| Point3::new(cx + x, cy + y, z))
        };
        let centre = |q: &[Point3; 4]| {
            Point3::from(q.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / 4.0)
        };
        for (lap, side) in [(40.0, 0.0), (40.0, 10.0), (40.0, 25.0), (30.0, 55.0)] {
            let (cx, cy) = (200.0 - lap, side);
            let a = diamond(0.0, 0.0, 2.6);
            let b = diamond(cx, cy, 0.0);
            let len = Real::hypot(cx, cy);
            let (ex, ey) = (cx / len, cy / len);
            let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
            for i in 0..=2000 {
                for j in 0..=2000 {
                    let (x, y) = (60.0 + 0.05 * i as Real, -50.0 + 0.05 * j as Real);
                    if x.abs() + y.abs() <= 100.0 && (x - cx).abs() + (y - cy).abs() <= 100.0 {
                        lo = lo.min(x * ex + y * ey);
                        hi = hi.max(x * ex + y * ey);
                    }
                }
            }
            let expected = if hi >= lo { hi - lo } else { 0.0 };
            let along = lap_overlap_length(&a, &b);
            assert!(
                (along - expected).abs() < 0.1,
                "lap {lap}, offset {side}: {along} vs {expected}"
            );
            // the tips' offset square to the line of centres
            assert!((tips_offset(&a, 0, &b, 2) - 200.0 * side / len).abs() < 1e-9);
            if side > lap {
                assert_eq!(along, 0.0);
                assert!(crate::solve::hub_overlap(&centre(&a), &a[0], &centre(&b), &b[2]) > 10.0);
            } else {
                assert!(along > 0.0);
            }
        }
    }

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

    #[test]
    fn a_side_reaches_into_a_plate_only_inside_its_outline_and_its_thickness() {
        let a = square(0.0, 0.0);
        let t = 0.05;
        // across a's plate, 0.02 above its mid-plane: reaches to the middle, 0.5 deep
        let (p, q) = (Point3::new(-0.5, 0.5, 0.02), Point3::new(1.5, 0.5, 0.02));
        assert!(
            (reach_into(&a, &p, &q, t) - 0.03).abs() < 1e-12,
            "capped by the thickness"
        );
        let (p, q) = (Point3::new(-0.5, 0.5, 0.0), Point3::new(0.2, 0.5, 0.0));
        assert!((reach_into(&a, &p, &q, 1.0) - 0.2).abs() < 1e-2);
        // above the plate by more than the thickness, or outside its outline: clear
        assert_eq!(
            reach_into(
                &a,
                &Point3::new(-0.5, 0.5, 0.2),
                &Point3::new(1.5, 0.5, 0.2),
                t
            ),
            0.0
        );
        assert_eq!(
            reach_into(
                &a,
                &Point3::new(1.0, 0.0, 0.0),
                &Point3::new(1.0, 1.0, 0.0),
                t
            ),
            0.0
        );
    }

    #[test]
    fn the_reach_is_the_exact_largest_not_the_largest_sample() {
        // a 100 x 100 plate; a long segment in its plane that cuts across its corner
        // (100, 0): 1 mm deep at (99, 1), between the samples
        let a = square(0.0, 0.0).map(|p| Point3::from(p.coords * 100.0));
        let (p, q) = (
            Point3::new(-103.0, -201.0, 0.0),
            Point3::new(101.0, 3.0, 0.0),
        );
        let exact = reach_into(&a, &p, &q, 2.5);
        assert!((exact - 1.0).abs() < 1e-12, "{exact}");
        // 17 even samples miss it; the solve's rows hold the peak too
        let sampled = (0..REACH_SAMPLES)
            .map(|i| {
                let x = p + (q - p) * (i as Real / (REACH_SAMPLES - 1) as Real);
                reach_into(&a, &x, &x, 2.5)
            })
            .fold(0.0, Real::max);
        assert!(sampled < 1.0, "the samples miss the peak: {sampled}");
        let rows = reach_profile(&a, &p, &q, 2.5);
        assert!((rows[REACH_SAMPLES] - 1.0).abs() < 1e-12, "{rows:?}");
        // brute force agrees
        let brute = (0..=100_000)
            .map(|i| {
                let x = p + (q - p) * (i as Real / 100_000.0);
                reach_into(&a, &x, &x, 2.5)
            })
            .fold(0.0, Real::max);
        assert!((brute - exact).abs() < 1e-3, "{brute} {exact}");
    }

    #[test]
    fn a_side_through_a_plate_deeper_than_a_thickness_has_a_slope_for_the_solve() {
        // a 100 x 100 plate, 2.5 thick; a side through its mid-plane, 20 or 30 mm inside its
        // outline (tilted so that it crosses the mid-plane there)
        let a = square(0.0, 0.0).map(|p| Point3::from(p.coords * 100.0));
        let t = 2.5;
        let through = |x: Real| (Point3::new(x, 0.0, -10.0), Point3::new(x, 100.0, 10.0));
        let rows = |x: Real| {
            let (p, q) = through(x);
            (reach_into(&a, &p, &q, t), reach_profile(&a, &p, &q, t))
        };
        let ((r20, p20), (r30, p30)) = (rows(20.0), rows(30.0));
        // the reach itself is the thickness either way
        assert!(
            (r20 - t).abs() < 1e-12 && (r30 - t).abs() < 1e-12,
            "{r20} {r30}"
        );
        // the deepest row goes on growing with the depth where it crosses
        let deepest = |r: &[Real; REACH_ROWS]| r[REACH_SAMPLES];
        assert!(
            (deepest(&p20) - (t + EXCESS * (20.0 - t))).abs() < 1e-9,
            "{p20:?}"
        );
        assert!((deepest(&p30) - deepest(&p20) - EXCESS * 10.0).abs() < 1e-9);
        // a side that only touches the plate, not through it, gets nothing added
        let (p, q) = (Point3::new(20.0, 0.0, 3.0), Point3::new(20.0, 100.0, 3.0));
        assert_eq!(reach_profile(&a, &p, &q, t), [0.0; REACH_ROWS]);
    }

    #[test]
    fn a_plate_as_cut_is_its_tile_less_the_insets() {
        // a rhombus with 60 degree corners, inset 2 on side 0 and 1 on side 2
        let (s, c) = 60f64.to_radians().sin_cos();
        let tile = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(10.0, 0.0, 0.0),
            Point3::new(10.0 + 10.0 * c, 10.0 * s, 0.0),
            Point3::new(10.0 * c, 10.0 * s, 0.0),
        ];
        let cut = plate_as_cut(&tile, [2.0, 0.0, 1.0, 0.0]);
        // sides 1 and 3 stay on their lines; sides 0 and 2 moved in by 2 and 1
        let dist = |p: &Point3, k: usize| {
            let n = plate_normal(&tile).unwrap();
            n.cross(&(tile[(k + 1) % 4] - tile[k]))
                .normalize()
                .dot(&(p - tile[k]))
        };
        for (k, want) in [(0, 2.0), (1, 0.0), (2, 1.0), (3, 0.0)] {
            assert!((dist(&cut[k], k) - want).abs() < 1e-12, "side {k}");
            assert!(
                (dist(&cut[(k + 1) % 4], k) - want).abs() < 1e-12,
                "side {k}"
            );
        }
        assert_eq!(plate_as_cut(&tile, [0.0; 4]), tile);
    }

    #[test]
    fn an_edge_touching_a_plate_edge_to_edge_or_on_its_face_has_no_gap() {
        let t = 0.1;
        let a = square(0.0, 0.0);
        // b beside a, edge to edge: a's edge at (1, 0.5) touches b's edge
        let b = square(0.0, 1.0);
        assert!(edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() < 1e-12);
        // b a bit away: the gap is the distance between the edges
        let b = square(0.0, 1.3);
        assert!((edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() - 0.3).abs() < 1e-12);
        // b lying on a's face, under a's edge: the edge rests on it
        let b = square(-t, 0.5);
        assert!(edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() < 1e-12);
        // ... and 0.2 lower: a gap of 0.2
        let b = square(-t - 0.2, 0.5);
        assert!((edge_to_plate(&a, &Point3::new(1.0, 0.5, 0.0), &b, t).norm() - 0.2).abs() < 1e-12);
    }

    #[test]
    fn a_fold_about_the_joint_has_no_bend_and_no_twist() {
        let a = square(0.0, 0.0);
        // b shares a's side 1 (x = 1) and is folded up about it by 30 degrees
        let (s, c) = 30f64.to_radians().sin_cos();
        let b = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0 + c, 0.0, s),
            Point3::new(1.0 + c, 1.0, s),
            Point3::new(1.0, 1.0, 0.0),
        ];
        let (bend, twist) = hinge_turn(&a, 1, &b, 3);
        assert!(bend.abs() < 1e-12 && twist.abs() < 1e-12, "{bend} {twist}");
        // b turned in a's plane by 2 degrees about the joint's middle: a bend of 2 degrees
        let (s2, c2) = 2f64.to_radians().sin_cos();
        let mid = Point3::new(1.0, 0.5, 0.0);
        let turn = |v: Vector3| Vector3::new(c2 * v.x - s2 * v.y, s2 * v.x + c2 * v.y, v.z);
        let bent = b.map(|p| mid + turn(p - mid));
        let (bend, twist) = hinge_turn(&a, 1, &bent, 3);
        assert!((bend.to_degrees().abs() - 2.0).abs() < 1e-9 && twist.abs() < 1e-12);
    }
}
