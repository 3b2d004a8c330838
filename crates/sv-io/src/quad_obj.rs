//! The hub mesh as a Wavefront OBJ quad mesh (mm): reader, validating reader and writer.

use std::fmt::Write as _;

use sv_frame::{MeshChecks, QuadMesh};

use crate::obj::parse_obj;
use crate::reach::within_reach;
use crate::text::{decode, real};
use crate::IoError;

/// Read a quad mesh (mm) from OBJ text. `name` is the file name used in messages.
///
/// Reads `v x y z [w]` (a weight `w` and trailing vertex colours are ignored) and
/// `f` statements in the forms `v`, `v/vt`, `v//vn`, `v/vt/vn`, with 1-based or negative
/// (relative) indices; every face must have exactly four vertices, listed
/// counter-clockwise seen from the side the hubs deploy to. Comments (`#` to the end of
/// the line), blank lines, CRLF endings, tabs, and statements that carry no quad-mesh data
/// (`vt`, `vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, lines, free-form geometry) are skipped.
/// Line continuations (`\` at the end of a line) are not supported.
///
/// This checks the syntax only; see [`read_and_validate_quad_obj`] for the mesh checks a
/// frame needs.
///
/// # Errors
/// One line naming the file and line, e.g.
/// `hubs.obj:12: face has 3 vertices; a quad mesh needs 4 per face`,
/// `hubs.obj: not an OBJ file (line 1: '...')`, or `hubs.obj: vertex 2 at (1e308, 0, 0)
/// is farther than 1e12 mm from the origin (a corrupt number, or not in mm?)` (1-based
/// vertex numbers; the target reader's reach).
pub fn read_quad_obj(text: &str, name: &str) -> Result<QuadMesh, IoError> {
    read_quad_obj_lines(text, name).map(|(mesh, _)| mesh)
}

/// [`read_quad_obj`], with the line of each face's `f` statement.
fn read_quad_obj_lines(text: &str, name: &str) -> Result<(QuadMesh, Vec<usize>), IoError> {
    let data = parse_obj(text, name, "an OBJ")?;
    if data.faces.is_empty() {
        return Err(IoError::whole(
            name,
            format!(
                "no faces (file has {} vertices and no 'f' lines)",
                data.vertices.len()
            ),
        ));
    }
    for (i, p) in data.vertices.iter().enumerate() {
        within_reach(name, p, || format!("vertex {}", i + 1))?;
    }
    let mut faces = Vec::with_capacity(data.faces.len());
    for face in &data.faces {
        match <[usize; 4]>::try_from(face.vertices.as_slice()) {
            Ok(quad) => faces.push(quad),
            Err(_) => {
                return Err(IoError::line(
                    name,
                    face.line,
                    format!(
                        "face has {} vertices; a quad mesh needs 4 per face",
                        face.vertices.len()
                    ),
                ))
            }
        }
    }
    let lines = data.faces.iter().map(|f| f.line).collect();
    let mesh = QuadMesh {
        vertices: data.vertices,
        faces,
    };
    Ok((mesh, lines))
}

/// [`read_quad_obj`] on raw bytes: drops a UTF-8 byte order mark and reads invalid UTF-8
/// as U+FFFD, so binary data is reported as `not an OBJ file (line N: '...')` while a
/// stray non-UTF-8 byte in a comment is harmless.
///
/// # Errors
/// As [`read_quad_obj`].
pub fn read_quad_obj_bytes(bytes: &[u8], name: &str) -> Result<QuadMesh, IoError> {
    read_quad_obj(&decode(bytes), name)
}

/// [`read_quad_obj`] followed by [`QuadMesh::validate`] (finite, non-degenerate, manifold,
/// consistently oriented, planar within `checks`, at least one interior edge).
///
/// # Errors
/// The syntax errors of [`read_quad_obj`], or the mesh error prefixed with the file name,
/// faces and vertices numbered as the file does (from 1) and each face with its line:
/// `hubs.obj: face 18 (line 43) is not planar: ...`.
pub fn read_and_validate_quad_obj(
    text: &str,
    name: &str,
    checks: &MeshChecks,
) -> Result<QuadMesh, IoError> {
    let (mesh, face_lines) = read_quad_obj_lines(text, name)?;
    mesh.validate(checks).map_err(|problem| IoError::Mesh {
        file: name.to_string(),
        problem,
        face_lines,
    })?;
    Ok(mesh)
}

