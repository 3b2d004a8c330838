//! Readers and writers at the edge of Spin-Valence: the file formats, and nothing else.
//!
//! Readers take text or bytes plus a display name for messages; writers return a
//! `String`. The crate does no file system access (the CLI reads and writes files). Every
//! reader error is one line naming the file and the place ([`IoError`]), and no input
//! makes a reader panic.
//!
//! - Hub mesh and the designer's coarse layout, OBJ quads (mm, every vertex within the
//!   target's reach): [`read_quad_obj`], [`read_quad_obj_bytes`],
//!   [`read_and_validate_quad_obj`] (adds [`sv_frame::QuadMesh::validate`]),
//!   [`write_quad_obj`] (round-trips every `f64` exactly).
//! - Target surface, [`TriMesh`] from OBJ, ASCII STL or binary STL: [`read_tri_mesh`];
//!   [`read_target`] also welds, orients and checks it, naming the file's lines.
//! - `frame.json` v1 (model.md): [`frame_to_json`], [`frame_from_json`] (checks the
//!   header, shapes, finiteness and indices, naming the JSON path).
//! - The frame for Rhino as OBJ (objects `hubs`, `primary`, `legs`): [`frame_to_obj`].
//!
//! ```
//! use sv_frame::{MeshChecks, QuadMesh};
//! use sv_io::{read_and_validate_quad_obj, read_quad_obj, write_quad_obj};
//!
//! let mesh = QuadMesh::sphere_cap(4, 3, 3000.0, 300.0);
//! let text = write_quad_obj(&mesh, "sphere cap, R = 3000 mm");
//! let back = read_and_validate_quad_obj(&text, "cap.obj", &MeshChecks::default()).unwrap();
//! assert_eq!(back, mesh); // exact, bit for bit
//!
//! let err = read_quad_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n", "hubs.obj").unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "hubs.obj:4: face has 3 vertices; a quad mesh needs 4 per face"
//! );
//! ```

mod error;
mod frame_json;
mod frame_obj;
mod obj;
mod quad_obj;
mod reach;
mod stl;
mod target;
mod text;
mod tri_mesh;

pub use error::IoError;
pub use frame_json::{
    frame_from_json, frame_to_json, inline_number_arrays, FRAME_LENGTH_UNIT, FRAME_VERSION,
};
pub use frame_obj::frame_to_obj;
pub use quad_obj::{
    read_and_validate_quad_obj, read_and_validate_quad_obj_bytes, read_quad_obj,
    read_quad_obj_bytes, write_quad_obj,
};
pub use target::{read_target, TargetFile, TargetRepairs};
pub use tri_mesh::{read_tri_mesh, TriMesh, WELD_RELATIVE_TOLERANCE};
