//! Cut profiles: the rounded steel contours of a strip (outline, hook slots, bridges).

use cavalier_contours::polyline::{
    BooleanOp, PlineCreation, PlineSource, PlineSourceMut, PlineVertex, Polyline,
};
use serde::{Deserialize, Serialize};
use sv_geom::{Contour, Point2, Vector2};
use sv_unit::UnitLayout;

use crate::plane::cross;
use crate::{FaceMark, FlatStrip, HubFace, ProfileParams, Relief, StripsError};

/// A text to etch: centred at `at`, baseline along `angle` (rad), cap height `height` (mm).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Label {
    /// The text (`0-9`, `A-Z`, `-`).
    pub text: String,
    /// Centre of the text box (mm).
    pub at: [f64; 2],
    /// Direction of the baseline (rad, counter-clockwise from +x).
    pub angle: f64,
    /// Cap height (mm).
    pub height: f64,
}

/// The direction `angle` (rad) or its opposite, whichever reads upright: in (-90, 90]
/// degrees of +x (straight up reads bottom to top; a baseline within 1e-9 rad of straight
/// down, as rounding leaves one, is turned up).
pub fn upright(angle: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    const ROUNDING: f64 = 1e-9;
    // (-pi, pi]
    let a = angle.rem_euclid(TAU);
    let a = if a > PI { a - TAU } else { a };
    if a > FRAC_PI_2 + ROUNDING {
        a - PI
    } else if a <= -FRAC_PI_2 + ROUNDING {
        a + PI
    } else {
        a
    }
}

impl Label {
    /// This label where the rigid motion `p -> R(rotation) p + translation` (rotation in
    /// rad, as a nest placement) puts it, turned half round about its centre where that
    /// reads upright ([`upright`]): the same box, the same text, never upside down.
    pub fn placed(&self, rotation: f64, translation: [f64; 2]) -> Label {
        let (s, c) = rotation.sin_cos();
        let [x, y] = self.at;
        Label {
            text: self.text.clone(),
            at: [
                c * x - s * y + translation[0],
                s * x + c * y + translation[1],
            ],
            angle: upright(self.angle + rotation),
            height: self.height,
        }
    }
}

/// The cut profile of one strip, in the strip's flat frame.
#[derive(Clone, Debug, PartialEq)]
pub struct StripProfile {
    /// The part outline (counter-clockwise).
    pub outline: Contour,
    /// The hook slots (clockwise), four per unit in unit order.
    pub cuts: Vec<Contour>,
    /// Frame unit of each cut.
    pub cut_units: Vec<usize>,
    /// Fold marks to etch across every neck and bridge (segments, mm).
    pub fold_marks: Vec<[[f64; 2]; 2]>,
    /// One label per unit (`A03-07`) on its hub, upright in the strip frame, plus none for
    /// the strip.
    pub labels: Vec<Label>,
    /// One mark per unit on its hub, beside its label: which face the hub comes out of.
    pub face_marks: Vec<FaceMark>,
    /// Nominal flat expanded primary tiles (closed quads) for the never-cut info layer.
    pub tiles: Vec<[[f64; 2]; 4]>,
    /// Net area of the part (mm^2): outline minus cuts.
    pub area: f64,
}

impl StripProfile {
    /// Length and width of the part as cut (mm): the extent of its outline, arcs included,
    /// along x and y of the strip's frame (the frame of `strips/ID.dxf`, long side on x).
    /// The nominal tiles' rectangle ([`crate::FlatStrip::size`]) is larger by the rounds
    /// of the tiles' corners.
    pub fn size(&self) -> [f64; 2] {
        self.outline
            .bounds()
            .map_or([0.0, 0.0], |(lo, hi)| [hi[0] - lo[0], hi[1] - lo[1]])
    }
}

fn p2a(p: Point2) -> [f64; 2] {
    [p.x, p.y]
}

use sv_unit::inset_sides;

fn closed(points: &[Point2]) -> Polyline<f64> {
    let mut p = Polyline::with_capacity(points.len(), true);
    for q in points {
        p.add(q.x, q.y, 0.0);
    }
    p
}

