//! The last automatic layout: the footprint triangulated in plan, neighbouring triangles
//! paired into convex quads, every quad split into four and every triangle left into three
//! (corner, edge midpoint, centre, edge midpoint), and the result smoothed in plan.
//!
//! It fits any footprint that is a single sheet over the target's plane: any number of
//! corners, reflex or not, and any number of holes. What it costs is irregular vertices:
//! a valence-3 vertex at every unpaired triangle's centre (its faces start as kites, sides
//! `1 : 0.58`) and the count of coarse faces at every coarse vertex, none of them where
//! the curvature wants them, so the hub mesh misses the conical goal at most of them. It is
//! only drawn where the layouts that follow the footprint start folded or with collapsed
//! edges (or there are three or more boundary loops), so that a valid target still gets a
//! hub mesh, its files and its unmet goals named, instead of no file at all.
//!
//! The triangulation is spade's constrained Delaunay triangulation of the boundary loops
//! (sampled at every corner and evenly between), refined to a largest area and a smallest
//! angle with the loops kept as they are sampled; interior points are lifted back onto
//! the target through its own triangles seen in plan.

use std::collections::HashMap;

use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};
use sv_frame::QuadMesh;
use sv_geom::{Point3, Real, Vector3};

use crate::target::{loop_arc, loop_at, TargetIndex};

/// Side of the coarse triangles, in units: a paired quad of side `s` splits into four of
/// side `s / 2` and a triangle left into kites whose sides (`s / 2` and `s / (2 sqrt 3)`)
/// have a mean of about `0.39 s`, so that this side subdivides every coarse face into about
/// 2 x 2 faces (fewer irregular vertices than 1 x 1, while the triangles stay small enough
/// for a court or an arm a few units wide).
pub(crate) const TRIANGLE_SIDE: Real = 5.0;

/// Fewest points of a loop without corners (a round court): three would make it a
/// triangle, whose faces fold where the court's round side bulges past its chords.
const ROUND_LOOP: usize = 8;

/// Smallest angle the refinement asks of a coarse triangle (degrees).
const SMALLEST_ANGLE: Real = 25.0;

/// The target's own triangles in plan (the target frame's plane), for lifting a point of
/// the plan onto the target.
pub(crate) struct Plan {
    centre: Point3,
    d1: Vector3,
    d2: Vector3,
    triangles: Vec<[[Real; 2]; 3]>,
    corners: Vec<[Point3; 3]>,
}

impl Plan {
    pub(crate) fn new(index: &TargetIndex<'_>) -> Self {
        let frame = crate::param::target_frame(index.mesh);
        let v = &index.mesh.vertices;
        let mut plan = Plan {
            centre: frame.centre,
            d1: frame.d1,
            d2: frame.d2,
            triangles: Vec::new(),
            corners: Vec::new(),
        };
        for t in &index.mesh.triangles {
            let p = t.map(|i| v[i]);
            plan.triangles.push(p.map(|q| plan.at(&q)));
            plan.corners.push(p);
        }
        plan
    }

    pub(crate) fn at(&self, p: &Point3) -> [Real; 2] {
        let d = p - self.centre;
        [d.dot(&self.d1), d.dot(&self.d2)]
    }

    /// The target's point over `q`, where exactly one sheet of it lies over `q`.
    pub(crate) fn lift(&self, q: [Real; 2]) -> Option<Point3> {
        let mut found: Option<Point3> = None;
        for (t, p) in self.triangles.iter().zip(&self.corners) {
            let area = cross(t[0], t[1], t[2]);
            if area.abs() < 1e-12 {
                continue;
            }
            let l = [
                cross(q, t[1], t[2]) / area,
                cross(t[0], q, t[2]) / area,
                cross(t[0], t[1], q) / area,
            ];
            if l.iter().all(|&x| x >= -1e-9) {
                let here =
                    Point3::from(p[0].coords * l[0] + p[1].coords * l[1] + p[2].coords * l[2]);
                // a second sheet over the same point (not the next triangle of one sheet)
                if found.is_some_and(|f| (f - here).norm() > 1.0) {
                    return None;
                }
                found = Some(here);
            }
        }
        found
    }
}

