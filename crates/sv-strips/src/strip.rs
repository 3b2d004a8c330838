//! Strips: chains of units along one mesh direction, unrolled flat.

use sv_frame::FrameFile;
use sv_geom::{segment_closest, Point2, Point3, Vector2, Vector3};

use crate::face::quad_normal;
use crate::plane::{convex_intersection_area, min_area_rect};
use crate::{HubFace, SplitRule, StripDirection, StripOptions, StripsError, TileSet};

/// The joint between two consecutive units of a strip (a pinned connection, paper fig. 12).
#[derive(Clone, Debug, PartialEq)]
pub struct Pin {
    /// The two frame units, in strip order.
    pub units: [usize; 2],
    /// The facing side of each unit (side `k` runs from corner `k` to corner `k + 1`).
    pub sides: [usize; 2],
    /// The pin in the strip's flat frame (mm): both units' pin points are placed here.
    pub point: Point2,
    /// Where the pin lies along each facing side (0 at corner `k`, 1 at corner `k + 1`).
    pub along: [f64; 2],
    /// Bending angle (rad): the dihedral between the two 3D tiles about the joint, signed
    /// by the right-hand rule about the first unit's side direction; 0 when coplanar.
    pub bend: f64,
    /// Twisting angle (rad, >= 0): angle between the two facing sides' directions in 3D.
    pub twist: f64,
    /// Distance between the two pin points in 3D (mm), the frame's gap on this link.
    pub gap: f64,
}

/// One unrolled strip. All coordinates in one 2D frame (mm); the strip's minimum-area
/// bounding rectangle is axis-aligned, its longer side along x, lower left at the origin.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatStrip {
    /// Strip id (`A01`, `A02`, ...).
    pub id: String,
    /// Frame unit indices in strip order.
    pub units: Vec<usize>,
    /// Flat expanded primary tile of each unit (frame corner order, counter-clockwise).
    pub tiles: Vec<[Point2; 4]>,
    /// The face of the flat part each unit's hub comes out of (`+z`, the face seen from
    /// above and etched, is [`HubFace::Etched`]).
    pub hub_faces: Vec<HubFace>,
    /// `pins[j]` joins `units[j]` and `units[j + 1]`.
    pub pins: Vec<Pin>,
    /// Length and width of the bounding rectangle of the tiles (mm).
    pub size: [f64; 2],
    /// Per unit: the reliefs cut into its hub plate for its neighbours' legs (empty but
    /// where [`unroll`] finds a frame whose hub plates lap one on the other).
    pub reliefs: Vec<Vec<crate::Relief>>,
}

/// Etched label and strip of a unit, for frame.json `id` / `strip`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnitLabel {
    /// `<strip>-<nn>`, e.g. `A03-07` (1-based along the strip).
    pub id: String,
    /// Strip id, e.g. `A03`.
    pub strip: String,
}

/// Strip id number `n` (0-based): `A01`..`A99`, `B01`, ... `Z99`.
pub fn strip_id(n: usize) -> Result<String, StripsError> {
    if n >= 26 * 99 {
        return Err(StripsError::TooManyStrips { count: n + 1 });
    }
    let letter = (b'A' + (n / 99) as u8) as char;
    Ok(format!("{letter}{:02}", n % 99 + 1))
}

/// Label of every unit (indexed by frame unit); units in no strip get empty labels.
pub fn unit_labels(strips: &[FlatStrip], unit_count: usize) -> Vec<UnitLabel> {
    let mut out = vec![
        UnitLabel {
            id: String::new(),
            strip: String::new(),
        };
        unit_count
    ];
    for s in strips {
        for (j, &u) in s.units.iter().enumerate() {
            if let Some(l) = out.get_mut(u) {
                *l = UnitLabel {
                    id: format!("{}-{:02}", s.id, j + 1),
                    strip: s.id.clone(),
                };
            }
        }
    }
    out
}

/// Write the labels into a frame's `units[].id` and `units[].strip`.
pub fn apply_labels(frame: &mut FrameFile, strips: &[FlatStrip]) {
    let labels = unit_labels(strips, frame.units.len());
    for (rec, l) in frame.units.iter_mut().zip(labels) {
        if !l.id.is_empty() {
            rec.id = l.id;
            rec.strip = l.strip;
        }
    }
}

