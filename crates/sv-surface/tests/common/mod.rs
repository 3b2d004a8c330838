//! What the integration tests of `sv-surface` share.

use std::path::PathBuf;

use sv_surface::TargetMesh;

/// A target of `fixtures/targets/`, read as `spinvalence build` reads it
/// (`sv_io::read_target`: welded, oriented, the same vertices in the same order), so that
/// these tests see the layouts the build draws.
pub fn load(name: &str) -> TargetMesh {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/targets")
        .join(name);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let file = sv_io::read_target(&bytes, name).unwrap_or_else(|e| panic!("{e}"));
    TargetMesh {
        vertices: file.mesh.vertices,
        triangles: file.mesh.triangles,
    }
}