fn one(mut v: Vec<Polyline<f64>>, what: &str) -> Result<Polyline<f64>, StripsError> {
    if v.len() == 1 {
        Ok(v.remove(0))
    } else {
        Err(StripsError::Internal {
            why: format!("{what}: expected one contour, got {}", v.len()),
        })
    }
}

/// A slot of width `width` around an open centre line: both offsets joined by half-circle
/// ends, clockwise (material on the left). Outer bends get arcs from the offset.
fn slot(center: &[Point2], width: f64) -> Result<Polyline<f64>, StripsError> {
    let mut c = Polyline::with_capacity(center.len(), false);
    for q in center {
        c.add(q.x, q.y, 0.0);
    }
    let left = one(c.parallel_offset(width / 2.0), "slot left side")?;
    let mut right = one(c.parallel_offset(-width / 2.0), "slot right side")?;
    right.invert_direction_mut();
    let mut out = Polyline::with_capacity(left.vertex_count() + right.vertex_count(), true);
    for (i, v) in left.iter_vertexes().enumerate() {
        let b = if i + 1 == left.vertex_count() {
            -1.0
        } else {
            v.bulge
        };
        out.add_vertex(PlineVertex::new(v.x, v.y, b));
    }
    for (i, v) in right.iter_vertexes().enumerate() {
        let b = if i + 1 == right.vertex_count() {
            -1.0
        } else {
            v.bulge
        };
        out.add_vertex(PlineVertex::new(v.x, v.y, b));
    }
    Ok(out)
}

/// Cut relief `r` as one with the hook slot it runs into: it must meet exactly one (one that
/// met two would cut the web between them, a neck).
fn cut_relief(slots: &mut [Polyline<f64>], r: &Relief, corner: f64) -> Result<(), String> {
    let [a, b, c, d] = r.outline;
    let mut notch = Polyline::with_capacity(4, true);
    notch.add(a.x, a.y, 0.0);
    notch.add(b.x, b.y, 0.0);
    notch.add(c.x, c.y, 0.0);
    // clockwise: round the back of the closed end clockwise
    notch.add(d.x, d.y, -1.0);
    if notch.area() < 0.0 {
        notch.invert_direction_mut();
    }
    // a bent relief: its lead run round the leg's section, square behind it (the corners
    // rounded as the slots'), round where it joins the run into the slot
    if let Some([p, q]) = r.lead {
        let half = r.width / 2.0;
        let round = corner.min(half / 2.0);
        let Some(along) = (q - p).try_normalize(1e-12) else {
            return Err(format!(
                "the relief for leg {} of unit {} has no lead",
                r.leg, r.leg_of
            ));
        };
        let left = Vector2::new(-along.y, along.x);
        // counter-clockwise: back along its left side, round its square end, forward along
        // its right side, round the front
        let quarter = (std::f64::consts::PI / 8.0).tan();
        let mut lead = Polyline::with_capacity(6, true);
        for (at, bulge) in [
            (q + left * half, 0.0),
            (p + left * half + along * round, quarter),
            (p + left * (half - round), 0.0),
            (p - left * (half - round), quarter),
            (p - left * half + along * round, 0.0),
            (q - left * half, 1.0),
        ] {
            lead.add(at.x, at.y, bulge);
        }
        let mut joined = notch.boolean(&lead, BooleanOp::Or);
        if joined.pos_plines.len() != 1 || !joined.neg_plines.is_empty() {
            return Err(format!(
                "the relief for leg {} of unit {} does not join its lead",
                r.leg, r.leg_of
            ));
        }
        notch = joined.pos_plines.remove(0).pline;
    }
    let mut met = None;
    for (i, s) in slots.iter().enumerate() {
        let mut s = s.clone();
        if s.area() < 0.0 {
            s.invert_direction_mut();
        }
        let mut joined = s.boolean(&notch, BooleanOp::Or);
        if joined.pos_plines.len() == 1 && joined.neg_plines.is_empty() {
            if met.is_some() {
                return Err(format!(
                    "the relief for leg {} of unit {} would cut through a neck",
                    r.leg, r.leg_of
                ));
            }
            let mut one = joined.pos_plines.remove(0).pline;
            // clockwise, as every slot
            if one.area() > 0.0 {
                one.invert_direction_mut();
            }
            met = Some((i, one));
        }
    }
    let (i, one) = met.ok_or_else(|| {
        format!(
            "the relief for leg {} of unit {} reaches no hook slot",
            r.leg, r.leg_of
        )
    })?;
    slots[i] = one;
    Ok(())
}

