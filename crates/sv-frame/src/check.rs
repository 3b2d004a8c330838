//! Re-verification of a frame file against the invariants of model.md.

use serde::Serialize;
use sv_geom::{segment_closest, Matrix3, Point3, Real, Vector3};

use crate::solve::hub_overlap;
use crate::{FrameFile, Hub, JointKind, QuadMesh};

/// Tolerances of [`check_frame`].
#[derive(Clone, Debug, PartialEq)]
pub struct CheckOptions {
    /// Relative tolerance on leg length vs side length, congruence and rhombus shape.
    pub relative_tolerance: Real,
    /// Absolute tolerance (mm) when recomputed gaps, overlaps and hubs are compared with
    /// the file; JSON numbers round-trip exactly, so this only absorbs arithmetic.
    pub length_tolerance: Real,
    /// Largest allowed planarity residual (diagonal distance / mean edge). Default: the
    /// hub-mesh goal [`GOAL_PLANARITY`].
    pub planarity_tolerance: Real,
    /// Largest allowed conical residual (rad, `QuadMesh::conical_residuals`). Default:
    /// the hub-mesh goal [`GOAL_CONICAL_DEG`] in radians.
    pub conical_tolerance: Real,
}

/// Planarity goal of the hub mesh (diagonal distance / mean edge), held by `check`.
pub const GOAL_PLANARITY: Real = 0.002;
/// Conical goal of the hub mesh (degrees), held by `check`.
pub const GOAL_CONICAL_DEG: Real = 0.5;

impl Default for CheckOptions {
    fn default() -> Self {
        Self {
            relative_tolerance: 1e-9,
            length_tolerance: 1e-6,
            planarity_tolerance: GOAL_PLANARITY,
            conical_tolerance: GOAL_CONICAL_DEG.to_radians(),
        }
    }
}

/// One row of the check table (in `report.json` a limit that holds nothing is `null`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckRow {
    /// What was checked.
    pub name: String,
    /// Worst value found.
    pub worst: Real,
    /// Allowed limit.
    pub limit: Real,
    /// Where the worst value is (unit id, link, face, vertex).
    pub at: String,
    /// Passed?
    pub ok: bool,
    /// Every unit where a value outside the limit was found (indices into frame.json's
    /// `units`, ascending): both units of a link, a strip's bridge or a leg reaching into a
    /// neighbour. Empty where the row holds or names no unit (frame.json's own checks).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub units: Vec<usize>,
}

impl CheckRow {
    /// What the row says: `info` where no limit holds it (nothing is checked yet), else
    /// `ok` or `FAIL`.
    pub fn verdict(&self) -> &'static str {
        if self.limit.is_infinite() {
            "info"
        } else if self.ok {
            "ok"
        } else {
            "FAIL"
        }
    }
}

/// The check table.
#[derive(Clone, Debug, PartialEq, Default, Serialize)]
pub struct CheckReport {
    /// Rows.
    pub rows: Vec<CheckRow>,
}

impl CheckReport {
    /// All rows passed.
    pub fn ok(&self) -> bool {
        self.rows.iter().all(|r| r.ok)
    }
}

/// The worst value of one check and where it is: the row of a [`CheckReport`]. A NaN is
/// the worst and stays; `ok` compares the worst with the limit in the row's sense.
pub struct Worst {
    name: &'static str,
    limit: Real,
    /// `true`: the value must stay at or above the limit (laps), else at or below.
    at_least: bool,
    worst: Option<(Real, String)>,
    /// How many values seen were outside the limit (a NaN counts).
    outside: usize,
    /// The units those values were found at ([`Worst::see_at`]).
    units: Vec<usize>,
}

impl Worst {
    /// A check whose values must stay at or below `limit`.
    pub fn max(name: &'static str, limit: Real) -> Self {
        Self {
            name,
            limit,
            at_least: false,
            worst: None,
            outside: 0,
            units: Vec::new(),
        }
    }

    /// A check whose values must stay at or above `limit`.
    pub fn min(name: &'static str, limit: Real) -> Self {
        Self {
            at_least: true,
            ..Self::max(name, limit)
        }
    }

    /// Take `value`, found where `at` says, if it is the worst so far.
    pub fn see(&mut self, value: Real, at: impl FnOnce() -> String) {
        self.see_at(value, &[], at);
    }

