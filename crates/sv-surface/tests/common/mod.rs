//! What the integration tests of `sv-surface` share.

use std::path::PathBuf;

use sv_geom::Point3;
use sv_surface::TargetMesh;

/// A target of `fixtures/targets/` in the OBJ subset the generator writes: `v x y z` and
/// `f a b c` (1-based).
pub fn load(name: &str) -> TargetMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/targets")
        .join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut m = TargetMesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.map(|s| s.parse().unwrap()).collect();
                m.vertices.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let i: Vec<usize> = it.map(|s| s.parse::<usize>().unwrap() - 1).collect();
                m.triangles.push([i[0], i[1], i[2]]);
            }
            _ => {}
        }
    }
    m
}
