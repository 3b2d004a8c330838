//! From the entities of a `dxf::Drawing` (model space, blocks expanded through nested
//! INSERTs with their arrays, every entity's extrusion direction applied, scaled to mm) to
//! world-coordinate pieces: open segments to chain, closed contours, etching, text
//! positions, and a note for every entity that is not read.

use std::cell::Cell;
use std::collections::{BTreeMap, HashMap};

use dxf::entities::{Entity, EntityType};
use sv_geom::text::printable;
use sv_geom::{Contour, Segment, Vertex};

use super::fit::{fit_arcs, Curve, Interpolant, Nurbs, MAX_SAMPLES};
use super::layers::{LayerRole, LayerRules};
use super::xform::{ocs, Affine};

/// Where a piece came from: layer, entity type and handle (with the INSERTs it came
/// through: `2F>85`).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Source {
    pub(crate) layer: String,
    pub(crate) entity: &'static str,
    pub(crate) handle: String,
}

/// The role of a cut piece, from its layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Cut {
    /// an outline by its layer
    Outside,
    /// a hole by its layer
    Inside,
    /// outline or hole by containment
    Either,
}

/// An open segment to chain, with its source.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Piece {
    pub(crate) seg: Segment,
    pub(crate) src: usize,
    pub(crate) cut: Cut,
}

/// A closed contour as drawn (CIRCLE, closed polyline, closed spline, full ellipse).
#[derive(Clone, Debug)]
pub(crate) struct Closed {
    pub(crate) contour: Contour,
    pub(crate) src: usize,
    pub(crate) cut: Cut,
}

/// Everything read from the entities.
#[derive(Default)]
pub(crate) struct Collected {
    pub(crate) sources: Vec<Source>,
    pub(crate) pieces: Vec<Piece>,
    pub(crate) closed: Vec<Closed>,
    pub(crate) etch: Vec<(Vec<[f64; 2]>, usize)>,
    /// closed or open entities of zero size
    pub(crate) zero: Vec<usize>,
    /// positions of TEXT / MTEXT (a title block inside a border tells the border)
    pub(crate) texts: Vec<[f64; 2]>,
    /// skipped entities: (layer, entity, why) -> handles
    pub(crate) skipped: BTreeMap<(String, &'static str, String), Vec<String>>,
    /// curves turned into arcs: (layer, entity, what) -> handles
    pub(crate) converted: BTreeMap<(String, &'static str, String), Vec<String>>,
}

/// What the walk needs to know.
pub(crate) struct Walk<'a> {
    pub(crate) blocks: HashMap<String, &'a dxf::Block>,
    /// layer (upper case) -> its line type (upper case)
    pub(crate) layer_line_types: HashMap<String, String>,
    /// line types (upper case) with dashes
    pub(crate) dashed: Vec<String>,
    pub(crate) rules: &'a LayerRules,
    pub(crate) arc_tolerance: f64,
    /// samples the curve fits may still take ([`MAX_SAMPLES`] for the file)
    samples_left: Cell<usize>,
    /// whether the file has handles (else entities are named by their position)
    pub(crate) handles: bool,
    pub(crate) out: Collected,
    count: usize,
}

/// The context an entity is read in: the map to world mm, and what it inherits from the
/// INSERT it came through.
#[derive(Clone)]
struct Ctx {
    xf: Affine,
    /// layer of the INSERT (entities on layer 0 in a block take it)
    layer: Option<String>,
    /// line type of the INSERT (for BYBLOCK)
    line_type: Option<String>,
    /// handles of the INSERTs on the way
    path: String,
    depth: usize,
}

const MAX_DEPTH: usize = 32;

/// Most entities read, block copies counted: an INSERT whose array or nesting would go past
/// it is skipped (a 30000 x 30000 array is a billion copies, not a drawing). A part
/// drawing has hundreds, a full sheet thousands, a shop's whole job tens of thousands:
/// the limit leaves room for any of them (200,000 circles read in about 1.5 s).
const MAX_ENTITIES: usize = 200_000;

/// Farthest a drawn point may be from the origin (mm), 1000 km: beyond it a drawing is in
/// the wrong units or holds a corrupt number, and areas and the chaining grid overflow.
const MAX_COORDINATE: f64 = 1e9;

fn kind(e: &EntityType) -> &'static str {
    match e {
        EntityType::Line(_) => "LINE",
        EntityType::Arc(_) => "ARC",
        EntityType::Circle(_) => "CIRCLE",
        EntityType::LwPolyline(_) => "LWPOLYLINE",
        EntityType::Polyline(_) => "POLYLINE",
        EntityType::Spline(_) => "SPLINE",
        EntityType::Ellipse(_) => "ELLIPSE",
        EntityType::Insert(_) => "INSERT",
        EntityType::Text(_) => "TEXT",
        EntityType::MText(_) => "MTEXT",
        EntityType::ModelPoint(_) => "POINT",
        EntityType::RotatedDimension(_)
        | EntityType::RadialDimension(_)
        | EntityType::DiameterDimension(_)
        | EntityType::AngularThreePointDimension(_)
        | EntityType::OrdinateDimension(_) => "DIMENSION",
        EntityType::Leader(_) => "LEADER",
        EntityType::Solid(_) => "SOLID",
        EntityType::Face3D(_) => "3DFACE",
        EntityType::Attribute(_) => "ATTRIB",
        EntityType::AttributeDefinition(_) => "ATTDEF",
        EntityType::Image(_) => "IMAGE",
        EntityType::Wipeout(_) => "WIPEOUT",
        EntityType::Trace(_) => "TRACE",
        EntityType::Ray(_) => "RAY",
        EntityType::XLine(_) => "XLINE",
        EntityType::Tolerance(_) => "TOLERANCE",
        EntityType::Region(_) => "REGION",
        EntityType::Body(_) => "BODY",
        EntityType::Solid3D(_) => "3DSOLID",
        EntityType::Helix(_) => "HELIX",
        EntityType::MLine(_) => "MLINE",
        EntityType::Shape(_) => "SHAPE",
        EntityType::Section(_) => "SECTION",
        _ => "entity",
    }
}