    /// Take `value`, found at `units` (indices into the frame's units) where `at` says: the
    /// worst so far, and where it is outside the limit, the units go into the row's list.
    pub fn see_at(&mut self, value: Real, units: &[usize], at: impl FnOnce() -> String) {
        let within = if self.at_least {
            value >= self.limit
        } else {
            value <= self.limit
        };
        self.outside += usize::from(!within);
        if !within {
            self.units.extend_from_slice(units);
        }
        let worse = match &self.worst {
            None => true,
            Some((w, _)) if w.is_nan() => false,
            Some(_) if value.is_nan() => true,
            Some((w, _)) => {
                if self.at_least {
                    value < *w
                } else {
                    value > *w
                }
            }
        };
        if worse {
            self.worst = Some((value, at()));
        }
    }

    /// How many values seen were outside the limit.
    pub fn outside(&self) -> usize {
        self.outside
    }

    /// The row: the worst value (none seen: 0 at `-`, or for an at-least check infinity at
    /// `nothing measured`). A held row (finite limit) whose worst is not finite fails: an
    /// at-least check that measured nothing has not shown its values reach the limit.
    pub fn row(mut self) -> CheckRow {
        let (worst, at) = self.worst.unwrap_or(if self.at_least {
            (Real::INFINITY, "nothing measured".into())
        } else {
            (0.0, "-".into())
        });
        let within = if self.at_least {
            worst >= self.limit
        } else {
            worst <= self.limit
        };
        let ok = within && (worst.is_finite() || self.limit.is_infinite());
        self.units.sort_unstable();
        self.units.dedup();
        CheckRow {
            name: self.name.into(),
            worst,
            limit: self.limit,
            at,
            ok,
            units: if ok { Vec::new() } else { self.units },
        }
    }
}

fn pt(a: &[Real; 3]) -> Point3 {
    Point3::new(a[0], a[1], a[2])
}

/// The rigid frame of a rhombic plate from its corners: centroid and the columns `x`
/// toward corner 0, `y`, `z` its normal; `None` when degenerate.
fn plate_frame(q: &[Point3; 4]) -> Option<(Point3, Matrix3, Real, Real)> {
    let c = Point3::from(q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0);
    let (d1, d2) = ((q[0] - q[2]) / 2.0, (q[1] - q[3]) / 2.0);
    let n = d1.cross(&d2);
    if n.norm() <= 1e-12 * d1.norm_squared() {
        return None;
    }
    let x = d1.normalize();
    let z = n.normalize();
    Some((
        c,
        Matrix3::from_columns(&[x, z.cross(&x), z]),
        d1.norm(),
        d2.norm(),
    ))
}

/// The legs of a unit as cut, rebuilt from the file alone: the cut of its tile (the primary
/// rhombus scaled by `e`, [`sv_unit::UnitLayout`]) gives the pins in the flat unit; the hub
/// pins go with the hub's rhombus, the rim pins with the primary's. Returns the deployed
/// pins `(hub, rim)` and each leg's flat pin-to-pin length.
#[allow(clippy::type_complexity)]
fn legs_as_cut(
    hub: &[Point3; 4],
    prim: &[Point3; 4],
    e: Real,
    w: &sv_unit::CutWidths,
) -> Option<(([Point3; 4], [Point3; 4]), [Real; 4])> {
    let (cp, fp, a, b) = plate_frame(prim)?;
    let (ch, fh, _, _) = plate_frame(hub)?;
    let tile = [
        sv_geom::Point2::new(a * e, 0.0),
        sv_geom::Point2::new(0.0, b * e),
        sv_geom::Point2::new(-a * e, 0.0),
        sv_geom::Point2::new(0.0, -b * e),
    ];
    let pins = sv_unit::UnitLayout::new(&tile, w).ok()?.pins();
    let lift = |p: &sv_geom::Point2| Vector3::new(p.x, p.y, 0.0);
    let flat = std::array::from_fn(|j| (pins.hub[j] - pins.rim[j]).norm());
    let on_hub = pins.hub.each_ref().map(|p| ch + fh * lift(p));
    let on_rim = pins.rim.each_ref().map(|p| cp + fp * lift(p));
    Some(((on_hub, on_rim), flat))
}

