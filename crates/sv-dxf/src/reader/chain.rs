//! Open segments (LINE, ARC, open polylines, fitted curves) into closed contours: repeated
//! and overlapping segments merged, ends within the join tolerance joined, dangling runs
//! reported as open contours, and where lines meet a contour inside it (bend lines drawn
//! on a cut layer, a title block's grid) the contour is the outer boundary and those lines
//! are reported, not chained through.

use std::collections::hash_map::Entry;
use std::collections::{HashMap, HashSet};

use sv_geom::{planar, Contour, Segment, Vertex};

use super::source::{Closed, Cut, Piece};

/// A contour made of pieces.
pub(crate) struct Chained {
    pub(crate) contour: Contour,
    pub(crate) srcs: Vec<usize>,
    pub(crate) cut: Cut,
}

/// A run of pieces that does not close.
pub(crate) struct Open {
    pub(crate) srcs: Vec<usize>,
    /// its loose ends
    pub(crate) loose: Vec<[f64; 2]>,
}

/// What the chaining did besides chaining: `(sources, what)`.
pub(crate) type Repair = (Vec<usize>, String);

#[derive(Default)]
pub(crate) struct Chains {
    pub(crate) contours: Vec<Chained>,
    pub(crate) open: Vec<Open>,
    pub(crate) repairs: Vec<Repair>,
}

/// A uniform grid over boxes, for neighbour queries.
struct Grid {
    cell: f64,
    map: HashMap<(i64, i64), Vec<usize>>,
}

impl Grid {
    fn new(cell: f64) -> Self {
        Self {
            cell: cell.max(1e-9),
            map: HashMap::new(),
        }
    }

    fn range(&self, lo: [f64; 2], hi: [f64; 2]) -> (i64, i64, i64, i64) {
        let c = |v: f64| (v / self.cell).floor() as i64;
        (c(lo[0]), c(lo[1]), c(hi[0]), c(hi[1]))
    }

    fn insert(&mut self, i: usize, lo: [f64; 2], hi: [f64; 2]) {
        let (x0, y0, x1, y1) = self.range(lo, hi);
        // a huge box (a border line) goes into a bounded number of cells per axis
        for x in x0..=x1.min(x0 + 4096) {
            for y in y0..=y1.min(y0 + 4096) {
                self.map.entry((x, y)).or_default().push(i);
            }
        }
    }

