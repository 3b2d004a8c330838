//! Fabrication drawings: what goes on the DXF and SVG of a profiled strip and of a nested
//! sheet (the DXF format itself is `sv-dxf`'s). Writers return `String`; the caller writes
//! files.
//!
//! - [`strip_dxf`]: one DXF per strip, layers `OUTSIDE`, `INSIDE`, `ETCH`, `INFO`.
//! - [`sheet_dxf`]: one DXF per nested sheet, same writer and layers, pierce points in scrap.
//! - [`strip_svg`]: a drawing for the fabricator (labels, fold marks, scale bar, title).
//! - [`sheet_svg`]: a preview of a nested sheet.
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

mod font;
mod preview;
mod sheet;
mod strip;
mod svg;

pub use font::{has_glyph, text_strokes, text_width};
pub use preview::sheet_svg;
pub use sheet::{
    sheet_dxf, sheet_file_stem, strip_sheet_part, CutDirection, EtchOrder, SheetCaption, SheetPart,
    ShopConvention,
};
pub use strip::{etch_strokes, strip_dxf};
pub use sv_dxf::{LAYER_ETCH, LAYER_INFO, LAYER_INSIDE, LAYER_OUTSIDE};
pub use svg::{path_data as svg_path_data, strip_svg};