/// The mesh vertex at corner `c` of every unit (corner `c` joins sides `c - 1` and `c`),
/// found through the links alone: crossing side `c` of `f` into side `m` of `g`, the same
/// vertex is corner `m + 1` of `g`. Returns the vertex of every corner, and per vertex its
/// number of units and whether the fan around it closes (an interior vertex).
fn corner_vertices(tiles: &TileSet) -> (Vec<[usize; 4]>, Vec<(usize, bool)>) {
    let n = tiles.len();
    let mut vertex = vec![[usize::MAX; 4]; n];
    let mut fans = Vec::new();
    for f in 0..n {
        for c in 0..4 {
            if vertex[f][c] != usize::MAX {
                continue;
            }
            let id = fans.len();
            // walk one way until back or open, then the other way from the start
            let mut count = 0;
            let mut closed = false;
            let (mut g, mut k) = (f, c);
            loop {
                if vertex[g][k] == id {
                    closed = true;
                    break;
                }
                vertex[g][k] = id;
                count += 1;
                match tiles.across[g][k] {
                    Some((h, m)) => (g, k) = (h, (m + 1) % 4),
                    None => break,
                }
            }
            if !closed {
                // the other way: across side c - 1, the vertex is corner m of the neighbour
                let (mut g, mut k) = (f, c);
                while let Some((h, m)) = tiles.across[g][(k + 3) % 4] {
                    if vertex[h][m] == id {
                        break;
                    }
                    vertex[h][m] = id;
                    count += 1;
                    (g, k) = (h, m);
                }
            }
            fans.push((count, closed));
        }
    }
    (vertex, fans)
}

/// Sides where strips must end: a path of mesh edges from every interior vertex of odd
/// valence (3, 5, ...) to the boundary or to another such vertex. Around an odd vertex the
/// two strip directions swap (a strip that went round it would come back crossing its
/// own sides), so some strips must end there; the path is where they end.
fn seams(tiles: &TileSet) -> Vec<[bool; 4]> {
    let n = tiles.len();
    let (vertex, fans) = corner_vertices(tiles);
    let nv = fans.len();
    // edges between vertices: side k of f joins corners k and k + 1
    let mut edges: Vec<Vec<(usize, usize, usize)>> = vec![Vec::new(); nv];
    for f in 0..n {
        for k in 0..4 {
            let (a, b) = (vertex[f][k], vertex[f][(k + 1) % 4]);
            edges[a].push((b, f, k));
            edges[b].push((a, f, k));
        }
    }
    let odd: Vec<bool> = fans
        .iter()
        .map(|&(c, closed)| closed && c % 2 == 1)
        .collect();
    let boundary: Vec<bool> = fans.iter().map(|&(_, closed)| !closed).collect();
    let mut done = vec![false; nv];
    let mut seam = vec![[false; 4]; n];
    for start in 0..nv {
        if !odd[start] || done[start] {
            continue;
        }
        done[start] = true;
        // breadth first to the boundary or to another odd vertex not yet joined
        let mut from: Vec<Option<(usize, usize, usize)>> = vec![None; nv];
        let mut seen = vec![false; nv];
        seen[start] = true;
        let mut queue = std::collections::VecDeque::from([start]);
        let mut end = None;
        while let Some(v) = queue.pop_front() {
            if v != start && (boundary[v] || (odd[v] && !done[v])) {
                end = Some(v);
                break;
            }
            for &(w, f, k) in &edges[v] {
                if !seen[w] {
                    seen[w] = true;
                    from[w] = Some((v, f, k));
                    queue.push_back(w);
                }
            }
        }
        let Some(mut v) = end else { continue };
        done[v] = true;
        while let Some((u, f, k)) = from[v] {
            seam[f][k] = true;
            if let Some((g, m)) = tiles.across[f][k] {
                seam[g][m] = true;
            }
            v = u;
        }
    }
    seam
}

