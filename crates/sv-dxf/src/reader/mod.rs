//! The DXF reader for plasma parts drawn by any CAD program.
//!
//! Parsing is the `dxf` crate's (ASCII and binary, R12 to R2018): we read its model space.
//! What we add, in order:
//! 1. **Units**: `$INSUNITS` (or [`ReadOptions::units`]) scales everything to mm; a code
//!    the DXF reference does not define is refused; no units reads as mm, with a note.
//! 2. **Entities** ([`source`]): LINE, ARC, CIRCLE, LWPOLYLINE, POLYLINE (2D and planar
//!    3D), SPLINE and ELLIPSE (turned into arcs within [`ReadOptions::arc_tolerance`]),
//!    INSERTs of blocks, nested, with rotation, scale, mirror and row/column arrays, every
//!    extrusion direction (a (0, 0, -1) OCS mirrors x). Layers and dashed line types say
//!    what is cut ([`LayerRules`]); the rest is skipped with a note.
//! 3. **Chains** ([`chain`]): repeated and overlapping segments merged, ends within
//!    [`ReadOptions::join_tolerance`] joined, the outer boundary where lines meet inside.
//! 4. **Parts** ([`parts`]): repeated contours removed, a drawing border recognised,
//!    outlines and holes by layer and containment, islands (contours inside holes) left
//!    out unless [`ReadOptions::islands`].
//!
//! Every entity skipped or repaired is named once in [`DxfParts::notes`] (layer, entity
//! type, handle); every contour that cannot be a part is in [`DxfParts::rejected`].

mod boxes;
mod chain;
mod fit;
mod layers;
mod parts;
mod source;
mod units;
mod xform;

use std::collections::BTreeMap;
use std::fmt;

use serde::Serialize;
use sv_geom::text::{excerpt, printable};
use sv_geom::Contour;

pub use layers::{LayerRole, LayerRule, LayerRules};
pub use units::Units;

use crate::DxfError;

/// Default join tolerance (mm): ends closer than this are one point. Exports leave gaps
/// of a few hundredths of a millimetre; a plasma kerf is over a millimetre wide.
pub const DEFAULT_JOIN_TOLERANCE: f64 = 0.05;

/// Default arc tolerance (mm): SPLINE and ELLIPSE become arcs within this distance of the
/// true curve, two orders of magnitude below what a plasma cutter resolves.
pub const DEFAULT_ARC_TOLERANCE: f64 = 0.01;

/// How to read a file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadOptions {
    /// The drawing's unit, overriding `$INSUNITS` (`None`: the file's, mm if it has none).
    pub units: Option<Units>,
    /// Ends closer than this (mm) are joined.
    pub join_tolerance: f64,
    /// Curves that are not arcs are replaced by arcs within this distance (mm).
    pub arc_tolerance: f64,
    /// What each layer holds.
    pub layers: LayerRules,
    /// Nest contours found inside holes (islands) as parts of their own.
    pub islands: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            units: None,
            join_tolerance: DEFAULT_JOIN_TOLERANCE,
            arc_tolerance: DEFAULT_ARC_TOLERANCE,
            layers: LayerRules::default(),
            islands: false,
        }
    }
}

/// A part as read from a file: its outline, its holes and what it etches, in the file's
/// coordinates scaled to mm.
#[derive(Clone, Debug, PartialEq)]
pub struct DxfPart {
    /// The file's name, with `#k` when the file holds several parts (file order).
    pub id: String,
    /// The outline.
    pub outer: Contour,
    /// The holes.
    pub holes: Vec<Contour>,
    /// Etched polylines on the part (not cut, not nested; drawn on the sheet).
    pub etch: Vec<Vec<[f64; 2]>>,
}

/// An entity named in a note.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct EntityRef {
    /// Its layer.
    pub layer: String,
    /// Its type (`LINE`, `SPLINE`, ...).
    pub entity: String,
    /// Its handle (hex), with the INSERTs it came through (`2F>85`); `#k` (k-th entity
    /// read) in a file without handles.
    pub handle: String,
}

/// Something the reader skipped or repaired, with the entities concerned.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Note {
    /// The file.
    pub file: String,
    /// What happened.
    pub what: String,
    /// The entities.
    pub entities: Vec<EntityRef>,
}

impl fmt::Display for Note {
    /// `a.dxf: what: layer 0: LINE 2A, 2B; ARC 3C`
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.file, self.what)?;
        f.write_str(&entity_list(&self.entities))
    }
}