/// Everything of one unit inside its plate.
struct UnitCut {
    slots: Vec<Polyline<f64>>,
    folds: Vec<[[f64; 2]; 2]>,
    label: Label,
    mark: FaceMark,
}

fn unit_error(strip: &str, unit: usize, why: String) -> StripsError {
    StripsError::Unit {
        strip: strip.to_string(),
        unit,
        why,
    }
}

/// The four hook slots of a unit whose tile is `tile`, where sv_unit::UnitLayout puts them.
fn unit_cuts(
    strip: &str,
    unit: usize,
    label: String,
    face: HubFace,
    tile: &[Point2; 4],
    reliefs: &[Relief],
    p: &ProfileParams,
) -> Result<UnitCut, StripsError> {
    let layout =
        UnitLayout::new(tile, &p.cut_widths()).map_err(|e| unit_error(strip, unit, e.0))?;
    let mut slots = layout
        .slot_paths
        .iter()
        .map(|c| slot(c, p.slot_width))
        .collect::<Result<Vec<_>, _>>()?;
    for r in reliefs {
        cut_relief(&mut slots, r, p.fillet_radius).map_err(|why| unit_error(strip, unit, why))?;
    }
    let folds = (0..4)
        .flat_map(|j| [layout.hub_necks[j], layout.rim_necks[(j + 1) % 4]])
        .map(|[a, b]| shorten(a, b, 0.75))
        .collect();
    let hub = layout.hub;
    let d0 = (hub[1] - hub[0]).normalize();
    let centre = Point2::from(hub.iter().fold(Vector2::zeros(), |acc, v| acc + v.coords) / 4.0);
    let inradius = (0..4)
        .map(|i| cross(&(hub[(i + 1) % 4] - hub[i]).normalize(), &(centre - hub[i])))
        .fold(f64::INFINITY, f64::min);
    let height = (inradius * 2.0 / (0.9 * label.len().max(1) as f64 + 1.0)).clamp(3.0, 25.0);
    let label = Label {
        text: label,
        at: p2a(centre),
        angle: upright(d0.y.atan2(d0.x)),
        height,
    };
    let (label, mark) = match face_mark(&hub, &label, face, p.min_web()) {
        Ok(mark) => (label, mark),
        Err(why) => {
            // on a small hub plate the label moves up so that the mark fits under it
            let raised = Label {
                at: p2a(Point2::from(label.at) + up_of(&label) * 1.25 * MIN_FACE_MARK_RADIUS),
                ..label
            };
            let mark = face_mark(&hub, &raised, face, p.min_web())
                .map_err(|_| unit_error(strip, unit, why))?;
            (raised, mark)
        }
    };
    Ok(UnitCut {
        slots,
        folds,
        label,
        mark,
    })
}

/// The direction up the page in a label's upright reading.
fn up_of(label: &Label) -> Vector2 {
    Vector2::new(-label.angle.sin(), label.angle.cos())
}

/// Smallest radius of a face mark (mm): below it a plasma etch is a blot.
const MIN_FACE_MARK_RADIUS: f64 = 3.0;