fn xy(p: &dxf::Point) -> [f64; 2] {
    [p.x, p.y]
}

fn xyz(v: &dxf::Vector) -> [f64; 3] {
    [v.x, v.y, v.z]
}

impl<'a> Walk<'a> {
    pub(crate) fn new(
        drawing: &'a dxf::Drawing,
        rules: &'a LayerRules,
        arc_tolerance: f64,
        handles: bool,
    ) -> Self {
        let blocks = drawing
            .blocks()
            .map(|b| (b.name.to_uppercase(), b))
            .collect();
        let layer_line_types = drawing
            .layers()
            .map(|l| (l.name.to_uppercase(), l.line_type_name.to_uppercase()))
            .collect();
        let dashed = drawing
            .line_types()
            .filter(|t| {
                t.dash_dot_space_lengths.iter().any(|&d| d != 0.0) || t.total_pattern_length > 0.0
            })
            .map(|t| t.name.to_uppercase())
            .collect();
        Self {
            blocks,
            layer_line_types,
            dashed,
            rules,
            arc_tolerance,
            samples_left: Cell::new(MAX_SAMPLES),
            handles,
            out: Collected::default(),
            count: 0,
        }
    }

    /// Reads the model-space entities of `drawing` scaled by `mm` per drawing unit.
    pub(crate) fn model_space(&mut self, drawing: &'a dxf::Drawing, mm: f64) {
        let ctx = Ctx {
            xf: Affine::scale(mm, mm),
            layer: None,
            line_type: None,
            path: String::new(),
            depth: 0,
        };
        for e in drawing.entities() {
            self.count += 1;
            if e.common.is_in_paper_space {
                let h = self.handle(&ctx, e);
                self.skip(
                    &e.common.layer,
                    kind(&e.specific),
                    "on a paper-space layout, not in the model",
                    h,
                );
                continue;
            }
            self.entity(e, &ctx);
        }
    }