/// Handles named per layer and entity type in a line (the rest counted): a note about
/// 40,000 entities stays a line one can read (`nest.json`'s notes list every one).
const HANDLES_NAMED: usize = 8;

/// `: layer 0: LINE 2A, 2B; ARC 3C`, by layer and entity type, at most [`HANDLES_NAMED`]
/// handles each.
fn entity_list(entities: &[EntityRef]) -> String {
    let mut by: BTreeMap<(&str, &str), Vec<&str>> = BTreeMap::new();
    for e in entities {
        by.entry((&e.layer, &e.entity)).or_default().push(&e.handle);
    }
    let mut s = String::new();
    let mut last_layer = None;
    for ((layer, entity), handles) in by {
        if last_layer != Some(layer) {
            s.push_str(if last_layer.is_none() { ": " } else { "; " });
            s.push_str(&format!("layer {}: ", printable(layer)));
            last_layer = Some(layer);
        } else {
            s.push_str(", ");
        }
        let named = handles.len().min(HANDLES_NAMED);
        s.push_str(&format!("{entity} {}", handles[..named].join(", ")));
        if handles.len() > named {
            s.push_str(&format!(" and {} more", handles.len() - named));
        }
    }
    s
}

/// Notes shown in one line: `: what: layer 0: INSERT #1 / what 2: ...` (without the file,
/// which the line names), at most [`NOTES_NAMED`], then how many more (`nest.json` lists
/// every one); empty without notes.
fn first_notes(notes: &[Note]) -> String {
    if notes.is_empty() {
        return String::new();
    }
    let named: Vec<String> = notes
        .iter()
        .take(NOTES_NAMED)
        .map(|n| format!("{}{}", n.what, entity_list(&n.entities)))
        .collect();
    let mut s = format!(": {}", named.join(" / "));
    if notes.len() > NOTES_NAMED {
        s.push_str(&format!(" / and {} more", notes.len() - NOTES_NAMED));
    }
    s
}

/// Notes named in a one-line error (the rest counted).
const NOTES_NAMED: usize = 2;

/// What a file gave: parts, contours left out, notes.
#[derive(Clone, Debug, Default)]
pub struct DxfParts {
    /// The parts, in file order.
    pub parts: Vec<DxfPart>,
    /// Contours that cannot be parts (open, zero size, an inside contour in no outline),
    /// each naming the file and the entities.
    pub rejected: Vec<DxfError>,
    /// Every entity skipped and every repair, once each.
    pub notes: Vec<Note>,
}

/// Reads DXF text with the default options; `name` names the file in messages and part ids.
pub fn parse_parts(text: &str, name: &str) -> Result<DxfParts, DxfError> {
    read_dxf(text.as_bytes(), name, &ReadOptions::default())
}

/// What a light scan of ASCII DXF text tells before parsing: the `$INSUNITS` code and
/// whether entities carry handles (the parser invents handles for those that have none).
fn prescan(bytes: &[u8]) -> (Option<i32>, bool) {
    if bytes.starts_with(b"AutoCAD Binary DXF") {
        // binary DXF always has handles; its units come from the parser
        return (None, true);
    }
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(64 << 20)]);
    let mut lines = text.lines().map(str::trim);
    let (mut units, mut handles, mut in_entities) = (None, false, false);
    let mut prev: Option<(i32, String)> = None;
    while let (Some(code), Some(value)) = (lines.next(), lines.next()) {
        let Ok(code) = code.parse::<i32>() else { break };
        if code == 0 {
            in_entities = in_entities && value != "ENDSEC";
        }
        if code == 2 && value == "ENTITIES" {
            in_entities = true;
        }
        if in_entities && code == 5 {
            handles = true;
        }
        if code == 70 && matches!(&prev, Some((9, v)) if v == "$INSUNITS") {
            units = value.parse().ok();
        }
        prev = Some((code, value.to_string()));
    }
    (units, handles)
}