/// The face mark of a unit: a circle of half the label's height (at least
/// [`MIN_FACE_MARK_RADIUS`]) centred under the label (in its upright reading), half a
/// radius below the text; smaller where the hub plate (`hub`, counter-clockwise) would not
/// hold it `margin` inside every side.
fn face_mark(
    hub: &[Point2; 4],
    label: &Label,
    face: HubFace,
    margin: f64,
) -> Result<FaceMark, String> {
    let up = up_of(label);
    let c0 = Point2::new(label.at[0], label.at[1]);
    let half = label.height / 2.0;
    // centre at c0 - up (half + 1.5 r); side i (inward normal n) holds it when
    // n.(c0 - hub_i) - (half + 1.5 r) n.up >= r + margin
    let sides: Vec<(f64, f64)> = (0..4)
        .map(|i| {
            let d = (hub[(i + 1) % 4] - hub[i]).normalize();
            let n = Vector2::new(-d.y, d.x);
            (n.dot(&(c0 - hub[i])), n.dot(&up))
        })
        .collect();
    let radius = sides
        .iter()
        .filter(|&&(_, nu)| 1.0 + 1.5 * nu > 0.0)
        .map(|&(depth, nu)| (depth - half * nu - margin) / (1.0 + 1.5 * nu))
        .fold(half.max(MIN_FACE_MARK_RADIUS), f64::min);
    let at = c0 - up * (half + 1.5 * radius);
    let fits = sides
        .iter()
        .all(|&(depth, nu)| depth - (half + 1.5 * radius) * nu >= radius + margin - 1e-9);
    if !(radius >= MIN_FACE_MARK_RADIUS && fits) {
        let inradius = sides
            .iter()
            .map(|&(depth, _)| depth)
            .fold(f64::INFINITY, f64::min);
        return Err(format!(
            "hub plate too small for a face mark of radius {MIN_FACE_MARK_RADIUS} mm \
             {margin} mm inside it under a {:.1} mm label: {:.1} mm from the label to the \
             nearest side (a larger unit size or narrower legs and rim give larger hub plates)",
            label.height, inradius
        ));
    }
    Ok(FaceMark {
        at: p2a(at),
        radius,
        face,
    })
}

/// The segment `a b` shortened by `by` at both ends.
fn shorten(a: Point2, b: Point2, by: f64) -> [[f64; 2]; 2] {
    let l = (b - a).norm();
    if l <= 2.0 * by {
        return [p2a(a), p2a(b)];
    }
    let u = (b - a) / l;
    [p2a(a + u * by), p2a(b - u * by)]
}

/// Plate with rounded corners: `q` opened by `r` (inset, then grown back).
fn rounded_plate(q: &[Point2; 4], r: f64) -> Result<Polyline<f64>, StripsError> {
    let inner = one(closed(q).parallel_offset(r), "plate inset")?;
    one(inner.parallel_offset(-r), "plate grow")
}

/// Straight range of a plate side along the line `o + t u`: the side's projection minus
/// the corner fillets `r / tan(angle / 2)`.
fn straight_range(q: &[Point2; 4], k: usize, o: Point2, u: Vector2, r: f64) -> (f64, f64) {
    let d = |i: usize| (q[(i + 1) % 4] - q[i % 4]).normalize();
    let trim = |i: usize| {
        // interior angle at corner i
        let a = (-d(i + 3)).angle(&d(i));
        r / (a / 2.0).tan()
    };
    let (t0, t1) = ((q[k] - o).dot(&u), (q[(k + 1) % 4] - o).dot(&u));
    let (lo, hi) = if t0 <= t1 {
        (t0 + trim(k), t1 - trim(k + 1))
    } else {
        (t1 + trim(k + 1), t0 - trim(k))
    };
    (lo, hi)
}