    fn handle(&self, ctx: &Ctx, e: &Entity) -> String {
        let own = if self.handles && e.common.handle.0 != 0 {
            format!("{:X}", e.common.handle.0)
        } else {
            format!("#{}", self.count)
        };
        format!("{}{own}", ctx.path)
    }

    fn skip(&mut self, layer: &str, entity: &'static str, why: &str, handle: String) {
        self.out
            .skipped
            .entry((layer.to_string(), entity, why.to_string()))
            .or_default()
            .push(handle);
    }

    fn source(&mut self, layer: &str, entity: &'static str, handle: String) -> usize {
        self.out.sources.push(Source {
            layer: layer.to_string(),
            entity,
            handle,
        });
        self.out.sources.len() - 1
    }

    /// Whether the entity's line type (own, by layer or by block) is dashed.
    fn dashed(&self, e: &Entity, layer: &str, ctx: &Ctx) -> Option<String> {
        let own = e.common.line_type_name.to_uppercase();
        let lt = match own.as_str() {
            "" | "BYLAYER" => self
                .layer_line_types
                .get(&layer.to_uppercase())
                .cloned()
                .unwrap_or_default(),
            "BYBLOCK" => ctx.line_type.clone().unwrap_or_default(),
            _ => own,
        };
        // named in the table with dashes, or by a name that says so when the table lacks it
        let named = ["DASH", "CENTER", "HIDDEN", "PHANTOM", "DOT", "DIVIDE"]
            .iter()
            .any(|k| lt.contains(k));
        (self.dashed.contains(&lt) || named).then_some(lt)
    }

    fn entity(&mut self, e: &Entity, ctx: &Ctx) {
        let k = kind(&e.specific);
        let layer = match (&ctx.layer, e.common.layer.as_str()) {
            (Some(parent), "0") => parent.clone(),
            (_, own) => own.to_string(),
        };
        let handle = self.handle(ctx, e);
        if let EntityType::Insert(ins) = &e.specific {
            self.insert(e, ins, &layer, ctx, handle);
            return;
        }
        let role = self.rules.role(&layer);
        let cut = match role {
            LayerRole::Skip(why) => {
                self.skip(&layer, k, &format!("layer rule: {why}"), handle);
                return;
            }
            LayerRole::Etch => {
                self.etch(e, &layer, ctx, handle);
                return;
            }
            LayerRole::Outside => Cut::Outside,
            LayerRole::Inside => Cut::Inside,
            LayerRole::Cut => Cut::Either,
        };
        let text_at = match &e.specific {
            EntityType::Text(t) => Some(&t.location),
            EntityType::MText(t) => Some(&t.insertion_point),
            _ => None,
        };
        if let Some(at) = text_at {
            self.out.texts.push(ctx.xf.apply(xy(at)));
            self.skip(
                &layer,
                k,
                "text is not cut (etch it on an ETCH layer)",
                handle,
            );
            return;
        }
        match &e.specific {
            EntityType::Line(_)
            | EntityType::Arc(_)
            | EntityType::Circle(_)
            | EntityType::LwPolyline(_)
            | EntityType::Polyline(_)
            | EntityType::Spline(_)
            | EntityType::Ellipse(_) => {}
            _ => {
                self.skip(&layer, k, "not a cut contour", handle);
                return;
            }
        }
        if let Some(lt) = self.dashed(e, &layer, ctx) {
            self.skip(
                &layer,
                k,
                &format!(
                    "dashed line type {}: a construction or bend line, not cut",
                    printable(&lt)
                ),
                handle,
            );
            return;
        }
        match self.curve(e, ctx) {
            Ok((segs, closed, note)) => {
                if segs.is_empty() {
                    // a contour of zero size is a part drawn wrong, not something to skip
                    let src = self.source(&layer, k, handle);
                    self.out.zero.push(src);
                    return;
                }
                if let Some(what) = note {
                    self.out
                        .converted
                        .entry((layer.clone(), k, what))
                        .or_default()
                        .push(handle.clone());
                }
                let src = self.source(&layer, k, handle);
                if closed {
                    let contour = Contour::new(
                        segs.iter()
                            .map(|s| Vertex::new(s.start[0], s.start[1], s.bulge))
                            .collect(),
                    );
                    self.out.closed.push(Closed { contour, src, cut });
                } else {
                    self.out
                        .pieces
                        .extend(segs.into_iter().map(|seg| Piece { seg, src, cut }));
                }
            }
            Err(why) => self.skip(&layer, k, &why, handle),
        }
    }

