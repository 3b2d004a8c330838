//! Poses of tiles, tolerance checks, rigid registration (Kabsch) and the assembly sequence.

use std::collections::{BTreeSet, HashMap};

use sv_frame::FrameFile;
use sv_geom::{Isometry3, Matrix3, Point3, UnitQuaternion, Vector3};

use crate::protocol::{Pose, Transform};

/// Collinearity threshold of registration points: the second principal spread over the first.
pub const DEFAULT_COLLINEAR_RATIO: f64 = 1e-3;

/// The pose of a quad tile: origin at the corner centroid, x toward corner 0, z along
/// `(c0 - c2) x (c1 - c3)`, `y = z x x`. `None` for a degenerate tile.
pub fn tile_pose(corners: &[[f64; 3]; 4]) -> Option<Isometry3> {
    let c = corners.map(|p| Point3::new(p[0], p[1], p[2]));
    let centroid = Point3::from((c[0].coords + c[1].coords + c[2].coords + c[3].coords) / 4.0);
    let z = (c[0] - c[2]).cross(&(c[1] - c[3])).try_normalize(1e-12)?;
    let x0 = c[0] - centroid;
    let x = (x0 - z * x0.dot(&z)).try_normalize(1e-12)?;
    let y = z.cross(&x);
    let m = Matrix3::from_columns(&[x, y, z]);
    let rotation =
        UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(m));
    Some(Isometry3::from_parts(centroid.coords.into(), rotation))
}

/// Wire pose of an isometry.
pub fn pose_of(iso: &Isometry3) -> Pose {
    let t = iso.translation.vector;
    let q = iso.rotation.coords; // nalgebra stores [x, y, z, w]
    Pose {
        position: [t.x, t.y, t.z],
        rotation: [q.x, q.y, q.z, q.w],
    }
}

/// Isometry of a wire pose; `None` unless finite with a non-zero quaternion.
///
/// The quaternion is scaled by its largest component before it is squared, so components up
/// to `f64::MAX` normalise exactly instead of overflowing to infinity (which would make every
/// rotation look like the identity).
pub fn iso_of(pose: &Pose) -> Option<Isometry3> {
    if !pose
        .position
        .iter()
        .chain(&pose.rotation)
        .all(|v| v.is_finite())
    {
        return None;
    }
    let [x, y, z, w] = pose.rotation;
    let big = pose.rotation.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if big == 0.0 {
        return None;
    }
    let q = nalgebra::Quaternion::new(w / big, x / big, y / big, z / big);
    let p = pose.position;
    Some(Isometry3::from_parts(
        Vector3::new(p[0], p[1], p[2]).into(),
        UnitQuaternion::new_normalize(q),
    ))
}

/// Length of a vector without overflow in the squares (scaled by its largest component).
pub fn safe_norm(v: &Vector3) -> f64 {
    let big = v.amax();
    if big == 0.0 || !big.is_finite() {
        return big;
    }
    big * (v / big).norm()
}

/// Compare a tracked pose with its target: (position error mm, angle error deg, target -
/// tracked), or `None` when a result is not a finite number (a pose near `f64::MAX`).
pub fn compare(target: &Isometry3, tracked: &Isometry3) -> Option<(f64, f64, [f64; 3])> {
    let d = target.translation.vector - tracked.translation.vector;
    let angle = target.rotation.angle_to(&tracked.rotation).to_degrees();
    let distance = safe_norm(&d);
    [distance, angle, d.x, d.y, d.z]
        .iter()
        .all(|v| v.is_finite())
        .then_some((distance, angle, [d.x, d.y, d.z]))
}

/// Result of a rigid fit.
#[derive(Clone, Debug)]
pub struct Fit {
    /// `site = iso * model`.
    pub iso: Isometry3,
    /// RMS residual (mm).
    pub rms: f64,
    /// Residual per point (mm).
    pub residuals: Vec<f64>,
}

