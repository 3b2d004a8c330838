//! Automatic coarse layouts for footprints that one four-sided patch cannot follow.
//!
//! A quad mesh of a disc satisfies `sum over boundary vertices (2 - faces) + sum over
//! interior vertices (4 - valence) = 4`: a convex corner of the footprint (one face)
//! counts +1, a reflex one (three faces) -1, a valence-3 interior vertex +1, a valence-5
//! one -1. Four convex corners need no irregular vertex (the conformal grid of
//! `param.rs`); any other footprint does, or a reflex corner. From the corners of the
//! outer boundary (where it turns by more than 45 degrees over a window of a fortieth of
//! the perimeter) this module draws a coarse layout that [`crate::layout`] subdivides to
//! the unit size like a designer's:
//!
//! | footprint | coarse layout | irregular vertices |
//! |---|---|---|
//! | no corner (oval, disc) | O-grid: an inner quad and a ring of four faces | four of valence 3 |
//! | 3 or 5+ convex corners (triangle, pentagon) | one face per corner around a centre | the centre, valence = corners |
//! | 5 convex corners and one reflex (L) | three faces meeting at the reflex corner | none (the reflex corner has three faces) |
//! | two boundary loops, one inside the other in plan (annulus) | a ring of eight faces | none |
//! | two boundary loops side by side or one over the other (a tube) | a ring of eight faces along it | none |
//! | sides along two directions at right angles, with reflex corners (not an L) or courts | rectangular cells cut by the lines through the corners (`cell_layout.rs`), tried before the rows above | none |
//!
//! Everything else (four corners, one or two corners, several reflex corners) goes to
//! the four-corner grid; three or more boundary loops that are not cells to none of these. A layout whose
//! subdivision starts with a face flipped against the target does not fit the footprint (an
//! O-grid round a horseshoe's centre, which lies outside its plan; the courtyard's ring
//! round an L-shaped court): [`fallback`] names the one `param.rs` tries next, and
//! [`Drawn::describe`] names each in the report's layout. After them all comes the
//! triangulated footprint (`triangle_layout.rs`).

use sv_frame::QuadMesh;
use sv_geom::{Point3, Real, Vector3};

use crate::target::{loop_arc, loop_at, TargetIndex};

/// Boundary turning above which a point is a corner of the footprint.
const CORNER_TURN: Real = std::f64::consts::FRAC_PI_4;

/// Faces of the ring layout of an annulus.
const RING_FACES: usize = 8;

/// Inner quad of the O-grid: its corners lie this fraction of the way from the centre to
/// the boundary points.
const O_GRID_INNER: Real = 0.7;

/// A corner of a boundary loop: its position in the loop and whether it turns inwards.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Corner {
    pub(crate) at: usize,
    reflex: bool,
}

/// Corners of the outer loop in loop order: local maxima of the turning over `window`
/// either side, above [`CORNER_TURN`], at least two windows apart.
pub(crate) fn corners(index: &TargetIndex<'_>, lp: &[usize], window: Real) -> Vec<Corner> {
    let v = &index.mesh.vertices;
    let arc = loop_arc(v, lp);
    let turn_over = |k: usize, w: Real| {
        let p = v[lp[k]];
        let a = p - loop_at(v, lp, &arc, arc[k] - w);
        let b = loop_at(v, lp, &arc, arc[k] + w) - p;
        if a.norm() == 0.0 || b.norm() == 0.0 {
            return (0.0, false);
        }
        // the outer loop runs counter-clockwise seen from the target's normal side
        let left = a.cross(&b).dot(&index.closest(&p).normal) >= 0.0;
        (a.angle(&b), !left)
    };
    let turn: Vec<(Real, bool)> = (0..lp.len()).map(|k| turn_over(k, window)).collect();
    let mut order: Vec<usize> = (0..lp.len()).filter(|&k| turn[k].0 > CORNER_TURN).collect();
    order.sort_by(|&a, &b| turn[b].0.total_cmp(&turn[a].0).then(a.cmp(&b)));
    let per = arc[lp.len()];
    let apart = |a: usize, b: usize| {
        let d = (arc[a] - arc[b]).abs();
        d.min(per - d) > 2.0 * window
    };
    let mut chosen: Vec<usize> = Vec::new();
    for k in order {
        if chosen.iter().all(|&c| apart(c, k)) {
            chosen.push(k);
        }
    }
    chosen.sort_unstable();
    chosen
        .into_iter()
        .map(|at| Corner {
            at,
            reflex: turn[at].1,
        })
        .collect()
}

