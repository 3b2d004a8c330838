//! The target reader the sv-surface examples share (`#[path]`-included; not an example
//! itself): `sv_io::read_target`, the one `spinvalence build` reads with, so that the
//! examples' figures are the build's (the same welded vertices in the same order).

use sv_surface::TargetMesh;

/// The target in OBJ or STL file `path`, welded and oriented; exits with the reader's
/// one-line message where the file cannot be read.
pub fn read_obj(path: &str) -> TargetMesh {
    let target = std::fs::read(path)
        .map_err(|e| format!("{path}: {e}"))
        .and_then(|bytes| sv_io::read_target(&bytes, path).map_err(|e| e.to_string()));
    match target {
        Ok(file) => TargetMesh {
            vertices: file.mesh.vertices,
            triangles: file.mesh.triangles,
        },
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
