//! The farthest coordinate the surface readers (target, layout) accept.

use sv_geom::Point3;

use crate::text::real;
use crate::IoError;

/// Farthest a surface's coordinate may be from the origin (mm): a million km, room for
/// site coordinates (a UTM northing is 5e9 mm) at a float resolution of 0.1 um. Beyond it
/// the size and areas of the surface overflow (a vertex at 1e308 made the target's
/// zero-area check pass on NaN, and a layout fail later as "initial face 0 is flipped").
const MAX_COORDINATE: f64 = 1e12;

/// `p` of file `name`, called `what` in the message (`vertex 3`), if it is within
/// [`MAX_COORDINATE`] of the origin on every axis; otherwise the error naming it.
pub(crate) fn within_reach(
    name: &str,
    p: &Point3,
    what: impl FnOnce() -> String,
) -> Result<(), IoError> {
    if p.iter().all(|x| x.abs() <= MAX_COORDINATE) {
        return Ok(());
    }
    Err(IoError::whole(
        name,
        format!(
            "{} at ({}, {}, {}) is farther than {MAX_COORDINATE:e} mm from the origin (a corrupt number, or not in mm?)",
            what(),
            real(p.x),
            real(p.y),
            real(p.z)
        ),
    ))
}
