//! Quality figures of a hub mesh against its target.

use serde::{Deserialize, Serialize};
use sv_frame::QuadMesh;
use sv_geom::{quad_diagonal_distance, Point3, Real};

use crate::target::TargetIndex;
use crate::topology::Topology;
use crate::TargetMesh;

/// Edge ratio (max edge / min edge of a face) counted as "nearly square".
pub const EDGE_RATIO_LIMIT: Real = 1.25;

/// Measured quality of a secondary (hub) mesh. Lengths are relative to the mesh's mean
/// edge (the actual unit side), angles in degrees.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SecondaryReport {
    /// Faces (units).
    pub faces: usize,
    /// Vertices.
    pub vertices: usize,
    /// Mean edge length (mm).
    pub mean_edge: Real,
    /// The requested unit size (mm) the face sides are measured against.
    #[serde(default)]
    pub unit_size: Real,
    /// Largest diagonal distance / face mean edge.
    pub planarity_max: Real,
    /// Face with the largest planarity residual.
    pub planarity_worst_face: usize,
    /// Largest conical residual (degrees) over interior vertices: the angle balance
    /// `|w1 - w2 + w3 - w4|` at four faces, the largest angle between a face normal and
    /// the best-fit cone of normals at five or more (valence 3 is always conical); the
    /// same figure as `sv_frame::QuadMesh::conical_residuals`, which is in radians.
    pub conical_max_deg: Real,
    /// Vertex with the largest conical residual.
    pub conical_worst_vertex: usize,
    /// Largest vertex distance to the target / mean edge.
    pub closeness_max: Real,
    /// Vertex farthest from the target.
    pub closeness_worst_vertex: usize,
    /// Largest boundary-vertex distance to the target boundary curve / mean edge.
    pub boundary_max: Real,
    /// Boundary vertex farthest from the boundary curve.
    pub boundary_worst_vertex: usize,
    /// Fraction of target area within 0.1 mean edge of the hub mesh (sampled at target
    /// triangle centroids, area weighted).
    pub coverage: Real,
    /// Fraction of faces with max edge / min edge <= [`EDGE_RATIO_LIMIT`].
    pub edge_ratio_fraction: Real,
    /// Largest edge ratio of any face.
    pub edge_ratio_max: Real,
    /// Largest rhombus-fit residual: max distance between a face's corners and the
    /// corners of its best-fit rhombus (`sv_frame::Hub::fit`, the hub the primary tile is
    /// congruent to) / the face's mean edge.
    pub rhombus_fit_max: Real,
    /// Face with the largest rhombus-fit residual.
    pub rhombus_fit_worst_face: usize,
    /// Shortest face side / the requested unit size.
    #[serde(default)]
    pub side_min: Real,
    /// Longest face side / the requested unit size.
    #[serde(default)]
    pub side_max: Real,
    /// Interior vertices with other than four faces (valence 3, 5, ...), in index order.
    #[serde(default)]
    pub irregular_vertices: Vec<usize>,
    /// Faces that are not strictly convex (an angle at or above 180 degrees).
    pub non_convex_faces: Vec<usize>,
    /// Gauss-Newton iterations run.
    pub iterations: usize,
    /// Goals not met, one line each naming the worst place. Empty when all goals hold.
    pub unmet: Vec<String>,
    /// The layout the hub mesh was drawn from, and the automatic ones tried before it
    /// that did not fit (empty where the mesh was only measured).
    #[serde(default)]
    pub layout: String,
}

/// Acceptance goals checked into [`SecondaryReport::unmet`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goals {
    /// Planarity max.
    pub planarity: Real,
    /// Conical residual max (degrees).
    pub conical_deg: Real,
    /// Closeness max (fraction of the mean edge).
    pub closeness: Real,
    /// Boundary distance max (fraction of the mean edge).
    pub boundary: Real,
    /// Covered fraction of target area.
    pub coverage: Real,
    /// Fraction of faces with edge ratio <= 1.25.
    pub edge_ratio_fraction: Real,
    /// Every face side within this range of the requested unit size.
    pub side_range: (Real, Real),
}

impl Default for Goals {
    /// The acceptance goals of issue 3.
    fn default() -> Self {
        Self {
            planarity: 0.002,
            conical_deg: 0.5,
            closeness: 0.05,
            boundary: 0.05,
            coverage: 0.85,
            edge_ratio_fraction: 0.95,
            side_range: (0.7, 1.4),
        }
    }
}

/// The quality figures and unmet goals of `mesh` as a hub mesh on the target of `index`
/// for the requested `unit_size` (mm), the figures [`crate::build_secondary`] reports.
pub fn measure_hub_mesh(
    index: &TargetIndex<'_>,
    mesh: &QuadMesh,
    unit_size: Real,
) -> Result<SecondaryReport, crate::SurfaceError> {
    let topo = Topology::new(mesh)?;
    Ok(measure(mesh, &topo, index, 0, unit_size, &Goals::default()))
}

