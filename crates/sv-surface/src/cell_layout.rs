//! The layout of a footprint whose sides all run along two directions at right angles (a
//! U, T or cross plan, a notched rectangle, a rectangle round rectangular courts): the
//! lines through its corners along both directions cut it into rectangular cells, one
//! coarse face each.
//!
//! Every interior vertex of the cells is regular (four cells meet there, or a T-junction
//! of a side is on the boundary with two), a convex corner of the footprint has one cell
//! and a reflex one three: the L's layout (three faces at its reflex corner) for any
//! number of reflex corners and courts. The four-corner grid, which the other footprints
//! with reflex corners get, cuts across them instead (a U plan's grid left a fifth of its
//! area uncovered, docs/secondary.md).

use sv_frame::QuadMesh;
use sv_geom::{Point3, Real};

use crate::layout::find;
use crate::target::{loop_arc, loop_at, TargetIndex};
use crate::triangle_layout::Plan;

/// Largest angle between a side (the chord between two consecutive corners) and the
/// nearer of the two directions (degrees).
const SIDE_TURN: Real = 12.0;

/// Corner coordinates closer than this fraction of the unit along a direction share one
/// line of cells.
const SAME_LINE: Real = 0.5;

/// One boundary loop's corners: where they are in the loop (arc length), on the target,
/// and in plan.
struct Sides {
    arc: Vec<Real>,
    length: Real,
    corners: Vec<(Real, Point3, [Real; 2])>,
}

/// The cells' coarse layout of `index`'s target at unit `h`, or `None` where a loop has
/// fewer than four corners or a side that does not run along one of two directions at
/// right angles, where the lines cut it into one cell only, or where a point inside is not
/// over exactly one sheet of the target. The corners are looked for over a unit's length
/// first (a notch a few units wide keeps all four), then over the fortieth of the loop the
/// other layouts use (a court's corners rounded with a radius of two units are corners).
pub(crate) fn cell_layout(index: &TargetIndex<'_>, h: Real) -> Option<QuadMesh> {
    let plan = Plan::new(index);
    cells_with_corners(index, &plan, h, true).or_else(|| cells_with_corners(index, &plan, h, false))
}