/// Per unit, which side parity (0: sides 0/2, 1: sides 1/3) the strips cross, propagated
/// breadth first over the links from the lowest unit of each piece, never across a seam.
fn chain_parity(tiles: &TileSet, seam: &[[bool; 4]], direction: StripDirection) -> Vec<usize> {
    let n = tiles.len();
    let mut axis = vec![usize::MAX; n];
    for seed in 0..n {
        if axis[seed] != usize::MAX {
            continue;
        }
        axis[seed] = 1; // U crosses sides 1 and 3 of the seed
        let mut queue = std::collections::VecDeque::from([seed]);
        while let Some(f) = queue.pop_front() {
            for k in 0..4 {
                if seam[f][k] {
                    continue;
                }
                if let Some((g, m)) = tiles.across[f][k] {
                    if axis[g] == usize::MAX {
                        axis[g] = if k % 2 == axis[f] { m % 2 } else { (m + 1) % 2 };
                        queue.push_back(g);
                    }
                }
            }
        }
    }
    match direction {
        StripDirection::U => axis,
        StripDirection::V => axis.into_iter().map(|a| 1 - a).collect(),
    }
}

/// Partition the units into chains along `direction` (before splitting): each chain enters
/// a unit through one side and leaves it through the opposite side. Chains are ordered by
/// their lowest unit index; a closed ring starts at its lowest unit. Nothing assumes a
/// grid: on a mesh with irregular vertices the chains end on a path of edges from every
/// vertex of odd valence to the boundary (see [`seams`]), and wherever the direction
/// propagated over the links does not agree.
pub fn chains(tiles: &TileSet, direction: StripDirection) -> Vec<Vec<usize>> {
    let n = tiles.len();
    let seam = seams(tiles);
    let parity = chain_parity(tiles, &seam, direction);
    // neighbour when leaving f through side k, if the step stays in the chain direction
    let step = |f: usize, k: usize| -> Option<(usize, usize)> {
        if seam[f][k] {
            return None;
        }
        let (g, m) = tiles.across[f][k]?;
        (k % 2 == parity[f] && m % 2 == parity[g]).then_some((g, m))
    };
    // walk backward through side 3 (U) or side 0 (V) of unit 0, so that strips run with
    // increasing i (U) or j (V) on a `QuadMesh::from_fn` grid
    let back_offset = match direction {
        StripDirection::U => 2,
        StripDirection::V => 0,
    };
    let mut used = vec![false; n];
    let mut out = Vec::new();
    for f in 0..n {
        if used[f] {
            continue;
        }
        // walk backward to the chain's start
        let (mut start, mut back) = (f, (parity[f] + back_offset) % 4);
        let mut seen = vec![f];
        while let Some((g, m)) = step(start, back) {
            if g == f {
                // a closed ring: cut it before f
                (start, back) = (f, (parity[f] + back_offset) % 4);
                break;
            }
            if used[g] || seen.contains(&g) {
                break;
            }
            seen.push(g);
            start = g;
            back = (m + 2) % 4;
        }
        // forward: leave through the side opposite to the one we came back through
        let mut chain = vec![start];
        used[start] = true;
        let mut fwd = (back + 2) % 4;
        let mut cur = start;
        while let Some((g, m)) = step(cur, fwd) {
            if used[g] {
                break;
            }
            used[g] = true;
            chain.push(g);
            cur = g;
            fwd = (m + 2) % 4;
        }
        out.push(chain);
    }
    out
}

/// Flatten a planar 3D quad into its own plane: centroid at the origin, x along side 0,
/// counter-clockwise about its normal `(q2 - q0) x (q3 - q1)`.
fn flatten(q: &[Point3; 4]) -> [Point2; 4] {
    let c = q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0;
    let e1 = (q[1] - q[0]).normalize();
    let e2 = quad_normal(q).cross(&e1);
    q.map(|p| {
        let d = p.coords - c;
        Point2::new(d.dot(&e1), d.dot(&e2))
    })
}

/// A 2D rigid motion `x -> R x + t`.
#[derive(Clone, Copy, Debug)]
struct Motion {
    c: f64,
    s: f64,
    t: Vector2,
}

impl Motion {
    fn apply(&self, p: &Point2) -> Point2 {
        Point2::new(
            self.c * p.x - self.s * p.y + self.t.x,
            self.s * p.x + self.c * p.y + self.t.y,
        )
    }
    /// Maps `from` to `to` with direction `dir_from` turned to `dir_to`.
    fn mapping(from: &Point2, dir_from: &Vector2, to: &Point2, dir_to: &Vector2) -> Self {
        let a = dir_to.y.atan2(dir_to.x) - dir_from.y.atan2(dir_from.x);
        let (s, c) = a.sin_cos();
        let r = Vector2::new(c * from.x - s * from.y, s * from.x + c * from.y);
        Self {
            c,
            s,
            t: to.coords - r,
        }
    }
}