/// Which automatic layout was drawn: the messages name it where it folds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Drawn {
    /// The four-corner conformal grid of `param.rs` (no coarse layout), for a footprint
    /// with these convex and reflex corners.
    FourCorner { convex: usize, reflex: usize },
    /// A footprint without corners: an inner quad and a ring of four faces.
    OGrid,
    /// One face per convex corner around the centre (that many corners).
    PerCorner(usize),
    /// An L: three faces meeting at the reflex corner.
    ReflexCorner,
    /// A ring of faces around a courtyard, each outer point joined to the hole's point in
    /// the same direction from the hole's centre.
    Courtyard,
    /// A ring of faces joining the two loops at equal shares of their lengths.
    RingByLength,
    /// A ring of faces along a tube.
    Tube,
    /// A footprint whose sides run along two directions at right angles cut into that
    /// many rectangular cells by the lines through its corners (`cell_layout.rs`).
    Cells(usize),
    /// None of the above: the target has this many boundary loops (three or more) and its
    /// sides do not run at right angles.
    NoLoopLayout(usize),
    /// The last: the footprint triangulated in plan (`triangle_layout.rs`).
    Triangulated,
}

/// How a layout starts: the four-corner grid of `param.rs`, a coarse quad mesh that
/// [`crate::layout`] subdivides, or why it cannot be drawn on this footprint.
pub(crate) enum Start {
    Grid,
    Coarse(QuadMesh),
    Unfit(String),
}

impl Drawn {
    /// The layout in the words of docs/secondary.md's table.
    pub(crate) fn describe(self) -> String {
        match self {
            Drawn::FourCorner { convex, reflex } => format!(
                "the four-corner grid (the footprint has {convex} convex and {reflex} reflex corners)"
            ),
            Drawn::OGrid => "the O-grid of a footprint without corners".into(),
            Drawn::PerCorner(k) => format!("one face per corner ({k} corners round the centre)"),
            Drawn::ReflexCorner => {
                "three faces at the reflex corner (five convex corners and one reflex)".into()
            }
            Drawn::Courtyard => format!("the ring of {RING_FACES} faces round the courtyard"),
            Drawn::RingByLength => format!(
                "the ring of {RING_FACES} faces joining the two loops at equal shares of their lengths"
            ),
            Drawn::Tube => format!("the ring of {RING_FACES} faces along the tube"),
            Drawn::Cells(n) => format!(
                "{n} cells cut by the lines through the corners (the sides run along two directions at right angles)"
            ),
            Drawn::NoLoopLayout(_) => "the cells (the sides do not run along two directions at right angles), the rings and grids".into(),
            Drawn::Triangulated => "the footprint triangulated in plan, its triangles paired into quads and split (irregular vertices wherever the triangulation puts them)".into(),
        }
    }
}

