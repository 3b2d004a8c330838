//! Minimal ASCII DXF reader for closed-contour parts.
//!
//! Reads `LWPOLYLINE` (with bulges), `POLYLINE`/`VERTEX`, `CIRCLE`, and chains of `LINE` and
//! `ARC` from the ENTITIES section. Contours are nested by containment: even depth = outer
//! contour of a part, odd depth = hole of its parent.
//!
//! Layers: the plasma-shop layers `ETCH` (etched marks) and `INFO` (never cut: nominal
//! tiles, titles, sheet outline, pierce points) are not contours, so the strip and sheet
//! drawings of spinvalence read back as their cut contours; `INFO` is ignored, `ETCH`
//! strokes (LWPOLYLINE, LINE) are kept per part to be etched on the sheet. In a file with an `OUTSIDE`
//! layer, its closed contours are the part outlines and every other cut contour (`INSIDE`)
//! is a hole of the smallest outline containing it (one outside every outline is rejected
//! by name); a file without one (layer `0` and the like) is nested by containment alone.

use sv_geom::planar::{point_in_polygon, polygon_area};
use sv_geom::{Contour, Vertex};

use crate::DxfError;

/// Endpoint matching tolerance (drawing units) when chaining LINE/ARC entities.
pub const DEFAULT_CHAIN_TOLERANCE: f64 = 1e-3;

/// A part as read from a file: its outline, its holes and what it etches, in the file's
/// coordinates (mm).
#[derive(Clone, Debug, PartialEq)]
pub struct DxfPart {
    /// The file's name, with `#k` when the file holds several parts.
    pub id: String,
    /// The outline.
    pub outer: Contour,
    /// The holes.
    pub holes: Vec<Contour>,
    /// The `ETCH` polylines and lines whose first point lies on the part (not cut, not
    /// nested; drawn on the sheet).
    pub etch: Vec<Vec<[f64; 2]>>,
}

/// Parts read from a DXF plus per-contour problems (open chains, ...).
#[derive(Clone, Debug, Default)]
pub struct DxfParts {
    /// parts built from closed contours
    pub parts: Vec<DxfPart>,
    /// contours that were rejected, each naming its part/contour
    pub rejected: Vec<DxfError>,
}

#[derive(Clone, Copy)]
struct Seg {
    a: [f64; 2],
    b: [f64; 2],
    bulge: f64,
    outside: bool,
}

/// A closed contour read from the file and whether it is on the `OUTSIDE` layer.
struct Read {
    contour: Contour,
    outside: bool,
}