/// Place `g`'s flat tile against the placed tile `placed_f` of `f` across `f`'s side `k`
/// (`g`'s side `m`): sides collinear, pin points coincident, tiles on opposite sides.
fn place_next(
    tiles: &TileSet,
    f: usize,
    placed_f: &[Point2; 4],
    k: usize,
    g: usize,
    m: usize,
) -> ([Point2; 4], Pin) {
    let (tf, tg) = (&tiles.tiles[f], &tiles.tiles[g]);
    let (a, b) = (tf[k], tf[(k + 1) % 4]);
    let (c, d) = (tg[m], tg[(m + 1) % 4]);
    let mut cl = segment_closest(&a, &b, &c, &d);
    // a frame whose joints were closed says where each bridge is
    if let (Some(jf), Some(jg)) = (tiles.joints[f][k], tiles.joints[g][m]) {
        cl.s = jf.along;
        cl.t = jg.along;
        cl.distance = ((a + (b - a) * cl.s) - (c + (d - c) * cl.t)).norm();
    }
    let (fa, fb) = (placed_f[k], placed_f[(k + 1) % 4]);
    let u = (fb - fa).normalize();
    let pin = fa + (fb - fa) * cl.s;
    let lg = flatten(tg);
    let (lc, ld) = (lg[m], lg[(m + 1) % 4]);
    let lpin = lc + (ld - lc) * cl.t;
    let mo = Motion::mapping(&lpin, &(ld - lc), &pin, &(-u));
    let placed = lg.map(|p| mo.apply(&p));
    let (nf, ng) = (quad_normal(tf), quad_normal(tg));
    let axis = (b - a).normalize();
    let bend = nf.cross(&ng).dot(&axis).atan2(nf.dot(&ng));
    let twist = (b - a)
        .normalize()
        .dot(&(c - d).normalize())
        .clamp(-1.0, 1.0)
        .acos();
    let p = Pin {
        units: [f, g],
        sides: [k, m],
        point: pin,
        along: [cl.s, cl.t],
        bend,
        twist,
        gap: cl.distance,
    };
    (placed, p)
}

fn bbox(q: &[Point2; 4]) -> [f64; 4] {
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for p in q {
        b[0] = b[0].min(p.x);
        b[1] = b[1].min(p.y);
        b[2] = b[2].max(p.x);
        b[3] = b[3].max(p.y);
    }
    b
}

fn boxes_meet(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3]
}

/// A strip piece under construction.
struct Piece {
    units: Vec<usize>,
    tiles: Vec<[Point2; 4]>,
    boxes: Vec<[f64; 4]>,
    pins: Vec<Pin>,
}

impl Piece {
    fn start(tiles: &TileSet, u: usize) -> Self {
        let t = flatten(&tiles.tiles[u]);
        Self {
            units: vec![u],
            boxes: vec![bbox(&t)],
            tiles: vec![t],
            pins: Vec::new(),
        }
    }

    /// The first tile of the piece this candidate would overlap, if any.
    fn overlap(&self, cand: &[Point2; 4], tolerance: f64) -> Option<usize> {
        let b = bbox(cand);
        (0..self.tiles.len()).find(|&i| {
            boxes_meet(&self.boxes[i], &b)
                && convex_intersection_area(&self.tiles[i], cand) > tolerance
        })
    }

    fn length_with(&self, cand: &[Point2; 4]) -> f64 {
        let pts: Vec<Point2> = self
            .tiles
            .iter()
            .flatten()
            .chain(cand.iter())
            .copied()
            .collect();
        min_area_rect(&pts).1
    }
}

/// Partition a frame's units into strips along `options.direction`, unroll them, and split
/// a strip wherever its flat pattern would exceed `options.max_length` or overlap itself.
/// Strips get ids `A01`, `A02`, ... in chain order.
pub fn unroll(frame: &FrameFile, options: &StripOptions) -> Result<Vec<FlatStrip>, StripsError> {
    options.validate()?;
    let tiles = TileSet::from_frame(frame)?;
    let mut strips = unroll_tiles(&tiles, options)?;
    crate::relief::add_reliefs(frame, &mut strips)?;
    Ok(strips)
}

