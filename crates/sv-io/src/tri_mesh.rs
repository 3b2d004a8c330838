//! Target surfaces as triangle meshes, read from OBJ or STL (ASCII or binary).

use std::collections::HashMap;

use sv_geom::Point3;

use crate::obj::parse_obj;
use crate::stl::{binary_stl_size, read_ascii_stl, read_binary_stl, STL_HEADER_BYTES};
use crate::text::{decode, is_binary_char};
use crate::IoError;

/// STL vertices closer than this fraction of the bounding-box diagonal are welded into
/// one. 1e-9 merges the copies a CAD exporter writes for each triangle (equal, or apart by
/// float rounding) and nothing a designer drew: on a 10 m surface it is 10 nanometres.
pub const WELD_RELATIVE_TOLERANCE: f64 = 1e-9;

/// A triangle mesh in mm, such as a target surface. Triangles list vertex indices in the
/// order of the file (counter-clockwise seen from the outside for a well-made STL).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions (mm), all finite.
    pub vertices: Vec<Point3>,
    /// Triangles as indices into `vertices`, each in range and with three distinct indices.
    pub triangles: Vec<[usize; 3]>,
}

/// Read a triangle mesh (mm) from the bytes of an OBJ, ASCII STL or binary STL file.
/// `name` is the file name used in messages.
///
/// - **Binary STL** is recognised by its size, `84 + 50 n` bytes for the `n` triangles the
///   header announces, not by the `solid` keyword (many binary files start with it).
/// - **ASCII STL** is text whose first word is `solid`.
/// - Anything else is read as **OBJ**; its polygons are fan-triangulated
///   (`a b c d` gives `a b c`, `a c d`), and a triangle that lists a vertex twice (of a
///   face such as `f 1 2 3 1`) is dropped.
///
/// STL lists every triangle's corners separately; they are welded when they coincide
/// exactly or within [`WELD_RELATIVE_TOLERANCE`] of the bounding-box diagonal, and
/// triangles that collapse under welding are dropped. OBJ vertices are kept as listed.
///
/// # Errors
/// One line naming the file and the line (text) or triangle (binary):
/// `file.stl:12: vertex coordinate "nan" is not a finite number`,
/// `file.stl: truncated binary STL: header says 120 triangles, file holds 37`,
/// `file.stl: triangle 4: vertex 2 has a non-finite coordinate`.
pub fn read_tri_mesh(bytes: &[u8], name: &str) -> Result<TriMesh, IoError> {
    if binary_stl_size(bytes) == Some(bytes.len()) {
        let soup = read_binary_stl(bytes, name)?;
        return welded(&soup, name);
    }
    let text = decode(bytes);
    let is_text = !text.contains(is_binary_char);
    if !is_text {
        return match binary_stl_size(bytes) {
            Some(expected) if bytes.len() < expected => Err(IoError::whole(
                name,
                format!(
                    "truncated binary STL: header says {} triangles, file holds {}",
                    (expected - STL_HEADER_BYTES) / 50,
                    (bytes.len() - STL_HEADER_BYTES) / 50
                ),
            )),
            Some(expected) => Err(IoError::whole(
                name,
                format!(
                    "binary STL has {} bytes after the {} triangles its header announces",
                    bytes.len() - expected,
                    (expected - STL_HEADER_BYTES) / 50
                ),
            )),
            None => Err(IoError::whole(
                name,
                format!(
                    "not an OBJ or STL file (binary data, {} bytes, too short for binary STL)",
                    bytes.len()
                ),
            )),
        };
    }
    let first_word = text
        .trim_start_matches('\u{feff}')
        .split_whitespace()
        .next()
        .unwrap_or("");
    if first_word.eq_ignore_ascii_case("solid") {
        let soup = read_ascii_stl(&text, name)?;
        return welded(&soup, name);
    }
    let data = parse_obj(&text, name, "an OBJ or STL")?;
    if data.faces.is_empty() {
        return Err(IoError::whole(
            name,
            format!(
                "no faces (file has {} vertices and no 'f' lines)",
                data.vertices.len()
            ),
        ));
    }
    let mut triangles = Vec::with_capacity(data.faces.len());
    for face in &data.faces {
        let v = &face.vertices;
        if v.len() < 3 {
            return Err(IoError::line(
                name,
                face.line,
                format!("face has {} vertices; a face needs at least 3", v.len()),
            ));
        }
        for k in 1..v.len() - 1 {
            let t = [v[0], v[k], v[k + 1]];
            // a face that lists a vertex twice (`f 1 2 3 1`) has collapsed triangles
            if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                triangles.push(t);
            }
        }
    }
    if triangles.is_empty() {
        return Err(IoError::whole(
            name,
            format!(
                "all {} faces are degenerate (each lists a vertex twice)",
                data.faces.len()
            ),
        ));
    }
    Ok(TriMesh {
        vertices: data.vertices,
        triangles,
    })
}

