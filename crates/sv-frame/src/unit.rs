//! The unit every face deploys: the unit as cut (four legs pinned at the necks of its cut,
//! [`sv_unit::Linkage`]) or, without cut widths, the paper's zero-width unit (closed form).
//! The solve, the figures and the frame file all read the units through this one type.

use sv_geom::{Matrix3, Point2, Point3, Real, Vector3};
use sv_unit::{CornerJacobian, CutWidths, Deployment, Linkage, UnitError, UnitLayout};

use crate::{FrameError, Hub};

/// Where a unit's hub sits on its primary plate: hub-frame points `x` at
/// `rotation x + translation` in the primary plate's (tile) frame, as `s = R r + P` in the
/// closed form. The translation's length is the frame depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitPose {
    /// `R`.
    pub rotation: Matrix3,
    /// `P` (mm).
    pub translation: Vector3,
}

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

    /// The pose of unit `f` at the chart point `dep`.
    pub fn pose(&self, f: usize, hub: &Hub, dep: &Deployment) -> Result<UnitPose, UnitError> {
        let (rotation, translation) = match &self.legs {
            Some(l) => l[f].pose(&hub.rhombus, dep)?,
            None => sv_unit::deploy(&hub.rhombus, dep).map(|d| (d.rotation, d.translation))?,
        };
        Ok(UnitPose {
            rotation,
            translation,
        })
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

    /// Corners of unit `f`'s tile scaled by `scale` about its centroid, in the world, with
    /// the unit at `pose`.
    pub fn primary_world(&self, hub: &Hub, pose: &UnitPose, scale: Real) -> [Point3; 4] {
        let rt = pose.rotation.transpose();
        hub.rhombus
            .corners()
            .map(|c| hub.to_world(&Point3::from(rt * (c * scale - pose.translation))))
    }

    /// Unit `f`'s hub plate as cut, in the world.
    pub fn hub_plate(&self, f: usize, hub: &Hub) -> [Point3; 4] {
        self.hub_plates[f].map(|p| hub.to_world(&p))
    }

    /// Leg `j`'s two pins of unit `f` in the world at `pose`: `(on the hub, on the rim)`.
    pub fn pins_world(&self, f: usize, hub: &Hub, pose: &UnitPose) -> ([Point3; 4], [Point3; 4]) {
        let legs = self.legs(f, hub);
        let rt = pose.rotation.transpose();
        (
            legs.hub.map(|h| hub.to_world(&Point3::from(h))),
            legs.rim
                .map(|y| hub.to_world(&Point3::from(rt * (y - pose.translation)))),
        )
    }
}
