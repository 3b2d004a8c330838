//! The unit every face deploys: the unit as cut (four legs pinned at the necks of its cut,
//! [`sv_unit::Linkage`]) or, without cut widths, the paper's zero-width unit (closed form).
//! The solve, the figures and the frame file all read the units through this one type.

use sv_geom::{Point2, Point3, Real, Vector3};
use sv_unit::{CornerJacobian, CutWidths, Deployment, Linkage, UnitError, UnitLayout};

use crate::{FrameError, Hub};

/// The units of a frame, one per hub.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameUnits {
    /// Expansion of the tiles about their centroids (the whole cut scales with it).
    expansion: Real,
    /// Per unit: the legs as cut, or `None` for the zero-width unit.
    legs: Option<Vec<Linkage>>,
    /// Per unit: the hub plate as cut, in the hub's frame.
    hub_plates: Vec<[Point3; 4]>,
}

impl FrameUnits {
    /// The units of `hubs`: as cut with `cut`, else zero-width.
    pub fn new(hubs: &[Hub], expansion: Real, cut: Option<&CutWidths>) -> Result<Self, FrameError> {
        let Some(w) = cut else {
            return Ok(Self {
                expansion,
                legs: None,
                hub_plates: hubs
                    .iter()
                    .map(|h| h.rhombus.corners().map(Point3::from))
                    .collect(),
            });
        };
        let mut legs = Vec::with_capacity(hubs.len());
        let mut hub_plates = Vec::with_capacity(hubs.len());
        for (f, hub) in hubs.iter().enumerate() {
            let tile = hub
                .rhombus
                .corners()
                .map(|c| Point2::new(c.x * expansion, c.y * expansion));
            let layout =
                UnitLayout::new(&tile, w).map_err(|e| FrameError::Cut { unit: f, why: e.0 })?;
            legs.push(Linkage::new(&layout.pins()));
            hub_plates.push(layout.hub.map(|p| Point3::new(p.x, p.y, 0.0)));
        }
        Ok(Self {
            expansion,
            legs: Some(legs),
            hub_plates,
        })
    }

    /// True for units as cut.
    pub fn as_cut(&self) -> bool {
        self.legs.is_some()
    }

    /// The expansion of the tiles.
    pub fn expansion(&self) -> Real {
        self.expansion
    }

    /// The legs of unit `f` (zero-width legs for the paper's unit).
    pub fn legs(&self, f: usize, hub: &Hub) -> Linkage {
        match &self.legs {
            Some(l) => l[f],
            None => Linkage::zero_width(&hub.rhombus),
        }
    }

    /// The pose `(R, P)` of unit `f` at `dep` (hub plate's points `x` at `R x + P` in the
    /// primary plate's frame).
    pub fn pose(
        &self,
        f: usize,
        hub: &Hub,
        dep: &Deployment,
    ) -> Result<(sv_geom::Matrix3, Vector3), UnitError> {
        match &self.legs {
            Some(l) => l[f].pose(&hub.rhombus, dep),
            None => sv_unit::deploy(&hub.rhombus, dep).map(|d| (d.rotation, d.translation)),
        }
    }

    /// Primary corners (tile scaled by the expansion) of unit `f` in the hub's frame, with
    /// their derivatives along `theta` and `phi`.
    pub fn primary_in_hub_frame(
        &self,
        f: usize,
        hub: &Hub,
        dep: &Deployment,
    ) -> Result<CornerJacobian, UnitError> {
        match &self.legs {
            Some(l) => l[f].primary_in_hub_frame(&hub.rhombus, dep, self.expansion),
            None => sv_unit::primary_in_hub_frame(&hub.rhombus, dep, self.expansion),
        }
    }

    /// Corners of unit `f`'s tile scaled by `scale` about its centroid, in the world.
    pub fn primary_world(
        &self,
        f: usize,
        hub: &Hub,
        dep: &Deployment,
        scale: Real,
    ) -> Result<[Point3; 4], UnitError> {
        let (r, p) = self.pose(f, hub, dep)?;
        let rt = r.transpose();
        Ok(hub
            .rhombus
            .corners()
            .map(|c| hub.to_world(&Point3::from(rt * (c * scale - p)))))
    }

    /// Unit `f`'s hub plate as cut, in the world.
    pub fn hub_plate(&self, f: usize, hub: &Hub) -> [Point3; 4] {
        self.hub_plates[f].map(|p| hub.to_world(&p))
    }

    /// Leg `j`'s two pins of unit `f` in the world at `dep`: `(on the hub, on the rim)`.
    pub fn pins_world(
        &self,
        f: usize,
        hub: &Hub,
        dep: &Deployment,
    ) -> Result<([Point3; 4], [Point3; 4]), UnitError> {
        let legs = self.legs(f, hub);
        let (r, p) = self.pose(f, hub, dep)?;
        let rt = r.transpose();
        Ok((
            legs.hub.map(|h| hub.to_world(&Point3::from(h))),
            legs.rim.map(|y| hub.to_world(&Point3::from(rt * (y - p)))),
        ))
    }
}
