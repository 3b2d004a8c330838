//! Fabrication file writers: DXF ASCII R2000 and SVG drawings of profiled strips. Writers
//! return `String`; the caller writes files.
//!
//! - [`strip_dxf`]: one DXF per strip, layers `OUTSIDE`, `INSIDE`, `ETCH`, `INFO`.
//! - [`sheet_dxf`]: one DXF per nested sheet, same writer and layers, pierce points in scrap.
//! - [`strip_svg`]: a drawing for the fabricator (labels, fold marks, scale bar, title).
//! - [`text_strokes`]: the built-in single-stroke font used for etched labels.
//!
//! ```
//! use sv_frame::{solve, QuadMesh, SolveOptions};
//! use sv_strips::{profile_strip, unroll, ProfileParams, StripOptions};
//! let mesh = QuadMesh::grid(3, 1, 300.0);
//! let frame = solve(&mesh, &SolveOptions::default(), &mut |_| {}).unwrap().to_frame_file(&mesh);
//! let strips = unroll(&frame, &StripOptions::default()).unwrap();
//! let params = ProfileParams::default();
//! let profile = profile_strip(&strips[0], &["A01-01".into(), "A01-02".into(), "A01-03".into()], &params).unwrap();
//! let dxf = sv_export::strip_dxf(&strips[0], &profile);
//! assert!(dxf.contains("AC1015") && dxf.contains("LWPOLYLINE"));
//! let svg = sv_export::strip_svg(&strips[0], &profile, &params);
//! assert!(svg.starts_with("<svg"));
//! ```

mod dxf;
mod font;
mod sheet;
mod svg;

pub use dxf::{etch_strokes, strip_dxf, LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};
pub use font::{has_glyph, text_strokes, text_width};
pub use sheet::{sheet_dxf, sheet_file_stem, strip_sheet_part, SheetCaption, SheetPart};
pub use svg::strip_svg;