/// Parses DXF text; `name` prefixes part ids.
pub fn parse_parts(text: &str, name: &str) -> Result<DxfParts, DxfError> {
    let err = |line: usize, m: &str| DxfError::Dxf {
        file: name.to_string(),
        message: format!("line {line}: {m}"),
    };
    let lines: Vec<&str> = text.lines().collect();
    if lines.len() < 2 {
        return Err(err(0, "empty or not an ASCII DXF"));
    }
    let mut pairs = Vec::with_capacity(lines.len() / 2);
    let mut i = 0;
    while i + 1 < lines.len() {
        let code: i32 = lines[i]
            .trim()
            .parse()
            .map_err(|_| err(i + 1, &format!("bad group code {:?}", lines[i].trim())))?;
        pairs.push((code, lines[i + 1].trim(), i + 1));
        i += 2;
    }
    // locate ENTITIES
    let start = pairs
        .windows(2)
        .position(|w| w[0].0 == 0 && w[0].1 == "SECTION" && w[1].0 == 2 && w[1].1 == "ENTITIES")
        .ok_or_else(|| err(0, "no ENTITIES section"))?
        + 2;
    // split entities
    let mut ents: Vec<&[(i32, &str, usize)]> = Vec::new();
    let mut k = start;
    while k < pairs.len() {
        if pairs[k].0 == 0 {
            if pairs[k].1 == "ENDSEC" {
                break;
            }
            let mut e = k + 1;
            while e < pairs.len() && pairs[e].0 != 0 {
                e += 1;
            }
            ents.push(&pairs[k..e]);
            k = e;
        } else {
            k += 1;
        }
    }
    let layer_of = |ent: &[(i32, &str, usize)]| {
        ent.iter()
            .find(|p| p.0 == 8)
            .map_or(String::new(), |p| p.1.to_ascii_uppercase())
    };
    let not_cut = |layer: &str| layer == "INFO";
    let num = |v: &str, line: usize| -> Result<f64, DxfError> {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| err(line, &format!("bad number {v:?}")))
    };
    let mut contours: Vec<Read> = Vec::new();
    let mut etch: Vec<Vec<[f64; 2]>> = Vec::new();
    let mut segs: Vec<Seg> = Vec::new();
    let mut rejected = Vec::new();
    let mut e = 0;
    while e < ents.len() {
        let ent = ents[e];
        let kind = ent[0].1;
        let layer = layer_of(ent);
        let outside = layer == "OUTSIDE";
        if kind != "VERTEX" && kind != "SEQEND" && not_cut(&layer) {
            // skip the entity (with the vertices of a POLYLINE)
            e += 1;
            while kind == "POLYLINE"
                && e < ents.len()
                && matches!(ents[e][0].1, "VERTEX" | "SEQEND")
            {
                e += 1;
            }
            continue;
        }
        let get = |c: i32| ent.iter().find(|p| p.0 == c);
        let getf =
            |c: i32, d: f64| -> Result<f64, DxfError> { get(c).map_or(Ok(d), |p| num(p.1, p.2)) };
        // the vertices of an LWPOLYLINE (10/20 pairs, 42 bulges)
        let lw_vertices = || -> Result<Vec<Vertex>, DxfError> {
            let mut vs: Vec<Vertex> = Vec::new();
            for p in &ent[1..] {
                match p.0 {
                    10 => vs.push(Vertex::line(num(p.1, p.2)?, 0.0)),
                    20 => {
                        if let Some(v) = vs.last_mut() {
                            v.y = num(p.1, p.2)?;
                        }
                    }
                    42 => {
                        if let Some(v) = vs.last_mut() {
                            v.bulge = num(p.1, p.2)?;
                        }
                    }
                    _ => {}
                }
            }
            Ok(vs)
        };
        if layer == "ETCH" {
            // straight etched strokes (spinvalence's labels and fold marks) are kept
            match kind {
                "LWPOLYLINE" => {
                    let mut pts: Vec<[f64; 2]> =
                        lw_vertices()?.iter().map(|v| [v.x, v.y]).collect();
                    if getf(70, 0.0)? as i64 & 1 == 1 && !pts.is_empty() {
                        pts.push(pts[0]);
                    }
                    if pts.len() > 1 {
                        etch.push(pts);
                    }
                }
                "LINE" => etch.push(vec![
                    [getf(10, 0.0)?, getf(20, 0.0)?],
                    [getf(11, 0.0)?, getf(21, 0.0)?],
                ]),
                _ => {}
            }
            e += 1;
            continue;
        }
        match kind {
            "LWPOLYLINE" => {
                let flags = getf(70, 0.0)? as i64;
                let vs = lw_vertices()?;
                let at = (ent[0].2, outside);
                push_polyline(vs, flags & 1 == 1, at, name, &mut contours, &mut rejected);
            }
            "POLYLINE" => {
                let flags = getf(70, 0.0)? as i64;
                let mut vs = Vec::new();
                e += 1;
                while e < ents.len() && ents[e][0].1 == "VERTEX" {
                    let v = ents[e];
                    let f = |c: i32| -> Result<f64, DxfError> {
                        v.iter()
                            .find(|p| p.0 == c)
                            .map_or(Ok(0.0), |p| num(p.1, p.2))
                    };
                    vs.push(Vertex {
                        x: f(10)?,
                        y: f(20)?,
                        bulge: f(42)?,
                    });
                    e += 1;
                }
                // e now at SEQEND (or next entity)
                if !(e < ents.len() && ents[e][0].1 == "SEQEND") {
                    e -= 1;
                }
                let at = (ent[0].2, outside);
                push_polyline(vs, flags & 1 == 1, at, name, &mut contours, &mut rejected);
            }
            "CIRCLE" => {
                let r = getf(40, 0.0)?;
                if r > 0.0 {
                    contours.push(Read {
                        contour: Contour::circle(getf(10, 0.0)?, getf(20, 0.0)?, r),
                        outside,
                    });
                } else {
                    rejected.push(DxfError::BadPart {
                        part: format!("{name} (circle at line {})", ent[0].2),
                        reason: "zero radius".into(),
                    });
                }
            }
            "LINE" => segs.push(Seg {
                a: [getf(10, 0.0)?, getf(20, 0.0)?],
                b: [getf(11, 0.0)?, getf(21, 0.0)?],
                bulge: 0.0,
                outside,
            }),
            "ARC" => {
                let (cx, cy, r) = (getf(10, 0.0)?, getf(20, 0.0)?, getf(40, 0.0)?);
                let (a0, mut a1) = (getf(50, 0.0)?, getf(51, 0.0)?);
                if a1 <= a0 {
                    a1 += 360.0;
                }
                let sweep = (a1 - a0).to_radians();
                let p = |a: f64| [cx + r * a.to_radians().cos(), cy + r * a.to_radians().sin()];
                segs.push(Seg {
                    a: p(a0),
                    b: p(a1),
                    bulge: (sweep / 4.0).tan(),
                    outside,
                });
            }
            _ => {}
        }
        e += 1;
    }
    chain(segs, name, &mut contours, &mut rejected);
    let parts = if contours.iter().any(|c| c.outside) {
        by_layer(contours, name, &mut rejected)
    } else {
        group(contours.into_iter().map(|c| c.contour).collect(), name)
    };
    let etch = etch_of(&parts, etch);
    let parts = parts
        .into_iter()
        .zip(etch)
        .map(|(p, etch)| DxfPart { etch, ..p })
        .collect();
    Ok(DxfParts { parts, rejected })
}