    fn near(&self, lo: [f64; 2], hi: [f64; 2]) -> Vec<usize> {
        let (x0, y0, x1, y1) = self.range(lo, hi);
        let mut out = Vec::new();
        for x in x0..=x1.min(x0 + 4096) {
            for y in y0..=y1.min(y0 + 4096) {
                if let Some(v) = self.map.get(&(x, y)) {
                    out.extend_from_slice(v);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

/// The sets of `parent` (a union-find over `0..n`), each ascending, in order of their
/// root: [`union`] makes the smallest index the root, so in order of their first member.
fn sets(parent: &mut [usize]) -> Vec<Vec<usize>> {
    let n = parent.len();
    let mut sets: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        let r = find(parent, i);
        sets[r].push(i);
    }
    sets.retain(|g| !g.is_empty());
    sets
}

fn bounds(s: &Segment) -> ([f64; 2], [f64; 2]) {
    let c = Contour::new(vec![
        Vertex::new(s.start[0], s.start[1], s.bulge),
        Vertex::line(s.end[0], s.end[1]),
    ]);
    // a two-vertex contour: the arc there and the chord back, whose box is the arc's
    c.bounds().unwrap_or((s.start, s.start))
}

/// A segment's carrier: the line (origin, unit direction) or the circle (centre, radius).
enum Carrier {
    Line([f64; 2], [f64; 2]),
    Circle([f64; 2], f64),
}

fn carrier(s: &Segment) -> Carrier {
    match s.arc() {
        Some((r, c)) => Carrier::Circle(c, r),
        None => {
            let l = s.chord().max(1e-300);
            Carrier::Line(
                s.start,
                [(s.end[0] - s.start[0]) / l, (s.end[1] - s.start[1]) / l],
            )
        }
    }
}

/// The parameter interval of `s` on `carrier` (line: distance along it; circle: angle,
/// counter-clockwise, starting in `[0, 2 pi)`), if `s` lies on the carrier within `tol`.
fn interval(c: &Carrier, s: &Segment, tol: f64) -> Option<(f64, f64)> {
    match (c, s.arc()) {
        (Carrier::Line(o, u), None) => {
            let off = |p: [f64; 2]| ((p[0] - o[0]) * u[1] - (p[1] - o[1]) * u[0]).abs();
            if off(s.start) > tol || off(s.end) > tol {
                return None;
            }
            let t = |p: [f64; 2]| (p[0] - o[0]) * u[0] + (p[1] - o[1]) * u[1];
            let (a, b) = (t(s.start), t(s.end));
            Some((a.min(b), a.max(b)))
        }
        (Carrier::Circle(c, r), Some((r2, c2))) => {
            if planar::distance(*c, c2) > tol || (r - r2).abs() > tol {
                return None;
            }
            let ang = |p: [f64; 2]| {
                (p[1] - c[1])
                    .atan2(p[0] - c[0])
                    .rem_euclid(std::f64::consts::TAU)
            };
            let (from, sweep) = if s.bulge > 0.0 {
                (ang(s.start), s.sweep())
            } else {
                (ang(s.end), -s.sweep())
            };
            Some((from, from + sweep))
        }
        _ => None,
    }
}

/// Whether two segments share more than a point (one repeats part of the other).
fn overlap(a: &Segment, b: &Segment, tol: f64) -> bool {
    let ca = carrier(if a.length() >= b.length() { a } else { b });
    let (Some(ia), Some(ib)) = (interval(&ca, a, tol), interval(&ca, b, tol)) else {
        return false;
    };
    let scale = match ca {
        Carrier::Line(..) => 1.0,
        Carrier::Circle(_, r) => r.max(1e-9),
    };
    let period = if matches!(ca, Carrier::Circle(..)) {
        std::f64::consts::TAU
    } else {
        0.0
    };
    [-period, 0.0, period].iter().any(|&shift| {
        let (lo, hi) = (ia.0.max(ib.0 + shift), ia.1.min(ib.1 + shift));
        (hi - lo) * scale > tol
    })
}

/// The groups of pieces that overlap one another (directly or through others), each in
/// ascending order, the groups in order of their first piece; and the pairs tried (the
/// work done, which a test bounds).
fn overlap_groups(pieces: &[Piece], tol: f64) -> (Vec<Vec<usize>>, usize) {
    let n = pieces.len();
    let mut tried = 0;
    let mut parent: Vec<usize> = (0..n).collect();
    // a segment drawn again the same way (an array inserting a block at one place)
    // overlaps what its first drawing overlaps: the copy joins the first drawing's group,
    // only the first is tried against the others (a copy too short to overlap its first
    // drawing is tried like any piece)
    let mut first: HashMap<[u64; 5], usize> = HashMap::new();
    let mut distinct: Vec<usize> = Vec::with_capacity(n);
    for (i, p) in pieces.iter().enumerate() {
        let s = &p.seg;
        let key = [s.start[0], s.start[1], s.end[0], s.end[1], s.bulge].map(f64::to_bits);
        if let Some(&f) = first.get(&key) {
            tried += 1;
            if overlap(&pieces[f].seg, s, tol) {
                union(&mut parent, f, i);
                continue;
            }
        } else {
            first.insert(key, i);
        }
        distinct.push(i);
    }
    let boxes: Vec<([f64; 2], [f64; 2])> =
        distinct.iter().map(|&i| bounds(&pieces[i].seg)).collect();
    let cell = {
        let total: f64 = boxes
            .iter()
            .map(|(lo, hi)| planar::distance(*lo, *hi))
            .sum();
        (total / boxes.len().max(1) as f64).max(tol * 4.0)
    };
    let lanes: Vec<Lane> = distinct
        .iter()
        .map(|&i| Lane::of(&pieces[i].seg, tol))
        .collect();
    let mut grids: HashMap<Lane, Grid> = HashMap::new();
    for (k, (lo, hi)) in boxes.iter().enumerate() {
        grids
            .entry(lanes[k])
            .or_insert_with(|| Grid::new(cell))
            .insert(k, *lo, *hi);
    }
    for (k, &i) in distinct.iter().enumerate() {
        let (lo, hi) = boxes[k];
        for (lane, later) in lanes[k].asks() {
            let Some(grid) = grids.get(&lane) else {
                continue;
            };
            for l in grid.near([lo[0] - tol, lo[1] - tol], [hi[0] + tol, hi[1] + tol]) {
                if later && l <= k {
                    continue;
                }
                let j = distinct[l];
                tried += 1;
                if overlap(&pieces[i].seg, &pieces[j].seg, tol) {
                    union(&mut parent, i, j);
                }
            }
        }
    }
    (sets(&mut parent), tried)
}

/// Levels of direction bins of [`Lane`]: level `l` splits the half turn into `2^l` bins.
const LEVELS: u32 = 9;

/// Which pieces may overlap ([`overlap`]): an arc only arcs, a line only lines in the same
/// or a neighbouring bin of direction, at the level of the shorter line. The shorter
/// line's ends within `tol` of the longer one's line turn it by at most `asin(2 tol / L)`,
/// so a line `L` long goes to the finest level whose bins are wider than
/// `asin(2.5 tol / L)` (level 9, bins of 0.35 degrees, from 16 mm at 0.05 mm; level 0, one
/// bin, below 0.125 mm) and is tried against the lines of its own level and coarser ones
/// in the three bins around it. So the lines through one point (a star of 40,000) are not
/// each tried against every other.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Lane {
    Arc,
    Line { level: u32, bin: usize },
}

impl Lane {
    fn of(s: &Segment, tol: f64) -> Self {
        if s.arc().is_some() {
            return Lane::Arc;
        }
        let half_turn = std::f64::consts::PI;
        let slack = 2.5 * tol / s.chord();
        let mut level = 0;
        while level < LEVELS && (half_turn / f64::from(1u32 << (level + 1))).sin() >= slack {
            level += 1;
        }
        let angle = (s.end[1] - s.start[1])
            .atan2(s.end[0] - s.start[0])
            .rem_euclid(half_turn);
        let bins = 1usize << level;
        let bin = ((angle / half_turn * bins as f64) as usize).min(bins - 1);
        Lane::Line { level, bin }
    }

    /// The lanes a piece of this lane is tried against, and whether only against later
    /// pieces there (a pair tried once: by the finer of the two lines, or by the first of
    /// two at one level).
    fn asks(self) -> Vec<(Lane, bool)> {
        match self {
            Lane::Arc => vec![(self, true)],
            Lane::Line { level, bin } => {
                let mut asks = Vec::new();
                for l in 0..=level {
                    let bins = 1usize << l;
                    let at = bin >> (level - l);
                    let mut near = vec![(at + bins - 1) % bins, at, (at + 1) % bins];
                    near.sort_unstable();
                    near.dedup();
                    asks.extend(
                        near.into_iter()
                            .map(|bin| (Lane::Line { level: l, bin }, l == level)),
                    );
                }
                asks
            }
        }
    }
}

/// Merges groups of overlapping pieces into the pieces of their union, split where the
/// members ended (so the rest still joins there).
fn merge_overlaps(pieces: Vec<Piece>, tol: f64, repairs: &mut Vec<Repair>) -> Vec<Piece> {
    let (groups, _) = overlap_groups(&pieces, tol);
    let mut out = Vec::with_capacity(pieces.len());
    for members in &groups {
        if members.len() == 1 {
            out.push(pieces[members[0]]);
            continue;
        }
        let longest = *members
            .iter()
            .max_by(|&&a, &&b| {
                pieces[a]
                    .seg
                    .length()
                    .total_cmp(&pieces[b].seg.length())
                    .then(b.cmp(&a))
            })
            .unwrap_or(&members[0]);
        let c = carrier(&pieces[longest].seg);
        let cut = members
            .iter()
            .map(|&m| pieces[m].cut)
            .min()
            .unwrap_or(Cut::Either);
        let src = pieces[longest].src;
        let mut iv: Vec<(f64, f64)> = members
            .iter()
            .filter_map(|&m| interval(&c, &pieces[m].seg, tol))
            .collect();
        let mut breaks: Vec<f64> = iv.iter().flat_map(|&(a, b)| [a, b]).collect();
        if let Carrier::Circle(..) = c {
            // unwrap the angles onto the longest member's turn
            let base = interval(&c, &pieces[longest].seg, tol).map_or(0.0, |i| i.0);
            for i in iv.iter_mut() {
                while i.0 < base - 1e-12 {
                    i.0 += std::f64::consts::TAU;
                    i.1 += std::f64::consts::TAU;
                }
            }
            breaks = iv.iter().flat_map(|&(a, b)| [a, b]).collect();
        }
        iv.sort_by(|a, b| a.0.total_cmp(&b.0));
        breaks.sort_by(f64::total_cmp);
        let scale = match c {
            Carrier::Line(..) => 1.0,
            Carrier::Circle(_, r) => r.max(1e-9),
        };
        let mut union_iv: Vec<(f64, f64)> = Vec::new();
        for (a, b) in iv {
            match union_iv.last_mut() {
                Some(last) if a <= last.1 + tol / scale => last.1 = last.1.max(b),
                _ => union_iv.push((a, b)),
            }
        }
        let member_length: f64 = members.iter().map(|&m| pieces[m].seg.length()).sum();
        let union_length: f64 = union_iv.iter().map(|(a, b)| (b - a) * scale).sum();
        if member_length > union_length + tol {
            repairs.push((
                members.iter().map(|&m| pieces[m].src).collect(),
                format!(
                    "repeated or overlapping segments merged ({:.3} mm drawn twice)",
                    member_length - union_length
                ),
            ));
        }
        let point = |t: f64| match c {
            Carrier::Line(o, u) => [o[0] + t * u[0], o[1] + t * u[1]],
            Carrier::Circle(cc, r) => [cc[0] + r * t.cos(), cc[1] + r * t.sin()],
        };
        for (a, b) in union_iv {
            let mut ts: Vec<f64> = vec![a];
            ts.extend(
                breaks
                    .iter()
                    .copied()
                    .filter(|&t| t > a + tol / scale && t < b - tol / scale),
            );
            ts.push(b);
            ts.dedup_by(|x, y| (*x - *y).abs() * scale <= tol);
            for w in ts.windows(2) {
                let bulge = match c {
                    Carrier::Line(..) => 0.0,
                    Carrier::Circle(..) => ((w[1] - w[0]) / 4.0).tan(),
                };
                if let Carrier::Circle(..) = c {
                    // a full circle in at most quarter turns
                    let k = ((w[1] - w[0]) / std::f64::consts::FRAC_PI_2)
                        .ceil()
                        .max(1.0) as usize;
                    for j in 0..k {
                        let (s, e) = (
                            w[0] + (w[1] - w[0]) * j as f64 / k as f64,
                            w[0] + (w[1] - w[0]) * (j + 1) as f64 / k as f64,
                        );
                        out.push(Piece {
                            seg: Segment {
                                start: point(s),
                                end: point(e),
                                bulge: ((e - s) / 4.0).tan(),
                            },
                            src,
                            cut,
                        });
                    }
                    continue;
                }
                out.push(Piece {
                    seg: Segment {
                        start: point(w[0]),
                        end: point(w[1]),
                        bulge,
                    },
                    src,
                    cut,
                });
            }
        }
    }
    out
}

/// Pieces that repeat a segment of a closed contour drawn as one entity are dropped.
fn drop_covered(
    pieces: Vec<Piece>,
    closed: &[Closed],
    tol: f64,
    repairs: &mut Vec<Repair>,
) -> Vec<Piece> {
    if closed.is_empty() || pieces.is_empty() {
        return pieces;
    }
    let segs: Vec<(Segment, usize)> = closed
        .iter()
        .flat_map(|c| c.contour.segments().map(move |s| (s, c.src)))
        .collect();
    let boxes: Vec<([f64; 2], [f64; 2])> = segs.iter().map(|(s, _)| bounds(s)).collect();
    let cell = (boxes
        .iter()
        .map(|(lo, hi)| planar::distance(*lo, *hi))
        .sum::<f64>()
        / boxes.len() as f64)
        .max(tol * 4.0);
    let mut grid = Grid::new(cell);
    for (i, (lo, hi)) in boxes.iter().enumerate() {
        grid.insert(i, *lo, *hi);
    }
    let mut out = Vec::with_capacity(pieces.len());
    for p in pieces {
        let (lo, hi) = bounds(&p.seg);
        let covered = grid
            .near([lo[0] - tol, lo[1] - tol], [hi[0] + tol, hi[1] + tol])
            .into_iter()
            .find(|&j| {
                let c = carrier(&segs[j].0);
                match (interval(&c, &segs[j].0, tol), interval(&c, &p.seg, tol)) {
                    (Some(a), Some(b)) => {
                        let period = if matches!(c, Carrier::Circle(..)) {
                            std::f64::consts::TAU
                        } else {
                            0.0
                        };
                        let scale = match c {
                            Carrier::Line(..) => 1.0,
                            Carrier::Circle(_, r) => r,
                        };
                        [-period, 0.0, period].iter().any(|&sh| {
                            b.0 + sh >= a.0 - tol / scale && b.1 + sh <= a.1 + tol / scale
                        })
                    }
                    _ => false,
                }
            });
        match covered {
            Some(j) => repairs.push((
                vec![p.src, segs[j].1],
                "repeats a closed contour drawn as one entity: dropped".into(),
            )),
            None => out.push(p),
        }
    }
    out
}

/// A half-edge: edge `e` run forward (`fwd`) or back.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Half {
    e: usize,
    fwd: bool,
}

struct Graph {
    nodes: Vec<[f64; 2]>,
    /// edge: (from node, to node, segment from -> to, piece)
    edges: Vec<(usize, usize, Segment, usize)>,
}

impl Graph {
    fn seg(&self, h: Half) -> Segment {
        let s = self.edges[h.e].2;
        if h.fwd {
            s
        } else {
            s.reversed()
        }
    }

    fn from(&self, h: Half) -> usize {
        if h.fwd {
            self.edges[h.e].0
        } else {
            self.edges[h.e].1
        }
    }

    fn to(&self, h: Half) -> usize {
        if h.fwd {
            self.edges[h.e].1
        } else {
            self.edges[h.e].0
        }
    }
}

/// The nodes of the piece ends `ends` (piece `k`'s start and end at `2k`, `2k + 1`) as a
/// union-find parent array. An end drawn again at the same place joins its first drawing at
/// once (many lines meeting at one point). Then a loose end (alone at its place) joins the
/// nearest node within `tol`, the nearest pairs first, unless that would put both ends of
/// one piece in one node. Two places where pieces already meet are not joined: a curve drawn
/// as lines shorter than the tolerance stays a curve instead of every vertex joining its
/// neighbours', down the whole chain, into one point.
fn join_ends(ends: &[[f64; 2]], tol: f64) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..ends.len()).collect();
    let mut first_at: HashMap<[u64; 2], usize> = HashMap::new();
    let mut grid = Grid::new(tol);
    let mut distinct = Vec::new();
    for (i, p) in ends.iter().enumerate() {
        match first_at.entry([p[0].to_bits(), p[1].to_bits()]) {
            Entry::Occupied(first) => union(&mut parent, *first.get(), i),
            Entry::Vacant(slot) => {
                slot.insert(i);
                grid.insert(i, *p, *p);
                distinct.push(i);
            }
        }
    }
    // the ends at each place, and the pieces with an end there (by root)
    let mut at: HashMap<usize, (usize, HashSet<usize>)> = HashMap::new();
    for i in 0..ends.len() {
        let r = find(&mut parent, i);
        let node = at.entry(r).or_default();
        node.0 += 1;
        node.1.insert(i / 2);
    }
    let mut near: Vec<(f64, usize, usize)> = Vec::new();
    for &i in &distinct {
        if at[&i].0 != 1 {
            continue;
        }
        let p = ends[i];
        for j in grid.near([p[0] - tol, p[1] - tol], [p[0] + tol, p[1] + tol]) {
            let d = planar::distance(p, ends[j]);
            // a pair of loose ends once
            if j != i && d <= tol && (at[&j].0 != 1 || j > i) {
                near.push((d, i.min(j), i.max(j)));
            }
        }
    }
    near.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    for (_, i, j) in near {
        let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
        if ri == rj || (at[&ri].0 != 1 && at[&rj].0 != 1) {
            continue;
        }
        // the smaller node's pieces looked up in, then moved into, the larger's
        let (big, small) = if at[&ri].1.len() >= at[&rj].1.len() {
            (ri, rj)
        } else {
            (rj, ri)
        };
        if at[&small].1.iter().any(|k| at[&big].1.contains(k)) {
            continue;
        }
        let (count, pieces) = at.remove(&small).unwrap_or_default();
        let mut node = at.remove(&big).unwrap_or_default();
        node.0 += count;
        node.1.extend(pieces);
        let (root, other) = (ri.min(rj), ri.max(rj));
        at.insert(root, node);
        parent[other] = root;
    }
    parent
}