impl Fit {
    /// Wire form.
    pub fn transform(&self) -> Transform {
        transform_of(&self.iso, self.rms)
    }
}

/// Wire form of an isometry plus its RMS.
pub fn transform_of(iso: &Isometry3, rms: f64) -> Transform {
    let p = pose_of(iso);
    Transform {
        rotation: p.rotation,
        translation: p.position,
        rms_mm: rms,
    }
}

/// Why a fit failed.
#[derive(Clone, Debug, PartialEq)]
pub enum FitError {
    /// Fewer than 3 pairs, non-finite values, or collinear model points.
    Degenerate(String),
}

/// Rigid (rotation + translation, no scale) least-squares fit of `measured ~ R model + t`
/// (Kabsch). Rejects fewer than 3 pairs and collinear or coincident model points: the second
/// principal spread must be at least `collinear_ratio` times the first.
pub fn kabsch(pairs: &[[[f64; 3]; 2]], collinear_ratio: f64) -> Result<Fit, FitError> {
    if pairs.len() < 3 {
        return Err(FitError::Degenerate(format!(
            "{} point pairs, need at least 3",
            pairs.len()
        )));
    }
    if !pairs.iter().flatten().flatten().all(|v| v.is_finite()) {
        return Err(FitError::Degenerate("non-finite coordinate".into()));
    }
    let to_v = |p: &[f64; 3]| Vector3::new(p[0], p[1], p[2]);
    let n = pairs.len() as f64;
    let cm = pairs.iter().map(|p| to_v(&p[0])).sum::<Vector3>() / n;
    let mut cov = Matrix3::zeros();
    for p in pairs {
        let a = to_v(&p[0]) - cm;
        cov += a * a.transpose();
    }
    let mut spread = cov
        .symmetric_eigenvalues()
        .iter()
        .map(|v| v.max(0.0).sqrt())
        .collect::<Vec<_>>();
    spread.sort_by(|a, b| b.total_cmp(a));
    if spread[0] < 1e-6 || spread[1] < collinear_ratio * spread[0] {
        return Err(FitError::Degenerate(
            "model points are collinear or coincident".into(),
        ));
    }
    let model: Vec<Point3> = pairs.iter().map(|p| Point3::from(to_v(&p[0]))).collect();
    let measured: Vec<Point3> = pairs.iter().map(|p| Point3::from(to_v(&p[1]))).collect();
    let (iso, _) = sv_geom::rigid_fit(&model, &measured).ok_or_else(|| {
        FitError::Degenerate("coordinates too large: the fit is not a finite number".into())
    })?;
    let residuals: Vec<f64> = pairs
        .iter()
        .map(|p| (iso * Point3::from(to_v(&p[0])) - Point3::from(to_v(&p[1]))).norm())
        .collect();
    let rms = (residuals.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
    let p = pose_of(&iso);
    if !(rms.is_finite() && p.position.iter().chain(&p.rotation).all(|v| v.is_finite())) {
        return Err(FitError::Degenerate(
            "coordinates too large: the fit is not a finite number".into(),
        ));
    }
    Ok(Fit {
        iso,
        rms,
        residuals,
    })
}

/// One unit's design target: the corners of its hub and primary tile (mm, model frame) and
/// the poses the protocol derives from them ([`tile_pose`]).
#[derive(Clone, Debug, PartialEq)]
pub struct UnitTarget {
    /// Hub corners.
    pub hub: [[f64; 3]; 4],
    /// Primary tile corners.
    pub primary: [[f64; 3]; 4],
    /// Hub pose.
    pub hub_pose: Isometry3,
    /// Primary tile pose.
    pub primary_pose: Isometry3,
}

/// Every unit's target, in file order: the one place the streamer takes target corners and
/// poses from a frame: the hub plate as cut (`hub_plate`, frame.json v2; the `hub` rhombus
/// of older files) and the `primary` plate.
/// An error names the unit whose tile is not finite or degenerate.
pub fn unit_targets(frame: &FrameFile) -> Result<Vec<UnitTarget>, String> {
    let ids = unit_ids(frame);
    frame
        .units
        .iter()
        .enumerate()
        .map(|(i, u)| {
            // the hub plate as cut where the frame has it (same pose, the plate's outline)
            let hub = u.hub_plate.unwrap_or(u.hub);
            let finite = hub
                .iter()
                .chain(&u.primary)
                .flatten()
                .all(|v| v.is_finite());
            match (finite, tile_pose(&hub), tile_pose(&u.primary)) {
                (true, Some(hub_pose), Some(primary_pose)) => Ok(UnitTarget {
                    hub,
                    primary: u.primary,
                    hub_pose,
                    primary_pose,
                }),
                _ => Err(format!("unit {} (index {i}) has a degenerate tile", ids[i])),
            }
        })
        .collect()
}

/// The design hub overlap (mm) of every link, keyed by its unit indices (smaller first): the
/// one place the streamer takes the expected overlap from: the link's `hub_overlap`, which
/// frame.json v2 measures on the hub plates as cut.
pub fn design_overlaps(frame: &FrameFile) -> Result<HashMap<(usize, usize), f64>, String> {
    let n = frame.units.len();
    let mut out = HashMap::new();
    for l in &frame.links {
        let [a, b] = l.units;
        if a >= n || b >= n || a == b {
            return Err(format!("link {a}-{b} does not join two units of the frame"));
        }
        if !l.hub_overlap.is_finite() {
            return Err(format!("link {a}-{b} has a non-finite hub_overlap"));
        }
        out.insert((a.min(b), a.max(b)), l.hub_overlap);
    }
    Ok(out)
}

/// Wire id of each unit: its `id` label when present (`"A03-02"`), else its index (`"7"`)
/// ([`FrameFile::unit_labels`], the labels `spinvalence check` names units by).
pub fn unit_ids(frame: &FrameFile) -> Vec<String> {
    frame.unit_labels()
}

/// Strip of each unit: its `strip` field when set, else the part of its label before the
/// first `-` (`"A03"` of `"A03-02"`), else `None`.
pub fn unit_strips(frame: &FrameFile) -> Vec<Option<String>> {
    frame
        .units
        .iter()
        .map(|u| {
            let strip = u.strip.trim();
            if !strip.is_empty() {
                return Some(strip.to_string());
            }
            match u.id.trim().split_once('-') {
                Some((s, _)) if !s.is_empty() => Some(s.to_string()),
                _ => None,
            }
        })
        .collect()
}

/// The assembly sequence (unit indices): strip by strip, each unit next to one already placed
/// whenever the mesh allows it.
///
/// Strips are taken in order of first appearance in the file; the first strip starts at its
/// unit with the fewest same-strip neighbours (a strip end). Within a strip the next unit is
/// the lowest-index unplaced unit of that strip adjacent to a placed unit. The next strip is
/// the first (in file order) with an unplaced unit adjacent to a placed one; it starts at that
/// unit. Disconnected parts start over at a strip end. Units without a strip
/// ([`unit_strips`]) form one group.
pub fn assembly_sequence(frame: &FrameFile) -> Vec<usize> {
    let strips = unit_strips(frame);
    let n = frame.units.len();
    let mut adj: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); n];
    for l in &frame.links {
        let [a, b] = l.units;
        if a < n && b < n && a != b {
            adj[a].insert(b);
            adj[b].insert(a);
        }
    }
    let mut strip_order: Vec<Option<&str>> = Vec::new();
    let mut strip_of: HashMap<Option<&str>, usize> = HashMap::new();
    let strip_idx: Vec<usize> = strips
        .iter()
        .map(|s| {
            let s = s.as_deref();
            *strip_of.entry(s).or_insert_with(|| {
                strip_order.push(s);
                strip_order.len() - 1
            })
        })
        .collect();
    let mut placed = vec![false; n];
    let mut seq = Vec::with_capacity(n);
    let touches = |u: usize, placed: &[bool]| adj[u].iter().any(|&v| placed[v]);
    while seq.len() < n {
        // choose the strip and its first unit
        let start = (0..n)
            .filter(|&u| !placed[u] && touches(u, &placed))
            .min_by_key(|&u| (strip_idx[u], u))
            .or_else(|| {
                (0..n).filter(|&u| !placed[u]).min_by_key(|&u| {
                    let same = adj[u]
                        .iter()
                        .filter(|&&v| strip_idx[v] == strip_idx[u])
                        .count();
                    (strip_idx[u], same, u)
                })
            });
        let Some(start) = start else { break };
        let strip = strip_idx[start];
        placed[start] = true;
        seq.push(start);
        loop {
            let next = (0..n)
                .filter(|&u| !placed[u] && strip_idx[u] == strip && touches(u, &placed))
                .min();
            match next {
                Some(u) => {
                    placed[u] = true;
                    seq.push(u);
                }
                None => break,
            }
        }
    }
    seq
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_of_square() {
        let c = [
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [-10.0, 0.0, 0.0],
            [0.0, -10.0, 0.0],
        ];
        let iso = tile_pose(&c).unwrap();
        let p = pose_of(&iso);
        assert!(p.position.iter().all(|v| v.abs() < 1e-12));
        assert!(p.rotation[3] > 0.999999);
        let back = iso_of(&p).unwrap();
        assert!((back.rotation.angle_to(&iso.rotation)).abs() < 1e-12);
    }

    #[test]
    fn huge_quaternions_keep_their_rotation() {
        // 90 degrees about z, scaled far beyond where squaring overflows
        let h = std::f64::consts::FRAC_1_SQRT_2;
        for scale in [1.0, 1e154, 1e300, f64::MAX / 2.0] {
            let pose = Pose {
                position: [0.0; 3],
                rotation: [0.0, 0.0, h * scale, h * scale],
            };
            let iso = iso_of(&pose).unwrap();
            let angle = iso.rotation.angle().to_degrees();
            assert!((angle - 90.0).abs() < 1e-9, "scale {scale}: {angle} deg");
        }
        let zero = Pose {
            position: [0.0; 3],
            rotation: [0.0; 4],
        };
        assert!(iso_of(&zero).is_none());
    }

    #[test]
    fn far_positions_give_finite_errors_or_none() {
        let target = Isometry3::identity();
        let far = iso_of(&Pose {
            position: [1e308, 1e308, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        })
        .unwrap();
        let (d, _, m) = compare(&target, &far).unwrap();
        assert!(d.is_finite() && d > 1.4e308, "{d}");
        assert_eq!(m[0], -1e308);
        let beyond = Isometry3::translation(-f64::MAX, 0.0, 0.0);
        let opposite = Isometry3::translation(f64::MAX, 0.0, 0.0);
        assert!(compare(&beyond, &opposite).is_none());
    }

    #[test]
    fn kabsch_recovers_motion() {
        let truth = Isometry3::new(
            Vector3::new(100.0, -20.0, 5.0),
            Vector3::new(0.1, 0.2, -0.3),
        );
        let model = [
            [0.0, 0.0, 0.0],
            [1000.0, 0.0, 0.0],
            [0.0, 800.0, 0.0],
            [300.0, 300.0, 400.0],
        ];
        let pairs: Vec<_> = model
            .iter()
            .map(|m| {
                let s = truth * Point3::new(m[0], m[1], m[2]);
                [*m, [s.x, s.y, s.z]]
            })
            .collect();
        let fit = kabsch(&pairs, DEFAULT_COLLINEAR_RATIO).unwrap();
        assert!(fit.rms < 1e-9);
        assert!(fit.iso.rotation.angle_to(&truth.rotation) < 1e-9);
        let line: Vec<_> = (0..4)
            .map(|i| [[i as f64, 2.0 * i as f64, 0.0]; 2])
            .collect();
        assert!(kabsch(&line, DEFAULT_COLLINEAR_RATIO).is_err());
    }
}