    fn etch(&mut self, e: &Entity, layer: &str, ctx: &Ctx, handle: String) {
        let k = kind(&e.specific);
        match self.curve(e, ctx) {
            Ok((segs, closed, _)) if !segs.is_empty() => {
                let mut line = Vec::new();
                for s in &segs {
                    line.push(s.start);
                    s.flatten_into(0.05, &mut line);
                }
                let end = if closed {
                    segs[0].start
                } else {
                    segs[segs.len() - 1].end
                };
                line.push(end);
                let src = self.source(layer, k, handle);
                self.out.etch.push((line, src));
            }
            Ok(_) => self.skip(layer, k, "zero size", handle),
            Err(_) if matches!(e.specific, EntityType::Text(_) | EntityType::MText(_)) => self
                .skip(
                    layer,
                    k,
                    "TEXT is not etched (many CAMs drop it): draw etched text as lines",
                    handle,
                ),
            Err(why) => self.skip(layer, k, &why, handle),
        }
    }

    fn insert(
        &mut self,
        e: &Entity,
        ins: &dxf::entities::Insert,
        layer: &str,
        ctx: &Ctx,
        handle: String,
    ) {
        let Some(block) = self.blocks.get(&ins.name.to_uppercase()).copied() else {
            self.skip(
                layer,
                "INSERT",
                &format!("block {:?} is not in the file", ins.name),
                handle,
            );
            return;
        };
        if ctx.depth >= MAX_DEPTH {
            self.skip(
                layer,
                "INSERT",
                &format!("blocks nested deeper than {MAX_DEPTH} (a block that inserts itself?)"),
                handle,
            );
            return;
        }
        let Some(plane) = ocs(xyz(&ins.extrusion_direction)) else {
            self.skip(
                layer,
                "INSERT",
                "not in the XY plane (tilted extrusion direction)",
                handle,
            );
            return;
        };
        if ins.x_scale_factor == 0.0 || ins.y_scale_factor == 0.0 {
            self.skip(layer, "INSERT", "zero scale", handle);
            return;
        }
        let rot = ins.rotation.to_radians();
        let base = xy(&block.base_point);
        let local = Affine::rotation(rot)
            .then(&Affine::scale(ins.x_scale_factor, ins.y_scale_factor))
            .then(&Affine::translation(-base[0], -base[1]));
        let (cols, rows) = (ins.column_count.max(1), ins.row_count.max(1));
        let cells = usize::from(cols.unsigned_abs()) * usize::from(rows.unsigned_abs());
        if cells.saturating_mul(block.entities.len()) > MAX_ENTITIES.saturating_sub(self.count) {
            self.skip(
                layer,
                "INSERT",
                &format!(
                    "{rows} x {cols} copies of block {:?} ({} entities) take the file past {MAX_ENTITIES} entities",
                    ins.name,
                    block.entities.len()
                ),
                handle,
            );
            return;
        }
        let line_type = match e.common.line_type_name.to_uppercase().as_str() {
            "" | "BYLAYER" => self.layer_line_types.get(&layer.to_uppercase()).cloned(),
            "BYBLOCK" => ctx.line_type.clone(),
            own => Some(own.to_string()),
        };
        let p = xy(&ins.location);
        for r in 0..rows {
            for c in 0..cols {
                // array offsets run along the rotated block axes, unscaled
                let off = Affine::rotation(rot).apply_vector([
                    f64::from(c) * ins.column_spacing,
                    f64::from(r) * ins.row_spacing,
                ]);
                let place = Affine::translation(p[0] + off[0], p[1] + off[1]);
                let cell = if cells > 1 {
                    format!("{handle}[{r},{c}]>")
                } else {
                    format!("{handle}>")
                };
                let child = Ctx {
                    xf: ctx.xf.then(&plane).then(&place).then(&local),
                    layer: Some(layer.to_string()),
                    line_type: line_type.clone(),
                    path: cell,
                    depth: ctx.depth + 1,
                };
                for be in &block.entities {
                    self.count += 1;
                    self.entity(be, &child);
                }
            }
        }
    }