/// Cut profile of a flat strip: unit plates joined by bridges at the pins, outline
/// fillets, four hook slots per unit, fold marks and labels. `labels[j]` is the etched
/// label of `strip.units[j]`.
pub fn profile_strip(
    strip: &FlatStrip,
    labels: &[String],
    params: &ProfileParams,
) -> Result<StripProfile, StripsError> {
    params.validate()?;
    let r = params.fillet_radius;
    let half = params.cut_widths().plate_inset();
    let mut outline: Option<Polyline<f64>> = None;
    let mut cuts = Vec::new();
    let mut cut_units = Vec::new();
    let mut fold_marks = Vec::new();
    let mut out_labels = Vec::new();
    let mut face_marks = Vec::new();
    let mut plates = Vec::with_capacity(strip.units.len());
    for (j, (&u, tile)) in strip.units.iter().zip(&strip.tiles).enumerate() {
        // the plate: the tile, less half the joint slot where a bridge joins the next or
        // the previous unit of the strip; elsewhere it reaches the tile's side, where the
        // neighbouring strip's plate meets it
        let mut delta = [0.0; 4];
        if let Some(p) = strip.pins.get(j) {
            delta[p.sides[0]] = half;
        }
        if let Some(p) = j.checked_sub(1).and_then(|i| strip.pins.get(i)) {
            delta[p.sides[1]] = half;
        }
        let q = inset_sides(tile, delta)
            .ok_or_else(|| unit_error(&strip.id, u, "tile smaller than the joint slot".into()))?;
        let label = labels.get(j).cloned().unwrap_or_default();
        let face = *strip
            .hub_faces
            .get(j)
            .ok_or_else(|| StripsError::Internal {
                why: format!("strip {}: unit {u} has no hub face", strip.id),
            })?;
        let reliefs = strip.reliefs.get(j).map_or(&[][..], |r| &r[..]);
        let cut = unit_cuts(&strip.id, u, label, face, tile, reliefs, params)?;
        for sl in &cut.slots {
            cuts.push(Contour::from_pline(sl));
            cut_units.push(u);
        }
        fold_marks.extend(cut.folds);
        out_labels.push(cut.label);
        face_marks.push(cut.mark);
        plates.push(q);
    }
    for (j, q) in plates.iter().enumerate() {
        let plate = rounded_plate(q, r)?;
        outline = Some(match outline {
            None => plate,
            Some(o) => union(&o, &plate, &strip.id, strip.units[j])?,
        });
        if let Some(pin) = strip.pins.get(j) {
            let tile = &strip.tiles[j];
            let k = pin.sides[0];
            let o = tile[k];
            let u = (tile[(k + 1) % 4] - o).normalize();
            let v = Vector2::new(-u.y, u.x);
            let (a0, a1) = straight_range(q, k, o, u, r);
            let (b0, b1) = straight_range(&plates[j + 1], pin.sides[1], o, u, r);
            let hw = params.neck_width / 2.0;
            let (lo, hi) = (a0.max(b0) + hw + r, a1.min(b1) - hw - r);
            if lo > hi {
                return Err(StripsError::NoBridge {
                    strip: strip.id.clone(),
                    units: pin.units,
                    width: params.neck_width,
                });
            }
            let t = (pin.point - o).dot(&u).clamp(lo, hi);
            let c = o + u * t;
            let e = half + r + 1.0;
            let rect = closed(&[
                c - u * hw - v * e,
                c + u * hw - v * e,
                c + u * hw + v * e,
                c - u * hw + v * e,
            ]);
            let ol = outline.take().ok_or_else(|| StripsError::Internal {
                why: "no outline".into(),
            })?;
            outline = Some(union(&ol, &rect, &strip.id, pin.units[1])?);
            fold_marks.push(shorten(c - u * hw, c + u * hw, 0.75));
        }
    }
    let outline = outline.ok_or_else(|| StripsError::Internal {
        why: format!("strip {} has no units", strip.id),
    })?;
    // fillet the inside corners (bridge to plate): closing by r
    let grown = one(outline.parallel_offset(-r), "outline closing")?;
    let mut outline = one(grown.parallel_offset(r), "outline closing back")?;
    if outline.area() < 0.0 {
        outline.invert_direction_mut();
    }
    let area = outline.area() - cuts.iter().map(|c| c.signed_area().abs()).sum::<f64>();
    Ok(StripProfile {
        outline: Contour::from_pline(&outline),
        cuts,
        cut_units,
        fold_marks,
        labels: out_labels,
        face_marks,
        tiles: strip.tiles.iter().map(|t| t.map(p2a)).collect(),
        area,
    })
}