pub(crate) fn measure(
    mesh: &QuadMesh,
    topo: &Topology,
    index: &TargetIndex<'_>,
    iterations: usize,
    unit_size: Real,
    goals: &Goals,
) -> SecondaryReport {
    let mean = mesh.mean_edge().max(1e-300);
    let mut r = SecondaryReport {
        faces: mesh.faces.len(),
        vertices: mesh.vertices.len(),
        mean_edge: mean,
        unit_size,
        planarity_max: 0.0,
        planarity_worst_face: 0,
        conical_max_deg: 0.0,
        conical_worst_vertex: 0,
        closeness_max: 0.0,
        closeness_worst_vertex: 0,
        boundary_max: 0.0,
        boundary_worst_vertex: 0,
        coverage: 0.0,
        edge_ratio_fraction: 0.0,
        edge_ratio_max: 0.0,
        rhombus_fit_max: 0.0,
        rhombus_fit_worst_face: 0,
        side_min: Real::INFINITY,
        side_max: 0.0,
        irregular_vertices: topo
            .stars
            .iter()
            .filter(|s| s.faces.len() != 4)
            .map(|s| s.vertex)
            .collect(),
        non_convex_faces: Vec::new(),
        iterations,
        unmet: Vec::new(),
        layout: String::new(),
    };
    let mut good = 0usize;
    let (mut side_min_face, mut side_max_face) = (0, 0);
    for (f, face) in mesh.faces.iter().enumerate() {
        let p = mesh.face_points(f);
        let e = [0, 1, 2, 3].map(|k| (p[(k + 1) % 4] - p[k]).norm());
        for &len in &e {
            if len / unit_size < r.side_min {
                r.side_min = len / unit_size;
                side_min_face = f;
            }
            if len / unit_size > r.side_max {
                r.side_max = len / unit_size;
                side_max_face = f;
            }
        }
        let fm = e.iter().sum::<Real>() / 4.0;
        let plan = quad_diagonal_distance(&p) / fm.max(1e-300);
        if plan > r.planarity_max {
            r.planarity_max = plan;
            r.planarity_worst_face = f;
        }
        let ratio = e.iter().copied().fold(0.0, Real::max)
            / e.iter()
                .copied()
                .fold(Real::INFINITY, Real::min)
                .max(1e-300);
        r.edge_ratio_max = r.edge_ratio_max.max(ratio);
        if ratio <= EDGE_RATIO_LIMIT {
            good += 1;
        }
        let n = (p[0] - p[2]).cross(&(p[1] - p[3]));
        let convex = (0..4).all(|k| {
            (p[(k + 1) % 4] - p[k])
                .cross(&(p[(k + 2) % 4] - p[(k + 1) % 4]))
                .dot(&n)
                > 0.0
        });
        if !convex {
            r.non_convex_faces.push(f);
        }
        let fit = rhombus_fit(&p) / fm.max(1e-300);
        if fit > r.rhombus_fit_max {
            r.rhombus_fit_max = fit;
            r.rhombus_fit_worst_face = f;
        }
        let _ = face;
    }
    r.edge_ratio_fraction = good as Real / mesh.faces.len().max(1) as Real;
    for (v, c) in mesh.conical_residuals() {
        let deg = c.to_degrees();
        if deg > r.conical_max_deg {
            r.conical_max_deg = deg;
            r.conical_worst_vertex = v;
        }
    }
    for (v, p) in mesh.vertices.iter().enumerate() {
        let d = (index.closest(p).point - p).norm() / mean;
        if d > r.closeness_max {
            r.closeness_max = d;
            r.closeness_worst_vertex = v;
        }
        if topo.boundary[v] {
            let b = (index.closest_on_boundary(p).point - p).norm() / mean;
            if b > r.boundary_max {
                r.boundary_max = b;
                r.boundary_worst_vertex = v;
            }
        }
    }
    let (cov, uncovered) = coverage(mesh, index.mesh, mean);
    r.coverage = cov;
    let g = goals;
    let pct = |x: Real| 100.0 * x;
    if r.planarity_max > g.planarity {
        r.unmet.push(format!(
            "planarity {:.5} > {} at face {} (diagonal distance {:.1} mm, {:.2} % of the side)",
            r.planarity_max,
            g.planarity,
            r.planarity_worst_face,
            r.planarity_max * mean,
            pct(r.planarity_max)
        ));
    }
    if r.conical_max_deg > g.conical_deg {
        r.unmet.push(format!(
            "conical residual {:.3} deg > {} deg at vertex {}",
            r.conical_max_deg, g.conical_deg, r.conical_worst_vertex
        ));
    }
    if r.closeness_max > g.closeness {
        r.unmet.push(format!(
            "distance to target {:.1} mm ({:.1} % of the side) > {} % at vertex {}",
            r.closeness_max * mean,
            pct(r.closeness_max),
            pct(g.closeness),
            r.closeness_worst_vertex
        ));
    }
    if r.boundary_max > g.boundary {
        r.unmet.push(format!(
            "distance to boundary {:.1} mm ({:.1} % of the side) > {} % at vertex {}",
            r.boundary_max * mean,
            pct(r.boundary_max),
            pct(g.boundary),
            r.boundary_worst_vertex
        ));
    }
    if r.coverage < g.coverage {
        let near = uncovered
            .map(|p| {
                let v = (0..mesh.vertices.len())
                    .min_by(|&a, &b| {
                        (mesh.vertices[a] - p)
                            .norm()
                            .total_cmp(&(mesh.vertices[b] - p).norm())
                    })
                    .unwrap_or(0);
                format!(
                    "; the target farthest from the mesh is at ({:.0}, {:.0}, {:.0}) mm, near vertex {v}",
                    p.x, p.y, p.z
                )
            })
            .unwrap_or_default();
        r.unmet
            .push(format!("coverage {:.3} < {}{near}", r.coverage, g.coverage));
    }
    if r.edge_ratio_fraction < g.edge_ratio_fraction {
        r.unmet.push(format!(
            "faces with edge ratio <= {EDGE_RATIO_LIMIT}: {:.3} < {} (max ratio {:.2})",
            r.edge_ratio_fraction, g.edge_ratio_fraction, r.edge_ratio_max
        ));
    }
    let (lo, hi) = g.side_range;
    if r.side_min < lo || r.side_max > hi {
        let (side, f) = if r.side_min < lo {
            (r.side_min, side_min_face)
        } else {
            (r.side_max, side_max_face)
        };
        r.unmet.push(format!(
            "face sides {:.2}..{:.2} of the unit size, outside {lo}..{hi}, worst {:.0} mm at face {f}",
            r.side_min,
            r.side_max,
            side * unit_size
        ));
    }
    if let Some(&f) = r.non_convex_faces.first() {
        r.unmet.push(format!(
            "{} non-convex face(s), first face {f}",
            r.non_convex_faces.len()
        ));
    }
    r
}