    /// The entity as segments in world mm, whether it is closed, and what was converted;
    /// refused where a coordinate is not finite or farther than [`MAX_COORDINATE`] from the
    /// origin.
    #[allow(clippy::type_complexity)]
    fn curve(&self, e: &Entity, ctx: &Ctx) -> Result<(Vec<Segment>, bool, Option<String>), String> {
        let (segs, closed, note) = self.drawn(e, ctx)?;
        for s in &segs {
            let ends = || s.start.iter().chain(&s.end);
            if !(ends().all(|v| v.is_finite()) && s.bulge.is_finite()) {
                return Err("a coordinate that is not a finite number".into());
            }
            let far = ends().fold(0.0, |m: f64, v| m.max(v.abs()));
            let reach = s
                .arc()
                .map_or(far, |(r, c)| far.max(c[0].abs().max(c[1].abs()) + r));
            if reach.is_nan() || reach > MAX_COORDINATE {
                return Err(format!(
                    "farther than {MAX_COORDINATE:e} mm from the origin (drawn in the wrong units, or a corrupt number?)"
                ));
            }
        }
        Ok((segs, closed, note))
    }

    /// [`Walk::curve`] before its coordinates are checked.
    #[allow(clippy::type_complexity)]
    fn drawn(&self, e: &Entity, ctx: &Ctx) -> Result<(Vec<Segment>, bool, Option<String>), String> {
        let tilted = || "not in the XY plane (tilted extrusion direction)".to_string();
        let tol = self.arc_tolerance;
        let left = &self.samples_left;
        match &e.specific {
            EntityType::Line(l) => {
                let (a, b) = (ctx.xf.apply(xy(&l.p1)), ctx.xf.apply(xy(&l.p2)));
                if (l.p1.z - l.p2.z).abs() > 1e-9 {
                    return Err("not in the XY plane (its ends differ in z)".into());
                }
                Ok((line(a, b), false, None))
            }
            EntityType::Arc(a) => {
                let xf = ctx.xf.then(&ocs(xyz(&a.normal)).ok_or_else(tilted)?);
                let (a0, a1) = (a.start_angle, a.end_angle);
                let a1 = turn_past(a0, a1, 360.0).ok_or_else(|| {
                    format!(
                        "start and end angle {a0:?}, {a1:?}: not finite, or beyond a million turns"
                    )
                })?;
                arc(
                    &xf,
                    xy(&a.center),
                    a.radius,
                    a0.to_radians(),
                    a1.to_radians(),
                    tol,
                    left,
                )
            }
            EntityType::Circle(c) => {
                let xf = ctx.xf.then(&ocs(xyz(&c.normal)).ok_or_else(tilted)?);
                if c.radius.is_nan() || c.radius <= 0.0 {
                    return Ok((Vec::new(), true, None));
                }
                let (mut segs, _, note) = arc(
                    &xf,
                    xy(&c.center),
                    c.radius,
                    0.0,
                    std::f64::consts::PI,
                    tol,
                    left,
                )?;
                let (more, _, _) = arc(
                    &xf,
                    xy(&c.center),
                    c.radius,
                    std::f64::consts::PI,
                    std::f64::consts::TAU,
                    tol,
                    left,
                )?;
                segs.extend(more);
                Ok((segs, true, note))
            }
            EntityType::LwPolyline(p) => {
                let xf = ctx
                    .xf
                    .then(&ocs(xyz(&p.extrusion_direction)).ok_or_else(tilted)?);
                let v: Vec<([f64; 2], f64)> =
                    p.vertices.iter().map(|v| ([v.x, v.y], v.bulge)).collect();
                polyline(&xf, &v, p.is_closed(), tol, left)
            }
            EntityType::Polyline(p) => {
                if p.flags & (16 | 64) != 0 {
                    return Err("a polygon or polyface mesh, not a contour".into());
                }
                let three_d = p.flags & 8 != 0;
                let xf = if three_d {
                    ctx.xf
                } else {
                    ctx.xf.then(&ocs(xyz(&p.normal)).ok_or_else(tilted)?)
                };
                // spline frame control points (vertex flag 16) are not on the curve
                let v: Vec<([f64; 2], f64)> = p
                    .vertices()
                    .filter(|v| v.flags & 16 == 0)
                    .map(|v| {
                        (
                            [v.location.x, v.location.y],
                            if three_d { 0.0 } else { v.bulge },
                        )
                    })
                    .collect();
                if three_d
                    && p.vertices().any(|v| {
                        (v.location.z - p.vertices().next().map_or(0.0, |f| f.location.z)).abs()
                            > 1e-9
                    })
                {
                    return Err("a 3D polyline not in one XY plane".into());
                }
                polyline(&xf, &v, p.flags & 1 != 0, tol, left)
            }
            EntityType::Spline(s) => spline(s, &ctx.xf, tol, left),
            EntityType::Ellipse(el) => ellipse(el, &ctx.xf, tol, left),
            _ => Err("not a contour".into()),
        }
    }
}

