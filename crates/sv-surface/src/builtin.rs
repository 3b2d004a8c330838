//! Built-in parametric targets, triangulated finely (about 50 mm edges), in mm, Z up.
//!
//! | name | shape | Gaussian curvature | footprint |
//! |---|---|---|---|
//! | `flat` | plane z = 0 | zero | rectangle 4.4 x 3.2 m |
//! | `vault` | barrel vault, radius 2.5 m, axis X | zero (single curved) | rectangle 5 x 3.6 m |
//! | `dome` | sphere cap, radius 4 m | positive | square 4 x 4 m |
//! | `saddle` | z = (x^2 - y^2) / 7000 | negative | square 4 x 4 m |
//! | `pavilion` | freeform shell arched along X, waved across Y | mixed (sign changes at abs(y) = 1.1 m) | rectangle with bulging sides, 6 x 4 m |

use sv_geom::{Point3, Real};

use crate::{SurfaceError, TargetMesh};

/// Names accepted by [`builtin_target`].
pub const BUILTIN_NAMES: [&str; 5] = ["flat", "vault", "dome", "saddle", "pavilion"];

/// Superellipse exponent of the built-in footprints: 400 gives a rectangle whose corners
/// are rounded over about 0.2 % of the half-width (under 4 mm on a 2 m half-width), so
/// the boundary turns by 90 degrees at a point and the hub grid's corner faces can be
/// rhombi. (Exponent 40, rounding over 2 % or 35 mm, put the grid corner on a chamfer:
/// corner faces were kites with a 145 degree corner at 150 mm units, their rhombus fit
/// 15-19 mm, and the worst link gaps of every built-in sat next to them.)
const FOOTPRINT_EXPONENT: Real = 400.0;

/// Default built-in target (the embedded default of `spinvalence build`).
pub const DEFAULT_BUILTIN: &str = "pavilion";

/// A built-in target by name (`flat`, `vault`, `dome`, `saddle`, `pavilion`); a leading
/// `builtin:` is accepted and ignored.
pub fn builtin_target(name: &str) -> Result<TargetMesh, SurfaceError> {
    let key = name.strip_prefix("builtin:").unwrap_or(name);
    let n = 96;
    let mesh = match key {
        "flat" => footprint_mesh(n, 2200.0, 1600.0, FOOTPRINT_EXPONENT, |_| 1.0, |_, _| 0.0),
        "vault" => footprint_mesh(
            n,
            2500.0,
            1800.0,
            FOOTPRINT_EXPONENT,
            |_| 1.0,
            |_, y| {
                let r: Real = 2500.0;
                (r * r - y * y).sqrt() - r
            },
        ),
        "dome" => footprint_mesh(
            n,
            2000.0,
            2000.0,
            FOOTPRINT_EXPONENT,
            |_| 1.0,
            |x, y| {
                let r: Real = 4000.0;
                (r * r - x * x - y * y).sqrt() - r
            },
        ),
        "saddle" => footprint_mesh(
            n,
            2000.0,
            2000.0,
            FOOTPRINT_EXPONENT,
            |_| 1.0,
            |x, y| (x * x - y * y) / 7000.0,
        ),
        "pavilion" => footprint_mesh(
            n,
            3000.0,
            2000.0,
            FOOTPRINT_EXPONENT,
            |phi| 1.0 + 0.04 * (2.0 * phi).cos(),
            |x, y| {
                // arched along X, waved across Y (curvature sign changes at |y| = 1100)
                let arch = 700.0 * (1.0 - (x / 3600.0).powi(2));
                let wave = 220.0 * (std::f64::consts::PI * y / 2200.0).cos();
                arch + wave
            },
        ),
        _ => {
            return Err(SurfaceError::UnknownBuiltin {
                name: name.to_string(),
            })
        }
    };
    Ok(mesh)
}

/// Height field `z = height(x, y)` over a superellipse footprint `|x/a|^p + |y/b|^p <= 1`
/// whose radius is modulated by `wobble(polar angle)`, triangulated from an `n` x `n`
/// square grid mapped radially onto the footprint.
fn footprint_mesh(
    n: usize,
    a: Real,
    b: Real,
    p: Real,
    wobble: impl Fn(Real) -> Real,
    height: impl Fn(Real, Real) -> Real,
) -> TargetMesh {
    let mut mesh = TargetMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let s = 2.0 * i as Real / n as Real - 1.0;
            let t = 2.0 * j as Real / n as Real - 1.0;
            let r_inf = s.abs().max(t.abs());
            let r_p = (s.abs().powf(p) + t.abs().powf(p)).powf(1.0 / p);
            let k = if r_p > 0.0 { r_inf / r_p } else { 1.0 };
            let w = wobble(t.atan2(s));
            let (x, y) = (a * s * k * w, b * t * k * w);
            mesh.vertices.push(Point3::new(x, y, height(x, y)));
        }
    }
    let id = |i: usize, j: usize| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            // split along the diagonal pointing away from the centre: no sliver fans
            let outward = (i < n / 2) == (j < n / 2);
            if outward {
                mesh.triangles
                    .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                mesh.triangles
                    .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                mesh.triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                mesh.triangles
                    .push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_is_a_valid_disc() {
        for name in BUILTIN_NAMES {
            let m = builtin_target(name).unwrap();
            m.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(m.area() > 10e6, "{name} area {}", m.area());
        }
        let p = builtin_target("builtin:pavilion").unwrap();
        let (lo, hi) = crate::target::bounding_box(&p.vertices);
        assert!((5000.0..7000.0).contains(&(hi.x - lo.x)));
        assert!((3500.0..4800.0).contains(&(hi.y - lo.y)));
        assert!(matches!(
            builtin_target("cube"),
            Err(SurfaceError::UnknownBuiltin { .. })
        ));
    }
}