/// ASCII DXF text without the tables other than LAYER and LTYPE; `None` when it is not
/// ASCII DXF or has no such tables to drop.
fn only_layer_tables(bytes: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(bytes).ok()?;
    let lines: Vec<&str> = text.lines().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut dropped = false;
    while i + 1 < lines.len() {
        let (code, value) = (lines[i].trim(), lines[i + 1].trim());
        let name = lines.get(i + 3).map_or("", |l| l.trim());
        if code == "0" && value == "TABLE" && !matches!(name, "LAYER" | "LTYPE") {
            // skip to the end of this table
            while i + 1 < lines.len()
                && !(lines[i].trim() == "0" && lines[i + 1].trim() == "ENDTAB")
            {
                i += 2;
            }
            i += 2;
            dropped = true;
            continue;
        }
        out.push_str(lines[i]);
        out.push('\n');
        out.push_str(lines[i + 1]);
        out.push('\n');
        i += 2;
    }
    dropped.then_some(out)
}

/// Longest parser message quoted in an error (characters, before escaping).
const PARSER_MESSAGE_CHARS: usize = 200;

/// The `dxf` crate's drawing of `bytes`, or why not in one line: its messages quote the
/// file (line breaks, binary bytes, a line of any length), so control characters are
/// escaped and the middle of a long message is cut out; and it panics on some values it cannot hold (a
/// header date such as `$TDCREATE` past the year 262143), which is an error like any other.
fn load(bytes: &[u8]) -> Result<dxf::Drawing, String> {
    let message = match quietly(|| dxf::Drawing::load(&mut std::io::Cursor::new(bytes))) {
        Ok(Ok(drawing)) => return Ok(drawing),
        Ok(Err(e)) => e.to_string(),
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            format!(
                "the parser failed on a value it cannot hold, such as a date out of range ({what})"
            )
        }
    };
    // the start and the end (where the place is), the quoted middle cut out
    Err(excerpt(&message, PARSER_MESSAGE_CHARS))
}

