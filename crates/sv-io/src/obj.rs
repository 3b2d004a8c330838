//! The Wavefront OBJ statements the readers need: `v` and `f`. Everything else that OBJ
//! defines (texture and normal vertices, groups, materials, free-form geometry, lines) is
//! skipped. Shared by [`crate::read_quad_obj`] and [`crate::read_tri_mesh`].

use sv_geom::Point3;

use crate::text::{is_binary_char, numbered_lines, snippet};
use crate::IoError;

/// OBJ statements that are valid but carry nothing a mesh reader needs.
const SKIPPED: &[&str] = &[
    "vt",
    "vn",
    "vp",
    "o",
    "g",
    "s",
    "usemtl",
    "mtllib",
    "l",
    "p",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "mg",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
];

/// A face as the file lists it, vertex indices resolved to 0-based.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ObjFace {
    /// Line of the `f` statement (1-based).
    pub line: usize,
    /// Vertex indices, 0-based, in range.
    pub vertices: Vec<usize>,
}

/// Vertices and faces of an OBJ file.
#[derive(Clone, Debug, PartialEq, Default)]
pub(crate) struct ObjData {
    /// Vertex positions (finite).
    pub vertices: Vec<Point3>,
    /// Faces, any number of vertices each.
    pub faces: Vec<ObjFace>,
}

/// A face vertex before positive indices are checked against the final vertex count
/// (OBJ allows a face to name a vertex listed later in the file).
struct RawFace {
    line: usize,
    vertices: Vec<usize>,
    /// The 1-based index as written, for messages.
    written: Vec<i64>,
}

/// Parse the `v` and `f` statements of `text`. `kind` names the expected format in the
/// "not a ... file" message (`"an OBJ"`).
pub(crate) fn parse_obj(text: &str, name: &str, kind: &str) -> Result<ObjData, IoError> {
    let mut vertices: Vec<Point3> = Vec::new();
    let mut raw_faces: Vec<RawFace> = Vec::new();
    let mut recognised = false;
    for (n, raw) in numbered_lines(text) {
        let not_obj = || {
            IoError::whole(
                name,
                format!("not {kind} file (line {n}: '{}')", snippet(raw)),
            )
        };
        if raw.chars().any(is_binary_char) {
            return Err(not_obj());
        }
        let content = raw.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let args: Vec<&str> = tokens.collect();
                vertices.push(parse_vertex(&args, name, n)?);
            }
            "f" | "fo" => {
                let count = vertices.len();
                let mut face = RawFace {
                    line: n,
                    vertices: Vec::new(),
                    written: Vec::new(),
                };
                for token in tokens {
                    let (index, written) = parse_face_vertex(token, count, name, n)?;
                    face.vertices.push(index);
                    face.written.push(written);
                }
                raw_faces.push(face);
            }
            k if SKIPPED.contains(&k) => {}
            _ if !recognised => return Err(not_obj()),
            _ => {
                return Err(IoError::line(
                    name,
                    n,
                    format!("unknown OBJ statement '{}'", snippet(keyword)),
                ))
            }
        }
        recognised = true;
    }
    if vertices.is_empty() && raw_faces.is_empty() {
        return Err(IoError::whole(name, "empty file (no vertices or faces)"));
    }
    let count = vertices.len();
    let mut faces = Vec::with_capacity(raw_faces.len());
    for face in raw_faces {
        if let Some(k) = face.vertices.iter().position(|&i| i >= count) {
            return Err(IoError::line(
                name,
                face.line,
                format!(
                    "vertex index {} out of range (file has {count} vertices)",
                    face.written[k]
                ),
            ));
        }
        faces.push(ObjFace {
            line: face.line,
            vertices: face.vertices,
        });
    }
    Ok(ObjData { vertices, faces })
}

/// `v x y z [w]`, also `v x y z r g b` (vertex colours, ignored) and `v x y z w r g b`.
fn parse_vertex(args: &[&str], name: &str, line: usize) -> Result<Point3, IoError> {
    if !matches!(args.len(), 3 | 4 | 6 | 7) {
        let got = std::iter::once("v")
            .chain(args.iter().copied())
            .collect::<Vec<_>>()
            .join(" ");
        return Err(IoError::line(
            name,
            line,
            format!("expected 'v x y z', got '{}'", snippet(&got)),
        ));
    }
    let mut xyz = [0.0; 3];
    for (k, token) in args.iter().enumerate() {
        let value: f64 = token.parse().map_err(|_| {
            IoError::line(
                name,
                line,
                format!("vertex coordinate \"{}\" is not a number", snippet(token)),
            )
        })?;
        if !value.is_finite() {
            return Err(IoError::line(
                name,
                line,
                format!(
                    "vertex coordinate \"{}\" is not a finite number",
                    snippet(token)
                ),
            ));
        }
        if k < 3 {
            xyz[k] = value;
        }
    }
    Ok(Point3::new(xyz[0], xyz[1], xyz[2]))
}