/// The layout to try where `drawn` does not fit `index`'s target (at unit `h`), if any:
/// the four-corner grid after a one-loop coarse layout (it opens its smooth corners into
/// valence-3 vertices as the O-grid has them), the ring joined by arc length after the
/// courtyard's ring (a courtyard not star-shaped about its centre: an L), the layouts
/// without cells after the cells, and after the last of those the triangulated footprint.
pub(crate) fn fallback(index: &TargetIndex<'_>, drawn: Drawn, h: Real) -> Option<(Drawn, Start)> {
    match drawn {
        Drawn::Cells(_) => Some(layout_without_cells(index)),
        Drawn::OGrid | Drawn::PerCorner(_) | Drawn::ReflexCorner => {
            let (convex, reflex) = corner_counts(index);
            Some((Drawn::FourCorner { convex, reflex }, Start::Grid))
        }
        Drawn::Courtyard => Some((Drawn::RingByLength, Start::Coarse(tube(index)))),
        Drawn::FourCorner { .. } | Drawn::RingByLength | Drawn::Tube | Drawn::NoLoopLayout(_) => {
            let side = crate::triangle_layout::TRIANGLE_SIDE * h;
            let start = match crate::triangle_layout::triangle_layout(index, side) {
                Some(coarse) => Start::Coarse(coarse),
                None => {
                    Start::Unfit("the footprint is not one sheet over the target's plane".into())
                }
            };
            Some((Drawn::Triangulated, start))
        }
        Drawn::Triangulated => None,
    }
}

/// Convex and reflex corners of the outer loop.
fn corner_counts(index: &TargetIndex<'_>) -> (usize, usize) {
    let found = corners(index, &index.boundary, index.perimeter() / 40.0);
    let convex = found.iter().filter(|c| !c.reflex).count();
    (convex, found.len() - convex)
}

/// The automatic layout of `index`'s target at unit `h` (see the module documentation):
/// three or more boundary loops that are not cells (a roof with two round courtyards) have
/// none of their own, and [`fallback`] goes on to the triangulated footprint.
pub(crate) fn coarse_layout(index: &TargetIndex<'_>, h: Real) -> (Drawn, Start) {
    let (convex, reflex) = corner_counts(index);
    let cells_first = index.loops.len() > 1 || (reflex > 0 && (convex, reflex) != (5, 1));
    if cells_first {
        if let Some(cells) = crate::cell_layout::cell_layout(index, h) {
            return (Drawn::Cells(cells.faces.len()), Start::Coarse(cells));
        }
    }
    layout_without_cells(index)
}

/// [`coarse_layout`] but for the cells.
fn layout_without_cells(index: &TargetIndex<'_>) -> (Drawn, Start) {
    let v = &index.mesh.vertices;
    match index.loops.len() {
        1 => {}
        2 => {
            let ring = if loops_nested_in_plan(index) {
                (Drawn::Courtyard, ring(index))
            } else {
                (Drawn::Tube, tube(index))
            };
            return (ring.0, Start::Coarse(ring.1));
        }
        n => {
            return (
                Drawn::NoLoopLayout(n),
                Start::Unfit(format!("for one or two boundary loops; the target has {n}")),
            )
        }
    }
    let lp = &index.boundary;
    let window = index.perimeter() / 40.0;
    let found = corners(index, lp, window);
    let convex = found.iter().filter(|c| !c.reflex).count();
    let reflex = found.len() - convex;
    let arc = loop_arc(v, lp);
    let point = |k: usize| v[lp[k]];
    let mid = |a: usize, b: usize| {
        let (sa, mut sb) = (arc[a], arc[b]);
        if sb <= sa {
            sb += arc[lp.len()];
        }
        loop_at(v, lp, &arc, 0.5 * (sa + sb))
    };
    let layout = match (convex, reflex) {
        (0, 0) => (Drawn::OGrid, o_grid(index)),
        (3, 0) | (5.., 0) => {
            // one face per corner: corner, midpoint to the next corner, centre, midpoint
            // from the previous corner
            let k = found.len();
            let centre = index
                .closest(&crate::param::target_frame(index.mesh).centre)
                .point;
            let mut vertices: Vec<Point3> = found.iter().map(|c| point(c.at)).collect();
            vertices.extend((0..k).map(|i| mid(found[i].at, found[(i + 1) % k].at)));
            vertices.push(centre);
            let faces = (0..k)
                .map(|i| [i, k + i, 2 * k, k + (i + k - 1) % k])
                .collect();
            (Drawn::PerCorner(k), QuadMesh { vertices, faces })
        }
        (5, 1) => {
            // an L: the reflex corner r, the corners around it c1 .. c5, the one opposite
            // it c3; the points p, q where the sides through r, continued, meet the far
            // sides
            let r = found.iter().position(|c| c.reflex).unwrap_or(0);
            let c = |i: usize| found[(r + i) % 6].at;
            let closest_between = |a: usize, b: usize| {
                let mut k = a;
                let mut best = (Real::INFINITY, a);
                while k != b {
                    let d = (point(k) - point(c(0))).norm();
                    if d < best.0 {
                        best = (d, k);
                    }
                    k = (k + 1) % lp.len();
                }
                point(best.1)
            };
            let p = closest_between(c(3), c(4));
            let q = closest_between(c(2), c(3));
            // vertices: r, c1 .. c5, p, q
            let mut vertices: Vec<Point3> = (0..6).map(|i| point(c(i))).collect();
            vertices.push(p);
            vertices.push(q);
            let faces = vec![[3, 6, 0, 7], [6, 4, 5, 0], [7, 0, 1, 2]];
            (Drawn::ReflexCorner, QuadMesh { vertices, faces })
        }
        _ => return (Drawn::FourCorner { convex, reflex }, Start::Grid),
    };
    (layout.0, Start::Coarse(layout.1))
}