thread_local! {
    /// Whether this thread is in [`quietly`]: its panics are caught and reported as errors.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// `f()`, a panic in it caught, and not printed by the panic hook either (the error that
/// reports it is the one line the user sees). The hook is wrapped once for the process;
/// other threads' panics go to the hook as before.
fn quietly<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    static WRAP: std::sync::Once = std::sync::Once::new();
    WRAP.call_once(|| {
        let hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                hook(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    out
}

/// Reads a DXF file's bytes (ASCII or binary); `name` names the file in messages and
/// part ids. A file that cannot be parsed, or whose units are unknown, is an error; a
/// file that parses gives its parts, with what it could not use in `rejected` and
/// `notes`.
pub fn read_dxf(bytes: &[u8], name: &str, options: &ReadOptions) -> Result<DxfParts, DxfError> {
    let fail = |message: String| DxfError::Dxf {
        file: name.to_string(),
        message,
    };
    for (what, v) in [
        ("join tolerance", options.join_tolerance),
        ("arc tolerance", options.arc_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(fail(format!("{what} {v}: must be a positive length in mm")));
        }
    }
    let (code, handles) = prescan(bytes);
    let mut notes: Vec<Note> = Vec::new();
    let drawing = match load(bytes) {
        Ok(d) => d,
        // the dxf crate fails on some tables the reader does not need (an R12 DIMSTYLE
        // naming its arrow blocks under group code 5, as ezdxf writes it): read the file
        // again with only the LAYER and LTYPE tables
        Err(e) => {
            let why = format!("not a readable DXF file: {e}");
            let trimmed = only_layer_tables(bytes).ok_or_else(|| fail(why.clone()))?;
            let d = load(trimmed.as_bytes()).map_err(|_| fail(why))?;
            notes.push(Note {
                file: name.to_string(),
                what: format!("the DXF parser failed on a table ({e}): read with the LAYER and LTYPE tables only"),
                entities: Vec::new(),
            });
            d
        }
    };
    let file_note = |what: String| Note {
        file: name.to_string(),
        what,
        entities: Vec::new(),
    };
    let units = match options.units {
        Some(u) => u,
        None => {
            match Units::from_insunits(code.unwrap_or(drawing.header.default_drawing_units as i32))
            {
                Ok(Some(u)) => {
                    if u.mm != 1.0 {
                        notes.push(file_note(format!(
                            "drawn in {u} ($INSUNITS): scaled by {} to mm",
                            u.mm
                        )));
                    }
                    u
                }
                Ok(None) => {
                    notes.push(file_note("no drawing units ($INSUNITS 0 or none): read as mm (--units to say otherwise)".into()));
                    Units::MM
                }
                Err(why) => return Err(fail(format!("{why}: say what it is with --units"))),
            }
        }
    };
    let mut walk = source::Walk::new(&drawing, &options.layers, options.arc_tolerance, handles);
    walk.model_space(&drawing, units.mm);
    let got = walk.out;
    let refs = |srcs: &[usize]| -> Vec<EntityRef> {
        let mut v: Vec<EntityRef> = srcs
            .iter()
            .map(|&s| {
                let src = &got.sources[s];
                EntityRef {
                    layer: src.layer.clone(),
                    entity: src.entity.to_string(),
                    handle: src.handle.clone(),
                }
            })
            .collect();
        v.dedup();
        v
    };
    let note = |srcs: &[usize], what: String| Note {
        file: name.to_string(),
        what,
        entities: refs(srcs),
    };
    // the first notes: what was skipped, one per layer, entity type and reason
    let skipped_notes = got.skipped.len();
    for (map, prefix) in [(&got.skipped, "skipped"), (&got.converted, "")] {
        for ((layer, entity, why), handles) in map {
            notes.push(Note {
                file: name.to_string(),
                what: if prefix.is_empty() {
                    why.clone()
                } else {
                    format!("{prefix}: {why}")
                },
                entities: handles
                    .iter()
                    .map(|h| EntityRef {
                        layer: layer.clone(),
                        entity: entity.to_string(),
                        handle: h.clone(),
                    })
                    .collect(),
            });
        }
    }
    let chains = chain::chain(got.pieces, &got.closed, options.join_tolerance);
    for (srcs, what) in &chains.repairs {
        notes.push(note(srcs, what.clone()));
    }
    let contours: Vec<&Contour> = got
        .closed
        .iter()
        .map(|c| &c.contour)
        .chain(chains.contours.iter().map(|c| &c.contour))
        .collect();
    let (attached, open) = parts::open_runs(chains.open, &contours, options.join_tolerance);
    for o in &attached {
        notes.push(note(
            &o.srcs,
            "lines that end on contours without closing (bend, construction or title-block lines?): not cut".into(),
        ));
    }
    let bad = |srcs: &[usize], reason: String| DxfError::BadPart {
        file: name.to_string(),
        entities: entity_list(&refs(srcs))
            .trim_start_matches(": ")
            .to_string(),
        reason,
    };
    // an entity skipped on the layer of an open contour may be what closed it (a SPLINE
    // that could not be read): the reason says so
    let skipped_on = |srcs: &[usize]| -> String {
        let layers: Vec<&str> = srcs
            .iter()
            .map(|&s| got.sources[s].layer.as_str())
            .collect();
        let near: Vec<Note> = notes[..skipped_notes]
            .iter()
            .filter(|n| {
                n.entities
                    .iter()
                    .any(|e| layers.contains(&e.layer.as_str()))
            })
            .cloned()
            .collect();
        if near.is_empty() {
            String::new()
        } else {
            format!(
                "; an entity skipped on its layer may have closed it ({} note{}{})",
                near.len(),
                if near.len() == 1 { "" } else { "s" },
                first_notes(&near)
            )
        }
    };
    let mut rejected: Vec<DxfError> = open
        .into_iter()
        .map(|(srcs, reason)| {
            let why = skipped_on(&srcs);
            bad(&srcs, reason + &why)
        })
        .collect();
    let cands = parts::candidates(got.closed, chains.contours);
    let mut found = parts::classify(cands, &got.texts, options.join_tolerance, options.islands);
    for (srcs, what) in &found.rejected {
        rejected.push(bad(srcs, what.clone()));
    }
    if !got.zero.is_empty() {
        rejected.push(bad(&got.zero, "zero size".into()));
    }
    if found.parts.is_empty() && rejected.is_empty() {
        rejected.push(DxfError::Dxf {
            file: name.to_string(),
            message: format!(
                "no closed contours to cut ({} notes on what was skipped{})",
                notes.len(),
                first_notes(&notes)
            ),
        });
    }
    let etch = parts::etch_of(&found.parts, got.etch, &mut found.notes);
    for (srcs, what) in &found.notes {
        notes.push(note(srcs, what.clone()));
    }
    let count = found.parts.len();
    let parts = found
        .parts
        .into_iter()
        .zip(etch)
        .enumerate()
        .map(|(k, ((outer, holes, _), etch))| DxfPart {
            id: if count == 1 {
                name.to_string()
            } else {
                format!("{name}#{}", k + 1)
            },
            outer,
            holes,
            etch,
        })
        .collect();
    Ok(DxfParts {
        parts,
        rejected,
        notes,
    })
}