/// What the strips stage plans for a frame before its joints close: which links its strips
/// bridge and how much each piece may grow and still fit its sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct StripPlan {
    /// Per link of the frame: consecutive units of one strip, one piece of steel (a bridge
    /// the joint solve must make a hinge); the others are welded.
    pub bridges: Vec<bool>,
    /// The pieces of more than one unit ([`sv_frame::JointOptions::pieces`]).
    pub pieces: Vec<sv_frame::PieceLength>,
}

/// How far short of `max_length` a piece's planned growth stops (mm): the piece's length
/// along its units stands in for its flat pattern's length in the joint solve.
const PIECE_LENGTH_MARGIN: f64 = 6.0;

/// How much room to grow a piece is planned with where that takes no more pieces: closing
/// the joints stretches tiles by up to about 1 %.
const PLANNED_STRETCH: f64 = 0.015;

/// [`StripPlan`] of `frame` unrolled with `options` ([`sv_frame::close_joints`] reads it).
/// A chain is cut for a sheet [`PLANNED_STRETCH`] shorter where that takes no more pieces,
/// so that the joint solve has room to stretch its tiles.
pub fn strip_plan(frame: &FrameFile, options: &StripOptions) -> Result<StripPlan, StripsError> {
    options.validate()?;
    let tiles = TileSet::from_frame(frame)?;
    let roomy = StripOptions {
        max_length: options.max_length * (1.0 - PLANNED_STRETCH),
        ..options.clone()
    };
    let mut pieces: Vec<Piece> = Vec::new();
    for chain in chains(&tiles, options.direction) {
        let tight = split_by_rule(&tiles, &chain, options)?;
        match split_by_rule(&tiles, &chain, &roomy) {
            Ok(p) if p.len() == tight.len() => pieces.extend(p),
            _ => pieces.extend(tight),
        }
    }
    let strips = named(&tiles, pieces)?;
    let index: std::collections::HashMap<(usize, usize), usize> = frame
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| ((l.units[0].min(l.units[1]), l.units[0].max(l.units[1])), i))
        .collect();
    let mut bridges = vec![false; frame.links.len()];
    let mut pieces = Vec::new();
    for strip in &strips {
        for pin in &strip.pins {
            let [a, b] = pin.units;
            if let Some(&i) = index.get(&(a.min(b), a.max(b))) {
                bridges[i] = true;
            }
        }
        if strip.pins.is_empty() {
            continue;
        }
        pieces.push(sv_frame::PieceLength {
            units: strip.units.clone(),
            sides: strip.pins.iter().map(|p| p.sides).collect(),
            room: (options.max_length - PIECE_LENGTH_MARGIN).max(0.0) / strip.size[0],
        });
    }
    Ok(StripPlan { bridges, pieces })
}

/// [`unroll`] on already extracted tiles.
pub fn unroll_tiles(
    tiles: &TileSet,
    options: &StripOptions,
) -> Result<Vec<FlatStrip>, StripsError> {
    options.validate()?;
    let mut pieces: Vec<Piece> = Vec::new();
    for chain in chains(tiles, options.direction) {
        pieces.extend(split_by_rule(tiles, &chain, options)?);
    }
    named(tiles, pieces)
}

/// Pieces with their ids (`A01`, `A02`, ... in order), laid straight.
fn named(tiles: &TileSet, pieces: Vec<Piece>) -> Result<Vec<FlatStrip>, StripsError> {
    pieces
        .into_iter()
        .enumerate()
        .map(|(i, p)| {
            let id = strip_id(i)?;
            let faces = p
                .units
                .iter()
                .map(|&u| {
                    tiles
                        .hub_faces
                        .get(u)
                        .copied()
                        .ok_or(StripsError::Internal {
                            why: format!("unit {u} has no hub face"),
                        })
                })
                .collect::<Result<_, _>>()?;
            Ok(normalise(id, p, faces))
        })
        .collect()
}