/// [`weld_soup`], also returning the soup corner `(triangle, corner)` that each welded
/// vertex was first seen at and the soup triangles dropped because they collapse.
pub(crate) fn weld_indexed(
    soup: &[[Point3; 3]],
    relative_tolerance: f64,
) -> (TriMesh, Vec<(usize, usize)>, Vec<usize>) {
    let (vertices, corners) = weld_map(soup, relative_tolerance);
    let mut first = vec![(usize::MAX, 0); vertices.len()];
    let mut triangles = Vec::with_capacity(soup.len());
    let mut dropped = Vec::new();
    for (t, tri) in corners.iter().enumerate() {
        for (k, &v) in tri.iter().enumerate() {
            if first[v].0 == usize::MAX {
                first[v] = (t, k);
            }
        }
        if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
            triangles.push(*tri);
        } else {
            dropped.push(t);
        }
    }
    (
        TriMesh {
            vertices,
            triangles,
        },
        first,
        dropped,
    )
}

/// [`weld_soup`] at [`WELD_RELATIVE_TOLERANCE`], refusing a mesh with nothing left.
fn welded(soup: &[[Point3; 3]], name: &str) -> Result<TriMesh, IoError> {
    let mesh = weld_soup(soup, WELD_RELATIVE_TOLERANCE);
    if mesh.triangles.is_empty() {
        return Err(IoError::whole(
            name,
            format!(
                "all {} triangles are degenerate (corners coincide after welding)",
                soup.len()
            ),
        ));
    }
    Ok(mesh)
}

/// Index a triangle soup: weld corners within `relative_tolerance` of the bounding-box
/// diagonal (the first corner seen represents the others) and drop triangles that
/// collapse. Corners must be finite.
pub(crate) fn weld_soup(soup: &[[Point3; 3]], relative_tolerance: f64) -> TriMesh {
    let (vertices, corners) = weld_map(soup, relative_tolerance);
    let triangles = corners
        .into_iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    TriMesh {
        vertices,
        triangles,
    }
}

