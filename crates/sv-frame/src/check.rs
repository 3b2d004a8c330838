//! Re-verification of a frame file against the invariants of model.md.

use sv_geom::{segment_closest, Matrix3, Point3, Real, Vector3};

use crate::solve::hub_overlap;
use crate::{FrameFile, Hub, QuadMesh};

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

/// One row of the check table.
#[derive(Clone, Debug, PartialEq)]
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
}

/// The check table.
#[derive(Clone, Debug, PartialEq, Default)]
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

/// Tracks the worst value of one check.
struct Worst {
    name: &'static str,
    limit: Real,
    worst: Real,
    at: String,
}

impl Worst {
    fn new(name: &'static str, limit: Real) -> Self {
        Self {
            name,
            limit,
            worst: 0.0,
            at: "-".into(),
        }
    }
    fn see(&mut self, value: Real, at: impl FnOnce() -> String) {
        // NaN is always the worst, and stays
        let worse = value.is_nan() || value > self.worst || (self.at == "-" && value >= self.worst);
        if worse && !self.worst.is_nan() {
            self.worst = value;
            self.at = at();
        }
    }
    fn row(self) -> CheckRow {
        CheckRow {
            ok: self.worst <= self.limit,
            name: self.name.into(),
            worst: self.worst,
            limit: self.limit,
            at: self.at,
        }
    }
}

fn pt(a: &[Real; 3]) -> Point3 {
    Point3::new(a[0], a[1], a[2])
}

/// Rigid fit (Kabsch) of `from` onto `to`: largest residual and whether the best
/// orthogonal map is a proper rotation.
fn rigid_fit(from: &[Point3; 4], to: &[Point3; 4]) -> (Real, bool) {
    let cf = from.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0;
    let ct = to.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0;
    let mut h = Matrix3::zeros();
    for i in 0..4 {
        h += (to[i].coords - ct) * (from[i].coords - cf).transpose();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return (Real::NAN, false);
    };
    let proper = (u * vt).determinant() > 0.0;
    let mut d = Matrix3::identity();
    if !proper {
        d[(2, 2)] = -1.0;
    }
    let r = u * d * vt;
    let res = (0..4)
        .map(|i| (r * (from[i].coords - cf) + ct - to[i].coords).norm())
        .fold(0.0, Real::max);
    // a reflection fits as well as the rotation only for flat sets; then check orientation
    let n_from = (from[0] - from[2]).cross(&(from[1] - from[3]));
    let n_to = (to[0] - to[2]).cross(&(to[1] - to[3]));
    let proper_flat = (r * n_from).dot(&n_to) > 0.0;
    (res, proper_flat)
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
    let mut congruent = Worst::new("hub congruent to primary (residual / side)", rel);
    let mut legs = Worst::new("leg length = side (relative error)", rel);
    let mut rhombic = Worst::new("primary is a rhombus (relative error)", rel);
    let mut axis = Worst::new("closed form reproduces hub (mm)", abs);
    let mut params = Worst::new("theta, phi match the file (rad)", 1e-6);
    let mut fitted = Worst::new("hub = spun best-fit rhombus of face (mm)", abs);
    let mut gaps = Worst::new("link gap matches file (mm)", abs);
    let mut overlaps = Worst::new("hub overlap matches file (mm)", abs);
    let mut coverage = Worst::new("interior edges without a link", 0.0);
    let mut orientation = Worst::new("hub and primary same orientation (0/1)", 0.0);

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
        for i in 0..4 {
            let s = (prim[i] - prim[(i + 1) % 4]).norm();
            let leg = (hub[i] - prim[(i + 1) % 4]).norm();
            legs.see((leg - s).abs() / s, || format!("unit {} leg {i}", u.id));
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
                frame.params.spin_angle,
            )
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
        let o = hub_overlap(
            &Point3::from(ca),
            &pt(&ua.hub[k]),
            &Point3::from(cb),
            &pt(&ub.hub[m]),
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

    let mut planar = Worst::new(
        "face planarity (diagonal distance / mean edge)",
        options.planarity_tolerance,
    );
    for (f, r) in mesh.planarity_residuals().into_iter().enumerate() {
        planar.see(r, || format!("face {f}"));
    }
    let mut conical = Worst::new(
        "conical residual (rad, any valence)",
        options.conical_tolerance,
    );
    for (v, r) in mesh.conical_residuals() {
        conical.see(r, || format!("vertex {v}"));
    }
    let rows = [
        congruent,
        orientation,
        legs,
        rhombic,
        axis,
        params,
        fitted,
        gaps,
        overlaps,
        coverage,
        planar,
        conical,
    ]
    .into_iter()
    .map(Worst::row)
    .collect();
    CheckReport { rows }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{solve, SolveOptions};

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
        assert_eq!(r.rows.len(), 12);
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
