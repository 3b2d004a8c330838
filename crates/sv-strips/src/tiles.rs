//! The input of the strip stage, read from a frame: expanded primary tiles and which unit
//! faces which across each side.

use sv_frame::FrameFile;
use sv_geom::{Point3, Vector3};

use crate::{hub_face, HubFace, StripsError};

/// Expanded primary tiles of a frame and their neighbours.
#[derive(Clone, Debug, PartialEq)]
pub struct TileSet {
    /// Per unit: the primary corners `r_i` scaled by the frame's expansion about their
    /// centroid (mm, world frame, frame corner order).
    pub tiles: Vec<[Point3; 4]>,
    /// Per unit and side `k`: the unit across that side and its own side index facing back.
    pub across: Vec<[Option<(usize, usize)>; 4]>,
    /// Per unit: the face of its flat tile the hub comes out of ([`hub_face`]).
    pub hub_faces: Vec<HubFace>,
    /// Per unit and side: the frame's joint there (`links[].joint`: a bridge or a weld, and
    /// where along the side), when the frame's joints were closed. Strips then run exactly
    /// through the bridges, each pinned where the frame put it.
    pub joints: Vec<[Option<SideJoint>; 4]>,
}

/// A joint seen from one side of a unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideJoint {
    /// True for a bridge (the two units are one piece).
    pub bridge: bool,
    /// Where along this side (0 at corner `k`, 1 at `k + 1`).
    pub along: f64,
}

impl TileSet {
    /// Read the tiles of a frame file. Links without `slots` get them from the mesh faces.
    pub fn from_frame(frame: &FrameFile) -> Result<Self, StripsError> {
        let e = frame.params.expansion;
        if !(e.is_finite() && e >= 1.0) {
            return Err(StripsError::Frame {
                why: format!("params.expansion = {e} must be a finite number >= 1"),
            });
        }
        let mut tiles = Vec::with_capacity(frame.units.len());
        let mut hub_faces = Vec::with_capacity(frame.units.len());
        for (u, rec) in frame.units.iter().enumerate() {
            let p: [Point3; 4] = rec.primary.map(|c| Point3::new(c[0], c[1], c[2]));
            if p.iter().any(|q| !q.coords.iter().all(|x| x.is_finite())) {
                return Err(StripsError::Frame {
                    why: format!("unit {u} has a non-finite primary corner"),
                });
            }
            let c = p.iter().fold(Vector3::zeros(), |a, q| a + q.coords) / 4.0;
            let t = p.map(|q| Point3::from(c + (q.coords - c) * e));
            let n = (t[2] - t[0]).cross(&(t[3] - t[1]));
            if n.norm() <= 1e-9 * (t[2] - t[0]).norm_squared().max(1e-300) {
                return Err(StripsError::Frame {
                    why: format!("unit {u} has a degenerate primary tile"),
                });
            }
            let hub = rec.hub.map(|c| Point3::new(c[0], c[1], c[2]));
            hub_faces.push(hub_face(&t, &hub).ok_or_else(|| StripsError::Frame {
                why: format!(
                    "unit {u}: its hub lies in the plane of its primary tile, so it comes out \
                     of neither face"
                ),
            })?);
            tiles.push(t);
        }
        let n = tiles.len();
        let mut across = vec![[None; 4]; n];
        let mut joints = vec![[None; 4]; n];
        for (li, l) in frame.links.iter().enumerate() {
            let [f, g] = l.units;
            if f >= n || g >= n || f == g {
                return Err(StripsError::Frame {
                    why: format!("link {li} refers to units {f}, {g} of {n}"),
                });
            }
            let [k, m] = match l.slots {
                Some(s) => s,
                None => {
                    let side_of = |u: usize, a: usize, b: usize| -> Option<usize> {
                        let face = frame.mesh.faces.get(frame.units[u].face)?;
                        (0..4).find(|&k| face[k] == a && face[(k + 1) % 4] == b)
                    };
                    let k = side_of(f, l.edge[0], l.edge[1]);
                    let m = side_of(g, l.edge[1], l.edge[0]);
                    match (k, m) {
                        (Some(k), Some(m)) => [k, m],
                        _ => {
                            return Err(StripsError::Frame {
                                why: format!(
                                    "link {li}: edge ({}, {}) is not a side of units {f} and {g}",
                                    l.edge[0], l.edge[1]
                                ),
                            })
                        }
                    }
                }
            };
            if k > 3 || m > 3 {
                return Err(StripsError::Frame {
                    why: format!("link {li} has slots ({k}, {m}) outside 0..4"),
                });
            }
            across[f][k] = Some((g, m));
            across[g][m] = Some((f, k));
            if let Some(j) = &l.joint {
                let bridge = j.kind == sv_frame::JointKind::Bridge;
                if !j.along.iter().all(|a| a.is_finite()) {
                    return Err(StripsError::Frame {
                        why: format!("link {li}: joint.along {:?} is not finite", j.along),
                    });
                }
                joints[f][k] = Some(SideJoint {
                    bridge,
                    along: j.along[0].clamp(0.0, 1.0),
                });
                joints[g][m] = Some(SideJoint {
                    bridge,
                    along: j.along[1].clamp(0.0, 1.0),
                });
            }
        }
        Ok(Self {
            tiles,
            across,
            hub_faces,
            joints,
        })
    }

    /// Number of units.
    pub fn len(&self) -> usize {
        self.tiles.len()
    }

    /// True when there are no units.
    pub fn is_empty(&self) -> bool {
        self.tiles.is_empty()
    }
}
