//! Bad input: every case exits 2 with exactly one line that names the file and the place,
//! and leaves no frame.json (nor anything else) behind.

use std::fmt::Write as _;

use sv_frame::QuadMesh;

use crate::fixtures;
use crate::util::{Dir, Output};

/// Where an error must point.
#[derive(Debug)]
enum Place {
    /// The file as a whole.
    File,
    /// `file:LINE:`.
    Line(usize),
    /// `file:LINE:` or `face F (line LINE)`.
    LineOrFace(usize, usize),
    /// `file:LINE:` or `vertex V`.
    LineOrVertex(usize, usize),
    /// `face F` for one of these faces.
    AnyFace(Vec<usize>),
    /// `file:LINE:`, `face F` or `edge (`.
    Edge(usize, usize),
}

// Faces and vertices above are given 0-based, as the mesh holds them; the messages number
// them as the file does, from 1, and name a face's line.

/// OBJ text of a mesh with no header: vertex `i` is on line `i + 1`, face `f` on line
/// `vertices + f + 1`.
struct Obj {
    vertices: Vec<String>,
    faces: Vec<String>,
}

impl Obj {
    fn from_mesh(mesh: &QuadMesh) -> Self {
        Self {
            vertices: mesh
                .vertices
                .iter()
                .map(|p| format!("v {} {} {}", p.x, p.y, p.z))
                .collect(),
            faces: mesh
                .faces
                .iter()
                .map(|f| format!("f {} {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1, f[3] + 1))
                .collect(),
        }
    }

    /// The 4 x 3 grid of `fixtures/grid_small.obj`.
    fn small() -> Self {
        Self::from_mesh(&QuadMesh::grid(4, 3, fixtures::SPACING))
    }

    fn face_line(&self, face: usize) -> usize {
        self.vertices.len() + face + 1
    }

    fn text(&self) -> String {
        let mut s = String::new();
        for line in self.vertices.iter().chain(&self.faces) {
            writeln!(s, "{line}").unwrap();
        }
        s
    }
}

fn assert_rejected(dir: &Dir, file: &str, out: &Output, place: &Place) {
    out.expect_code(2);
    let line = out.one_error_line();
    assert!(line.contains(file), "the error must name {file}:{out:?}");
    let at_line = |n: usize| line.contains(&format!("{file}:{n}:"));
    let at_face = |f: usize| line.contains(&format!("face {} ", f + 1));
    let ok = match place {
        Place::File => true,
        Place::Line(n) => at_line(*n),
        Place::LineOrFace(n, f) => at_line(*n) || at_face(*f),
        Place::LineOrVertex(n, v) => at_line(*n) || line.contains(&format!("vertex {}", v + 1)),
        Place::AnyFace(faces) => faces.iter().any(|&f| at_face(f)),
        Place::Edge(n, f) => at_line(*n) || at_face(*f) || line.contains("edge ("),
    };
    assert!(ok, "the error must point at {place:?}:{out:?}");
    assert!(
        dir.entries("out").is_empty(),
        "nothing may be written: {:?}{out:?}",
        dir.entries("out")
    );
}

fn solve_bytes(file: &str, bytes: &[u8], place: Place) {
    let dir = Dir::new();
    dir.write(file, bytes);
    let out = dir.run(&["solve", "--mesh", file, "--out", "out"]);
    assert_rejected(&dir, file, &out, &place);
}

#[test]
fn empty_file() {
    solve_bytes("empty.obj", b"", Place::File);
}

#[test]
fn only_comments_and_blank_lines() {
    solve_bytes("comments.obj", b"# nothing here\n\n   \n", Place::File);
}

#[test]
fn binary_garbage() {
    let bytes: Vec<u8> = (0..2048u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    solve_bytes("garbage.obj", &bytes, Place::File);
}

#[test]
fn text_that_is_not_obj() {
    solve_bytes("notes.obj", b"{\"this\": \"is json\"}\n", Place::File);
}

#[test]
fn truncated_in_a_face_line() {
    let obj = Obj::small();
    let mut text = obj.text();
    // cut the last face line after its second index: "f a b" is not a quad
    let last = obj.faces.last().unwrap();
    let keep = last.match_indices(' ').nth(2).unwrap().0;
    text.truncate(text.len() - last.len() - 1 + keep);
    solve_bytes(
        "truncated.obj",
        text.as_bytes(),
        Place::Line(obj.face_line(obj.faces.len() - 1)),
    );
}

#[test]
fn truncated_in_a_vertex_line() {
    let obj = Obj::small();
    let text = obj.text();
    // keep two vertex lines and the first two fields of the third: "v 600"
    let cut = text.match_indices('\n').nth(1).unwrap().0 + 1 + "v 600".len();
    assert!(text[..cut].ends_with("v 600"));
    solve_bytes("truncated.obj", &text.as_bytes()[..cut], Place::Line(3));
}

#[test]
fn nan_coordinate() {
    let mut obj = Obj::small();
    obj.vertices[7] = "v 300 nan 0".into();
    solve_bytes("nan.obj", obj.text().as_bytes(), Place::LineOrVertex(8, 7));
}

#[test]
fn infinite_coordinate() {
    let mut obj = Obj::small();
    obj.vertices[2] = "v 1e400 0 0".into();
    solve_bytes("inf.obj", obj.text().as_bytes(), Place::LineOrVertex(3, 2));
}

#[test]
fn index_out_of_range() {
    let mut obj = Obj::small();
    obj.faces[4] = "f 6 7 12 99".into();
    solve_bytes(
        "index.obj",
        obj.text().as_bytes(),
        Place::LineOrFace(obj.face_line(4), 4),
    );
}

#[test]
fn triangle_face() {
    let mut obj = Obj::small();
    obj.faces[3] = "f 4 5 10".into();
    solve_bytes(
        "triangle.obj",
        obj.text().as_bytes(),
        Place::LineOrFace(obj.face_line(3), 3),
    );
}

#[test]
fn ngon_face() {
    let mut obj = Obj::small();
    obj.faces[5] = "f 7 8 13 12 11".into();
    solve_bytes(
        "ngon.obj",
        obj.text().as_bytes(),
        Place::LineOrFace(obj.face_line(5), 5),
    );
}

#[test]
fn non_manifold_edge() {
    // a third face on the interior edge between faces 0 and 1 (vertices 2 and 7, 1-based)
    let mut obj = Obj::small();
    obj.vertices.push("v 300 150 300".into());
    obj.vertices.push("v 300 0 300".into());
    let (a, b) = (obj.vertices.len() - 1, obj.vertices.len());
    obj.faces.push(format!("f 2 7 {a} {b}"));
    let face = obj.faces.len() - 1;
    solve_bytes(
        "nonmanifold.obj",
        obj.text().as_bytes(),
        Place::Edge(obj.face_line(face), face),
    );
}

#[test]
fn degenerate_face() {
    let mut obj = Obj::small();
    obj.faces[6] = "f 8 9 9 13".into();
    solve_bytes(
        "degenerate.obj",
        obj.text().as_bytes(),
        Place::LineOrFace(obj.face_line(6), 6),
    );
}

#[test]
fn single_face_is_smaller_than_a_frame() {
    let obj = Obj::from_mesh(&QuadMesh::grid(1, 1, fixtures::SPACING));
    solve_bytes("single.obj", obj.text().as_bytes(), Place::File);
}

#[test]
fn non_planar_face() {
    let mesh = QuadMesh::grid(4, 3, fixtures::SPACING);
    let mut obj = Obj::from_mesh(&mesh);
    let v = 6; // interior vertex (1, 1)
    obj.vertices[v] = format!("v {} {} 60", mesh.vertices[v].x, mesh.vertices[v].y);
    let faces: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| mesh.faces[f].contains(&v))
        .collect();
    assert_eq!(faces.len(), 4);
    solve_bytes("bent.obj", obj.text().as_bytes(), Place::AnyFace(faces));
}

#[test]
fn non_planar_face_passes_with_a_looser_tolerance() {
    // the same bent mesh is accepted when the user allows it: the tolerance is honoured
    let mesh = QuadMesh::grid(4, 3, fixtures::SPACING);
    let mut obj = Obj::from_mesh(&mesh);
    obj.vertices[6] = "v 300 300 3".into();
    let dir = Dir::new();
    dir.write("slightly_bent.obj", obj.text());
    let strict = dir.run(&[
        "solve",
        "-q",
        "--mesh",
        "slightly_bent.obj",
        "--planarity-tolerance",
        "1e-4",
        "--out",
        "out",
    ]);
    assert_rejected(
        &dir,
        "slightly_bent.obj",
        &strict,
        &Place::AnyFace(vec![0, 1, 4, 5]),
    );
    dir.run(&[
        "solve",
        "-q",
        "--mesh",
        "slightly_bent.obj",
        "--planarity-tolerance",
        "0.05",
        "--out",
        "out",
    ])
    .expect_code(0);
}

#[test]
fn missing_mesh_file() {
    let dir = Dir::new();
    let out = dir.run(&["solve", "--mesh", "no_such_mesh.obj", "--out", "out"]);
    assert_rejected(&dir, "no_such_mesh.obj", &out, &Place::File);
}

#[test]
fn mesh_is_a_directory() {
    let dir = Dir::new();
    std::fs::create_dir(dir.join("meshdir.obj")).unwrap();
    let out = dir.run(&["solve", "--mesh", "meshdir.obj", "--out", "out"]);
    assert_rejected(&dir, "meshdir.obj", &out, &Place::File);
}

#[test]
fn bad_spin_angles() {
    for value in ["0", "90", "120", "nan", "-30", "inf"] {
        let dir = Dir::new();
        let out = dir.run(&[
            "solve",
            "--mesh",
            fixtures::grid_small().to_str().unwrap(),
            "--spin-angle",
            value,
            "--out",
            "out",
        ]);
        out.expect_code(2);
        let line = out.one_error_line();
        assert!(line.contains("--spin-angle"), "{out:?}");
        assert!(dir.entries("out").is_empty(), "{out:?}");
    }
}

#[test]
fn bad_expansion() {
    for value in ["0.5", "0", "-1", "nan", "inf"] {
        let dir = Dir::new();
        let out = dir.run(&[
            "solve",
            "--mesh",
            fixtures::grid_small().to_str().unwrap(),
            "--expansion",
            value,
            "--out",
            "out",
        ]);
        out.expect_code(2);
        assert!(out.one_error_line().contains("--expansion"), "{out:?}");
        assert!(dir.entries("out").is_empty(), "{out:?}");
    }
}

#[test]
fn not_a_number() {
    let dir = Dir::new();
    let out = dir.run(&[
        "solve",
        "--mesh",
        fixtures::grid_small().to_str().unwrap(),
        "--spin-angle",
        "forty",
        "--out",
        "out",
    ]);
    out.expect_code(2);
    assert!(out.one_error_line().contains("--spin-angle"), "{out:?}");
}

#[test]
fn output_directory_not_writable() {
    let dir = Dir::new();
    dir.write("taken", "a file, not a directory");
    let mesh = fixtures::grid_small();
    let mesh = mesh.to_str().unwrap();
    for out_dir in ["taken", "taken/sub"] {
        let out = dir.run(&["solve", "--mesh", mesh, "--out", out_dir]);
        out.expect_code(2);
        assert!(out.one_error_line().contains(out_dir), "{out:?}");
        assert_eq!(
            std::fs::read_to_string(dir.join("taken")).unwrap(),
            "a file, not a directory"
        );
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let locked = dir.join("locked");
        std::fs::create_dir(&locked).unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
        // root ignores permission bits: only assert where the directory really is read-only
        let really_read_only = std::fs::write(locked.join("probe"), "").is_err();
        let _ = std::fs::remove_file(locked.join("probe"));
        let out = dir.run(&["solve", "--mesh", mesh, "--out", "locked"]);
        if really_read_only {
            out.expect_code(2);
            assert!(out.one_error_line().contains("locked"), "{out:?}");
            assert!(dir.entries("locked").is_empty(), "{out:?}");
        }
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}