/// `end` moved on by whole turns of `turn` (360 degrees, or 2 pi) until it is past `start`,
/// for a curve that runs counter-clockwise from `start`: in one step, not a turn at a time
/// (which never ends at 1e20 degrees, where adding a turn changes nothing). `None` for an
/// angle that is not finite or beyond a million turns (where a float no longer tells a
/// degree).
fn turn_past(start: f64, end: f64, turn: f64) -> Option<f64> {
    let limit = 1e6 * turn;
    if !(start.abs() <= limit && end.abs() <= limit) {
        return None;
    }
    if end > start {
        return Some(end);
    }
    let mut past = end + turn * (((start - end) / turn).floor() + 1.0);
    if past <= start {
        past += turn;
    }
    Some(past)
}

fn line(a: [f64; 2], b: [f64; 2]) -> Vec<Segment> {
    if a == b {
        return Vec::new();
    }
    vec![Segment {
        start: a,
        end: b,
        bulge: 0.0,
    }]
}

/// The arc of radius `r` about `c` from `a0` to `a1` (rad, counter-clockwise, in the
/// entity's coordinates) mapped by `xf`: one bulge segment under a similarity, arcs fitted
/// to the ellipse otherwise.
fn arc(
    xf: &Affine,
    c: [f64; 2],
    r: f64,
    a0: f64,
    a1: f64,
    tol: f64,
    left: &Cell<usize>,
) -> Result<(Vec<Segment>, bool, Option<String>), String> {
    let at = |t: f64| xf.apply([c[0] + r * t.cos(), c[1] + r * t.sin()]);
    if xf.is_conformal() {
        let sweep = a1 - a0;
        let sign = if xf.mirrors() { -1.0 } else { 1.0 };
        // arcs above a half turn in two, so no bulge is huge
        let n = if sweep > std::f64::consts::PI { 2 } else { 1 };
        let segs = (0..n)
            .map(|k| {
                let (s, e) = (
                    a0 + sweep * k as f64 / n as f64,
                    a0 + sweep * (k + 1) as f64 / n as f64,
                );
                Segment {
                    start: at(s),
                    end: at(e),
                    bulge: sign * ((e - s) / 4.0).tan(),
                }
            })
            .collect();
        Ok((segs, false, None))
    } else {
        let segs = fit_arcs(
            &Curve {
                at: &at,
                t0: a0,
                t1: a1,
                breaks: vec![],
            },
            tol,
            left,
        )?;
        Ok((
            segs,
            false,
            Some(format!(
                "arc under a non-uniform block scale: an ellipse, fitted by arcs within {tol} mm"
            )),
        ))
    }
}