/// Chains `pieces` into contours (see the module doc).
pub(crate) fn chain(pieces: Vec<Piece>, closed: &[Closed], tol: f64) -> Chains {
    let mut chains = Chains::default();
    let pieces = drop_covered(pieces, closed, tol, &mut chains.repairs);
    let pieces = merge_overlaps(pieces, tol, &mut chains.repairs);
    if pieces.is_empty() {
        return chains;
    }
    // nodes: ends within the tolerance of each other
    let ends: Vec<[f64; 2]> = pieces
        .iter()
        .flat_map(|p| [p.seg.start, p.seg.end])
        .collect();
    let mut parent = join_ends(&ends, tol);
    let mut node_of: HashMap<usize, usize> = HashMap::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let mut end_node = vec![0; ends.len()];
    for i in 0..ends.len() {
        let r = find(&mut parent, i);
        let k = *node_of.entry(r).or_insert_with(|| {
            members.push(Vec::new());
            members.len() - 1
        });
        members[k].push(i);
        end_node[i] = k;
    }
    let nodes: Vec<[f64; 2]> = members
        .iter()
        .map(|m| {
            // an end of the file's own precision stays put; a gap closes at its middle
            let n = m.len() as f64;
            let (x, y) = m.iter().fold((0.0, 0.0), |(x, y), &i| {
                (x + ends[i][0] / n, y + ends[i][1] / n)
            });
            [x, y]
        })
        .collect();
    for (k, m) in members.iter().enumerate() {
        let points: Vec<[f64; 2]> = m.iter().map(|&i| ends[i]).collect();
        let spread = sv_geom::planar::diameter(&points);
        if spread > 1e-6 {
            let mut srcs: Vec<usize> = m.iter().map(|&i| pieces[i / 2].src).collect();
            srcs.sort_unstable();
            srcs.dedup();
            chains.repairs.push((
                srcs,
                format!(
                    "gap of {spread:.4} mm closed at ({:.3}, {:.3}) (join tolerance {tol} mm)",
                    nodes[k][0], nodes[k][1]
                ),
            ));
        }
    }
    let mut graph = Graph {
        nodes,
        edges: Vec::new(),
    };
    for (i, p) in pieces.iter().enumerate() {
        let (a, b) = (end_node[2 * i], end_node[2 * i + 1]);
        if a == b {
            // shorter than the tolerance (or a full circle drawn as one arc: not from
            // entities, those are closed contours already)
            chains.repairs.push((
                vec![p.src],
                format!(
                    "a piece shorter than the join tolerance ({:.4} mm) dropped",
                    p.seg.length()
                ),
            ));
            continue;
        }
        let seg = Segment {
            start: graph.nodes[a],
            end: graph.nodes[b],
            bulge: p.seg.bulge,
        };
        graph.edges.push((a, b, seg, i));
    }
    let mut alive = vec![true; graph.edges.len()];
    loop {
        let changed = prune(&graph, &mut alive, &pieces, &mut chains);
        if !trace(&graph, &mut alive, &pieces, &mut chains) && !changed {
            break;
        }
    }
    chains
}

