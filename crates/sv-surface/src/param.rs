//! Initial quad grid: the target is mapped harmonically onto a rectangle whose four
//! corners are boundary points chosen along the principal-curvature frame, and the
//! integer lattice of that rectangle is lifted back to the target.

use nalgebra::{Matrix2, Matrix6, Vector6};
use sv_frame::QuadMesh;
use sv_geom::{Point3, Real, Vector3};

use crate::sparse::SpdSolver;
use crate::target::TargetIndex;
use crate::{SecondaryOptions, SurfaceError, TargetMesh};

/// Frame of the target: centre, in-plane directions `d1`, `d2` (aligned with the mean
/// principal curvature directions when the surface has a clear one).
pub(crate) struct Frame {
    pub(crate) centre: Point3,
    pub(crate) d1: Vector3,
    pub(crate) d2: Vector3,
}

pub(crate) fn target_frame(mesh: &TargetMesh) -> Frame {
    let v = &mesh.vertices;
    let mut area = 0.0;
    let mut c = Vector3::zeros();
    let mut normal = Vector3::zeros();
    for t in &mesh.triangles {
        let n = (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]]));
        let a = 0.5 * n.norm();
        c += (v[t[0]].coords + v[t[1]].coords + v[t[2]].coords) * (a / 3.0);
        area += a;
        normal += n;
    }
    let centre = Point3::from(c / area);
    let mut cov = nalgebra::Matrix3::zeros();
    for t in &mesh.triangles {
        let a = crate::target::triangle_area(v, t);
        for &i in t {
            let d = v[i] - centre;
            cov += d * d.transpose() * (a / 3.0);
        }
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut d3: Vector3 = eig.eigenvectors.column(order[2]).into();
    if d3.dot(&normal) < 0.0 {
        d3 = -d3;
    }
    let e1: Vector3 = eig.eigenvectors.column(order[0]).into();
    let e1 = (e1 - d3 * d3.dot(&e1)).normalize();
    let e2 = d3.cross(&e1);
    // quadratic fit z = a x^2 + b xy + c y^2 + d x + e y + f in (e1, e2, d3)
    let mut ata = Matrix6::zeros();
    let mut atb = Vector6::zeros();
    for p in v {
        let d = p - centre;
        let (x, y, z) = (d.dot(&e1), d.dot(&e2), d.dot(&d3));
        let row = Vector6::new(x * x, x * y, y * y, x, y, 1.0);
        ata += row * row.transpose();
        atb += row * z;
    }
    let mut angle = 0.0;
    if let Some(sol) = ata.lu().solve(&atb) {
        let h = Matrix2::new(sol[0], sol[1] / 2.0, sol[1] / 2.0, sol[2]);
        let e = h.symmetric_eigen();
        let (l0, l1) = (e.eigenvalues[0], e.eigenvalues[1]);
        let big = l0.abs().max(l1.abs());
        if big > 0.0 && (l0 - l1).abs() > 0.3 * big {
            let k = if l0.abs() >= l1.abs() { 0 } else { 1 };
            let dir = e.eigenvectors.column(k);
            angle = dir[1].atan2(dir[0]);
            // keep the grid's first direction closest to the long axis (e1)
            while angle > std::f64::consts::FRAC_PI_4 {
                angle -= std::f64::consts::FRAC_PI_2;
            }
            while angle < -std::f64::consts::FRAC_PI_4 {
                angle += std::f64::consts::FRAC_PI_2;
            }
        }
    }
    let d1 = e1 * angle.cos() + e2 * angle.sin();
    let d2 = d3.cross(&d1);
    Frame { centre, d1, d2 }
}

/// The initial hub grid on `target` at `opts.unit_size`: a structured `nx` x `ny` quad
/// grid whose outer ring lies on the target boundary (corners where the boundary is
/// extreme along the frame diagonals) and whose interior follows a harmonic map.
pub fn initial_grid(
    target: &TargetMesh,
    opts: &SecondaryOptions,
) -> Result<QuadMesh, SurfaceError> {
    opts.check()?;
    let index = TargetIndex::new(target)?;
    initial_grid_indexed(&index, opts)
}

