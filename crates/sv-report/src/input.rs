//! What the report is made from.

use std::collections::HashMap;

use sv_frame::{CheckReport, FrameFile};
use sv_nest::{ById, NestReport};
use sv_strips::{StripRecord, StripsFile};
use sv_surface::SecondaryReport;

use crate::ReportError;

/// Everything a build produced that the report shows. Borrowed: the report copies nothing
/// it does not draw.
#[derive(Clone, Copy, Debug)]
pub struct ReportInput<'a> {
    /// What was built (`builtin:pavilion`, a file name): the page title.
    pub target: &'a str,
    /// Who made it (`spinvalence 0.1.0`), for the footer.
    pub generator: &'a str,
    /// The deployed, labelled frame (`frame.json`).
    pub frame: &'a FrameFile,
    /// The strips and their cut profiles (`strips.json`).
    pub strips: &'a StripsFile,
    /// The sheets, when the build nested the strips.
    pub nest: Option<NestInput<'a>>,
    /// Hub mesh quality against the target (`report.json`), when known.
    pub hub_mesh: Option<&'a SecondaryReport>,
    /// The fold check of the parts as cut (`spinvalence check DIR`), when it was run.
    pub fold_check: Option<&'a CheckReport>,
}

/// The nesting results: `nest.json` and the file of every sheet.
#[derive(Clone, Copy, Debug)]
pub struct NestInput<'a> {
    /// `nest.json`.
    pub report: &'a NestReport,
    /// The file name of each sheet's drawing, as the build wrote it (e.g.
    /// `sheets/sheet-01.dxf`), in sheet order; may be shorter than the sheets (then the
    /// sheet number stands alone).
    pub sheet_files: &'a [String],
}

/// Where one strip is on the sheets: `p_sheet = R(rotation_deg) p_strip + translation`,
/// `p_strip` in the strip's own drawing frame (`strips.json`, `strips/<id>.dxf`).
#[derive(Clone, Debug, PartialEq)]
pub struct Placement {
    /// Sheet number, 1-based.
    pub sheet: usize,
    /// Translation (mm).
    pub translation: [f64; 2],
    /// Rotation about the strip drawing's origin (degrees, counter-clockwise).
    pub rotation_deg: f64,
}

impl<'a> ReportInput<'a> {
    /// The strips by id (the placements name them).
    pub fn strips_by_id(&self) -> ById<'a, StripRecord> {
        ById::new(&self.strips.strips, |s| &s.id)
    }

    /// Check that the inputs belong together: every unit a strip or link names exists,
    /// every placed part is a strip, placed once.
    pub fn validate(&self) -> Result<(), ReportError> {
        let units = self.frame.units.len();
        let vertices = self.frame.mesh.vertices.len();
        for (face, f) in self.frame.mesh.faces.iter().enumerate() {
            if let Some(&vertex) = f.iter().find(|&&v| v >= vertices) {
                return Err(ReportError::BadFace {
                    face,
                    vertex,
                    vertices,
                });
            }
        }
        for s in &self.strips.strips {
            if let Some(&unit) = s.units.iter().find(|&&u| u >= units) {
                return Err(ReportError::UnknownUnit {
                    strip: s.id.clone(),
                    unit,
                    units,
                });
            }
        }
        for (link, l) in self.frame.links.iter().enumerate() {
            if let Some(&unit) = l.units.iter().find(|&&u| u >= units) {
                return Err(ReportError::UnknownLinkUnit { link, unit, units });
            }
        }
        self.placements().map(|_| ())
    }

    /// Every placed strip's [`Placement`], by strip id; empty without nesting.
    pub fn placements(&self) -> Result<HashMap<&str, Placement>, ReportError> {
        let mut out: HashMap<&str, Placement> = HashMap::new();
        let Some(nest) = self.nest else {
            return Ok(out);
        };
        let strips = self.strips_by_id();
        for (i, sheet) in nest.report.sheets.iter().enumerate() {
            for p in &sheet.placements {
                let Some(strip) = strips.get(&p.strip) else {
                    return Err(ReportError::UnknownPart {
                        sheet: i + 1,
                        part: p.strip.clone(),
                    });
                };
                if let Some(first) = out.get(strip.id.as_str()) {
                    return Err(ReportError::PlacedTwice {
                        strip: strip.id.clone(),
                        first: first.sheet,
                        second: i + 1,
                    });
                }
                out.insert(
                    strip.id.as_str(),
                    Placement {
                        sheet: i + 1,
                        translation: p.translation,
                        rotation_deg: p.rotation_deg,
                    },
                );
            }
        }
        Ok(out)
    }

    /// The file name of sheet `sheet` (1-based), or its number when no file is known.
    pub fn sheet_name(&self, sheet: usize) -> String {
        self.nest
            .and_then(|n| n.sheet_files.get(sheet - 1))
            .cloned()
            .unwrap_or_else(|| sheet.to_string())
    }
}