fn incidence(g: &Graph, alive: &[bool]) -> Vec<Vec<Half>> {
    let mut at = vec![Vec::new(); g.nodes.len()];
    for (e, &(a, b, _, _)) in g.edges.iter().enumerate() {
        if alive[e] {
            at[a].push(Half { e, fwd: true });
            at[b].push(Half { e, fwd: false });
        }
    }
    at
}

/// Removes dangling runs (ends that meet nothing), reporting each run as an open contour.
fn prune(g: &Graph, alive: &mut [bool], pieces: &[Piece], chains: &mut Chains) -> bool {
    let at = incidence(g, alive);
    let mut degree: Vec<usize> = at.iter().map(|v| v.len()).collect();
    let loose: Vec<usize> = (0..g.nodes.len()).filter(|&n| degree[n] == 1).collect();
    if loose.is_empty() {
        return false;
    }
    let mut removed = Vec::new();
    let mut stack = loose.clone();
    while let Some(n) = stack.pop() {
        if degree[n] != 1 {
            continue;
        }
        let Some(h) = at[n].iter().copied().find(|h| alive[h.e]) else {
            continue;
        };
        alive[h.e] = false;
        removed.push(h.e);
        degree[n] -= 1;
        let m = g.to(h);
        degree[m] -= 1;
        if degree[m] == 1 {
            stack.push(m);
        }
    }
    // group the removed edges into runs
    let mut parent: Vec<usize> = (0..g.nodes.len()).collect();
    for &e in &removed {
        union(&mut parent, g.edges[e].0, g.edges[e].1);
    }
    let mut runs: HashMap<usize, Vec<usize>> = HashMap::new();
    for &e in &removed {
        let r = find(&mut parent, g.edges[e].0);
        runs.entry(r).or_default().push(e);
    }
    // each run's loose ends, in one pass over them
    let mut loose_of: HashMap<usize, Vec<[f64; 2]>> = HashMap::new();
    for &n in &loose {
        loose_of
            .entry(find(&mut parent, n))
            .or_default()
            .push(g.nodes[n]);
    }
    let mut keys: Vec<usize> = runs.keys().copied().collect();
    keys.sort_unstable();
    for k in keys {
        let run = &runs[&k];
        let mut srcs: Vec<usize> = run.iter().map(|&e| pieces[g.edges[e].3].src).collect();
        srcs.sort_unstable();
        srcs.dedup();
        chains.open.push(Open {
            srcs,
            loose: loose_of.remove(&k).unwrap_or_default(),
        });
    }
    true
}

