//! Parts to nest: an outline and its holes as [`Contour`]s (the workspace's one arc
//! contour, `sv_geom`), outline validation and placements that keep arcs as arcs.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
pub use sv_geom::planar::{bbox, point_in_polygon, polygon_area, segments_intersect};
pub use sv_geom::{Contour, Vertex};

use crate::NestError;

/// Default chord tolerance (mm) used to flatten arcs for collision detection.
///
/// The flattened outline is grown by this amount before nesting, so a coarser tolerance is
/// still safe (never closer than the spacing) but wastes a little sheet.
pub const DEFAULT_FLATTEN_TOLERANCE: f64 = 0.05;

/// A list looked up by id in one step (the placements of a report name their parts by
/// id); where ids repeat, the first item with the id.
pub struct ById<'a, T> {
    items: &'a [T],
    index: HashMap<&'a str, usize>,
}

impl<'a, T> ById<'a, T> {
    /// `items` by the id `id` gives each.
    pub fn new(items: &'a [T], id: impl Fn(&'a T) -> &'a str) -> Self {
        let mut index = HashMap::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            index.entry(id(item)).or_insert(i);
        }
        Self { items, index }
    }

    /// Where the first item with `id` is in the list.
    pub fn position(&self, id: &str) -> Option<usize> {
        self.index.get(id).copied()
    }

    /// The first item with `id`.
    pub fn get(&self, id: &str) -> Option<&'a T> {
        self.position(id).map(|i| &self.items[i])
    }
}

/// A part to nest: an outer contour, inner cut-outs and an identifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Part {
    /// identifier reported back in placements (`strip` in `nest.json`)
    pub id: String,
    /// outside contour
    pub outer: Contour,
    /// inside contours (holes); kept for output, ignored for nesting
    #[serde(default)]
    pub holes: Vec<Contour>,
}

impl Part {
    /// A part without holes.
    pub fn new(id: impl Into<String>, outer: Contour) -> Self {
        Self {
            id: id.into(),
            outer,
            holes: Vec::new(),
        }
    }

    /// The part moved by a placement: rotate about the origin of its own coordinates, then
    /// translate. Holes follow the outer contour.
    pub fn transformed(&self, rotation_deg: f64, translation: [f64; 2]) -> Self {
        Self {
            id: self.id.clone(),
            outer: self.outer.transformed(rotation_deg, translation),
            holes: self
                .holes
                .iter()
                .map(|h| h.transformed(rotation_deg, translation))
                .collect(),
        }
    }

    /// Validates the outer contour as the nesting does (finite, at least three distinct
    /// points, positive area, no self-intersection, within cavalier's tolerance) and
    /// flattens it within `tolerance`: a counter-clockwise polygon.
    pub fn validated_outline(&self, tolerance: f64) -> Result<Vec<[f64; 2]>, NestError> {
        crate::shape::outline(&self.outer).map_err(|reason| NestError::BadPart {
            part: self.id.clone(),
            reason,
        })?;
        let mut pts = self.outer.flatten(tolerance);
        dedup_points(&mut pts);
        if polygon_area(&pts) < 0.0 {
            pts.reverse();
        }
        Ok(pts)
    }
}

/// Removes consecutive duplicates (and a closing duplicate).
pub(crate) fn dedup_points(pts: &mut Vec<[f64; 2]>) {
    pts.dedup_by(|a, b| (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
    while pts.len() > 1 {
        let (f, l) = (pts[0], pts[pts.len() - 1]);
        if (f[0] - l[0]).abs() < 1e-9 && (f[1] - l[1]).abs() < 1e-9 {
            pts.pop();
        } else {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bowtie_is_rejected() {
        let p = Part::new(
            "bow",
            Contour::polygon(&[[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 10.0]]),
        );
        let err = p.validated_outline(0.1).unwrap_err().to_string();
        assert!(
            err.contains("bow") && err.contains("self-intersecting"),
            "{err}"
        );
    }

    #[test]
    fn placements_keep_bulges_and_move_the_holes() {
        let mut p = Part::new("disc", Contour::circle(5.0, 0.0, 1.0));
        p.holes.push(Contour::circle(5.0, 0.0, 0.5));
        let t = p.transformed(90.0, [1.0, 2.0]);
        let (o, h) = (t.outer.vertices[0], t.holes[0].vertices[0]);
        assert!((o.x - 1.0).abs() < 1e-12 && (o.y - 8.0).abs() < 1e-12);
        assert!((h.x - 1.0).abs() < 1e-12 && (h.y - 7.5).abs() < 1e-12);
        assert_eq!((o.bulge, h.bulge), (1.0, 1.0));
        assert_eq!(t.id, "disc");
    }
}