/// A polyline of `(point, bulge)` vertices mapped by `xf`.
fn polyline(
    xf: &Affine,
    v: &[([f64; 2], f64)],
    closed: bool,
    tol: f64,
    left: &Cell<usize>,
) -> Result<(Vec<Segment>, bool, Option<String>), String> {
    let mut v = v.to_vec();
    // a closing vertex repeated at the end
    if v.len() > 2 && v[0].0 == v[v.len() - 1].0 {
        v.pop();
        return polyline(xf, &v, true, tol, left);
    }
    let n = v.len();
    let count = if closed { n } else { n.saturating_sub(1) };
    let mut out = Vec::new();
    if xf.is_conformal() {
        // arcs stay arcs: the ends move, the bulge keeps its size (its sign under a mirror)
        let sign = if xf.mirrors() { -1.0 } else { 1.0 };
        for i in 0..count {
            let (a, bulge) = v[i];
            let b = v[(i + 1) % n].0;
            // a closed polyline keeps its vertices as written (a repeated one is harmless
            // there); an open one loses zero-length pieces, which would not chain
            if closed || a != b {
                out.push(Segment {
                    start: xf.apply(a),
                    end: xf.apply(b),
                    bulge: sign * bulge,
                });
            }
        }
        return Ok((out, closed && !v.is_empty(), None));
    }
    let mut note = None;
    for i in 0..count {
        let (a, bulge) = v[i];
        let b = v[(i + 1) % n].0;
        if a == b {
            continue;
        }
        if bulge.abs() <= sv_geom::BULGE_EPS {
            out.extend(line(xf.apply(a), xf.apply(b)));
            continue;
        }
        // the arc in the entity's coordinates, mapped
        let s = Segment {
            start: a,
            end: b,
            bulge,
        };
        let Some((r, c)) = s.arc() else { continue };
        let a0 = (a[1] - c[1]).atan2(a[0] - c[0]);
        let (segs, _, n2) = arc(
            xf,
            c,
            r,
            a0.min(a0 + s.sweep()),
            a0.max(a0 + s.sweep()),
            tol,
            left,
        )?;
        note = note.or(n2);
        if s.sweep() > 0.0 {
            out.extend(segs);
        } else {
            out.extend(segs.iter().rev().map(|s| s.reversed()));
        }
    }
    Ok((out, closed && !v.is_empty(), note))
}