/// Each etched polyline goes with the smallest part whose outline holds its first point;
/// one on no part is dropped.
fn etch_of(parts: &[DxfPart], lines: Vec<Vec<[f64; 2]>>) -> Vec<Vec<Vec<[f64; 2]>>> {
    let (flat, area) = flat_areas(parts.iter().map(|p| &p.outer));
    let mut out = vec![Vec::new(); parts.len()];
    for l in lines {
        if let Some(k) = smallest_holding(&flat, &area, l[0]) {
            out[k].push(l);
        }
    }
    out
}

fn push_polyline(
    mut vs: Vec<Vertex>,
    closed_flag: bool,
    (line, outside): (usize, bool),
    name: &str,
    out: &mut Vec<Read>,
    rejected: &mut Vec<DxfError>,
) {
    let same = |a: &Vertex, b: &Vertex| (a.x - b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9;
    let closed = closed_flag || (vs.len() > 2 && same(&vs[0], &vs[vs.len() - 1]));
    if vs.len() > 1 && same(&vs[0], &vs[vs.len() - 1]) {
        vs.pop();
    }
    if !closed {
        rejected.push(DxfError::BadPart {
            part: format!("{name} (polyline at line {line})"),
            reason: "open contour".into(),
        });
    } else if vs.len() < 2 {
        rejected.push(DxfError::BadPart {
            part: format!("{name} (polyline at line {line})"),
            reason: "fewer than 2 vertices (zero size)".into(),
        });
    } else {
        out.push(Read {
            contour: Contour { vertices: vs },
            outside,
        });
    }
}

fn chain(mut segs: Vec<Seg>, name: &str, out: &mut Vec<Read>, rejected: &mut Vec<DxfError>) {
    let tol = DEFAULT_CHAIN_TOLERANCE;
    let close = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) <= tol;
    while let Some(first) = segs.pop() {
        let mut chain = vec![first];
        loop {
            let end = chain[chain.len() - 1].b;
            if close(end, chain[0].a) {
                break;
            }
            let next = segs.iter().position(|s| close(s.a, end) || close(s.b, end));
            match next {
                Some(k) => {
                    let s = segs.swap_remove(k);
                    chain.push(if close(s.a, end) {
                        s
                    } else {
                        Seg {
                            a: s.b,
                            b: s.a,
                            bulge: -s.bulge,
                            outside: s.outside,
                        }
                    });
                }
                None => break,
            }
        }
        if close(chain[chain.len() - 1].b, chain[0].a) {
            out.push(Read {
                contour: Contour {
                    vertices: chain
                        .iter()
                        .map(|s| Vertex {
                            x: s.a[0],
                            y: s.a[1],
                            bulge: s.bulge,
                        })
                        .collect(),
                },
                outside: chain[0].outside,
            });
        } else {
            let p = chain[0].a;
            rejected.push(DxfError::BadPart {
                part: format!("{name} (LINE/ARC chain from ({:.3}, {:.3}))", p[0], p[1]),
                reason: "open contour".into(),
            });
        }
    }
}