/// Turns the components of the live graph into contours; returns whether bridges (lines
/// joining two contours) were removed, so that the caller prunes again.
fn trace(g: &Graph, alive: &mut [bool], pieces: &[Piece], chains: &mut Chains) -> bool {
    let at = incidence(g, alive);
    // components by node
    let mut parent: Vec<usize> = (0..g.nodes.len()).collect();
    for (e, &(a, b, _, _)) in g.edges.iter().enumerate() {
        if alive[e] {
            union(&mut parent, a, b);
        }
    }
    let mut comps: HashMap<usize, Vec<usize>> = HashMap::new();
    for (e, &(a, _, _, _)) in g.edges.iter().enumerate() {
        if alive[e] {
            let r = find(&mut parent, a);
            comps.entry(r).or_default().push(e);
        }
    }
    let mut keys: Vec<usize> = comps.keys().copied().collect();
    keys.sort_unstable();
    // sorted outgoing half-edges per node, counter-clockwise by tangent, then curvature
    let key = |h: Half| {
        let s = g.seg(h);
        let (t, _) = s.tangent_angles();
        let curvature = s.arc().map_or(0.0, |(r, _)| s.bulge.signum() / r);
        (t.rem_euclid(std::f64::consts::TAU), curvature)
    };
    let mut bridged = false;
    let mut done: Vec<usize> = Vec::new();
    for k in keys {
        let edges = &comps[&k];
        let branched = edges
            .iter()
            .any(|&e| at[g.edges[e].0].len() != 2 || at[g.edges[e].1].len() != 2);
        let faces: Vec<Vec<Half>> = if branched {
            let mut order: HashMap<usize, Vec<Half>> = HashMap::new();
            for &e in edges {
                for n in [g.edges[e].0, g.edges[e].1] {
                    order.entry(n).or_insert_with(|| {
                        let mut v = at[n].clone();
                        v.sort_by(|a, b| {
                            let (ka, kb) = (key(*a), key(*b));
                            ka.0.total_cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
                        });
                        v
                    });
                }
            }
            let mut seen: HashMap<(usize, bool), bool> = HashMap::new();
            let mut faces = Vec::new();
            for &e in edges {
                for fwd in [true, false] {
                    let start = Half { e, fwd };
                    if seen.contains_key(&(e, fwd)) {
                        continue;
                    }
                    let mut face = Vec::new();
                    let mut h = start;
                    loop {
                        seen.insert((h.e, h.fwd), true);
                        face.push(h);
                        let v = g.to(h);
                        let around = &order[&v];
                        let twin = Half {
                            e: h.e,
                            fwd: !h.fwd,
                        };
                        let i = around.iter().position(|&x| x == twin).unwrap_or(0);
                        h = around[(i + around.len() - 1) % around.len()];
                        if h == start || face.len() > 4 * edges.len() {
                            break;
                        }
                    }
                    faces.push(face);
                }
            }
            faces
        } else {
            // a simple cycle
            let mut face = Vec::new();
            let start = Half {
                e: edges[0],
                fwd: true,
            };
            let mut h = start;
            loop {
                face.push(h);
                let v = g.to(h);
                let next = at[v].iter().copied().find(|x| x.e != h.e).unwrap_or(h);
                h = if g.from(next) == v {
                    next
                } else {
                    Half {
                        e: next.e,
                        fwd: !next.fwd,
                    }
                };
                if h == start || face.len() > edges.len() {
                    break;
                }
            }
            vec![face]
        };
        let contour_of = |face: &[Half]| {
            Contour::new(
                face.iter()
                    .map(|&h| {
                        let s = g.seg(h);
                        Vertex::new(s.start[0], s.start[1], s.bulge)
                    })
                    .collect(),
            )
        };
        let outer = if branched {
            // the outer face runs clockwise: the most negative area
            let areas: Vec<f64> = faces.iter().map(|f| contour_of(f).signed_area()).collect();
            let i = (0..faces.len())
                .min_by(|&a, &b| areas[a].total_cmp(&areas[b]))
                .unwrap_or(0);
            faces[i].clone()
        } else {
            faces[0].clone()
        };
        let srcs_of = |es: &mut dyn Iterator<Item = usize>| {
            let mut s: Vec<usize> = es.map(|e| pieces[g.edges[e].3].src).collect();
            s.sort_unstable();
            s.dedup();
            s
        };
        if branched {
            let on: Vec<(usize, bool)> = outer.iter().map(|h| (h.e, h.fwd)).collect();
            let bridges: Vec<usize> = outer
                .iter()
                .filter(|h| on.contains(&(h.e, !h.fwd)) && h.fwd)
                .map(|h| h.e)
                .collect();
            if !bridges.is_empty() {
                for &e in &bridges {
                    alive[e] = false;
                }
                chains.repairs.push((
                    srcs_of(&mut bridges.iter().copied()),
                    "a line joining two contours: not cut".into(),
                ));
                bridged = true;
                continue;
            }
            let inner: Vec<usize> = edges
                .iter()
                .copied()
                .filter(|e| !on.iter().any(|o| o.0 == *e))
                .collect();
            if !inner.is_empty() {
                chains.repairs.push((
                    srcs_of(&mut inner.iter().copied()),
                    "lines inside a contour that meet it at both ends (bend or construction lines?): not cut".into(),
                ));
            }
        }
        let mut contour = contour_of(&outer);
        if branched {
            contour = contour.reversed();
        }
        // collinear pieces (an edge split where a bend line met it) become one segment
        let simplified = cavalier_contours::polyline::PlineSource::remove_redundant(&contour, 1e-9)
            .map(|p| Contour::from_pline(&p))
            .unwrap_or(contour);
        let cut = outer
            .iter()
            .map(|h| pieces[g.edges[h.e].3].cut)
            .min()
            .unwrap_or(Cut::Either);
        chains.contours.push(Chained {
            contour: simplified,
            srcs: srcs_of(&mut outer.iter().map(|h| h.e)),
            cut,
        });
        done.extend(edges.iter().copied());
    }
    for e in done {
        alive[e] = false;
    }
    bridged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn piece(start: [f64; 2], end: [f64; 2], bulge: f64, src: usize) -> Piece {
        Piece {
            seg: Segment { start, end, bulge },
            src,
            cut: Cut::Either,
        }
    }

    /// The groups as every pair tried gives them.
    fn every_pair(pieces: &[Piece], tol: f64) -> Vec<Vec<usize>> {
        let n = pieces.len();
        let mut parent: Vec<usize> = (0..n).collect();
        for i in 0..n {
            for j in i + 1..n {
                if overlap(&pieces[i].seg, &pieces[j].seg, tol) {
                    union(&mut parent, i, j);
                }
            }
        }
        sets(&mut parent)
    }

    /// Lines and arcs drawn twice, reversed, overlapping, touching, a hair apart and too
    /// short to overlap, mixed: grouped as when every pair is tried.
    #[test]
    fn overlap_groups_are_those_of_every_pair() {
        let tol = 0.05;
        let mut pieces = Vec::new();
        let mut add = |a: [f64; 2], b: [f64; 2], bulge: f64| {
            let src = pieces.len();
            pieces.push(piece(a, b, bulge, src));
        };
        for k in 0..3 {
            let y = 10.0 * k as f64;
            add([0.0, y], [100.0, y], 0.0);
            add([0.0, y], [100.0, y], 0.0); // drawn twice
            add([100.0, y], [0.0, y], 0.0); // reversed
            add([50.0, y + 0.01], [150.0, y + 0.01], 0.0); // overlapping, a hair off
            add([150.01, y], [200.0, y], 0.0); // touching only
            add([300.0, y], [300.04, y], 0.0); // too short to overlap
            add([300.0, y], [300.04, y], 0.0);
            add([0.0, y + 0.2], [100.0, y + 0.2], 0.0); // parallel, too far
            add([400.0, y], [420.0, y + 20.0], 0.5); // arcs
            add([400.0, y], [420.0, y + 20.0], 0.5);
            add([420.0, y + 20.0], [400.0, y], -0.5);
        }
        let (groups, _) = overlap_groups(&pieces, tol);
        assert_eq!(groups, every_pair(&pieces, tol));
        // the first line, its copies and the one overlapping it are one group
        assert_eq!(groups[0], vec![0, 1, 2, 3]);
        assert!(groups.contains(&vec![8, 9, 10]));
        assert!(groups.contains(&vec![5]) && groups.contains(&vec![6]));
    }

    /// Lines through one point (a star), long and short, at every angle, and two lines
    /// that overlap across a bin's edge: the groups of every pair, with a few tries per
    /// line rather than one per other line.
    #[test]
    fn a_star_of_lines_is_grouped_with_a_few_tries_per_line() {
        let tol = 0.05;
        let n = 1_000;
        let ray = |t: f64, from: f64, to: f64, side: f64| {
            let (c, s) = (t.cos(), t.sin());
            (
                [from * c - side * s, from * s + side * c],
                [to * c - side * s, to * s + side * c],
            )
        };
        let mut pieces: Vec<Piece> = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                let (a, b) = ray(t, 0.0, if k % 3 == 0 { 10.0 } else { 300.0 }, 0.0);
                piece(a, b, 0.0, k)
            })
            .collect();
        // along ray 1, a hair to its side
        let (a, b) = ray(std::f64::consts::TAU / n as f64, 50.0, 400.0, 0.01);
        pieces.push(piece(a, b, 0.0, n));
        // away from the star, two lines 1e-5 rad apart on either side of a bin's edge
        let edge = 37.0 * std::f64::consts::PI / 512.0;
        for (k, t) in [edge - 5e-6, edge + 5e-6].into_iter().enumerate() {
            let (a, b) = ray(t, 2000.0 + 10.0 * k as f64, 2300.0, 0.0);
            pieces.push(piece(a, b, 0.0, n + 1 + k));
        }
        let lanes: Vec<Lane> = pieces[n + 1..]
            .iter()
            .map(|p| Lane::of(&p.seg, tol))
            .collect();
        let bins = |l: &Lane| match *l {
            Lane::Line { level: 9, bin } => bin,
            _ => usize::MAX,
        };
        assert_eq!(lanes.iter().map(bins).collect::<Vec<_>>(), [36, 37]);
        let (groups, tried) = overlap_groups(&pieces, tol);
        assert!(groups == every_pair(&pieces, tol), "the groups differ");
        assert!(groups.contains(&vec![1, n]), "ray 1 and its neighbour");
        assert!(
            groups.contains(&vec![n + 1, n + 2]),
            "the lines across the bin edge"
        );
        assert_eq!(groups.len(), n + 1);
        assert!(
            tried <= 40 * pieces.len(),
            "{tried} pairs tried for {} lines",
            pieces.len()
        );
    }

    /// Thousands of copies of one segment (an array of a block inserting it at one place)
    /// are grouped with a few tries each, not every pair (20,000 copies: 200 million).
    #[test]
    fn thousands_of_copies_are_grouped_in_linear_work() {
        let n = 20_000;
        let mut pieces: Vec<Piece> = (0..n)
            .map(|k| match k % 4 {
                0 | 1 => piece([0.0, 0.0], [100.0, 0.0], 0.0, k),
                2 => piece([100.0, 0.0], [0.0, 0.0], 0.0, k),
                _ => piece([0.0, 5.0], [10.0, 15.0], 0.3, k),
            })
            .collect();
        pieces.push(piece([50.0, 0.0], [150.0, 0.0], 0.0, n));
        let (groups, tried) = overlap_groups(&pieces, 0.05);
        assert!(tried <= 3 * n, "{tried} pairs tried for {n} pieces");
        assert_eq!(groups.len(), 2);
        assert_eq!(groups[0].len(), 3 * n / 4 + 1);
        assert_eq!(groups[1].len(), n / 4);
        let mut repairs = Vec::new();
        let merged = merge_overlaps(pieces, 0.05, &mut repairs);
        // the line split where the members ended (0, 50, 100, 150), the arc as drawn
        assert_eq!(merged.len(), 4, "{merged:?}");
        assert_eq!(repairs.len(), 2);
    }
}