fn spline(
    s: &dxf::entities::Spline,
    xf: &Affine,
    tol: f64,
    left: &Cell<usize>,
) -> Result<(Vec<Segment>, bool, Option<String>), String> {
    if s.fit_points.iter().chain(&s.control_points).any(|p| {
        (p.z - s
            .control_points
            .first()
            .or(s.fit_points.first())
            .map_or(0.0, |f| f.z))
        .abs()
            > 1e-9
    }) {
        return Err("a SPLINE not in one XY plane".into());
    }
    let closed_flag = s.flags & 1 != 0;
    let what = format!("SPLINE fitted by arcs within {tol} mm");
    if !s.control_points.is_empty() {
        let n = Nurbs {
            degree: s.degree_of_curve.max(0) as usize,
            knots: s.knot_values.clone(),
            // an affine map of the control points maps the curve
            points: s.control_points.iter().map(|p| xf.apply(xy(p))).collect(),
            weights: if s.weight_values.iter().all(|&w| w == 1.0) {
                Vec::new()
            } else {
                s.weight_values.clone()
            },
        };
        if let Some(why) = n.problem() {
            return Err(format!("SPLINE with an invalid definition ({why})"));
        }
        let (t0, t1) = n.domain();
        let at = |t: f64| n.at(t);
        let segs = fit_arcs(
            &Curve {
                at: &at,
                t0,
                t1,
                breaks: n.breaks(),
            },
            tol,
            left,
        )?;
        let closed = closed_flag || ends_meet(&segs);
        return Ok((segs, closed, Some(what)));
    }
    if s.fit_points.len() >= 2 {
        let pts: Vec<[f64; 2]> = s.fit_points.iter().map(|p| xf.apply(xy(p))).collect();
        let tangent = |p: &dxf::Point| {
            let v = xf.apply_vector([p.x, p.y]);
            (v[0].hypot(v[1]) > 0.0).then_some(v)
        };
        let i = Interpolant::new(&pts, tangent(&s.start_tangent), tangent(&s.end_tangent));
        let (t0, t1) = i.domain();
        let at = |t: f64| i.at(t);
        let segs = fit_arcs(
            &Curve {
                at: &at,
                t0,
                t1,
                breaks: i.breaks(),
            },
            tol,
            left,
        )?;
        let closed = closed_flag || ends_meet(&segs);
        return Ok((
            segs,
            closed,
            Some(format!("SPLINE with fit points only: interpolated (cubic, chord-length) and fitted by arcs within {tol} mm")),
        ));
    }
    Err("SPLINE without control or fit points".into())
}

fn ends_meet(segs: &[Segment]) -> bool {
    match (segs.first(), segs.last()) {
        (Some(a), Some(b)) => {
            a.start == b.end || (a.start[0] - b.end[0]).hypot(a.start[1] - b.end[1]) < 1e-9
        }
        _ => false,
    }
}

fn ellipse(
    el: &dxf::entities::Ellipse,
    xf: &Affine,
    tol: f64,
    left: &Cell<usize>,
) -> Result<(Vec<Segment>, bool, Option<String>), String> {
    let n = xyz(&el.normal);
    if ocs(n).is_none() {
        return Err("not in the XY plane (tilted extrusion direction)".into());
    }
    let c = xy(&el.center);
    let m = [el.major_axis.x, el.major_axis.y];
    // minor axis: ratio * (normal x major), so a -Z normal runs the ellipse clockwise
    let z = if n[2] < 0.0 { -1.0 } else { 1.0 };
    let minor = [
        -z * m[1] * el.minor_axis_ratio,
        z * m[0] * el.minor_axis_ratio,
    ];
    if !(m[0].hypot(m[1]) > 0.0 && el.minor_axis_ratio > 0.0) {
        return Ok((Vec::new(), false, None));
    }
    let t0 = el.start_parameter;
    let mut t1 = turn_past(t0, el.end_parameter, std::f64::consts::TAU).ok_or_else(|| {
        format!(
            "start and end parameter {t0:?}, {:?}: not finite, or beyond a million turns",
            el.end_parameter
        )
    })?;
    let full = (t1 - t0) >= std::f64::consts::TAU - 1e-9;
    if full {
        t1 = t0 + std::f64::consts::TAU;
    }
    let at = |t: f64| {
        let (s, k) = t.sin_cos();
        xf.apply([
            c[0] + k * m[0] + s * minor[0],
            c[1] + k * m[1] + s * minor[1],
        ])
    };
    let mut segs = fit_arcs(
        &Curve {
            at: &at,
            t0,
            t1,
            breaks: vec![],
        },
        tol,
        left,
    )?;
    if full {
        if let (Some(first), Some(last)) = (segs.first().copied(), segs.last_mut()) {
            last.end = first.start;
        }
    }
    Ok((
        segs,
        full,
        Some(format!("ELLIPSE fitted by arcs within {tol} mm")),
    ))
}