fn union(
    a: &Polyline<f64>,
    b: &Polyline<f64>,
    strip: &str,
    unit: usize,
) -> Result<Polyline<f64>, StripsError> {
    let mut res = a.boolean(b, BooleanOp::Or);
    if res.pos_plines.len() != 1 || !res.neg_plines.is_empty() {
        return Err(unit_error(
            strip,
            unit,
            format!(
                "plate does not join the strip in one piece ({} pieces, {} holes)",
                res.pos_plines.len(),
                res.neg_plines.len()
            ),
        ));
    }
    let mut p = res.pos_plines.remove(0).pline;
    if p.area() < 0.0 {
        p.invert_direction_mut();
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn upright_turns_every_direction_into_minus_90_to_90_degrees() {
        for k in -40..=40 {
            let a = k as f64 * 0.1;
            let u = upright(a);
            assert!(u > -FRAC_PI_2 && u <= FRAC_PI_2 + 1e-9, "{a} -> {u}");
            // the same line: a or a + pi, modulo a turn
            let d = (u - a).rem_euclid(PI);
            assert!(d < 1e-9 || PI - d < 1e-9, "{a} -> {u}");
        }
        assert_eq!(upright(0.3), 0.3);
        assert!((upright(PI - 0.3) + 0.3).abs() < 1e-12);
        assert!((upright(-FRAC_PI_2) - FRAC_PI_2).abs() < 1e-12);
        assert!((upright(FRAC_PI_2) - FRAC_PI_2).abs() < 1e-12);
        // straight down but for rounding reads up
        assert!((upright(-FRAC_PI_2 + 1e-15) - FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_placed_label_moves_with_the_part_and_reads_upright() {
        let l = Label {
            text: "A01-02".into(),
            at: [10.0, 0.0],
            angle: 0.2,
            height: 20.0,
        };
        // a half turn about the origin and a shift: same box, not upside down
        let p = l.placed(PI, [100.0, 50.0]);
        assert!((p.at[0] - 90.0).abs() < 1e-9 && (p.at[1] - 50.0).abs() < 1e-9);
        assert!((p.angle - 0.2).abs() < 1e-12);
        assert_eq!((p.text.as_str(), p.height), ("A01-02", 20.0));
        // a quarter turn keeps an upright label upright
        assert!((l.placed(FRAC_PI_2, [0.0, 0.0]).angle - (0.2 + FRAC_PI_2 - PI)).abs() < 1e-12);
    }

    /// Distance from `p` inside the counter-clockwise quad `q` to its nearest side.
    fn depth(q: &[Point2; 4], p: Point2) -> f64 {
        (0..4)
            .map(|i| cross(&(q[(i + 1) % 4] - q[i]).normalize(), &(p - q[i])))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn on_small_hub_plates_the_label_moves_up_so_that_the_mark_fits_under_it() {
        // square tiles from 200 mm down to 40: wherever a unit can be cut, its mark lies a margin
        // inside the hub plate and half a radius under its label; on the smallest the
        // label left the plate's centre to make room
        let p = ProfileParams::default();
        let (mut raised, mut centred) = (0, 0);
        for side in (40..=200).rev().step_by(2) {
            let a = side as f64;
            let tile = [
                Point2::new(0.0, 0.0),
                Point2::new(a, 0.0),
                Point2::new(a, a),
                Point2::new(0.0, a),
            ];
            let Ok(cut) = unit_cuts("A01", 0, "A01-01".into(), HubFace::Back, &tile, &[], &p)
            else {
                continue;
            };
            let hub = UnitLayout::new(&tile, &p.cut_widths()).unwrap().hub;
            let (m, l) = (&cut.mark, &cut.label);
            let c = Point2::new(m.at[0], m.at[1]);
            assert!(
                depth(&hub, c) >= m.radius + p.min_web() - 1e-9,
                "{a}: {m:?}"
            );
            assert!(m.radius >= MIN_FACE_MARK_RADIUS, "{a}: {m:?}");
            let below = (Point2::new(l.at[0], l.at[1]) - c).dot(&up_of(l));
            assert!(
                (below - (l.height / 2.0 + 1.5 * m.radius)).abs() < 1e-9,
                "{a}"
            );
            let centre = Point2::from(hub.iter().fold(Vector2::zeros(), |s, v| s + v.coords) / 4.0);
            if (Point2::new(l.at[0], l.at[1]) - centre).norm() > 1e-9 {
                raised += 1;
            } else {
                centred += 1;
            }
        }
        assert!(
            raised > 0 && centred > 0,
            "raised {raised}, centred {centred}"
        );
    }

    #[test]
    fn the_face_mark_sits_under_the_label_inside_the_hub_plate() {
        // a skewed hub plate
        let hub = [
            Point2::new(0.0, 0.0),
            Point2::new(200.0, 30.0),
            Point2::new(230.0, 220.0),
            Point2::new(20.0, 190.0),
        ];
        let label = Label {
            text: "A01-01".into(),
            at: [115.0, 110.0],
            angle: 0.15,
            height: 25.0,
        };
        let m = face_mark(&hub, &label, HubFace::Back, 3.75).unwrap();
        assert_eq!((m.radius, m.face), (12.5, HubFace::Back));
        // half a radius below the text's lower edge, in the label's upright reading
        let up = Vector2::new(-label.angle.sin(), label.angle.cos());
        let c = Point2::new(m.at[0], m.at[1]);
        let below = -(c - Point2::new(115.0, 110.0)).dot(&up);
        assert!((below - (12.5 + 1.5 * 12.5)).abs() < 1e-9, "{below}");
        assert!(depth(&hub, c) >= m.radius + 3.75);
        // a narrow plate: the mark shrinks to stay a margin inside it
        let narrow = [
            Point2::new(0.0, 75.0),
            Point2::new(200.0, 75.0),
            Point2::new(200.0, 160.0),
            Point2::new(0.0, 160.0),
        ];
        let label = Label {
            angle: 0.0,
            ..label
        };
        let m = face_mark(&narrow, &label, HubFace::Etched, 3.75).unwrap();
        let c = Point2::new(m.at[0], m.at[1]);
        assert!(m.radius < 12.5 && m.radius >= MIN_FACE_MARK_RADIUS, "{m:?}");
        assert!(
            (depth(&narrow, c) - (m.radius + 3.75)).abs() < 1e-9,
            "{m:?}"
        );
        // a small label (4 mm) still gets a mark of the smallest radius that etches well
        let small = Label {
            height: 4.0,
            at: [100.0, 130.0],
            ..label.clone()
        };
        let m = face_mark(&narrow, &small, HubFace::Etched, 3.75).unwrap();
        let c = Point2::new(m.at[0], m.at[1]);
        assert_eq!(m.radius, MIN_FACE_MARK_RADIUS, "{m:?}");
        assert!((130.0 - c.y - (2.0 + 1.5 * m.radius)).abs() < 1e-9, "{m:?}");
        assert!(depth(&narrow, c) >= m.radius + 3.75);
        // no room at all: an error that says how much there is, not a mark on the cut
        let label = Label {
            at: [100.0, 90.0],
            ..label
        };
        let why = face_mark(&narrow, &label, HubFace::Etched, 3.75).unwrap_err();
        assert!(why.contains("15.0 mm from the label"), "{why}");
    }

    /// A relief 10 mm wide from 20 mm inside the hub down into a straight slot along x
    /// (4 mm wide): one cut of the slot's area plus the relief's band to the slot's centre
    /// line and the half disc round its closed end.
    #[test]
    fn a_relief_is_cut_as_one_with_the_slot_it_runs_into() {
        let slot_path = [Point2::new(-50.0, 0.0), Point2::new(50.0, 0.0)];
        let mut slots = vec![slot(&slot_path, 4.0).unwrap()];
        let before = slots[0].area().abs();
        let r = Relief {
            // clockwise, as relief::relief_for builds it: the closed end's corners last and
            // first
            outline: [
                Point2::new(5.0, 20.0),
                Point2::new(5.0, 0.0),
                Point2::new(-5.0, 0.0),
                Point2::new(-5.0, 20.0),
            ],
            width: 10.0,
            lead: None,
            leg_of: 1,
            leg: 2,
        };
        cut_relief(&mut slots, &r, 1.5).unwrap();
        let band = 10.0 * (20.0 - 2.0);
        let disc = std::f64::consts::PI * 25.0 / 2.0;
        let after = slots[0].area().abs();
        assert!(
            (after - before - band - disc).abs() < 0.05,
            "{after} - {before}"
        );
        // clockwise, as every slot
        assert!(slots[0].area() < 0.0);

        // bent: a lead run from its square end at x = 20 to the closed end of the run into
        // the slot, 10 across; it adds its band less what the run and its half disc
        // already cut (a 5 x 5 square and a quarter disc) and its two rounded corners
        let mut slots = vec![slot(&slot_path, 4.0).unwrap()];
        let bent = Relief {
            lead: Some([Point2::new(20.0, 20.0), Point2::new(0.0, 20.0)]),
            ..r
        };
        cut_relief(&mut slots, &bent, 1.5).unwrap();
        let corners = 2.0 * (1.5 * 1.5 - std::f64::consts::PI * 1.5 * 1.5 / 4.0);
        let lead = 10.0 * 20.0 - 25.0 - disc / 2.0 - corners;
        let after = slots[0].area().abs();
        assert!(
            (after - before - band - disc - lead).abs() < 0.05,
            "{after} - {before}"
        );
        assert!(slots[0].area() < 0.0);
    }
}
