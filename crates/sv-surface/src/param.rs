//! Initial quad grid: the target is mapped conformally onto a rectangle whose four
//! corners are boundary points chosen along the principal-curvature frame, and the
//! integer lattice of that rectangle is lifted back to the target.

use nalgebra::{Matrix2, Matrix6, Vector6};
use sv_frame::QuadMesh;
use sv_geom::{Point3, Real, Vector3};

use crate::target::TargetIndex;
use crate::{SecondaryOptions, SurfaceError, TargetMesh};
use sv_geom::sparse::SpdSolver;

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
/// extreme along the frame diagonals and turns most) and whose lattice follows the
/// conformal map of the patch onto a rectangle, so its faces start out square. Where the
/// footprint needs irregular vertices (no corner, three or five corners, an L, a hole) it
/// is instead the automatic coarse layout subdivided to the unit size (`auto_layout.rs`).
pub fn initial_grid(
    target: &TargetMesh,
    opts: &SecondaryOptions,
) -> Result<QuadMesh, SurfaceError> {
    opts.check()?;
    let index = TargetIndex::new(target)?;
    Ok(initial_mesh_indexed(&index, opts)?.0)
}

/// The initial hub mesh: the automatic coarse layout subdivided where the footprint
/// needs irregular vertices (`auto_layout.rs`), else the four-corner conformal grid.
///
/// A layout that does not fit the footprint starts with faces flipped against the target
/// (an O-grid round the centre of a horseshoe's plan, which lies outside it; the
/// courtyard's ring round an L-shaped courtyard) or with edges the optimiser takes for
/// collapsed (one face per corner where the centre lies by a boomerang's inner bend): the
/// next one is tried (`auto_layout::fallback`). So is one that starts unfolded but covers
/// less of the target than the coverage goal (a four-corner grid whose corners are a
/// horseshoe's extremes), kept only where nothing after it fits. Where none fits, the
/// error names each, what is wrong with it and where, and the designer's layout as the
/// lever; the last resort, the footprint triangulated (`triangle_layout.rs`), fits any
/// footprint that is one sheet over its plane. With the mesh comes the layout's name, and
/// where it is not the first, the ones tried before it.
pub(crate) fn initial_mesh_indexed(
    index: &TargetIndex<'_>,
    opts: &SecondaryOptions,
) -> Result<(QuadMesh, String), SurfaceError> {
    use crate::auto_layout::{coarse_layout, fallback, Start};
    let mut tried: Vec<String> = Vec::new();
    // the first layout that fits but leaves much of the target bare: kept in case no later
    // one fits at all
    let mut bare: Option<(QuadMesh, String, usize)> = None;
    let mut next = Some(coarse_layout(index, opts.unit_size));
    while let Some((drawn, start)) = next {
        let mesh = match start {
            Start::Coarse(coarse) => {
                let (area, h) = (index.mesh.area(), opts.unit_size);
                if area < 4.0 * h * h {
                    return Err(SurfaceError::TooSmall(format!(
                        "area {:.3} m^2 holds fewer than 4 units of {h} mm",
                        area * 1e-6
                    )));
                }
                crate::layout::layout_mesh_indexed(index, &coarse, opts)?
            }
            Start::Grid => initial_grid_indexed(index, opts)?,
            Start::Unfit(why) => {
                tried.push(format!("{} ({why})", drawn.describe()));
                next = fallback(index, drawn, opts.unit_size);
                continue;
            }
        };
        let fault = match crate::optimise::start_fault(index, &mesh) {
            Some(fault) => fault,
            None => {
                let covered = crate::report::coverage(&mesh, index.mesh, mesh.mean_edge()).0;
                if covered >= crate::Goals::default().coverage {
                    return Ok((mesh, named(drawn.describe(), &tried)));
                }
                if bare.is_none() {
                    bare = Some((mesh, drawn.describe(), tried.len()));
                }
                format!("it covers {:.0} % of the target", 100.0 * covered)
            }
        };
        tried.push(format!("{} ({fault})", drawn.describe()));
        next = fallback(index, drawn, opts.unit_size);
    }
    if let Some((mesh, name, at)) = bare {
        // nothing later fits: the bare one, named with every other layout tried
        tried.remove(at);
        return Ok((mesh, named(name, &tried)));
    }
    let what = if tried.len() == 1 {
        "the layout drawn starts folded or with collapsed edges"
    } else {
        "every layout tried starts folded or with collapsed edges"
    };
    Err(SurfaceError::NeedsLayout(format!(
        "{what}: {}; give the layout as a coarse quad mesh (--layout COARSE.obj or [surface] layout; docs/secondary.md, \"The designer's layout\")",
        tried.join(", then ")
    )))
}