pub(crate) fn initial_grid_indexed(
    index: &TargetIndex<'_>,
    opts: &SecondaryOptions,
) -> Result<QuadMesh, SurfaceError> {
    let target = index.mesh;
    let h = opts.unit_size;
    let frame = target_frame(target);
    let lp = &index.boundary;
    let m = lp.len();
    let v = &target.vertices;
    let xy: Vec<(Real, Real)> = lp
        .iter()
        .map(|&i| {
            let d = v[i] - frame.centre;
            (d.dot(&frame.d1), d.dot(&frame.d2))
        })
        .collect();
    let wx = xy.iter().map(|p| p.0.abs()).fold(0.0, Real::max).max(1e-9);
    let wy = xy.iter().map(|p| p.1.abs()).fold(0.0, Real::max).max(1e-9);
    // turning of the boundary (angle between the chords to the points half a unit
    // before and after) at every boundary vertex: grid corners go where it turns most
    let turning: Vec<Real> = (0..m)
        .map(|k| {
            let s = index.boundary_arc[k];
            let p = v[lp[k]];
            let a = p - index.boundary_at(s - 0.75 * h);
            let b = index.boundary_at(s + 0.75 * h) - p;
            if a.norm() > 0.0 && b.norm() > 0.0 {
                a.angle(&b)
            } else {
                0.0
            }
        })
        .collect();
    let pick = |sx: Real, sy: Real| {
        let score = |a: usize| sx * xy[a].0 / wx + sy * xy[a].1 / wy;
        let best = (0..m).map(score).fold(Real::NEG_INFINITY, Real::max);
        // among the points nearly extreme along the diagonal, the sharpest turn
        (0..m)
            .filter(|&a| score(a) >= best - 0.3)
            .max_by(|&a, &b| {
                let fa = turning[a] + 0.5 * score(a);
                let fb = turning[b] + 0.5 * score(b);
                fa.total_cmp(&fb)
            })
            .unwrap_or(0)
    };
    // loop runs counter-clockwise seen from d3: SW, SE, NE, NW
    let mut corners = [
        pick(-1.0, -1.0),
        pick(1.0, -1.0),
        pick(1.0, 1.0),
        pick(-1.0, 1.0),
    ];
    let rel = |k: usize| (corners[k] + m - corners[0]) % m;
    let ordered = rel(1) > 0 && rel(1) < rel(2) && rel(2) < rel(3);
    if !ordered {
        corners = [0, m / 4, m / 2, 3 * m / 4].map(|k| (corners[0] + k) % m);
    }
    let arc = |k: usize| index.boundary_arc[corners[k]];
    let per = index.perimeter();
    let side = |k: usize| (arc((k + 1) % 4) - arc(k)).rem_euclid(per);
    let sides = [side(0), side(1), side(2), side(3)];
    let ratio = (sides[0] + sides[2]) / (sides[1] + sides[3]);
    let area = target.area();
    let ny = (area / (ratio * h * h)).sqrt().round().max(1.0) as usize;
    let nx = (ratio * ny as Real).round().max(1.0) as usize;
    if nx < 2 || ny < 2 {
        return Err(SurfaceError::TooSmall(format!(
            "area {:.3} m^2 gives a {nx} x {ny} grid at unit size {h} mm; at least 2 x 2 units are needed",
            area * 1e-6
        )));
    }
    // boundary vertices -> rectangle [0, nx] x [0, ny]
    let counts = [nx, ny, nx, ny];
    let rect_corner = [
        (0.0, 0.0),
        (nx as Real, 0.0),
        (nx as Real, ny as Real),
        (0.0, ny as Real),
    ];
    let mut uv = vec![(0.0, 0.0); v.len()];
    let mut is_boundary = vec![false; v.len()];
    for (k, &c) in corners.iter().enumerate() {
        let (a, b) = (rect_corner[k], rect_corner[(k + 1) % 4]);
        let len = sides[k].max(1e-12);
        let mut i = c;
        loop {
            let t = ((index.boundary_arc[i] - arc(k)).rem_euclid(per) / len).min(1.0);
            uv[lp[i]] = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            is_boundary[lp[i]] = true;
            i = (i + 1) % m;
            if i == corners[(k + 1) % 4] {
                break;
            }
        }
    }
    harmonic_interior(target, &is_boundary, &mut uv)?;
    let locator = Locator::new(target, &uv, nx, ny);
    let arc_at = |k: usize, t: Real| arc(k) + sides[k] * t;
    let failure = std::cell::Cell::new(None);
    let mesh = QuadMesh::from_fn(nx, ny, |i, j| {
        let on_edge = |s: usize, t: Real| index.boundary_at(arc_at(s, t));
        if j == 0 {
            return on_edge(0, i as Real / counts[0] as Real);
        }
        if i == nx {
            return on_edge(1, j as Real / counts[1] as Real);
        }
        if j == ny {
            return on_edge(2, (nx - i) as Real / counts[2] as Real);
        }
        if i == 0 {
            return on_edge(3, (ny - j) as Real / counts[3] as Real);
        }
        match locator.lift(i as Real, j as Real) {
            Some(p) => p,
            None => {
                failure.set(Some((i, j)));
                Point3::origin()
            }
        }
    });
    if let Some((i, j)) = failure.get() {
        return Err(SurfaceError::Internal(format!(
            "grid point ({i}, {j}) is outside the parametrised target"
        )));
    }
    Ok(mesh)
}

