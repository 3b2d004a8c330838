//! Every file in `fixtures/bad/` is refused with one line that names the file and place.

use sv_frame::MeshChecks;
use sv_io::{frame_from_json, read_and_validate_quad_obj, read_quad_obj_bytes, read_tri_mesh};

macro_rules! fixture {
    ($name:literal) => {
        (
            $name,
            include_bytes!(concat!("../../../fixtures/bad/", $name)).as_slice(),
        )
    };
}

/// `(file, expected message)` for the OBJ quad-mesh fixtures.
const QUAD_OBJ: &[((&str, &[u8]), &str)] = &[
    (
        fixture!("triangle_face.obj"),
        "triangle_face.obj:7: face has 3 vertices; a quad mesh needs 4 per face",
    ),
    (
        fixture!("nan_vertex.obj"),
        "nan_vertex.obj:3: vertex coordinate \"nan\" is not a finite number",
    ),
    (
        fixture!("index_out_of_range.obj"),
        "index_out_of_range.obj:5: vertex index 42 out of range (file has 4 vertices)",
    ),
    (
        fixture!("truncated_vertex.obj"),
        "truncated_vertex.obj:9: expected 'v x y z', got 'v 0 30'",
    ),
    (
        fixture!("truncated_binary.stl"),
        "truncated_binary.stl: not an OBJ file (line 1: 'solid truncated by a failed upload",
    ),
];

fn assert_one_line(message: &str) {
    assert!(!message.contains('\n'), "{message}");
    assert!(!message.ends_with('.'), "{message}");
}

#[test]
fn bad_quad_objs_name_file_and_line() {
    for ((name, bytes), want) in QUAD_OBJ {
        let e = read_quad_obj_bytes(bytes, name).unwrap_err().to_string();
        assert!(
            e.starts_with(want),
            "{name}: {e:?} does not start with {want:?}"
        );
        assert_one_line(&e);
    }
}

#[test]
fn non_planar_fixture_fails_validation_with_the_face() {
    let (name, bytes) = fixture!("non_planar.obj");
    let text = std::str::from_utf8(bytes).unwrap();
    let e = read_and_validate_quad_obj(text, name, &MeshChecks::default())
        .unwrap_err()
        .to_string();
    assert!(
        // the second face, on line 8, numbered as the file numbers it
        e.starts_with("non_planar.obj: face 2 (line 8) is not planar: "),
        "{e}"
    );
    assert_one_line(&e);
}

#[test]
fn truncated_binary_stl_fixture() {
    let (name, bytes) = fixture!("truncated_binary.stl");
    let e = read_tri_mesh(bytes, name).unwrap_err().to_string();
    assert_eq!(
        e,
        "truncated_binary.stl: truncated binary STL: header says 120 triangles, file holds 37"
    );
}

#[test]
fn bad_frame_json_fixtures() {
    let (name, bytes) = fixture!("frame_version_1.json");
    let e = frame_from_json(std::str::from_utf8(bytes).unwrap(), name)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "frame_version_1.json: version: version 1 describes the paper's zero-width units, not \
         the parts as cut; rebuild the frame with this build (it reads version 2)"
    );
    let (name, bytes) = fixture!("frame_syntax.json");
    let e = frame_from_json(std::str::from_utf8(bytes).unwrap(), name)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "frame_syntax.json:5:29: expected value");
}