/// A layout's name and the ones tried before it that did not fit.
fn named(layout: String, tried: &[String]) -> String {
    if tried.is_empty() {
        layout
    } else {
        format!(
            "{layout}, after {} (a layout of your own: --layout COARSE.obj)",
            tried.join(", then ")
        )
    }
}

fn initial_grid_indexed(
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
    // boundary loop positions of each side, corner to corner inclusive
    let side_loop: Vec<Vec<usize>> = (0..4)
        .map(|k| {
            let mut out = vec![corners[k]];
            let mut i = corners[k];
            while i != corners[(k + 1) % 4] {
                i = (i + 1) % m;
                out.push(i);
            }
            out
        })
        .collect();
    let area = target.area();
    let conf = conformal_coordinates(target, lp, &side_loop)?;
    let ratio = conf.modulus;
    let ny = (area / (ratio * h * h)).sqrt().round().max(1.0) as usize;
    let nx = (ratio * ny as Real).round().max(1.0) as usize;
    if nx < 2 || ny < 2 {
        return Err(SurfaceError::TooSmall(format!(
            "area {:.3} m^2 gives a {nx} x {ny} grid at unit size {h} mm; at least 2 x 2 units are needed",
            area * 1e-6
        )));
    }
    let smooth = corners.map(|c| turning[c] < SMOOTH_CORNER_TURN);
    // the lattice of an `nx` x `ny` grid lifted onto the target
    let grid = |nx: usize, ny: usize| -> Result<QuadMesh, SurfaceError> {
        let uv: Vec<(Real, Real)> = conf
            .u
            .iter()
            .zip(&conf.v)
            .map(|(u, w)| (u * nx as Real, w * ny as Real))
            .collect();
        let locator = Locator::new(target, &uv, nx, ny);
        // lattice point on side k where the side's free coordinate equals `t` (0..1)
        let on_side = |k: usize, t: Real| {
            let coord = |i: usize| {
                let b = lp[side_loop[k][i]];
                if k.is_multiple_of(2) {
                    conf.u[b]
                } else {
                    conf.v[b]
                }
            };
            let sl = &side_loop[k];
            let mut best = (Real::INFINITY, v[lp[sl[0]]]);
            for i in 0..sl.len() - 1 {
                let (a, b) = (coord(i), coord(i + 1));
                if (a - t) * (b - t) <= 0.0 && a != b {
                    let s = (t - a) / (b - a);
                    let p = v[lp[sl[i]]] + (v[lp[sl[i + 1]]] - v[lp[sl[i]]]) * s;
                    return p;
                }
                if (a - t).abs() < best.0 {
                    best = ((a - t).abs(), v[lp[sl[i]]]);
                }
            }
            best.1
        };
        let open = nx >= 4 && ny >= 4 && smooth.iter().any(|&s| s);
        let failure = std::cell::Cell::new(None);
        let mesh = QuadMesh::from_fn(nx, ny, |i, j| {
            let (fu, fv) = (i as Real / nx as Real, j as Real / ny as Real);
            if j == 0 {
                return on_side(0, fu);
            }
            if i == nx {
                return on_side(1, fv);
            }
            if j == ny {
                return on_side(2, fu);
            }
            if i == 0 {
                return on_side(3, fv);
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
        // a grid corner where the boundary hardly turns would get a face corner near 180
        // degrees: open it into two faces meeting at an interior valence-3 vertex
        if open {
            return Ok(open_smooth_corners(&mesh, nx, ny, smooth));
        }
        Ok(mesh)
    };
    let mesh = grid(nx, ny)?;
    // The conformal factor varies over the patch (corners of other than 90 degrees, a
    // torus's inner and outer side), so the grid sized by the mean area can have sides
    // outside the goal's 0.7-1.4 of the unit while a grid one or two rows finer or
    // coarser has them all inside: among the nearby counts (the aspect kept within one
    // column of the modulus) take the one whose sides are farthest inside the range.
    let (lo, hi) = SIDE_GOAL;
    let fit = |m: &QuadMesh| side_fit(m, h, lo, hi);
    if fit(&mesh) >= SIDE_MARGIN {
        return Ok(mesh);
    }
    // ... and as many nearly square faces as the grid sized by the area (at most 0.98)
    let square = square_fraction(&mesh).min(0.98);
    let mut best = (fit(&mesh), None);
    for ny2 in ny.saturating_sub(3).max(2)..=ny + 3 {
        let nx0 = (ratio * ny2 as Real).round().max(2.0) as usize;
        for nx2 in nx0.saturating_sub(1).max(2)..=nx0 + 1 {
            if (nx2, ny2) == (nx, ny) {
                continue;
            }
            // faces stay within 1.15 of square (the conformal faces are square)
            let aspect = (nx2 as Real / ny2 as Real / ratio).ln().abs();
            if aspect > SIZE_ASPECT.ln() {
                continue;
            }
            let Ok(m) = grid(nx2, ny2) else { continue };
            let f = fit(&m);
            if f > best.0 + 1e-9 && square_fraction(&m) >= square {
                best = (f, Some(m));
            }
        }
    }
    // a grid no count brings inside the range (rows that cannot grow: annular sectors)
    // keeps the counts sized by the area
    match best {
        (f, Some(m)) if f >= 1.0 => Ok(m),
        _ => Ok(mesh),
    }
}

/// The face-side goal (every side within this range of the unit size), as in
/// [`crate::Goals`].
const SIDE_GOAL: (Real, Real) = (0.7, 1.4);
/// A grid whose sides are within the goal by this factor (the optimiser moves them a
/// little) keeps the counts sized by the area.
const SIDE_MARGIN: Real = 1.04;
/// Largest aspect (width / height over the conformal modulus) of a resized grid's faces.
const SIZE_ASPECT: Real = 1.15;

/// Fraction of the faces of `mesh` whose longest side is within
/// [`crate::EDGE_RATIO_LIMIT`] of their shortest.
fn square_fraction(mesh: &QuadMesh) -> Real {
    let good = (0..mesh.faces.len())
        .filter(|&f| {
            let p = mesh.face_points(f);
            let e = [0, 1, 2, 3].map(|k| (p[(k + 1) % 4] - p[k]).norm());
            let long = e.iter().copied().fold(0.0, Real::max);
            let short = e.iter().copied().fold(Real::INFINITY, Real::min);
            long <= crate::EDGE_RATIO_LIMIT * short
        })
        .count();
    good as Real / mesh.faces.len().max(1) as Real
}

/// How far inside `lo..hi` (times the unit `h`) the sides of `mesh` are:
/// `min(shortest / lo, hi / longest)`, at least 1 when every side is inside.
fn side_fit(mesh: &QuadMesh, h: Real, lo: Real, hi: Real) -> Real {
    let (mut short, mut long) = (Real::INFINITY, 0.0 as Real);
    for f in 0..mesh.faces.len() {
        let p = mesh.face_points(f);
        for k in 0..4 {
            let e = (p[(k + 1) % 4] - p[k]).norm() / h;
            short = short.min(e);
            long = long.max(e);
        }
    }
    (short / lo).min(hi / long)
}

/// Boundary turning (radians, over 0.75 unit either side) below which a grid corner is
/// opened by [`open_smooth_corners`]: sharp corners of the targets turn by 73-100 degrees,
/// smooth boundaries by under 10.
const SMOOTH_CORNER_TURN: Real = std::f64::consts::FRAC_PI_4;

/// Replace the corner face of an `nx` x `ny` grid (built by `QuadMesh::from_fn`) and its two
/// neighbours along the boundary by two faces that share the corner vertex, at every corner
/// flagged in `smooth` (SW, SE, NE, NW). The corner vertex then has two faces, like any
/// boundary vertex, and the grid vertex diagonally inside it three (an irregular vertex):
/// in the conformal map a grid corner's 90 degrees open to the 180 degrees of a smooth
/// boundary, two faces of about 90 degrees each. Needs `nx, ny >= 4`.
fn open_smooth_corners(grid: &QuadMesh, nx: usize, ny: usize, smooth: [bool; 4]) -> QuadMesh {
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let cell = |i: usize, j: usize| j * nx + i;
    let mut drop_face = vec![false; grid.faces.len()];
    let mut drop_vertex = vec![false; grid.vertices.len()];
    let mut extra = Vec::new();
    let at = |c: usize, k: isize| {
        if c == 0 {
            k as usize
        } else {
            (c as isize - k) as usize
        }
    };
    for (k, (ci, cj)) in [(0, 0), (nx, 0), (nx, ny), (0, ny)].into_iter().enumerate() {
        if !smooth[k] {
            continue;
        }
        // lattice points at steps (a, b) inward from the corner
        let p = |a: isize, b: isize| id(at(ci, a), at(cj, b));
        let f =
            |a: isize, b: isize| cell(at(ci, a).min(at(ci, a + 1)), at(cj, b).min(at(cj, b + 1)));
        for (a, b) in [(0, 0), (1, 0), (0, 1)] {
            drop_face[f(a, b)] = true;
        }
        drop_vertex[p(1, 0)] = true;
        drop_vertex[p(0, 1)] = true;
        let mut f1 = [p(0, 0), p(2, 0), p(2, 1), p(1, 1)];
        let mut f2 = [p(0, 2), p(0, 0), p(1, 1), p(1, 2)];
        // mirrored corners (SE, NW) reverse the cyclic order
        if k % 2 == 1 {
            f1.reverse();
            f2.reverse();
        }
        extra.push(f1);
        extra.push(f2);
    }
    let mut index = vec![usize::MAX; grid.vertices.len()];
    let mut vertices = Vec::with_capacity(grid.vertices.len());
    for (v, p) in grid.vertices.iter().enumerate() {
        if !drop_vertex[v] {
            index[v] = vertices.len();
            vertices.push(*p);
        }
    }
    let faces = grid
        .faces
        .iter()
        .zip(&drop_face)
        .filter(|(_, &d)| !d)
        .map(|(f, _)| *f)
        .chain(extra)
        .map(|f| f.map(|v| index[v]))
        .collect();
    QuadMesh { vertices, faces }
}

/// Conformal coordinates of a patch with four marked sides.
struct Conformal {
    /// 0 on side 3, 1 on side 1, harmonic, free (natural boundary) on sides 0 and 2
    u: Vec<Real>,
    /// 0 on side 0, 1 on side 2, likewise
    v: Vec<Real>,
    /// width / height of the rectangle the patch maps to conformally
    modulus: Real,
}

/// The two harmonic measures of the quadrilateral: the level lines of `u` and `v` cross at
/// right angles (the pair maps the patch conformally onto a rectangle of aspect `modulus`),
/// so the lattice lifted from them has square faces, sized by the conformal factor.
fn conformal_coordinates(
    target: &TargetMesh,
    lp: &[usize],
    side_loop: &[Vec<usize>],
) -> Result<Conformal, SurfaceError> {
    let nv = target.vertices.len();
    let dirichlet = |lo: usize, hi: usize| {
        let mut fixed = vec![None; nv];
        for &k in &side_loop[lo] {
            fixed[lp[k]] = Some(0.0);
        }
        for &k in &side_loop[hi] {
            fixed[lp[k]] = Some(1.0);
        }
        fixed
    };
    let (u, eu) = laplace_dirichlet(target, &dirichlet(3, 1))?;
    let (v, ev) = laplace_dirichlet(target, &dirichlet(0, 2))?;
    if !(eu > 0.0 && ev > 0.0) {
        return Err(SurfaceError::Internal(
            "conformal modulus of the target is degenerate".into(),
        ));
    }
    Ok(Conformal {
        u,
        v,
        modulus: (ev / eu).sqrt(),
    })
}

/// Cotangent weights `w_ij` (half the sum of the cotangents opposite each edge), as a list
/// of `(i, j, w)` per triangle corner.
fn cotangent_weights(target: &TargetMesh) -> Vec<(usize, usize, Real)> {
    let v = &target.vertices;
    let mut out = Vec::with_capacity(3 * target.triangles.len());
    for t in &target.triangles {
        for k in 0..3 {
            let (i, j, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let a = v[i] - v[o];
            let b = v[j] - v[o];
            let cot = a.dot(&b) / a.cross(&b).norm().max(1e-300);
            out.push((i, j, 0.5 * cot));
        }
    }
    out
}

/// Minimise the Dirichlet energy (cotangent Laplacian) with the values `fixed` where set;
/// returns the solution and its energy.
fn laplace_dirichlet(
    target: &TargetMesh,
    fixed: &[Option<Real>],
) -> Result<(Vec<Real>, Real), SurfaceError> {
    let nv = target.vertices.len();
    let mut col = vec![usize::MAX; nv];
    let mut n = 0;
    for t in &target.triangles {
        for &i in t {
            if fixed[i].is_none() && col[i] == usize::MAX {
                col[i] = n;
                n += 1;
            }
        }
    }
    let weights = cotangent_weights(target);
    let mut x: Vec<Real> = fixed.iter().map(|f| f.unwrap_or(0.0)).collect();
    if n > 0 {
        let mut pattern = Vec::new();
        let mut values = Vec::new();
        let mut rhs = vec![0.0; n];
        for &(i, j, w) in &weights {
            for (p, q) in [(i, j), (j, i)] {
                if col[p] == usize::MAX {
                    continue;
                }
                pattern.push((col[p], col[p]));
                values.push(w);
                match fixed[q] {
                    Some(val) => rhs[col[p]] += w * val,
                    None if p < q => {
                        pattern.push((col[p], col[q]));
                        values.push(-w);
                    }
                    None => {}
                }
            }
        }
        let mut solver = SpdSolver::new(n, &pattern)?;
        solver.set_values(&values);
        if !solver.solve(&mut rhs)? {
            return Err(SurfaceError::Internal(
                "conformal parametrisation is singular".into(),
            ));
        }
        for i in 0..nv {
            if col[i] != usize::MAX {
                x[i] = rhs[col[i]];
            }
        }
    }
    let energy = weights
        .iter()
        .map(|&(i, j, w)| w * (x[i] - x[j]).powi(2))
        .sum();
    Ok((x, energy))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Flat annular sector, radii `r1..r2`, angle `phi`, sampled `n` x `n`.
    fn sector(n: usize, r1: Real, r2: Real, phi: Real) -> (TargetMesh, [usize; 4]) {
        let mut m = TargetMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let a = phi * (i as Real / n as Real - 0.5);
                let r = r1 + (r2 - r1) * j as Real / n as Real;
                m.vertices.push(Point3::new(r * a.sin(), r * a.cos(), 0.0));
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (m, [id(0, 0), id(n, 0), id(n, n), id(0, n)])
    }

    #[test]
    fn conformal_modulus_of_an_annular_sector_is_angle_over_log_ratio() {
        // log maps the sector onto a rectangle phi wide and ln(r2 / r1) high
        let (phi, r1, r2) = (1.2, 1000.0, 2500.0);
        let (mesh, corner_vertices) = sector(48, r1, r2, phi);
        let lp = mesh.validate().unwrap().remove(0);
        let corners = corner_vertices.map(|c| lp.iter().position(|&b| b == c).unwrap());
        let side_loop: Vec<Vec<usize>> = (0..4)
            .map(|k| {
                let mut out = vec![corners[k]];
                let mut i = corners[k];
                while i != corners[(k + 1) % 4] {
                    i = (i + 1) % lp.len();
                    out.push(i);
                }
                out
            })
            .collect();
        let conf = conformal_coordinates(&mesh, &lp, &side_loop).unwrap();
        let expected = phi / (r2 / r1).ln();
        assert!(
            (conf.modulus / expected - 1.0).abs() < 0.01,
            "modulus {} expected {expected}",
            conf.modulus
        );
        // v is the normalised log radius, u the normalised angle
        for (k, p) in mesh.vertices.iter().enumerate() {
            let r = p.coords.norm();
            let v = (r / r1).ln() / (r2 / r1).ln();
            let u = p.x.atan2(p.y) / phi + 0.5;
            assert!(
                (conf.v[k] - v).abs() < 0.01,
                "vertex {k}: v {} vs {v}",
                conf.v[k]
            );
            assert!(
                (conf.u[k] - u).abs() < 0.01,
                "vertex {k}: u {} vs {u}",
                conf.u[k]
            );
        }
    }

    #[test]
    fn initial_grid_on_a_sector_has_square_faces_of_growing_size() {
        let (mesh, _) = sector(48, 1000.0, 2500.0, 1.2);
        let opts = SecondaryOptions {
            unit_size: 200.0,
            ..Default::default()
        };
        let grid = initial_grid(&mesh, &opts).unwrap();
        let ratios: Vec<Real> = (0..grid.faces.len())
            .map(|f| {
                let p = grid.face_points(f);
                let e = [0, 1, 2, 3].map(|k| (p[(k + 1) % 4] - p[k]).norm());
                e.iter().copied().fold(0.0, Real::max)
                    / e.iter().copied().fold(Real::INFINITY, Real::min)
            })
            .collect();
        let worst = ratios.iter().copied().fold(0.0, Real::max);
        assert!(worst < 1.3, "worst edge ratio {worst}");
        // conformal: faces near the outer arc are larger than near the inner one
        let size = |f: usize| {
            let p = grid.face_points(f);
            (p[2] - p[0]).norm()
        };
        let (first, last) = (size(0), size(grid.faces.len() - 1));
        assert!(
            (first / last - 1.0).abs() > 0.5,
            "corner faces {first} and {last} mm"
        );
    }

    /// Ellipse with semi-axes `a`, `b` (a square grid squeezed onto the disc) on the
    /// paraboloid of revolution `z = -(x^2 + y^2) / (2 radius)` (flat when `radius` is 0).
    fn oval(n: usize, a: Real, b: Real, radius: Real) -> TargetMesh {
        let mut m = TargetMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let s = 2.0 * i as Real / n as Real - 1.0;
                let t = 2.0 * j as Real / n as Real - 1.0;
                let (x, y) = (
                    a * s * (1.0 - t * t / 2.0).sqrt(),
                    b * t * (1.0 - s * s / 2.0).sqrt(),
                );
                let z = if radius > 0.0 {
                    -(x * x + y * y) / (2.0 * radius)
                } else {
                    0.0
                };
                m.vertices.push(Point3::new(x, y, z));
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                m.triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        m
    }

    #[test]
    fn smooth_boundary_gets_opened_corners() {
        let mesh = oval(48, 2200.0, 1600.0, 0.0);
        let opts = SecondaryOptions {
            unit_size: 300.0,
            ..Default::default()
        };
        let grid = initial_grid(&mesh, &opts).unwrap();
        let mut faces_at = vec![0usize; grid.vertices.len()];
        for f in &grid.faces {
            for &v in f {
                faces_at[v] += 1;
            }
        }
        // no grid corner with a single face; four interior vertices of valence 3
        assert!(faces_at.iter().all(|&c| c >= 2), "{faces_at:?}");
        let topo = crate::topology::Topology::new(&grid).unwrap();
        let irregular = (0..grid.vertices.len())
            .filter(|&v| !topo.boundary[v] && faces_at[v] == 3)
            .count();
        assert_eq!(irregular, 4);
        assert!((0..grid.vertices.len()).all(|v| !topo.corner[v]));
        // every face convex and counter-clockwise seen from +Z
        for f in 0..grid.faces.len() {
            let p = grid.face_points(f);
            for k in 0..4 {
                let turn = (p[(k + 1) % 4] - p[k]).cross(&(p[(k + 2) % 4] - p[(k + 1) % 4]));
                assert!(turn.z > 0.0, "face {f} corner {}", (k + 1) % 4);
            }
        }
        // a rectangle keeps its four single-face corners
        let (sector_mesh, _) = sector(48, 1000.0, 2500.0, 1.2);
        let grid = initial_grid(&sector_mesh, &opts).unwrap();
        let topo = crate::topology::Topology::new(&grid).unwrap();
        assert_eq!(topo.corner.iter().filter(|&&c| c).count(), 4);
    }

    #[test]
    fn oval_dome_is_planar_and_conical_at_300() {
        // smooth boundary on a dome of revolution: the opened corners keep every face
        // planar and every vertex conical; the faces next to them stay small (edge ratio,
        // docs/secondary.md)
        let target = oval(48, 2200.0, 1600.0, 4500.0);
        let opts = SecondaryOptions {
            unit_size: 300.0,
            ..Default::default()
        };
        let (_, r) = crate::build_secondary(&target, &opts, &mut |_, _| {}).unwrap();
        assert!(r.planarity_max <= 0.002, "{r:?}");
        assert!(r.conical_max_deg <= 0.5, "{r:?}");
        assert!(r.closeness_max <= 0.05, "{r:?}");
        assert!(r.boundary_max <= 0.05, "{r:?}");
        assert!(r.non_convex_faces.is_empty(), "{r:?}");
    }
}
