//! The target as the joint solve sees it (`sv_frame::Surface`): where each hub mesh vertex
//! must stay, on the target's tangent plane at its nearest target point, and a boundary
//! vertex also on the boundary's tangent line there. The solve asks again at every step, so
//! the planes follow the vertices as they move.

use sv_frame::{Anchor, QuadMesh};
use sv_geom::Point3;

use crate::{SurfaceError, TargetIndex, TargetMesh};

/// A target and which vertices of a hub mesh lie on its boundary.
pub struct TargetSurface<'a> {
    index: TargetIndex<'a>,
    boundary: Vec<bool>,
}

impl<'a> TargetSurface<'a> {
    /// The target under the hub mesh `mesh`.
    pub fn new(target: &'a TargetMesh, mesh: &QuadMesh) -> Result<Self, SurfaceError> {
        Ok(Self {
            index: TargetIndex::new(target)?,
            boundary: mesh.boundary_vertices(),
        })
    }

    /// The target's index (closest points), to measure a hub mesh on it.
    pub fn index(&self) -> &TargetIndex<'a> {
        &self.index
    }
}

impl sv_frame::Surface for TargetSurface<'_> {
    fn anchor(&self, v: usize, p: &Point3) -> Anchor {
        let c = self.index.closest(p);
        Anchor {
            point: c.point,
            normal: c.normal,
            boundary: self.boundary.get(v).copied().unwrap_or(false).then(|| {
                let b = self.index.closest_on_boundary(p);
                (b.point, b.tangent)
            }),
        }
    }
}