/// Boundary points where the loop is extreme along the target frame's diagonals, in loop
/// order, and the frame centre on the target.
fn diagonal_extremes(index: &TargetIndex<'_>, lp: &[usize], count: usize) -> Vec<Point3> {
    let v = &index.mesh.vertices;
    let frame = crate::param::target_frame(index.mesh);
    let mut at: Vec<usize> = (0..count)
        .map(|k| {
            let phi = std::f64::consts::FRAC_PI_4
                + 2.0 * std::f64::consts::PI * k as Real / count as Real;
            let dir: Vector3 = frame.d1 * phi.cos() + frame.d2 * phi.sin();
            (0..lp.len())
                .max_by(|&a, &b| {
                    (v[lp[a]] - frame.centre)
                        .dot(&dir)
                        .total_cmp(&(v[lp[b]] - frame.centre).dot(&dir))
                })
                .unwrap_or(0)
        })
        .collect();
    // loop order, starting anywhere
    let first = at[0];
    at.sort_by_key(|&k| (k + lp.len() - first) % lp.len());
    at.dedup();
    at.into_iter().map(|k| v[lp[k]]).collect()
}

/// O-grid of a footprint without corners: four boundary points at the extremes along the
/// frame diagonals, an inner quad between them and the centre.
fn o_grid(index: &TargetIndex<'_>) -> QuadMesh {
    let rim = diagonal_extremes(index, &index.boundary, 4);
    let centre = index
        .closest(&crate::param::target_frame(index.mesh).centre)
        .point;
    let n = rim.len();
    let mut vertices = rim.clone();
    vertices.extend(rim.iter().map(|b| centre + (b - centre) * O_GRID_INNER));
    let mut faces: Vec<[usize; 4]> = (0..n)
        .map(|k| [k, (k + 1) % n, n + (k + 1) % n, n + k])
        .collect();
    if n == 4 {
        faces.push([4, 5, 6, 7]);
    }
    QuadMesh { vertices, faces }
}

/// Share of the outer loop's area in plan below which a second loop inside it is a hole
/// (a courtyard); above it the two loops are the ends of a tube (an open cylinder standing
/// with its rims one over the other has equal areas in plan).
const HOLE_AREA_SHARE: Real = 0.9;