/// [`read_and_validate_quad_obj`] on raw bytes, read as [`read_quad_obj_bytes`] reads them.
///
/// # Errors
/// As [`read_and_validate_quad_obj`].
pub fn read_and_validate_quad_obj_bytes(
    bytes: &[u8],
    name: &str,
    checks: &MeshChecks,
) -> Result<QuadMesh, IoError> {
    read_and_validate_quad_obj(&decode(bytes), name, checks)
}

/// Write `mesh` as OBJ text: each line of `header` as a `# ` comment, then `v x y z` lines
/// (mm, written so that [`read_quad_obj`] gives back the same `f64` bit for bit) and
/// 1-based `f a b c d` lines in the mesh's order. Non-finite coordinates are written as
/// `NaN`/`inf`, which the reader rejects: validate the mesh first.
pub fn write_quad_obj(mesh: &QuadMesh, header: &str) -> String {
    let mut out = String::with_capacity(32 * mesh.vertices.len() + 24 * mesh.faces.len() + 128);
    for line in header.lines() {
        out.push_str(format!("# {line}").trim_end());
        out.push('\n');
    }
    let _ = writeln!(
        out,
        "# quad mesh, units: mm, {} vertices, {} faces",
        mesh.vertices.len(),
        mesh.faces.len()
    );
    for p in &mesh.vertices {
        let _ = writeln!(out, "v {} {} {}", real(p.x), real(p.y), real(p.z));
    }
    for f in &mesh.faces {
        let _ = writeln!(out, "f {} {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1, f[3] + 1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use sv_frame::MeshError;
    use sv_geom::Point3;

    const GOOD: &str = "# a 2 x 1 grid\r\nmtllib grid.mtl\r\no grid\r\n\
        v 0 0 0\r\nv 100 0 0\r\nv 200 0 0\r\nv\t0 100 0 1\r\nv 100 100 0\r\nv 200 100 0\r\n\
        vt 0 0\r\nvn 0 0 1\r\ng faces\r\nusemtl steel\r\ns off\r\n\
        f 1//1 2//1 5//1 4//1\r\nf -5/1/1 -4/1/1 -1/1/1 -2/1/1   # last face\r\n";

    fn grid() -> QuadMesh {
        QuadMesh::grid(2, 1, 100.0)
    }

    /// Assert that reading `text` fails with a message that contains `want` (which names
    /// the file and, where there is one, the line).
    fn check_err(text: &str, want: &str) {
        match read_quad_obj(text, "hubs.obj") {
            Ok(m) => panic!("expected an error containing {want:?}, got a mesh {m:?}"),
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains(want), "{msg:?} does not contain {want:?}");
                assert!(msg.starts_with("hubs.obj"), "{msg}");
                assert!(!msg.contains('\n') && !msg.ends_with('.'), "{msg}");
            }
        }
    }

    #[test]
    fn reads_all_supported_forms() {
        let m = read_quad_obj(GOOD, "hubs.obj").unwrap();
        assert_eq!(m, grid());
        m.validate(&MeshChecks::default()).unwrap();
    }

    #[test]
    fn round_trip_is_exact() {
        let mut mesh = QuadMesh::sphere_cap(5, 4, 3000.0, 300.0);
        mesh.vertices[0] = Point3::new(1e-7, -1.0 / 3.0, 1.234_567_890_123_4e11);
        mesh.vertices[1].x = -0.0;
        let text = write_quad_obj(&mesh, "sphere cap\nR = 3000 mm");
        assert!(text.starts_with("# sphere cap\n# R = 3000 mm\n"));
        let back = read_quad_obj(&text, "cap.obj").unwrap();
        assert_eq!(back.faces, mesh.faces);
        for (a, b) in back.vertices.iter().zip(&mesh.vertices) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
        assert_eq!(write_quad_obj(&back, "sphere cap\nR = 3000 mm"), text);
    }

    #[test]
    fn bad_input_names_file_and_line() {
        check_err(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n",
            "hubs.obj:4: face has 3 vertices; a quad mesh needs 4 per face",
        );
        check_err(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4 5\n",
            "hubs.obj:6: face has 5 vertices",
        );
        check_err(
            "v 0 0 0\nv 1 nan 0\n",
            "hubs.obj:2: vertex coordinate \"nan\" is not a finite number",
        );
        check_err(
            "v 0 0 0\nv 1 inf 0\n",
            "hubs.obj:2: vertex coordinate \"inf\" is not a finite number",
        );
        check_err(
            "v 0 0 1e400\n",
            "hubs.obj:1: vertex coordinate \"1e400\" is not a finite number",
        );
        check_err(
            "v 0 0 0\nv 1 0,5 0\n",
            "hubs.obj:2: vertex coordinate \"0,5\" is not a number",
        );
        check_err(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 42\n",
            "hubs.obj:5: vertex index 42 out of range (file has 4 vertices)",
        );
        check_err(
            "v 0 0 0\n# c\nv 1 2\n",
            "hubs.obj:3: expected 'v x y z', got 'v 1 2'",
        );
        check_err("", "hubs.obj: empty file (no vertices or faces)");
        check_err(
            "# only a comment\n\n  \n",
            "hubs.obj: empty file (no vertices or faces)",
        );
        check_err("o x\ng y\n", "hubs.obj: empty file (no vertices or faces)");
        check_err(
            "v 0 0 0\nv 1 0 0\n",
            "hubs.obj: no faces (file has 2 vertices",
        );
        check_err(
            "hello world\nv 1 2 3\n",
            "hubs.obj: not an OBJ file (line 1: 'hello world')",
        );
        check_err(
            "\n\n{\"format\": 1}",
            "hubs.obj: not an OBJ file (line 3: '{\"format\": 1}')",
        );
        check_err(
            "v 0 0 0\x00\x01\x02",
            "hubs.obj: not an OBJ file (line 1: 'v 0 0 0\\0\\u{1}\\u{2}')",
        );
    }

    #[test]
    fn a_vertex_far_out_is_named() {
        let mut text = write_quad_obj(&grid(), "");
        text = text.replacen("v 0 0 0\n", "v 0 0 0\nv 1e308 0 0\n", 1);
        let e = read_quad_obj_bytes(text.as_bytes(), "layout.obj").unwrap_err();
        assert_eq!(e.to_string(), "layout.obj: vertex 2 at (1e308, 0, 0) is farther than 1e12 mm from the origin (a corrupt number, or not in mm?)");
        // within reach, it reads
        let near = text.replace("1e308", "1e12");
        assert!(read_quad_obj(&near, "hubs.obj").is_ok());
    }

    #[test]
    fn binary_bytes_are_not_obj() {
        let mut bytes = vec![0u8; 84];
        bytes[..5].copy_from_slice(b"solid");
        bytes.extend([0xff, 0xfe, 0x00, 0x12]);
        let e = read_quad_obj_bytes(&bytes, "hubs.obj")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("hubs.obj: not an OBJ file (line 1: 'solid\\0"),
            "{e}"
        );
        let e = read_quad_obj_bytes(b"\xff\xfe\xfd\xfc", "hubs.obj")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("hubs.obj: not an OBJ file (line 1:"), "{e}");
        // a Latin-1 degree sign in a comment is harmless
        let mut text = b"# angle 45\xb0\n".to_vec();
        text.extend(GOOD.bytes());
        assert_eq!(read_quad_obj_bytes(&text, "hubs.obj").unwrap(), grid());
    }

    #[test]
    fn truncated_last_line_is_read_or_reported() {
        // complete last line without its newline
        let text = GOOD.trim_end();
        assert_eq!(read_quad_obj(text, "hubs.obj").unwrap(), grid());
        // last face cut short
        let cut = &GOOD[..GOOD.rfind("-1/1/1").unwrap()];
        check_err(cut, "hubs.obj:16: face has 2 vertices");
        // last vertex cut short
        let text = "v 0 0 0\nv 1 0 0\nv 1 1";
        check_err(text, "hubs.obj:3: expected 'v x y z', got 'v 1 1'");
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 1.5e";
        check_err(
            text,
            "hubs.obj:3: vertex coordinate \"1.5e\" is not a number",
        );
    }

    #[test]
    fn validation_errors_are_prefixed_with_the_file() {
        let mut mesh = grid();
        mesh.vertices[5].z = 30.0; // only face 1 uses vertex 5
        let text = write_quad_obj(&mesh, "bent");
        let e = read_and_validate_quad_obj(&text, "hubs.obj", &MeshChecks::default()).unwrap_err();
        assert!(
            matches!(
                &e,
                IoError::Mesh {
                    problem: MeshError::NonPlanar { face: 1, .. },
                    ..
                }
            ),
            "{e}"
        );
        // numbered as the file numbers them: the second face, on its own line
        let face_line = |text: &str, k: usize| {
            1 + text
                .lines()
                .enumerate()
                .filter(|(_, l)| l.starts_with("f "))
                .nth(k)
                .unwrap()
                .0
        };
        assert!(
            e.to_string().starts_with(&format!(
                "hubs.obj: face 2 (line {}) is not planar: ",
                face_line(&text, 1)
            )),
            "{e}"
        );

        let mut mesh = grid();
        mesh.faces[1].reverse();
        let text = write_quad_obj(&mesh, "");
        let e = read_and_validate_quad_obj(&text, "hubs.obj", &MeshChecks::default()).unwrap_err();
        assert!(e.to_string().starts_with("hubs.obj: edge ("), "{e}");
        assert!(e.to_string().contains("non-manifold"), "{e}");
        assert!(
            e.to_string()
                .contains(&format!("2 (line {})", face_line(&text, 1))),
            "{e}"
        );
        // a face listed twice is named as such, with both lines
        let mut mesh = grid();
        mesh.faces.push(mesh.faces[0]);
        let text = write_quad_obj(&mesh, "");
        let e = read_and_validate_quad_obj(&text, "hubs.obj", &MeshChecks::default()).unwrap_err();
        let last = mesh.faces.len();
        assert!(
            e.to_string().contains(&format!(
                "the same face is listed twice (faces 1 (line {}), {last} (line {}))",
                face_line(&text, 0),
                face_line(&text, last - 1)
            )),
            "{e}"
        );

        let text = write_quad_obj(&QuadMesh::grid(1, 1, 100.0), "");
        let e = read_and_validate_quad_obj(&text, "one.obj", &MeshChecks::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("one.obj: mesh is smaller than a frame"),
            "{e}"
        );

        let ok = read_and_validate_quad_obj(GOOD, "hubs.obj", &MeshChecks::default()).unwrap();
        assert_eq!(ok, grid());
    }

    #[test]
    fn mutated_and_truncated_files_never_panic() {
        let base = write_quad_obj(&QuadMesh::sphere_cap(3, 2, 3000.0, 300.0), "cap");
        let bytes = base.as_bytes();
        let first_face = base.find("\nf ").unwrap() + 1;
        for cut in 0..bytes.len() {
            let text = decode(&bytes[..cut]);
            match read_and_validate_quad_obj(&text, "cut.obj", &MeshChecks::default()) {
                Ok(m) => {
                    assert!(cut > first_face, "cut at {cut} read as a mesh");
                    m.validate(&MeshChecks::default()).unwrap();
                }
                Err(e) => assert!(e.to_string().starts_with("cut.obj"), "{e}"),
            }
        }
        let replacements: &[&[u8]] = &[
            b"-", b"0", b"/", b" ", b"\n", b"x", b"9", b"e", b"\0", b"#", b"f", b"v",
        ];
        for at in 0..bytes.len() {
            for r in replacements {
                let mut m = bytes.to_vec();
                m.splice(at..at + 1, r.iter().copied());
                if let Err(e) =
                    read_and_validate_quad_obj(&decode(&m), "m.obj", &MeshChecks::default())
                {
                    assert!(e.to_string().starts_with("m.obj"), "{e}");
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_text_never_panics(text in "[vf0-9 ./\\-eE#\n\r\tnai]{0,200}") {
            if let Err(e) = read_and_validate_quad_obj(&text, "p.obj", &MeshChecks::default()) {
                proptest::prop_assert!(e.to_string().starts_with("p.obj"));
            }
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..300)) {
            if let Err(e) = read_quad_obj_bytes(&bytes, "b.obj") {
                proptest::prop_assert!(e.to_string().starts_with("b.obj"));
            }
        }
    }
}