/// [`cell_layout`] with the corners found over a unit's length (`fine`) or a fortieth of
/// the loop.
fn cells_with_corners(
    index: &TargetIndex<'_>,
    plan: &Plan,
    h: Real,
    fine: bool,
) -> Option<QuadMesh> {
    let v = &index.mesh.vertices;
    let loops: Vec<Sides> = index
        .loops
        .iter()
        .map(|lp| {
            let arc = loop_arc(v, lp);
            let length = arc[lp.len()];
            let window = if fine {
                (length / 40.0).min(h)
            } else {
                length / 40.0
            };
            let corners = crate::auto_layout::corners(index, lp, window)
                .iter()
                .map(|c| {
                    let p = v[lp[c.at]];
                    (arc[c.at], p, plan.at(&p))
                })
                .collect();
            Sides {
                arc,
                length,
                corners,
            }
        })
        .collect();
    if loops.iter().any(|l| l.corners.len() < 4) {
        return None;
    }
    // every side follows its loop within a unit or a quarter of its length (a rounded
    // corner's middle, where it was found, lies 0.29 of the radius off the straight sides;
    // a side across a court's opening whose rounded corners were not found lies the court's
    // depth off)
    for (l, lp) in loops.iter().zip(&index.loops) {
        let k = l.corners.len();
        for i in 0..k {
            let (s0, mut s1) = (l.corners[i].0, l.corners[(i + 1) % k].0);
            if s1 <= s0 {
                s1 += l.length;
            }
            let (a, b) = (l.corners[i].2, l.corners[(i + 1) % k].2);
            let tolerance = h.max(0.25 * (b[0] - a[0]).hypot(b[1] - a[1]));
            let steps = ((s1 - s0) / (0.25 * h)).ceil().max(1.0) as usize;
            let off = (1..steps).any(|j| {
                let q = plan.at(&loop_at(
                    v,
                    lp,
                    &l.arc,
                    s0 + (s1 - s0) * j as Real / steps as Real,
                ));
                sv_geom::planar::point_segment_distance(q, a, b) > tolerance
            });
            if off {
                return None;
            }
        }
    }
    // the two directions: the sides' mean direction modulo a right angle
    let sides: Vec<[Real; 2]> = loops
        .iter()
        .flat_map(|l| {
            let k = l.corners.len();
            (0..k).map(move |i| {
                let (a, b) = (l.corners[i].2, l.corners[(i + 1) % k].2);
                [b[0] - a[0], b[1] - a[1]]
            })
        })
        .collect();
    let (mut c, mut s) = (0.0, 0.0);
    for d in &sides {
        let angle = 4.0 * d[1].atan2(d[0]);
        let w = d[0].hypot(d[1]);
        c += w * angle.cos();
        s += w * angle.sin();
    }
    let axis = s.atan2(c) / 4.0;
    let (ca, sa) = (axis.cos(), axis.sin());
    let along = |p: [Real; 2]| [ca * p[0] + sa * p[1], -sa * p[0] + ca * p[1]];
    let back = |q: [Real; 2]| [ca * q[0] - sa * q[1], sa * q[0] + ca * q[1]];
    let quarter = std::f64::consts::FRAC_PI_2;
    for d in &sides {
        let off = (d[1].atan2(d[0]) - axis).rem_euclid(quarter);
        if off.min(quarter - off) > SIDE_TURN.to_radians() {
            return None;
        }
    }
    // every corner in plan along the two directions, the loops one after the other
    let at: Vec<[Real; 2]> = loops
        .iter()
        .flat_map(|l| l.corners.iter().map(|c| along(c.2)))
        .collect();
    let starts: Vec<usize> = loops
        .iter()
        .scan(0, |n, l| {
            *n += l.corners.len();
            Some(*n - l.corners.len())
        })
        .collect();
    // the lines: the two ends of a side share the line it runs along (the plan of a
    // tilted roof turns its sides by a few degrees), then lines nearer than half a unit
    // are one
    let lines = |k: usize| -> (Vec<Real>, Vec<usize>) {
        let mut parent: Vec<usize> = (0..at.len()).collect();
        for (l, &start) in loops.iter().zip(&starts) {
            let n = l.corners.len();
            for i in 0..n {
                let (a, b) = (start + i, start + (i + 1) % n);
                let d = [at[b][0] - at[a][0], at[b][1] - at[a][1]];
                // a side along direction 1 - k keeps coordinate k
                if d[k].abs() < d[1 - k].abs() {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    parent[ra] = rb;
                }
            }
        }
        let mut members: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for c in 0..at.len() {
            members.entry(find(&mut parent, c)).or_default().push(c);
        }
        let mut groups: Vec<(Real, Vec<usize>)> = members
            .into_values()
            .map(|g| {
                (
                    g.iter().map(|&c| at[c][k]).sum::<Real>() / g.len() as Real,
                    g,
                )
            })
            .collect();
        groups.sort_by(|a, b| a.0.total_cmp(&b.0));
        // (sum of coordinates, corners) per line
        let mut lines: Vec<(Real, usize)> = Vec::new();
        let mut line_of = vec![0usize; at.len()];
        for (x, group) in groups {
            let merge = lines
                .last()
                .is_some_and(|&(sum, n)| x - sum / (n as Real) < SAME_LINE * h);
            if !merge {
                lines.push((0.0, 0));
            }
            let last = lines.len() - 1;
            lines[last].0 += x * group.len() as Real;
            lines[last].1 += group.len();
            for c in group {
                line_of[c] = last;
            }
        }
        (
            lines.iter().map(|&(sum, n)| sum / n as Real).collect(),
            line_of,
        )
    };
    let ((xs, x_of), (ys, y_of)) = (lines(0), lines(1));
    // every loop as a polygon of grid points (its corners on their lines)
    let snapped: Vec<Vec<(usize, usize)>> = loops
        .iter()
        .zip(&starts)
        .map(|(l, &start)| {
            (start..start + l.corners.len())
                .map(|c| (x_of[c], y_of[c]))
                .collect()
        })
        .collect();
    // every side along one line, and not collapsed onto a point
    for grid in &snapped {
        let k = grid.len();
        for i in 0..k {
            let (p, q) = (grid[i], grid[(i + 1) % k]);
            if (p.0 == q.0) == (p.1 == q.1) {
                return None;
            }
        }
    }
    let polygon =
        |k: usize| -> Vec<[Real; 2]> { snapped[k].iter().map(|&(i, j)| [xs[i], ys[j]]).collect() };
    let outer = polygon(0);
    let courts: Vec<Vec<[Real; 2]>> = (1..loops.len()).map(polygon).collect();
    let inside = |p: [Real; 2]| {
        sv_geom::planar::point_in_polygon(p, &outer)
            && !courts
                .iter()
                .any(|c| sv_geom::planar::point_in_polygon(p, c))
    };
    let (nx, ny) = (xs.len(), ys.len());
    let mut cells = Vec::new();
    for i in 0..nx.saturating_sub(1) {
        for j in 0..ny.saturating_sub(1) {
            if inside([(xs[i] + xs[i + 1]) / 2.0, (ys[j] + ys[j + 1]) / 2.0]) {
                cells.push((i, j));
            }
        }
    }
    if cells.len() < 2 {
        return None;
    }
    // the grid points the cells use: a loop's corner where it is, a point on a side at its
    // share of the side's length along the loop, any other lifted onto the target
    let mut id = vec![usize::MAX; nx * ny];
    let mut vertices: Vec<Point3> = Vec::new();
    let mut faces = Vec::with_capacity(cells.len());
    for &(i, j) in &cells {
        let mut face = [0usize; 4];
        for (k, &(a, b)) in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            .iter()
            .enumerate()
        {
            if id[a * ny + b] == usize::MAX {
                let p = grid_point(index, &loops, &snapped, (a, b), (&xs, &ys))
                    .or_else(|| plan.lift(back([xs[a], ys[b]])))?;
                vertices.push(p);
                id[a * ny + b] = vertices.len() - 1;
            }
            face[k] = id[a * ny + b];
        }
        faces.push(face);
    }
    Some(QuadMesh { vertices, faces })
}

