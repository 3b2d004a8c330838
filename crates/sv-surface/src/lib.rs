//! Stage 1 of Spin-Valence: a target surface becomes the secondary (hub) quad mesh of
//! paper sec. 3.1, with planar, nearly square faces and conical vertices, close to the
//! target and with its boundary on the target boundary.
//!
//! Core items:
//! - [`TargetMesh`]: the design surface (triangles, mm, Z up), [`TargetMesh::validate`];
//! - [`builtin_target`]: `flat`, `vault`, `dome`, `saddle`, `pavilion` (the default);
//! - [`initial_grid`]: a quad grid at the unit size whose outer ring follows the boundary
//!   and whose lattice follows the conformal map of the target onto a rectangle;
//! - [`optimise`]: guided projection (Gauss-Newton with auxiliary face normals);
//! - [`build_secondary`]: both in one call, returning the mesh and a [`SecondaryReport`];
//! - [`layout_mesh`], [`build_secondary_with_layout`]: the designer's coarse quad layout
//!   (irregular vertices where the designer wants them) subdivided to the unit size;
//! - [`TargetIndex`]: closest points on the target and its boundary loops;
//!   [`measure_hub_mesh`]: the goals of a hub mesh on a target.
//!
//! ```
//! use sv_surface::{build_secondary, builtin_target, SecondaryOptions};
//! let target = builtin_target("saddle").unwrap();
//! let opts = SecondaryOptions { unit_size: 500.0, ..Default::default() };
//! let (mesh, report) = build_secondary(&target, &opts, &mut |_, _| {}).unwrap();
//! assert_eq!(mesh.faces.len(), report.faces);
//! assert!(report.planarity_max < 0.01);
//! ```

mod anchors;
mod auto_layout;
mod builtin;
mod cell_layout;
mod cross_field;
mod error;
mod layout;
mod optimise;
mod options;
mod param;
mod report;
mod target;
mod topology;
mod triangle_layout;

pub use anchors::TargetSurface;
pub use builtin::{builtin_target, BUILTIN_NAMES, DEFAULT_BUILTIN};
pub use cross_field::{cross_field, CrossField, DEFAULT_ALIGNMENT};
pub use error::SurfaceError;
pub use layout::layout_mesh;
pub use optimise::optimise;
pub use options::SecondaryOptions;
pub use param::initial_grid;
pub use report::{measure_hub_mesh, Goals, SecondaryReport, EDGE_RATIO_LIMIT};
pub use target::{BoundaryPoint, ClosestPoint, TargetIndex, TargetMesh};

use sv_frame::QuadMesh;

/// Target surface to optimised hub mesh: [`initial_grid`] then [`optimise`], validating the
/// target once. `progress(iteration, energy)` is called after every iteration.
pub fn build_secondary(
    target: &TargetMesh,
    opts: &SecondaryOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(QuadMesh, SecondaryReport), SurfaceError> {
    opts.check()?;
    let index = target::TargetIndex::new(target)?;
    let (initial, layout) = param::initial_mesh_indexed(&index, opts)?;
    let (mesh, mut report) =
        optimise::optimise_indexed(&index, initial, opts, optimise::Pins::Corners, progress)?;
    report.layout = layout;
    Ok((mesh, report))
}

/// Target surface and the designer's coarse quad layout to optimised hub mesh:
/// [`layout_mesh`] (subdivided to the unit size, the layout's irregular vertices kept)
/// then [`optimise`].
pub fn build_secondary_with_layout(
    target: &TargetMesh,
    layout: &QuadMesh,
    opts: &SecondaryOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(QuadMesh, SecondaryReport), SurfaceError> {
    opts.check()?;
    let index = target::TargetIndex::new(target)?;
    let mesh = layout::layout_mesh_indexed(&index, layout, opts)?;
    let (mesh, mut report) = optimise::optimise_indexed(
        &index,
        mesh,
        opts,
        optimise::Pins::CornersAndIrregular,
        progress,
    )?;
    report.layout = format!(
        "the designer's layout ({} coarse faces)",
        layout.faces.len()
    );
    Ok((mesh, report))
}
