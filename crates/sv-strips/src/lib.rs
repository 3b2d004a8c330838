//! Strips, unrolling and rounded steel cut profiles of a Spin-Valence frame (paper sec. 4).
//!
//! Pure math, no file I/O: the writers live in `sv-export`.
//!
//! - [`unroll`]: partition the units into strips along one mesh direction
//!   ([`StripDirection`]), lay each strip's expanded primary tiles flat ([`FlatStrip`]) with
//!   consecutive tiles pinned on a common line, split where the pattern would exceed the
//!   sheet or overlap itself, and report bend and twist per [`Pin`].
//! - [`unit_labels`] / [`apply_labels`]: `A03-07` labels for frame.json `id` / `strip`.
//! - [`profile_strip`]: the cut profile ([`StripProfile`]): rounded outline with bridges,
//!   four hook slots per unit, fold marks, upright labels and face marks, as [`Contour`]s
//!   with arcs.
//! - [`hub_face`] / [`HubFace`] / [`FaceMark`]: which face of the flat part each hub comes
//!   out of (`+z`, the etched face, or the back) and the mark etched for it.
//! - [`check_profile`]: the design-rule check ([`Violation`]).
//! - [`StripsFile`]: `strips.json` v1.
//!
//! ```
//! use sv_frame::{solve, QuadMesh, SolveOptions};
//! use sv_strips::{check_profile, profile_strip, unit_labels, unroll, ProfileParams, StripOptions};
//! let params = ProfileParams::default();
//! let mesh = QuadMesh::grid(4, 2, 300.0);
//! // the units deploy as they are cut
//! let options = SolveOptions { cut: Some(params.cut_widths()), ..Default::default() };
//! let frame = solve(&mesh, &options, &mut |_| {}).unwrap().to_frame_file(&mesh);
//! let strips = unroll(&frame, &StripOptions::default()).unwrap();
//! assert_eq!(strips.len(), 2);
//! let labels = unit_labels(&strips, frame.units.len());
//! assert_eq!(labels[0].id, "A01-01");
//! let names: Vec<String> = strips[0].units.iter().map(|&u| labels[u].id.clone()).collect();
//! let profile = profile_strip(&strips[0], &names, &params).unwrap();
//! assert_eq!(profile.cuts.len(), 16);
//! assert!(check_profile(&strips[0], &profile, &params).is_empty());
//! ```

mod drc;
mod error;
mod face;
mod file;
mod fold;
mod leg_plate;
mod params;
mod plane;
mod profile;
mod relief;
mod strip;
mod tiles;

pub use drc::{check_profile, DrcRule, Violation, DRC_ARC_TOLERANCE};
pub use error::StripsError;
pub use face::{hub_face, FaceMark, HubFace};
pub use file::{FlatTile, PinRecord, StripRecord, StripsFile, StripsParams, STRIPS_FORMAT};
pub use fold::{fold_check, FoldLimits};
pub use params::{
    ProfileParams, SplitRule, StripDirection, StripOptions, BRIDGE_STRAIN, DEFAULT_SHEET_LENGTH,
    DEFAULT_SHEET_MARGIN, MIN_INSIDE_RADIUS,
};
pub use plane::convex_intersection_area;
pub use profile::{profile_strip, Label, StripProfile};
pub use relief::{add_reliefs, Relief};
pub use strip::{
    apply_labels, chains, strip_id, strip_plan, unit_labels, unroll, unroll_tiles, FlatStrip, Pin,
    StripPlan, UnitLabel,
};
/// The contours of a profile: the workspace's one arc contour (outlines counter-clockwise,
/// cuts clockwise, so the material is on the left).
pub use sv_geom::Contour;
pub use tiles::TileSet;