/// One face vertex `v`, `v/vt`, `v//vn` or `v/vt/vn`; returns the 0-based vertex index
/// (negative indices count back from the `count` vertices read so far) and the index as
/// written. Positive indices are checked against the vertex count later.
fn parse_face_vertex(
    token: &str,
    count: usize,
    name: &str,
    line: usize,
) -> Result<(usize, i64), IoError> {
    let bad = |why: &str| {
        IoError::line(
            name,
            line,
            format!("face vertex '{}' {why}", snippet(token)),
        )
    };
    let parts: Vec<&str> = token.split('/').collect();
    if parts.len() > 3 {
        return Err(bad("is not v, v/vt, v//vn or v/vt/vn"));
    }
    for part in &parts[1..] {
        if !part.is_empty() && part.parse::<i64>().is_err() {
            return Err(bad("is not v, v/vt, v//vn or v/vt/vn"));
        }
    }
    let written: i64 = parts[0]
        .parse()
        .map_err(|_| bad("does not start with an integer vertex index"))?;
    let index = if written > 0 {
        usize::try_from(written - 1).ok()
    } else if written < 0 {
        // relative: -1 is the last vertex read so far
        usize::try_from(written.unsigned_abs())
            .ok()
            .and_then(|back| count.checked_sub(back))
    } else {
        return Err(IoError::line(
            name,
            line,
            "vertex index 0 is invalid (OBJ indices start at 1)",
        ));
    };
    match index {
        Some(i) => Ok((i, written)),
        None if written < 0 => Err(IoError::line(
            name,
            line,
            format!("vertex index {written} out of range ({count} vertices read before this line)"),
        )),
        None => Err(IoError::line(
            name,
            line,
            format!("vertex index {written} out of range"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<ObjData, IoError> {
        parse_obj(text, "t.obj", "an OBJ")
    }

    #[test]
    fn all_face_forms_and_relative_indices() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n\
                    f 1 2/1 3//1 4/1/1\nf -4 -3 -2 -1\n";
        let data = parse(text).unwrap();
        assert_eq!(data.faces.len(), 2);
        assert_eq!(data.faces[0].vertices, vec![0, 1, 2, 3]);
        assert_eq!(data.faces[1].vertices, vec![0, 1, 2, 3]);
        assert_eq!(data.faces[1].line, 8);
    }

    #[test]
    fn forward_references_are_allowed() {
        let data = parse("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
        assert_eq!(data.faces[0].vertices, vec![0, 1, 2]);
    }

    #[test]
    fn bad_face_vertices_name_the_line() {
        let cases = [
            ("v 0 0 0\nf 1 0 1\n", "t.obj:2: vertex index 0 is invalid"),
            (
                "v 0 0 0\nf 1 -2 1\n",
                "t.obj:2: vertex index -2 out of range (1 vertices read",
            ),
            (
                "v 0 0 0\nf 1 x 1\n",
                "t.obj:2: face vertex 'x' does not start",
            ),
            ("v 0 0 0\nf 1 1/2/3/4 1\n", "t.obj:2: face vertex '1/2/3/4'"),
            ("v 0 0 0\nf 1 1/a 1\n", "t.obj:2: face vertex '1/a'"),
            (
                "v 0 0 0\n\nf 1 99999999999999999999 1\n",
                "t.obj:3: face vertex",
            ),
            (
                "v 0 0 0\nf 1 9223372036854775807 1\n",
                "t.obj:2: vertex index 9223372036854775807 out of range (file has 1",
            ),
            (
                "v 0 0 0\nf 1 -9223372036854775808 1\n",
                "t.obj:2: vertex index -9223372036854775808 out of range",
            ),
            (
                "v 0 0 0\nv 1 2 3\nfoo 1\n",
                "t.obj:3: unknown OBJ statement 'foo'",
            ),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.starts_with(want), "{e:?} does not start with {want:?}");
        }
    }
}