/// Twice the signed area of the triangle `a b c` in plan.
fn cross(a: [Real; 2], b: [Real; 2], c: [Real; 2]) -> Real {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Points of one boundary loop for the triangulation: its corners and, between
/// consecutive corners, points evenly by arc length about `side` apart; [`ROUND_LOOP`] at
/// least on a loop without corners.
fn loop_samples(index: &TargetIndex<'_>, lp: &[usize], side: Real) -> Vec<Point3> {
    let v = &index.mesh.vertices;
    let arc = loop_arc(v, lp);
    let length = arc[lp.len()];
    let corners = crate::auto_layout::corners(index, lp, length / 40.0);
    let mut at: Vec<Real> = corners.iter().map(|c| arc[c.at]).collect();
    if at.is_empty() {
        at.push(0.0);
    }
    let mut out = Vec::new();
    for (k, &start) in at.iter().enumerate() {
        let mut end = at[(k + 1) % at.len()];
        if end <= start {
            end += length;
        }
        let pieces = (((end - start) / side).round() as usize).max(1);
        let pieces = if at.len() == 1 {
            pieces.max(ROUND_LOOP)
        } else {
            pieces
        };
        out.extend((0..pieces).map(|i| {
            loop_at(
                v,
                lp,
                &arc,
                start + (end - start) * i as Real / pieces as Real,
            )
        }));
    }
    out
}

/// The triangles paired into quads across their shared edges where the quad is convex,
/// the pairs whose worst corner is nearest a right angle first (greedy matching); the
/// triangles left over stay triangles (the smoothing evens out the quads' shapes, and an
/// unpaired triangle costs a valence-3 vertex, so any convex pair is taken). Every
/// polygon runs the way its triangles ran.
fn pair_triangles(vertices: &[Point3], triangles: &[[usize; 3]]) -> Vec<Vec<usize>> {
    let mut across: HashMap<(usize, usize), usize> = HashMap::new();
    let mut pairs: Vec<(Real, usize, usize, [usize; 4])> = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            // the neighbour lists the edge the other way
            let Some(&u) = across.get(&(b, a)) else {
                across.insert((a, b), t);
                continue;
            };
            let other = triangles[u];
            let apex = tri[(k + 2) % 3];
            let opposite = other
                .iter()
                .copied()
                .find(|&x| x != a && x != b)
                .unwrap_or(a);
            let quad = [a, opposite, b, apex];
            if let Some(turn) = corner_turn(vertices, &quad) {
                pairs.push((turn, u, t, quad));
            }
        }
    }
    pairs.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    let mut used = vec![false; triangles.len()];
    let mut out = Vec::new();
    for (_, u, t, quad) in pairs {
        if !used[u] && !used[t] {
            used[u] = true;
            used[t] = true;
            out.push(quad.to_vec());
        }
    }
    out.extend(
        (0..triangles.len())
            .filter(|&t| !used[t])
            .map(|t| triangles[t].to_vec()),
    );
    out
}

/// The largest turn of a quad's corner angles from a right angle (radians), or `None`
/// where the quad is not convex (its corners' normals disagree).
fn corner_turn(vertices: &[Point3], quad: &[usize; 4]) -> Option<Real> {
    let p = quad.map(|i| vertices[i]);
    let normal = (p[2] - p[0]).cross(&(p[3] - p[1]));
    let mut worst: Real = 0.0;
    for k in 0..4 {
        let (a, b) = (p[(k + 3) % 4] - p[k], p[(k + 1) % 4] - p[k]);
        if b.cross(&a).dot(&normal) <= 0.0 {
            return None;
        }
        worst = worst.max((a.angle(&b) - std::f64::consts::FRAC_PI_2).abs());
    }
    Some(worst)
}