/// The boundary point of grid point `(a, b)` where it is a loop's corner or lies on one of
/// its sides, else `None`.
fn grid_point(
    index: &TargetIndex<'_>,
    loops: &[Sides],
    snapped: &[Vec<(usize, usize)>],
    (a, b): (usize, usize),
    (xs, ys): (&[Real], &[Real]),
) -> Option<Point3> {
    let v = &index.mesh.vertices;
    for (l, (sides, grid)) in loops.iter().zip(snapped).enumerate() {
        let k = grid.len();
        for i in 0..k {
            let (p, q) = (grid[i], grid[(i + 1) % k]);
            if (a, b) == p {
                return Some(sides.corners[i].1);
            }
            // on the side from p to q (a side runs along one line)
            let t = if p.0 == q.0 && a == p.0 && (p.1.min(q.1)..=p.1.max(q.1)).contains(&b) {
                (ys[b] - ys[p.1]) / (ys[q.1] - ys[p.1])
            } else if p.1 == q.1 && b == p.1 && (p.0.min(q.0)..=p.0.max(q.0)).contains(&a) {
                (xs[a] - xs[p.0]) / (xs[q.0] - xs[p.0])
            } else {
                continue;
            };
            let (s0, mut s1) = (sides.corners[i].0, sides.corners[(i + 1) % k].0);
            if s1 <= s0 {
                s1 += sides.length;
            }
            let lp = &index.loops[l];
            return Some(loop_at(v, lp, &sides.arc, s0 + t * (s1 - s0)));
        }
    }
    None
}
