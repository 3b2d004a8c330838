//! The OBJ reader the sv-surface examples share (`#[path]`-included; not an example itself).

use sv_surface::TargetMesh;

/// Minimal OBJ reader (`v x y z`, `f a b c` with optional `/`-suffixes, 1-based).
pub fn read_obj(path: &str) -> TargetMesh {
    let text = std::fs::read_to_string(path).expect("read OBJ");
    let mut m = TargetMesh::default();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|s| s.parse().expect("number")).collect();
                m.vertices.push(sv_geom::Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let idx: Vec<usize> = it
                    .map(|s| {
                        s.split('/')
                            .next()
                            .unwrap_or("")
                            .parse::<usize>()
                            .expect("index")
                            - 1
                    })
                    .collect();
                for k in 1..idx.len() - 1 {
                    m.triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    m
}