/// Solve the Laplace equation with clamped positive cotangent weights (a Tutte embedding:
/// injective for the convex rectangle) for the interior parameters.
fn harmonic_interior(
    target: &TargetMesh,
    is_boundary: &[bool],
    uv: &mut [(Real, Real)],
) -> Result<(), SurfaceError> {
    let v = &target.vertices;
    let mut col = vec![usize::MAX; v.len()];
    let mut n = 0;
    let mut used = vec![false; v.len()];
    for t in &target.triangles {
        for &i in t {
            used[i] = true;
        }
    }
    for i in 0..v.len() {
        if used[i] && !is_boundary[i] {
            col[i] = n;
            n += 1;
        }
    }
    if n == 0 {
        return Ok(());
    }
    let mut pattern = Vec::new();
    let mut values = Vec::new();
    let mut rhs_u = vec![0.0; n];
    let mut rhs_v = vec![0.0; n];
    for t in &target.triangles {
        for k in 0..3 {
            let (i, j, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let a = v[i] - v[o];
            let b = v[j] - v[o];
            let cot = a.dot(&b) / a.cross(&b).norm().max(1e-300);
            let w = (0.5 * cot).max(0.05);
            for (p, q) in [(i, j), (j, i)] {
                if col[p] == usize::MAX {
                    continue;
                }
                pattern.push((col[p], col[p]));
                values.push(w);
                if col[q] == usize::MAX {
                    rhs_u[col[p]] += w * uv[q].0;
                    rhs_v[col[p]] += w * uv[q].1;
                } else if p < q {
                    pattern.push((col[p], col[q]));
                    values.push(-w);
                }
            }
        }
    }
    let mut solver = SpdSolver::new(n, &pattern)?;
    if !solver.solve(&values, &mut rhs_u)? || !solver.solve(&values, &mut rhs_v)? {
        return Err(SurfaceError::Internal(
            "harmonic parametrisation is singular".into(),
        ));
    }
    for i in 0..v.len() {
        if col[i] != usize::MAX {
            uv[i] = (rhs_u[col[i]], rhs_v[col[i]]);
        }
    }
    Ok(())
}

/// Point location in the parameter rectangle by a bucket grid of unit cells.
struct Locator<'a> {
    target: &'a TargetMesh,
    uv: &'a [(Real, Real)],
    nx: usize,
    ny: usize,
    cells: Vec<Vec<usize>>,
}

impl<'a> Locator<'a> {
    fn new(target: &'a TargetMesh, uv: &'a [(Real, Real)], nx: usize, ny: usize) -> Self {
        let mut cells = vec![Vec::new(); (nx + 1) * (ny + 1)];
        for (ti, t) in target.triangles.iter().enumerate() {
            let us = t.map(|i| uv[i].0);
            let vs = t.map(|i| uv[i].1);
            let cl = |x: Real, n: usize| (x.floor().max(0.0) as usize).min(n);
            let (u0, u1) = (
                cl(us.iter().copied().fold(Real::INFINITY, Real::min), nx),
                cl(us.iter().copied().fold(Real::NEG_INFINITY, Real::max), nx),
            );
            let (v0, v1) = (
                cl(vs.iter().copied().fold(Real::INFINITY, Real::min), ny),
                cl(vs.iter().copied().fold(Real::NEG_INFINITY, Real::max), ny),
            );
            for y in v0..=v1 {
                for x in u0..=u1 {
                    cells[y * (nx + 1) + x].push(ti);
                }
            }
        }
        Self {
            target,
            uv,
            nx,
            ny,
            cells,
        }
    }

    fn lift(&self, u: Real, w: Real) -> Option<Point3> {
        let x = (u.floor().max(0.0) as usize).min(self.nx);
        let y = (w.floor().max(0.0) as usize).min(self.ny);
        let mut best: Option<(Real, Point3)> = None;
        for dy in y.saturating_sub(1)..=(y + 1).min(self.ny) {
            for dx in x.saturating_sub(1)..=(x + 1).min(self.nx) {
                for &ti in &self.cells[dy * (self.nx + 1) + dx] {
                    let t = self.target.triangles[ti];
                    let [a, b, c] = t.map(|i| self.uv[i]);
                    let det = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
                    if det.abs() < 1e-300 {
                        continue;
                    }
                    let l1 = ((u - a.0) * (c.1 - a.1) - (c.0 - a.0) * (w - a.1)) / det;
                    let l2 = ((b.0 - a.0) * (w - a.1) - (u - a.0) * (b.1 - a.1)) / det;
                    let l0 = 1.0 - l1 - l2;
                    let worst = l0.min(l1).min(l2);
                    if best.as_ref().is_none_or(|b| worst > b.0) {
                        let p = &self.target.vertices;
                        let q = Point3::from(
                            p[t[0]].coords * l0 + p[t[1]].coords * l1 + p[t[2]].coords * l2,
                        );
                        best = Some((worst, q));
                    }
                }
            }
        }
        best.filter(|b| b.0 > -1e-6).map(|b| b.1)
    }
}