/// Rigid fit (Kabsch) of `from` onto `to`: largest residual and whether the fitted rotation
/// carries `from`'s corner-order normal onto `to`'s (a flat set fits a mirror image as well
/// as itself, so the orientation is checked on the normals).
fn rigid_fit(from: &[Point3; 4], to: &[Point3; 4]) -> (Real, bool) {
    let Some((motion, res)) = sv_geom::rigid_fit(from, to) else {
        return (Real::NAN, false);
    };
    let n_from = (from[0] - from[2]).cross(&(from[1] - from[3]));
    let n_to = (to[0] - to[2]).cross(&(to[1] - to[3]));
    (res, (motion.rotation * n_from).dot(&n_to) > 0.0)
}

/// Re-verify every invariant of model.md on a frame file: congruence, leg lengths, the
/// rotation axis, rhombic tiles, hubs fitted to the mesh, recorded (theta, phi), gaps and
/// overlaps, links covering every interior edge, planarity and conicality.
pub fn check_frame(frame: &FrameFile, options: &CheckOptions) -> CheckReport {
    let rel = options.relative_tolerance;
    let abs = options.length_tolerance;
    let mesh = QuadMesh {
        vertices: frame.mesh.vertices.iter().map(pt).collect(),
        faces: frame.mesh.faces.clone(),
    };
    let mut congruent = Worst::max("hub congruent to primary (residual / side)", rel);
    let mut legs = Worst::max("leg length = side (relative error)", rel);
    let mut rhombic = Worst::max("primary is a rhombus (relative error)", rel);
    let mut axis = Worst::max("closed form reproduces hub (mm)", abs);
    let mut params = Worst::max("theta, phi match the file (rad)", 1e-6);
    let mut fitted = Worst::max("hub = spun best-fit rhombus of face (mm)", abs);
    let mut gaps = Worst::max("link gap matches file (mm)", abs);
    let mut overlaps = Worst::max("hub overlap matches file (mm)", abs);
    let mut coverage = Worst::max("interior edges without a link", 0.0);
    let mut orientation = Worst::max("hub and primary same orientation (0/1)", 0.0);
    // the unit as cut: legs pin to pin, pins where the cut of the tile puts them
    let cut = frame.params.cut;
    let mut pinned = Worst::max("leg pin to pin = its length as cut (mm)", abs);
    let mut pins_match = Worst::max("pins match the cut of the tile (mm)", abs);
    // model.md 1: each face is one unit; each unit its own label (the streamer's rule too)
    let mut units_on_faces = Worst::max("faces without exactly one unit, ids used twice", 0.0);
    let problems = frame.unit_problems();
    units_on_faces.see(problems.len() as Real, || {
        problems
            .first()
            .map_or("-".into(), |p| match problems.len() {
                1 => p.to_string(),
                n => format!("{p} (and {} more)", n - 1),
            })
    });

    let e = frame.params.expansion;
    let mut expanded: Vec<Option<[Point3; 4]>> = Vec::with_capacity(frame.units.len());
    for u in &frame.units {
        let hub = u.hub.map(|p| pt(&p));
        let prim = u.primary.map(|p| pt(&p));
        let side = (prim[0] - prim[1]).norm();
        let name = || format!("unit {}", u.id);
        let (res, proper) = rigid_fit(&prim, &hub);
        congruent.see(res / side, name);
        orientation.see(if proper { 0.0 } else { 1.0 }, name);
        if let Some(w) = &cut {
            match legs_as_cut(&hub, &prim, e, w) {
                Some((world, flat)) => {
                    for j in 0..4 {
                        let err = ((world.0[j] - world.1[j]).norm() - flat[j]).abs();
                        pinned.see(err, || format!("unit {} leg {j}", u.id));
                    }
                    if let Some(p) = &u.pins {
                        let off = (0..4)
                            .map(|j| {
                                (pt(&p.hub[j]) - world.0[j])
                                    .norm()
                                    .max((pt(&p.rim[j]) - world.1[j]).norm())
                            })
                            .fold(0.0, Real::max);
                        pins_match.see(off, name);
                    }
                }
                None => pinned.see(Real::INFINITY, name),
            }
        } else {
            for i in 0..4 {
                let s = (prim[i] - prim[(i + 1) % 4]).norm();
                let leg = (hub[i] - prim[(i + 1) % 4]).norm();
                legs.see((leg - s).abs() / s, || format!("unit {} leg {i}", u.id));
            }
        }
        let d1 = prim[0] - prim[2];
        let d2 = prim[1] - prim[3];
        let mid =
            ((prim[0].coords + prim[2].coords) - (prim[1].coords + prim[3].coords)).norm() / 2.0;
        rhombic.see(
            (d1.dot(&d2).abs() / (d1.norm() * d2.norm())).max(mid / side),
            name,
        );
        match sv_unit::inverse(&hub, &prim, Real::INFINITY) {
            // the closed form holds only for the zero-width unit
            _ if cut.is_some() => {}
            Ok(inv) => {
                axis.see(inv.residual, name);
                let d = inv.deployment;
                params.see((d.theta - u.theta).abs().max((d.phi - u.phi).abs()), name);
            }
            Err(_) => axis.see(Real::INFINITY, name),
        }
        match frame.mesh.faces.get(u.face).and_then(|f| {
            let q = f.map(|v| frame.mesh.vertices.get(v).map(pt));
            let q: Option<Vec<Point3>> = q.into_iter().collect();
            Hub::fit(
                &[
                    q.as_ref()?[0],
                    q.as_ref()?[1],
                    q.as_ref()?[2],
                    q.as_ref()?[3],
                ],
                u.spin.unwrap_or(frame.params.spin_angle),
            )
            .and_then(|mut h| {
                h.rhombus = h.rhombus.scaled(u.tile_scale.unwrap_or([1.0, 1.0])).ok()?;
                h.centre += h.normal() * u.hub_lift.unwrap_or(0.0);
                Some(h)
            })
        }) {
            Some(h) => fitted.see(
                (0..4)
                    .map(|i| (h.corner(i) - hub[i]).norm())
                    .fold(0.0, Real::max),
                name,
            ),
            None => fitted.see(Real::INFINITY, name),
        }
        let c = prim.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0;
        expanded.push(Some(prim.map(|p| Point3::from(c + (p.coords - c) * e))));
    }

    // links: recompute gaps and overlaps from the tiles
    let face_of: std::collections::HashMap<usize, usize> = frame
        .units
        .iter()
        .enumerate()
        .map(|(i, u)| (u.face, i))
        .collect();
    let slot = |unit: usize, v: usize, w: usize| -> Option<usize> {
        let f = frame.mesh.faces.get(frame.units.get(unit)?.face)?;
        (0..4).find(|&k| (f[k] == v && f[(k + 1) % 4] == w) || (f[k] == w && f[(k + 1) % 4] == v))
    };
    let mut linked = std::collections::HashSet::new();
    for (li, l) in frame.links.iter().enumerate() {
        let [a, b] = l.units;
        let at = || format!("link {li} (units {a}, {b})");
        let (Some(k), Some(m)) = (slot(a, l.edge[0], l.edge[1]), slot(b, l.edge[0], l.edge[1]))
        else {
            gaps.see(Real::INFINITY, at);
            continue;
        };
        linked.insert((l.edge[0].min(l.edge[1]), l.edge[0].max(l.edge[1])));
        let (Some(Some(pa)), Some(Some(pb))) = (expanded.get(a), expanded.get(b)) else {
            gaps.see(Real::INFINITY, at);
            continue;
        };
        let g = segment_closest(&pa[k], &pa[(k + 1) % 4], &pb[m], &pb[(m + 1) % 4]).distance;
        gaps.see((g - l.primary_gap).abs(), at);
        let (ua, ub) = (&frame.units[a], &frame.units[b]);
        let ca = ua
            .hub
            .iter()
            .fold(Vector3::zeros(), |s, p| s + pt(p).coords)
            / 4.0;
        let cb = ub
            .hub
            .iter()
            .fold(Vector3::zeros(), |s, p| s + pt(p).coords)
            / 4.0;
        // measured on the hub plates as cut where the file has them
        let plate =
            |u: &crate::UnitRecord, k: usize| pt(&u.hub_plate.as_ref().unwrap_or(&u.hub)[k]);
        let o = hub_overlap(
            &Point3::from(ca),
            &plate(ua, k),
            &Point3::from(cb),
            &plate(ub, m),
        );
        overlaps.see((o - l.hub_overlap).abs(), at);
    }
    let mut missing = 0.0;
    let mut first_missing = None;
    if mesh
        .faces
        .iter()
        .flatten()
        .all(|&v| v < mesh.vertices.len())
    {
        for l in mesh.links() {
            let key = (l.edge[0].min(l.edge[1]), l.edge[0].max(l.edge[1]));
            let both_units = face_of.contains_key(&l.faces[0]) && face_of.contains_key(&l.faces[1]);
            if both_units && !linked.contains(&key) {
                missing += 1.0;
                first_missing.get_or_insert(key);
            }
        }
    }
    coverage.see(missing, || {
        first_missing.map_or("-".into(), |(v, w)| format!("edge ({v}, {w})"))
    });

    let joints = check_joints(frame, &expanded, &slot);

    let mut planar = Worst::max(
        "face planarity (diagonal distance / mean edge)",
        options.planarity_tolerance,
    );
    for (f, r) in mesh.planarity_residuals().into_iter().enumerate() {
        planar.see(r, || format!("face {f}"));
    }
    // conicality is the paper's stand-in for "the primary tiles can meet"; where the
    // joints were closed on the plates themselves it is shown, not held
    let mut conical = if joints.is_empty() {
        Worst::max(
            "conical residual (rad, any valence)",
            options.conical_tolerance,
        )
    } else {
        Worst::max(
            "conical residual (rad; not held: the joints are closed)",
            Real::INFINITY,
        )
    };
    for (v, r) in mesh.conical_residuals() {
        conical.see(r, || format!("vertex {v}"));
    }
    let kinematics = match cut {
        Some(_) => [pinned, pins_match, rhombic],
        None => [legs, rhombic, axis],
    };
    let rows = [units_on_faces, congruent, orientation]
        .into_iter()
        .chain(kinematics)
        .chain(cut.is_none().then_some(params))
        .chain([fitted, gaps, overlaps, coverage])
        .chain(joints)
        .chain([planar, conical])
        .map(Worst::row)
        .collect();
    CheckReport { rows }
}

