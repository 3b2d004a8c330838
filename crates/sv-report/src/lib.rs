//! The build report: what a designer or fabricator looks at and sends around.
//!
//! Pure: data in, strings out; no files, no printing. `spinvalence build` writes the
//! strings to `DIR/report.html` and `DIR/bom.csv`.
//!
//! - [`report_html`]: one self-contained HTML page (no network, opens from `file://`): a
//!   summary with definitions, the 3D view of the frame (`sv-viewer`, the same module as the
//!   AR client) coloured by gap, hub overlap or strip with a unit panel on click, inline SVG
//!   plots (gap and overlap histograms, planarity and conical residuals, theta and depth
//!   across the surface), the nested sheets with their utilisation, and the strips table.
//! - [`bom_csv`]: the bill of materials, one row per strip ([`BOM_COLUMNS`]).
//! - [`Summary`]: the figures of the summary table (units, strips, sheets, steel area and
//!   weight, cut length, pierces, welds), defined in `docs/report.md`.
//! - [`ReportInput`] / [`NestInput`]: what the report is made of; [`ReportError`] when the
//!   pieces do not belong together.
//!
//! ```
//! use sv_frame::{solve, QuadMesh, SolveOptions};
//! use sv_strips::{profile_strip, unit_labels, unroll, apply_labels, ProfileParams, StripOptions, StripsFile};
//! let mesh = QuadMesh::grid(3, 2, 300.0);
//! let mut frame = solve(&mesh, &SolveOptions::default(), &mut |_| {}).unwrap().to_frame_file(&mesh);
//! let strips = unroll(&frame, &StripOptions::default()).unwrap();
//! apply_labels(&mut frame, &strips);
//! let params = ProfileParams::default();
//! let profiles: Vec<_> = strips
//!     .iter()
//!     .map(|s| {
//!         let names: Vec<String> = s.units.iter().map(|&u| frame.units[u].id.clone()).collect();
//!         profile_strip(s, &names, &params).unwrap()
//!     })
//!     .collect();
//! let file = StripsFile::new(&strips, &profiles, &params, 1.0, &StripOptions::default());
//! let input = sv_report::ReportInput {
//!     target: "grid 3 x 2", generator: "doc test", frame: &frame, strips: &file,
//!     nest: None, hub_mesh: None, fold_check: None,
//! };
//! let summary = sv_report::Summary::of(&input);
//! assert_eq!((summary.units, summary.strips, summary.sheets), (6, 2, None));
//! // 7 interior edges: every one a hub weld, the 3 between the two strips primary welds too
//! assert_eq!((summary.hub_welds, summary.primary_welds, summary.welds), (7, 3, 10));
//! let html = sv_report::report_html(&input).unwrap();
//! assert!(html.contains("createFrameView") && html.contains("No nesting data"));
//! let csv = sv_report::bom_csv(&input).unwrap();
//! assert_eq!(csv.lines().count(), 3);
//! ```

mod bom;
mod error;
mod html;
mod input;
pub mod plot;
mod sheets;
mod summary;

pub use bom::{bom_csv, csv_field, BOM_COLUMNS};
pub use error::ReportError;
pub use html::{report_html, CONTENT_SECURITY_POLICY, VIEW_BACKGROUND};
pub use input::{NestInput, Placement, ReportInput};
pub use summary::{strip_cut_length, strip_hub_face, strip_pierces, Summary, STEEL_DENSITY};