/// Whether the second boundary loop lies inside the first seen in plan (along the normal
/// of the target's plane), as a courtyard does in a roof, rather than across the surface
/// from it, as the two rims of a tube do.
fn loops_nested_in_plan(index: &TargetIndex<'_>) -> bool {
    let v = &index.mesh.vertices;
    let frame = crate::param::target_frame(index.mesh);
    let plan = |lp: &[usize]| -> Vec<[Real; 2]> {
        lp.iter()
            .map(|&i| {
                let d = v[i] - frame.centre;
                [d.dot(&frame.d1), d.dot(&frame.d2)]
            })
            .collect()
    };
    let (outer, inner) = (plan(&index.loops[0]), plan(&index.loops[1]));
    let area = |p: &[[Real; 2]]| sv_geom::planar::polygon_area(p).abs();
    area(&inner) < HOLE_AREA_SHARE * area(&outer)
        && inner
            .iter()
            .all(|&p| sv_geom::planar::point_in_polygon(p, &outer))
}

/// Ring of [`RING_FACES`] faces along a tube (two loops across the surface from each
/// other, an open cylinder standing or lying): points evenly by arc length on the first
/// loop, each joined to the point of the second at the same share of its length, run the
/// other way (each loop has the surface on its left), turned to the start that makes the
/// joins shortest (the rulings of a cylinder). No irregular vertex and no corner.
fn tube(index: &TargetIndex<'_>) -> QuadMesh {
    let v = &index.mesh.vertices;
    let (first, second) = (&index.loops[0], &index.loops[1]);
    let (arc1, arc2) = (loop_arc(v, first), loop_arc(v, second));
    let (len1, len2) = (arc1[first.len()], arc2[second.len()]);
    let n = RING_FACES;
    let rim: Vec<Point3> = (0..n)
        .map(|k| loop_at(v, first, &arc1, len1 * k as Real / n as Real))
        .collect();
    let across = |start: Real| -> Vec<Point3> {
        (0..n)
            .map(|k| loop_at(v, second, &arc2, start - len2 * k as Real / n as Real))
            .collect()
    };
    let joins = |other: &[Point3]| -> Real {
        rim.iter()
            .zip(other)
            .map(|(a, b)| (a - b).norm_squared())
            .sum()
    };
    // the start on the second loop: each of its vertices tried
    let start = (0..second.len())
        .map(|k| arc2[k])
        .min_by(|&a, &b| joins(&across(a)).total_cmp(&joins(&across(b))))
        .unwrap_or(0.0);
    let mut vertices = rim;
    vertices.extend(across(start));
    let faces = (0..n)
        .map(|k| [k, (k + 1) % n, n + (k + 1) % n, n + k])
        .collect();
    QuadMesh { vertices, faces }
}

/// Ring of [`RING_FACES`] faces between the outer loop and the hole: outer points evenly
/// by arc length, each joined to the hole's point in the same direction from the hole's
/// centre.
fn ring(index: &TargetIndex<'_>) -> QuadMesh {
    let v = &index.mesh.vertices;
    let (outer, inner) = (&index.loops[0], &index.loops[1]);
    let arc = loop_arc(v, outer);
    let hole =
        Point3::from(inner.iter().map(|&i| v[i].coords).sum::<Vector3>() / inner.len() as Real);
    let normal = index.closest(&hole).normal;
    let flat = |d: Vector3| d - normal * normal.dot(&d);
    let rim: Vec<Point3> = (0..RING_FACES)
        .map(|k| {
            loop_at(
                v,
                outer,
                &arc,
                arc[outer.len()] * k as Real / RING_FACES as Real,
            )
        })
        .collect();
    let court: Vec<Point3> = rim
        .iter()
        .map(|o| {
            let dir = flat(o - hole);
            let k = inner
                .iter()
                .max_by(|&&a, &&b| {
                    let ca = flat(v[a] - hole).normalize().dot(&dir);
                    let cb = flat(v[b] - hole).normalize().dot(&dir);
                    ca.total_cmp(&cb)
                })
                .copied()
                .unwrap_or(inner[0]);
            v[k]
        })
        .collect();
    let n = RING_FACES;
    let mut vertices = rim;
    vertices.extend(court);
    let faces = (0..n)
        .map(|k| [k, (k + 1) % n, n + (k + 1) % n, n + k])
        .collect();
    QuadMesh { vertices, faces }
}