/// Max distance between the corners of `quad` and those of its best-fit rhombus (mm);
/// infinite when no rhombus fits (degenerate face).
pub(crate) fn rhombus_fit(quad: &[Point3; 4]) -> Real {
    match sv_frame::Hub::fit(quad, 0.0) {
        Some(h) => (0..4)
            .map(|k| (h.corner(k) - quad[k]).norm())
            .fold(0.0, Real::max),
        None => Real::INFINITY,
    }
}

/// Area fraction of the target within `0.1 * mean` of the hub mesh (triangulated), and the
/// sampled target point farthest from the mesh when some are not covered.
pub(crate) fn coverage(mesh: &QuadMesh, target: &TargetMesh, mean: Real) -> (Real, Option<Point3>) {
    let mut tri = TargetMesh {
        vertices: mesh.vertices.clone(),
        triangles: Vec::with_capacity(mesh.faces.len() * 4),
    };
    // split each quad into 4 triangles around its centroid (symmetric, no diagonal bias)
    for f in &mesh.faces {
        let c = tri.vertices.len();
        let centre = Point3::from(
            f.iter()
                .map(|&i| mesh.vertices[i].coords)
                .sum::<sv_geom::Vector3>()
                / 4.0,
        );
        tri.vertices.push(centre);
        for k in 0..4 {
            tri.triangles.push([f[k], f[(k + 1) % 4], c]);
        }
    }
    let Ok(index) = TargetIndex::new(&tri) else {
        return (0.0, None);
    };
    let v = &target.vertices;
    let mut covered = 0.0;
    let mut total = 0.0;
    let mut farthest: Option<(Real, Point3)> = None;
    let mut hint = None;
    for t in &target.triangles {
        let a = crate::target::triangle_area(v, t);
        let c = Point3::from((v[t[0]].coords + v[t[1]].coords + v[t[2]].coords) / 3.0);
        total += a;
        let cp = index.closest_near(&c, hint);
        hint = Some(cp.triangle);
        let d = (cp.point - c).norm();
        if d <= 0.1 * mean {
            covered += a;
        } else if farthest.is_none_or(|f| d > f.0) {
            farthest = Some((d, c));
        }
    }
    if total > 0.0 {
        (covered / total, farthest.map(|f| f.1))
    } else {
        (0.0, None)
    }
}