/// Split one chain by `options.split`. Both rules start from the greedy split, which needs
/// the fewest pieces `k`, and only re-split with a cap on the units per piece when that
/// still takes `k` pieces.
fn split_by_rule(
    tiles: &TileSet,
    chain: &[usize],
    options: &StripOptions,
) -> Result<Vec<Piece>, StripsError> {
    let greedy = split_chain(tiles, chain, options, usize::MAX)?;
    // where the frame's joints were closed, it decided the pieces (its bridges)
    if tiles.joints.iter().flatten().any(Option::is_some) {
        return Ok(greedy);
    }
    let k = greedy.len();
    let sizes: Vec<usize> = greedy.iter().map(|p| p.units.len()).collect();
    let shortest = sizes.iter().copied().min().unwrap_or(0);
    let longest = sizes.iter().copied().max().unwrap_or(0);
    let cap = match options.split {
        // a one-unit stub (a part of its own and a joint welded on site for one unit): one
        // unit less per piece moves units into it
        SplitRule::Fill if k > 1 && shortest == 1 => longest - 1,
        // at most ceil(n / k) units per piece
        SplitRule::Balanced if k > 1 && shortest < chain.len().div_ceil(k) => {
            chain.len().div_ceil(k)
        }
        _ => return Ok(greedy),
    };
    let again = split_chain(tiles, chain, options, cap)?;
    Ok(if again.len() == k { again } else { greedy })
}

/// Split one chain into pieces, greedily: a piece ends where the next tile would overlap
/// it, make it longer than `options.max_length`, or make it more than `cap` units long.
fn split_chain(
    tiles: &TileSet,
    chain: &[usize],
    options: &StripOptions,
    cap: usize,
) -> Result<Vec<Piece>, StripsError> {
    let mut pieces = Vec::new();
    let first = chain[0];
    let t0 = flatten(&tiles.tiles[first]);
    let (_, long0, _) = min_area_rect(&t0);
    if long0 > options.max_length {
        return Err(StripsError::Unit {
            strip: "-".into(),
            unit: first,
            why: format!(
                "flat tile is {long0:.1} mm long, more than max_length {}",
                options.max_length
            ),
        });
    }
    let mut piece = Piece::start(tiles, first);
    for w in chain.windows(2) {
        let (f, g) = (w[0], w[1]);
        let k = (0..4)
            .find(|&k| tiles.across[f][k].map(|x| x.0) == Some(g))
            .ok_or_else(|| StripsError::Internal {
                why: format!("chain step {f} -> {g} without a link"),
            })?;
        let m = tiles.across[f][k].map(|x| x.1).unwrap_or(0);
        let last = *piece.tiles.last().ok_or_else(|| StripsError::Internal {
            why: "empty strip piece".into(),
        })?;
        let (placed, pin) = place_next(tiles, f, &last, k, g, m);
        // a joint the frame welds is where a strip ends
        let welded = tiles.joints[f][k].is_some_and(|j| !j.bridge) || options.breaks_between(f, g);
        let fits = !welded
            && piece
                .overlap(&placed, options.overlap_area_tolerance)
                .is_none()
            && piece.length_with(&placed) <= options.max_length
            && piece.units.len() < cap;
        if fits {
            piece.units.push(g);
            piece.boxes.push(bbox(&placed));
            piece.tiles.push(placed);
            piece.pins.push(pin);
        } else {
            pieces.push(std::mem::replace(&mut piece, Piece::start(tiles, g)));
        }
    }
    pieces.push(piece);
    Ok(pieces)
}

/// Rotate and translate a piece so its minimum-area rectangle is axis-aligned, long side on x.
fn normalise(id: String, p: Piece, hub_faces: Vec<HubFace>) -> FlatStrip {
    let pts: Vec<Point2> = p.tiles.iter().flatten().copied().collect();
    let (angle, long, short) = min_area_rect(&pts);
    let (s, c) = (-angle).sin_cos();
    let rot = |q: &Point2| Point2::new(c * q.x - s * q.y, s * q.x + c * q.y);
    let (mut x0, mut y0) = (f64::MAX, f64::MAX);
    for q in &pts {
        let r = rot(q);
        x0 = x0.min(r.x);
        y0 = y0.min(r.y);
    }
    let tr = |q: &Point2| {
        let r = rot(q);
        Point2::new(r.x - x0, r.y - y0)
    };
    FlatStrip {
        id,
        units: p.units,
        tiles: p.tiles.iter().map(|t| t.map(|q| tr(&q))).collect(),
        hub_faces,
        pins: p
            .pins
            .into_iter()
            .map(|mut pin| {
                pin.point = tr(&pin.point);
                pin
            })
            .collect(),
        size: [long, short],
        reliefs: Vec::new(),
    }
}