/// Part ids: the file's name, with `#k` when it holds several parts.
fn part_id(name: &str, k: usize, count: usize) -> String {
    if count == 1 {
        name.to_string()
    } else {
        format!("{name}#{}", k + 1)
    }
}

/// The smallest of the closed polygons `flat` (areas `area`) that holds `p`.
fn smallest_holding(flat: &[Vec<[f64; 2]>], area: &[f64], p: [f64; 2]) -> Option<usize> {
    (0..flat.len())
        .filter(|&k| point_in_polygon(p, &flat[k]))
        .min_by(|&a, &b| area[a].total_cmp(&area[b]))
}

/// Flattened outlines of `contours` and their areas.
fn flat_areas<'a>(contours: impl Iterator<Item = &'a Contour>) -> (Vec<Vec<[f64; 2]>>, Vec<f64>) {
    let flat: Vec<Vec<[f64; 2]>> = contours.map(|c| c.flatten(0.01)).collect();
    let area = flat.iter().map(|f| polygon_area(f).abs()).collect();
    (flat, area)
}

/// Parts of a file with shop layers: each `OUTSIDE` contour is an outline (in file order),
/// every other contour a hole of the smallest outline containing its first point.
fn by_layer(contours: Vec<Read>, name: &str, rejected: &mut Vec<DxfError>) -> Vec<DxfPart> {
    let (outer, inner): (Vec<Read>, Vec<Read>) = contours.into_iter().partition(|c| c.outside);
    let (flat, area) = flat_areas(outer.iter().map(|c| &c.contour));
    let count = outer.len();
    let mut parts: Vec<DxfPart> = outer
        .into_iter()
        .enumerate()
        .map(|(k, c)| DxfPart {
            id: part_id(name, k, count),
            outer: c.contour,
            holes: Vec::new(),
            etch: Vec::new(),
        })
        .collect();
    for h in inner {
        let probe = h.contour.vertices[0];
        match smallest_holding(&flat, &area, [probe.x, probe.y]) {
            Some(k) => parts[k].holes.push(h.contour),
            None => rejected.push(DxfError::BadPart {
                part: format!(
                    "{name} (inside contour at ({:.3}, {:.3}))",
                    probe.x, probe.y
                ),
                reason: "not within any OUTSIDE outline".into(),
            }),
        }
    }
    parts
}

fn group(contours: Vec<Contour>, name: &str) -> Vec<DxfPart> {
    let (flat, area) = flat_areas(contours.iter());
    let mut idx: Vec<usize> = (0..contours.len()).collect();
    idx.sort_by(|&a, &b| area[b].total_cmp(&area[a]));
    // parent = smallest larger contour containing the first vertex
    let mut parent = vec![None; contours.len()];
    for (k, &c) in idx.iter().enumerate() {
        let probe = flat[c][0];
        for &o in idx[..k].iter().rev() {
            if point_in_polygon(probe, &flat[o]) {
                parent[c] = Some(o);
                break;
            }
        }
    }
    let depth = |mut c: usize| {
        let mut d = 0;
        while let Some(p) = parent[c] {
            d += 1;
            c = p;
        }
        d
    };
    let outers: Vec<usize> = idx.iter().copied().filter(|&c| depth(c) % 2 == 0).collect();
    outers
        .iter()
        .enumerate()
        .map(|(k, &o)| DxfPart {
            id: part_id(name, k, outers.len()),
            outer: contours[o].clone(),
            holes: idx
                .iter()
                .filter(|&&h| parent[h] == Some(o))
                .map(|&h| contours[h].clone())
                .collect(),
            etch: Vec::new(),
        })
        .collect()
}