/// The welded vertices of a soup and the welded index of every corner.
fn weld_map(soup: &[[Point3; 3]], relative_tolerance: f64) -> (Vec<Point3>, Vec<[usize; 3]>) {
    let corners = || soup.iter().flatten();
    let Some(first) = corners().next() else {
        return (Vec::new(), Vec::new());
    };
    let (mut lo, mut hi) = (*first, *first);
    for p in corners() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let tolerance = relative_tolerance * (hi - lo).norm();
    // cells of the tolerance's size: a partner within it is in one of the 27 around
    let cell = if tolerance > 0.0 && tolerance.is_finite() {
        tolerance
    } else {
        1.0
    };
    let key = |p: &Point3| -> [i64; 3] {
        let d = (p - lo) / cell;
        // saturating casts; coordinates are finite and d <= 1 / relative_tolerance
        [d.x.floor() as i64, d.y.floor() as i64, d.z.floor() as i64]
    };
    let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut vertices: Vec<Point3> = Vec::new();
    let mut index_of = |p: &Point3| -> usize {
        let k = key(p);
        let mut best: Option<usize> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let n = [
                        k[0].saturating_add(dx),
                        k[1].saturating_add(dy),
                        k[2].saturating_add(dz),
                    ];
                    for &i in cells.get(&n).into_iter().flatten() {
                        if (vertices[i] - p).norm() <= tolerance && best.is_none_or(|b| i < b) {
                            best = Some(i);
                        }
                    }
                }
            }
        }
        best.unwrap_or_else(|| {
            vertices.push(*p);
            cells.entry(k).or_default().push(vertices.len() - 1);
            vertices.len() - 1
        })
    };
    let corners: Vec<[usize; 3]> = soup
        .iter()
        .map(|t| [index_of(&t[0]), index_of(&t[1]), index_of(&t[2])])
        .collect();
    (vertices, corners)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stl::tests::{ascii_stl, binary_stl};

    /// A tetrahedron-like patch: a pyramid of four triangles over a square, corners exactly
    /// representable in `f32`.
    fn pyramid() -> Vec<[Point3; 3]> {
        let a = Point3::new(0.0, 0.0, 0.0);
        let b = Point3::new(300.0, 0.0, 0.0);
        let c = Point3::new(300.0, 300.0, 0.5);
        let d = Point3::new(0.0, 300.0, 0.0);
        let top = Point3::new(150.25, 150.0, 75.125);
        vec![[a, b, top], [b, c, top], [c, d, top], [d, a, top]]
    }

    fn pyramid_mesh() -> TriMesh {
        let p = pyramid();
        TriMesh {
            vertices: vec![p[0][0], p[0][1], p[0][2], p[1][1], p[2][1]],
            triangles: vec![[0, 1, 2], [1, 3, 2], [3, 4, 2], [4, 0, 2]],
        }
    }

    fn check_err(bytes: &[u8], want: &str) {
        match read_tri_mesh(bytes, "file.stl") {
            Ok(m) => panic!("expected an error containing {want:?}, got {m:?}"),
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains(want), "{msg:?} does not contain {want:?}");
                assert!(msg.starts_with("file.stl"), "{msg}");
            }
        }
    }

    #[test]
    fn ascii_and_binary_stl_give_the_same_welded_mesh() {
        let soup = pyramid();
        let from_ascii = read_tri_mesh(ascii_stl(&soup).as_bytes(), "p.stl").unwrap();
        let from_binary = read_tri_mesh(&binary_stl(&soup, b"binary"), "p.stl").unwrap();
        assert_eq!(from_ascii, pyramid_mesh());
        assert_eq!(from_binary, from_ascii);
    }

    #[test]
    fn binary_stl_starting_with_solid_is_binary() {
        let bytes = binary_stl(&pyramid(), b"solid pyramid exported by a CAD tool");
        assert_eq!(read_tri_mesh(&bytes, "p.stl").unwrap(), pyramid_mesh());
    }

    #[test]
    fn nearly_coincident_corners_are_welded() {
        let mut soup = pyramid();
        soup[1][0].x += 300.0 * 1e-12; // copy of b, off by float noise
        soup[3][1].y += 1e-3; // copy of a, 1 um away: a different point
        let m = weld_soup(&soup, WELD_RELATIVE_TOLERANCE);
        assert_eq!(m.vertices.len(), 6);
        assert_eq!(m.triangles[1], [1, 3, 2]);
        assert_eq!(m.triangles[3], [4, 5, 2]);
        // a triangle that collapses is dropped
        let mut soup = pyramid();
        soup[0][1] = soup[0][0];
        assert_eq!(weld_soup(&soup, WELD_RELATIVE_TOLERANCE).triangles.len(), 3);
        // one repeated point
        let p = Point3::new(1.0, 2.0, 3.0);
        let m = weld_soup(&[[p, p, p]], WELD_RELATIVE_TOLERANCE);
        assert_eq!((m.vertices.len(), m.triangles.len()), (1, 0));
    }

    #[test]
    fn obj_polygons_are_fan_triangulated() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n";
        let m = read_tri_mesh(text.as_bytes(), "t.obj").unwrap();
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
        let e = read_tri_mesh(b"v 0 0 0\nv 1 0 0\nf 1 2\n", "t.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.obj:3: face has 2 vertices; a face needs at least 3"
        );
        let e = read_tri_mesh(b"v 0 0 0\nv 1 nan 0\nf 1 2 1\n", "t.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.obj:2: vertex coordinate \"nan\" is not a finite number"
        );
        let e = read_tri_mesh(b"what is this\n", "t.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.obj: not an OBJ or STL file (line 1: 'what is this')"
        );
    }

    /// An OBJ face that lists a vertex twice (`f 1 1 2`, or `f 1 2 3 1` closing its loop) gave
    /// triangles such as [0, 0, 1], against the promise of three distinct indices.
    #[test]
    fn obj_triangles_that_repeat_a_vertex_are_dropped() {
        let m = read_tri_mesh(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3 1\nf 2 2 3\n", "t.obj").unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        let e = read_tri_mesh(b"v 0 0 0\nv 1 0 0\nf 1 2 2\nf 1 1 1\n", "t.obj").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.obj: all 2 faces are degenerate (each lists a vertex twice)"
        );
    }

    #[test]
    fn truncated_binary_stl_says_how_much_is_there() {
        let soup: Vec<_> = pyramid().into_iter().cycle().take(120).collect();
        let bytes = binary_stl(&soup, b"");
        let m = read_tri_mesh(&bytes, "file.stl").unwrap();
        assert_eq!(m.vertices, pyramid_mesh().vertices);
        assert_eq!(m.triangles.len(), 120);
        assert_eq!(m.triangles[116..], pyramid_mesh().triangles[..]);
        check_err(
            &bytes[..84 + 50 * 37 + 20],
            "file.stl: truncated binary STL: header says 120 triangles, file holds 37",
        );
        let mut long = bytes.clone();
        long.extend([0u8; 7]);
        check_err(
            &long,
            "file.stl: binary STL has 7 bytes after the 120 triangles",
        );
        check_err(
            &bytes[..40],
            "file.stl: not an OBJ or STL file (binary data, 40 bytes",
        );
    }

    #[test]
    fn binary_stl_with_nan_names_the_triangle() {
        let mut soup = pyramid();
        soup[2][1].z = f64::NAN;
        check_err(
            &binary_stl(&soup, b""),
            "file.stl: triangle 2: vertex 1 has a non-finite coordinate",
        );
        let bytes = binary_stl(&[], b"");
        check_err(
            &bytes,
            "file.stl: empty file (binary STL with no triangles)",
        );
    }

    #[test]
    fn mutated_stl_files_never_panic() {
        let ascii = ascii_stl(&pyramid());
        let binary = binary_stl(&pyramid(), b"solid");
        for base in [ascii.as_bytes(), &binary[..]] {
            for cut in 0..base.len() {
                if let Err(e) = read_tri_mesh(&base[..cut], "cut.stl") {
                    assert!(e.to_string().starts_with("cut.stl"), "{e}");
                }
            }
            for at in 0..base.len() {
                for r in [0u8, b' ', b'\n', b'-', b'x', 0xff, 0x7f] {
                    let mut m = base.to_vec();
                    m[at] = r;
                    if let Ok(mesh) = read_tri_mesh(&m, "m.stl") {
                        let n = mesh.vertices.len();
                        assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
                        assert!(mesh
                            .vertices
                            .iter()
                            .all(|p| p.iter().all(|c| c.is_finite())));
                    }
                }
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400)) {
            if let Err(e) = read_tri_mesh(&bytes, "b.stl") {
                proptest::prop_assert!(e.to_string().starts_with("b.stl"));
            }
        }

        #[test]
        fn arbitrary_binary_stl_never_panics(n in 0u32..4, body in proptest::collection::vec(proptest::num::u8::ANY, 0..250)) {
            let mut bytes = vec![0u8; 80];
            bytes.extend(n.to_le_bytes());
            bytes.extend(body);
            if let Ok(m) = read_tri_mesh(&bytes, "b.stl") {
                let count = m.vertices.len();
                proptest::prop_assert!(m.triangles.iter().flatten().all(|&i| i < count));
            }
        }
    }
}
