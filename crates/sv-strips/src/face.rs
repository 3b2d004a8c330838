//! Which face of the flat part a unit's hub comes out of, and the mark etched for it.
//!
//! A strip DXF shows its part seen from `+z`, the face the torch etches. A unit's cut spins
//! one way: pushed out of the other face its hub deploys the mirror way, which no cut can
//! fix (a mirrored cut spins the other way), so every part says which face.

use serde::{Deserialize, Serialize};
use sv_geom::{Point3, Vector3};

/// The face of the flat part a hub comes out of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HubFace {
    /// The etched face (`+z` of the strip and sheet DXFs, seen in them): the hub comes out
    /// towards whoever reads the etching. Marked by a circle with a dot.
    Etched,
    /// The back (un-etched) face: the hub goes away from whoever reads the etching. Marked
    /// by a circle with a cross.
    Back,
}

impl HubFace {
    /// `etched` or `back`, as in `strips.json` and `bom.csv`.
    pub fn name(self) -> &'static str {
        match self {
            HubFace::Etched => "etched",
            HubFace::Back => "back",
        }
    }
}

/// The normal of a planar quad (unit length): `(q2 - q0) x (q3 - q1)`. The quad is
/// counter-clockwise about it, so a quad laid flat counter-clockwise has it as `+z`.
pub(crate) fn quad_normal(q: &[Point3; 4]) -> Vector3 {
    (q[2] - q[0]).cross(&(q[3] - q[1])).normalize()
}

/// The face the hub comes out of when the primary tile `primary` (frame corner order) is
/// laid flat counter-clockwise (as [`crate::unroll`] lays it: its normal
/// `(r2 - r0) x (r3 - r1)` becomes `+z`, the etched face): the side of the tile's plane
/// the hub's centre lies on. `None` when the hub lies in that plane (within 1e-6 mm).
pub fn hub_face(primary: &[Point3; 4], hub: &[Point3; 4]) -> Option<HubFace> {
    let centre = |q: &[Point3; 4]| q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 4.0;
    let height = (centre(hub) - centre(primary)).dot(&quad_normal(primary));
    if !height.is_finite() || height.abs() < 1e-6 {
        None
    } else if height > 0.0 {
        Some(HubFace::Etched)
    } else {
        Some(HubFace::Back)
    }
}

/// The mark etched on a unit's hub plate for its [`HubFace`]: a circle of `radius` about
/// `at` (strip frame, mm), with a dot (towards you: the hub comes out of the etched face)
/// or a cross (away from you: out of the back), the engineering convention for an arrow
/// seen from its tip or its tail.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FaceMark {
    /// Centre of the circle (mm).
    pub at: [f64; 2],
    /// Radius of the circle (mm).
    pub radius: f64,
    /// The face the hub comes out of.
    pub face: HubFace,
}

impl FaceMark {
    /// Radius of the dot, as a share of the circle's.
    pub const DOT: f64 = 0.2;
    /// Half length of a bar of the cross, as a share of the circle's radius.
    pub const CROSS: f64 = 0.8;
    /// Segments of the circle (chord error 0.2 % of the radius).
    pub const SEGMENTS: usize = 48;

    /// The mark as open polylines (closed rings repeat their first point): the circle,
    /// then the dot (a small ring) or the cross (two bars at 45 degrees to the axes).
    pub fn strokes(&self) -> Vec<Vec<[f64; 2]>> {
        let [x, y] = self.at;
        let ring = |r: f64| -> Vec<[f64; 2]> {
            // the last point is the first, exactly
            (0..=Self::SEGMENTS)
                .map(|i| {
                    let a =
                        std::f64::consts::TAU * (i % Self::SEGMENTS) as f64 / Self::SEGMENTS as f64;
                    [x + r * a.cos(), y + r * a.sin()]
                })
                .collect()
        };
        let mut out = vec![ring(self.radius)];
        match self.face {
            HubFace::Etched => out.push(ring(Self::DOT * self.radius)),
            HubFace::Back => {
                let d = Self::CROSS * self.radius / 2f64.sqrt();
                out.push(vec![[x - d, y - d], [x + d, y + d]]);
                out.push(vec![[x - d, y + d], [x + d, y - d]]);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: f64) -> [Point3; 4] {
        [
            Point3::new(150.0, 0.0, z),
            Point3::new(0.0, 150.0, z),
            Point3::new(-150.0, 0.0, z),
            Point3::new(0.0, -150.0, z),
        ]
    }

    #[test]
    fn the_hub_comes_out_of_the_face_its_centre_lies_on() {
        // counter-clockwise about +z: laid flat, +z is the etched face
        let primary = square(0.0);
        assert_eq!(hub_face(&primary, &square(200.0)), Some(HubFace::Etched));
        assert_eq!(hub_face(&primary, &square(-200.0)), Some(HubFace::Back));
        // the same tile listed the other way round is laid flat turned over
        let mut reversed = primary;
        reversed.reverse();
        assert_eq!(hub_face(&reversed, &square(200.0)), Some(HubFace::Back));
        // a hub tilted and moved sideways still counts by its centre's side
        let hub = square(50.0).map(|p| Point3::new(p.x + 400.0, p.y, p.z + 0.01 * p.x));
        assert_eq!(hub_face(&primary, &hub), Some(HubFace::Etched));
        // in the plane: no face
        assert_eq!(hub_face(&primary, &square(1e-9)), None);
        assert_eq!(HubFace::Etched.name(), "etched");
        assert_eq!(
            serde_json::to_string(&HubFace::Back).unwrap(),
            "\"back\"".to_string()
        );
    }

    #[test]
    fn the_mark_is_a_circle_with_a_dot_or_a_cross() {
        let mark = |face| FaceMark {
            at: [10.0, 20.0],
            radius: 12.0,
            face,
        };
        let dist = |p: [f64; 2]| (p[0] - 10.0).hypot(p[1] - 20.0);
        let dot = mark(HubFace::Etched).strokes();
        assert_eq!(dot.len(), 2);
        for (s, r) in dot.iter().zip([12.0, 12.0 * FaceMark::DOT]) {
            assert_eq!(s.len(), FaceMark::SEGMENTS + 1);
            assert_eq!(s.first(), s.last());
            assert!(s.iter().all(|&p| (dist(p) - r).abs() < 1e-9));
        }
        let cross = mark(HubFace::Back).strokes();
        assert_eq!(cross.len(), 3);
        assert!(cross[0].iter().all(|&p| (dist(p) - 12.0).abs() < 1e-9));
        for bar in &cross[1..] {
            // two points, inside the circle, through its centre
            assert_eq!(bar.len(), 2);
            assert!(bar.iter().all(|&p| (dist(p) - 9.6).abs() < 1e-9));
            let mid = [(bar[0][0] + bar[1][0]) / 2.0, (bar[0][1] + bar[1][1]) / 2.0];
            assert!(dist(mid) < 1e-9);
        }
    }
}
