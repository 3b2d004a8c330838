//! Write the OBJ fixtures of `fixtures/` (hub meshes in mm), so they are reproducible.
//!
//! ```text
//! cargo run -p spinvalence --example make_fixtures            # into fixtures/
//! cargo run -p spinvalence --example make_fixtures -- DIR     # somewhere else
//! ```
//!
//! The definitions live in `tests/e2e/fixtures.rs`, which the end-to-end tests share; a
//! test there fails when a committed fixture differs from what this program writes.

#[allow(dead_code)]
#[path = "../../../tests/e2e/fixtures.rs"]
mod fixtures;

use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let dir = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(fixtures::dir);
    for fixture in fixtures::generated() {
        let path = dir.join(fixture.file);
        if let Err(e) = std::fs::write(&path, fixture.obj()) {
            eprintln!("error: {}: {e}", path.display());
            return ExitCode::from(2);
        }
        println!(
            "{}: {} faces, {} vertices",
            path.display(),
            fixture.mesh.faces.len(),
            fixture.mesh.vertices.len()
        );
    }
    ExitCode::SUCCESS
}