/// The triangulated layout of `index`'s target with coarse triangles of about `side` (mm),
/// paired into convex quads, every quad split into four and every triangle left into
/// three, smoothed in plan; `None` where the footprint is not a single sheet over the
/// target's plane (a loop crossing itself or another in plan, a point of the plan with
/// two sheets of the target over it).
pub(crate) fn triangle_layout(index: &TargetIndex<'_>, side: Real) -> Option<QuadMesh> {
    // one size of triangle throughout, small enough for the shortest loop: the subdivision
    // cuts every chord of faces into one count, and a chord running from small triangles
    // by a round court to large ones far from it cut the small ones into slivers
    let v = &index.mesh.vertices;
    let shortest = index
        .loops
        .iter()
        .map(|lp| loop_arc(v, lp)[lp.len()])
        .fold(Real::INFINITY, Real::min);
    let side = side.min(shortest / ROUND_LOOP as Real);
    let plan = Plan::new(index);
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<Real>>::new();
    let mut position: HashMap<FixedVertexHandle, Point3> = HashMap::new();
    for lp in &index.loops {
        let samples = loop_samples(index, lp, side);
        let mut handles = Vec::with_capacity(samples.len());
        for p in &samples {
            let [x, y] = plan.at(p);
            let h = cdt.insert(Point2::new(x, y)).ok()?;
            position.insert(h, *p);
            handles.push(h);
        }
        for k in 0..handles.len() {
            let (a, b) = (handles[k], handles[(k + 1) % handles.len()]);
            if a == b || !cdt.can_add_constraint(a, b) {
                return None;
            }
            cdt.add_constraint(a, b);
        }
    }
    let area = 3.0_f64.sqrt() / 4.0 * side * side;
    let refined = cdt.refine(
        RefinementParameters::<Real>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_max_allowed_area(area)
            .with_angle_limit(AngleLimit::from_deg(SMALLEST_ANGLE)),
    );
    let outside: std::collections::HashSet<_> = refined.excluded_faces.into_iter().collect();
    // corners of the coarse triangles: the loops' samples where they are, the rest lifted
    let mut vertices: Vec<Point3> = Vec::new();
    let mut id: HashMap<FixedVertexHandle, usize> = HashMap::new();
    let mut triangles: Vec<[usize; 3]> = Vec::new();
    for face in cdt.inner_faces() {
        if outside.contains(&face.fix()) {
            continue;
        }
        let mut tri = [0usize; 3];
        for (k, vh) in face.vertices().iter().enumerate() {
            let h = vh.fix();
            let i = match id.get(&h) {
                Some(&i) => i,
                None => {
                    let p = match position.get(&h) {
                        Some(p) => *p,
                        None => plan.lift([vh.position().x, vh.position().y])?,
                    };
                    vertices.push(p);
                    id.insert(h, vertices.len() - 1);
                    vertices.len() - 1
                }
            };
            tri[k] = i;
        }
        triangles.push(tri);
    }
    if triangles.is_empty() {
        return None;
    }
    let coarse = pair_triangles(&vertices, &triangles);
    // every quad into four quads and every triangle left over into three (corner, edge
    // midpoint, centre, edge midpoint), the edge midpoints shared, all on the target
    let on_target = |p: Vector3| index.closest(&Point3::from(p)).point;
    let mut midpoint: HashMap<(usize, usize), usize> = HashMap::new();
    let mut faces = Vec::new();
    for polygon in &coarse {
        let n = polygon.len();
        let mut mid = Vec::with_capacity(n);
        for k in 0..n {
            let (a, b) = (polygon[k], polygon[(k + 1) % n]);
            let key = (a.min(b), a.max(b));
            mid.push(match midpoint.get(&key) {
                Some(&m) => m,
                None => {
                    vertices.push(on_target((vertices[a].coords + vertices[b].coords) / 2.0));
                    midpoint.insert(key, vertices.len() - 1);
                    vertices.len() - 1
                }
            });
        }
        let centre = polygon.iter().map(|&i| vertices[i].coords).sum::<Vector3>() / n as Real;
        vertices.push(on_target(centre));
        let g = vertices.len() - 1;
        // spade's faces run counter-clockwise in plan, seen from the target's normal side
        for k in 0..n {
            faces.push([polygon[k], mid[k], g, mid[(k + n - 1) % n]]);
        }
    }
    let mut mesh = QuadMesh { vertices, faces };
    smooth_in_plan(&plan, &mut mesh);
    Some(mesh)
}

/// Rounds of [`smooth_in_plan`].
const SMOOTHING_ROUNDS: usize = 30;

/// Every interior vertex of `mesh` moved to the mean of its neighbours in plan (one vertex
/// after the other, in index order, [`SMOOTHING_ROUNDS`] times) where every face round it
/// stays convex and counter-clockwise in plan, as the triangulation made them, then lifted
/// back onto the target. The pairing and the splits leave faces from a fifth to twice the
/// mean side (kites at a triangle's centre, slivers by the loops' samples), which the
/// subdivision's one count per chord cannot even out; on the two round courts at 300 mm
/// one edge started at a fifth of the mean and the layout was refused.
fn smooth_in_plan(plan: &Plan, mesh: &mut QuadMesh) {
    let n = mesh.vertices.len();
    let mut at: Vec<[Real; 2]> = mesh.vertices.iter().map(|p| plan.at(p)).collect();
    // every vertex's faces and neighbours, each once; a boundary vertex stays where it is
    let boundary = mesh.boundary_vertices();
    let mut faces_at: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (f, face) in mesh.faces.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (face[k], face[(k + 1) % 4]);
            faces_at[a].push(f);
            neighbours[a].push(b);
            neighbours[b].push(a);
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    let convex = |face: &[usize; 4], at: &[[Real; 2]]| {
        let p = face.map(|i| at[i]);
        (0..4).all(|k| cross(p[(k + 3) % 4], p[k], p[(k + 1) % 4]) > 0.0)
    };
    let mut moved = vec![false; n];
    for _ in 0..SMOOTHING_ROUNDS {
        for v in (0..n).filter(|&v| !boundary[v] && !neighbours[v].is_empty()) {
            let k = neighbours[v].len() as Real;
            let old = at[v];
            at[v] = neighbours[v].iter().fold([0.0, 0.0], |m, &u| {
                [m[0] + at[u][0] / k, m[1] + at[u][1] / k]
            });
            if faces_at[v].iter().all(|&f| convex(&mesh.faces[f], &at)) {
                moved[v] = true;
            } else {
                at[v] = old;
            }
        }
    }
    for v in (0..n).filter(|&v| moved[v]) {
        if let Some(p) = plan.lift(at[v]) {
            mesh.vertices[v] = p;
        }
    }
}