/// The rows of the joints recorded in `links[].joint` (none when the file has none): each
/// remeasured on the file's plates against the record. Whether the joints hold their limits
/// is the fold check's question, asked of the parts as cut (`sv_strips::fold_check`).
fn check_joints(
    frame: &FrameFile,
    expanded: &[Option<[Point3; 4]>],
    slot: &dyn Fn(usize, usize, usize) -> Option<usize>,
) -> Vec<Worst> {
    if !frame.joints_closed() {
        return Vec::new();
    }
    let thickness = frame.params.thickness.unwrap_or(0.0);
    let mut claims = Worst::max("joint records = the plates in the file (mm, rad)", 1e-6);
    let mut unrecorded = Worst::max("links without a joint record", 0.0);
    // the plates as cut: half the joint slot off every side a bridge joins
    let half = frame.params.cut.map_or(0.0, |c| c.plate_inset());
    let mut insets = vec![[0.0; 4]; frame.units.len()];
    for l in &frame.links {
        if l.joint.is_some_and(|j| j.kind == JointKind::Bridge) {
            for u in l.units {
                if let (Some(k), Some(inset)) = (slot(u, l.edge[0], l.edge[1]), insets.get_mut(u)) {
                    inset[k] = half;
                }
            }
        }
    }
    for (li, l) in frame.links.iter().enumerate() {
        let [a, b] = l.units;
        let at = || {
            let id = |u: usize| frame.units.get(u).map_or("?".into(), |r| r.id.clone());
            format!("link {li} ({} - {})", id(a), id(b))
        };
        let Some(j) = l.joint else {
            unrecorded.see(1.0, at);
            continue;
        };
        let (Some(k), Some(m)) = (slot(a, l.edge[0], l.edge[1]), slot(b, l.edge[0], l.edge[1]))
        else {
            claims.see(Real::INFINITY, at);
            continue;
        };
        let (Some(Some(pa)), Some(Some(pb))) = (expanded.get(a), expanded.get(b)) else {
            claims.see(Real::INFINITY, at);
            continue;
        };
        let r = crate::joint::joint_record(
            [pa, pb],
            [insets[a], insets[b]],
            [k, m],
            j.along[0],
            j.kind,
            thickness,
        );
        claims.see(
            [
                r.gap - j.gap,
                r.bend - j.bend,
                r.twist - j.twist,
                r.collision - j.collision,
                r.along[1] - j.along[1],
            ]
            .iter()
            .fold(0.0, |m: Real, v| m.max(v.abs())),
            at,
        );
    }
    vec![claims, unrecorded]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{solve, SolveOptions, UnitProblem};

    /// A row keeps its worst value and where it was, a NaN once seen, and compares with its
    /// limit in its own sense; with nothing seen it holds.
    #[test]
    fn a_row_keeps_its_worst_and_where() {
        let mut over = Worst::max("over", 2.5);
        for (v, at) in [(1.0, "a"), (3.0, "b"), (2.0, "c"), (3.0, "d")] {
            over.see(v, || at.into());
        }
        let row = over.row();
        assert_eq!((row.worst, row.at.as_str(), row.ok), (3.0, "b", false));
        let mut under = Worst::min("under", 1.5);
        for (v, at) in [(5.0, "a"), (2.0, "b"), (4.0, "c")] {
            under.see(v, || at.into());
        }
        let row = under.row();
        assert_eq!((row.worst, row.at.as_str(), row.ok), (2.0, "b", true));
        let mut nan = Worst::max("nan", 1.0);
        for (v, at) in [(0.5, "a"), (Real::NAN, "b"), (9.0, "c")] {
            nan.see(v, || at.into());
        }
        let row = nan.row();
        assert!(row.worst.is_nan() && row.at == "b" && !row.ok);
        let (none_max, none_min) = (Worst::max("m", 0.0).row(), Worst::min("n", 1.0).row());
        assert_eq!(
            (none_max.worst, none_max.at.as_str(), none_max.ok),
            (0.0, "-", true)
        );
        // a lap row that measured no lap has not shown a lap reaches the minimum
        assert!(none_min.worst.is_infinite() && !none_min.ok, "{none_min:?}");
        assert_eq!(none_min.at, "nothing measured");
        let mut inf = Worst::min("inf", 1.0);
        inf.see(Real::INFINITY, || "a".into());
        assert!(!inf.row().ok);
        // a row without a limit informs, whatever it saw
        let mut info = Worst::max("info", Real::INFINITY);
        info.see(Real::INFINITY, || "a".into());
        assert!(info.row().ok);
    }

    /// A failing row lists every unit where a value was outside its limit, once each and
    /// in order; a row that holds lists none.
    #[test]
    fn a_failing_row_lists_the_units_outside_its_limit() {
        let mut welds = Worst::max("welds", 1.5);
        for (v, units) in [(2.0, [7, 3]), (1.0, [1, 2]), (1.6, [3, 5]), (0.2, [9, 0])] {
            welds.see_at(v, &units, || "link".into());
        }
        assert_eq!(welds.row().units, vec![3, 5, 7]);
        let mut laps = Worst::min("laps", 25.0);
        laps.see_at(30.0, &[4, 8], || "link".into());
        laps.see_at(20.0, &[6, 2], || "link".into());
        assert_eq!(laps.row().units, vec![2, 6]);
        let mut held = Worst::max("held", 1.5);
        held.see_at(1.2, &[1, 2], || "link".into());
        let row = held.row();
        assert!(row.ok && row.units.is_empty(), "{row:?}");
    }

    fn solved_cap() -> FrameFile {
        let mesh = QuadMesh::sphere_cap(5, 5, 3000.0, 300.0);
        solve(&mesh, &SolveOptions::default(), &mut |_| {})
            .unwrap()
            .to_frame_file(&mesh)
    }

    #[test]
    fn solved_frames_pass() {
        let r = check_frame(&solved_cap(), &CheckOptions::default());
        assert!(r.ok(), "{r:#?}");
        assert_eq!(r.rows.len(), 13);
    }

    /// A frame that lost its units, or got one twice, had every row pass: nothing measured
    /// the units that were not there.
    #[test]
    fn a_face_without_exactly_one_unit_fails_and_is_named() {
        let row = |f: &FrameFile| {
            check_frame(f, &CheckOptions::default())
                .rows
                .into_iter()
                .find(|r| r.name.starts_with("faces without exactly one unit"))
                .unwrap()
        };
        let good = solved_cap();
        assert!(row(&good).ok && good.unit_problems().is_empty());
        let mut none = good.clone();
        none.units.clear();
        none.links.clear();
        let r = row(&none);
        assert!(!r.ok && r.at == "the frame has no units", "{r:?}");
        assert!(!check_frame(&none, &CheckOptions::default()).ok());
        let mut twice = good.clone();
        twice.units.push(good.units[0].clone());
        let r = row(&twice);
        assert!(!r.ok && r.worst == 2.0, "{r:?}");
        let id = &good.units[0].id;
        assert_eq!(
            r.at,
            format!("face 0 has 2 units ({id}, {id}) (and 1 more)")
        );
        assert_eq!(
            twice.unit_problems()[1].to_string(),
            format!("duplicate unit id \"{id}\" (units[0] and units[25])")
        );
        // many units on one face: a few named, the rest counted
        let mut many = good.clone();
        for k in 0..40 {
            let mut u = good.units[0].clone();
            u.id = format!("X{k}");
            many.units.push(u);
        }
        assert_eq!(
            many.unit_problems()[0].to_string(),
            format!("face 0 has 41 units ({id}, X0, X1, ... and 38 more)")
        );
        let mut lost = good.clone();
        lost.units.remove(7);
        assert_eq!(
            lost.unit_problems(),
            vec![UnitProblem::FaceWithoutUnit { face: 7 }]
        );
        assert!(!row(&lost).ok);
    }

    fn solved_cap_as_cut() -> FrameFile {
        let mesh = QuadMesh::sphere_cap(5, 5, 3000.0, 300.0);
        let options = SolveOptions {
            cut: Some(sv_unit::CutWidths::STEEL_3MM),
            ..SolveOptions::default()
        };
        solve(&mesh, &options, &mut |_| {})
            .unwrap()
            .to_frame_file(&mesh)
    }

    #[test]
    fn frames_as_cut_pass_and_a_pose_moved_2_mm_is_caught_at_its_legs() {
        let f = solved_cap_as_cut();
        let r = check_frame(&f, &CheckOptions::default());
        assert!(r.ok(), "{r:#?}");
        assert!(r.rows.iter().any(|r| r.name.starts_with("leg pin to pin")));
        // the primary plate of unit 12 moved 2 mm along its normal: the legs no longer fit
        let mut moved = f.clone();
        let p = moved.units[12].primary.map(|c| pt(&c));
        let n = (p[2] - p[0]).cross(&(p[3] - p[1])).normalize();
        for c in &mut moved.units[12].primary {
            for k in 0..3 {
                c[k] += 2.0 * n[k];
            }
        }
        let r = check_frame(&moved, &CheckOptions::default());
        let legs = r
            .rows
            .iter()
            .find(|r| r.name.starts_with("leg pin to pin"))
            .unwrap();
        assert!(!legs.ok && legs.worst > 0.5, "{legs:?}");
        assert!(legs.at.contains(&moved.units[12].id), "{legs:?}");
    }

    #[test]
    fn moved_hub_corner_is_caught_and_named() {
        let mut f = solved_cap();
        f.units[7].hub[2][2] += 5.0;
        let r = check_frame(&f, &CheckOptions::default());
        assert!(!r.ok());
        let bad: Vec<_> = r.rows.iter().filter(|r| !r.ok).collect();
        assert!(
            bad.iter().any(|r| r.at.contains(&f.units[7].id)),
            "{bad:#?}"
        );
    }

    #[test]
    fn wrong_gap_and_missing_link_are_caught() {
        let mut f = solved_cap();
        f.links[3].primary_gap += 1.0;
        let r = check_frame(&f, &CheckOptions::default());
        assert!(r.rows.iter().any(|r| !r.ok && r.at.starts_with("link 3")));
        let mut f = solved_cap();
        f.links.pop();
        let r = check_frame(&f, &CheckOptions::default());
        assert!(r
            .rows
            .iter()
            .any(|r| !r.ok && r.name.contains("without a link")));
    }

    #[test]
    fn mirrored_primary_is_not_congruent_by_a_rotation() {
        let mut f = solved_cap();
        // reflect unit 0's primary tile through its own plane of diagonals: swap corners 1, 3
        f.units[0].primary.swap(1, 3);
        let r = check_frame(&f, &CheckOptions::default());
        assert!(!r.ok());
    }
}
