//! STL, ASCII and binary, read as a triangle soup (each triangle with its own corners).

use sv_geom::Point3;

use crate::text::{numbered_lines, snippet};
use crate::IoError;

/// Bytes before the first triangle of a binary STL: an 80-byte header and a `u32` count.
pub(crate) const STL_HEADER_BYTES: usize = 84;
/// Bytes per triangle of a binary STL: normal, three corners (12 `f32`), attribute `u16`.
const STL_TRIANGLE_BYTES: usize = 50;

/// The size a binary STL must have for the triangle count in its header, or `None` when
/// `bytes` is shorter than the header.
pub(crate) fn binary_stl_size(bytes: &[u8]) -> Option<usize> {
    let count = bytes.get(80..84)?;
    let n = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as usize;
    Some(STL_HEADER_BYTES + STL_TRIANGLE_BYTES * n)
}

/// Triangles of a binary STL whose size matches its header (checked by the caller).
pub(crate) fn read_binary_stl(bytes: &[u8], name: &str) -> Result<Vec<[Point3; 3]>, IoError> {
    let body = bytes.get(STL_HEADER_BYTES..).unwrap_or(&[]);
    if body.is_empty() {
        return Err(IoError::whole(
            name,
            "empty file (binary STL with no triangles)",
        ));
    }
    let mut soup = Vec::with_capacity(body.len() / STL_TRIANGLE_BYTES);
    for (t, record) in body.chunks_exact(STL_TRIANGLE_BYTES).enumerate() {
        let f = |k: usize| {
            let at = 12 + 4 * k;
            f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]]) as f64
        };
        let mut tri = [Point3::origin(); 3];
        for (c, corner) in tri.iter_mut().enumerate() {
            *corner = Point3::new(f(3 * c), f(3 * c + 1), f(3 * c + 2));
            if !corner.iter().all(|x| x.is_finite()) {
                return Err(IoError::Triangle {
                    file: name.to_string(),
                    triangle: t,
                    message: format!("vertex {c} has a non-finite coordinate"),
                });
            }
        }
        soup.push(tri);
    }
    Ok(soup)
}

/// Where the ASCII STL reader is.
#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    /// Before `solid` or after `endsolid`.
    Outside,
    /// Inside `solid`, between facets.
    Solid,
    /// After `facet normal`, before `outer loop`.
    Facet,
    /// Inside `outer loop`.
    Loop,
    /// After `endloop`, before `endfacet`.
    AfterLoop,
}

impl State {
    fn expected(self) -> &'static str {
        match self {
            State::Outside => "solid",
            State::Solid => "facet normal' or 'endsolid",
            State::Facet => "outer loop",
            State::Loop => "vertex x y z' or 'endloop",
            State::AfterLoop => "endfacet",
        }
    }
}

/// Triangles of an ASCII STL (`solid` ... `endsolid`, several solids allowed). A facet
/// loop with more than three vertices is fan-triangulated. Keywords are case-insensitive.
pub(crate) fn read_ascii_stl(text: &str, name: &str) -> Result<Vec<[Point3; 3]>, IoError> {
    let mut state = State::Outside;
    let mut soup = Vec::new();
    let mut corners: Vec<Point3> = Vec::new();
    let mut last_line = 1;
    for (n, raw) in numbered_lines(text) {
        last_line = n;
        let tokens: Vec<&str> = raw.split_whitespace().collect();
        let Some(first) = tokens.first() else {
            continue;
        };
        let keyword = first.to_ascii_lowercase();
        let second = tokens.get(1).map(|s| s.to_ascii_lowercase());
        let unexpected = || {
            IoError::line(
                name,
                n,
                format!("expected '{}', got '{}'", state.expected(), snippet(raw)),
            )
        };
        state = match (state, keyword.as_str()) {
            (State::Outside, "solid") => State::Solid,
            (State::Solid, "facet") if second.as_deref() == Some("normal") => State::Facet,
            (State::Solid, "endsolid") => State::Outside,
            (State::Facet, "outer") if second.as_deref() == Some("loop") => {
                corners.clear();
                State::Loop
            }
            (State::Loop, "vertex") => {
                corners.push(parse_stl_vertex(&tokens[1..], raw, name, n)?);
                State::Loop
            }
            (State::Loop, "endloop") => {
                if corners.len() < 3 {
                    return Err(IoError::line(
                        name,
                        n,
                        format!("facet has {} vertices; a triangle needs 3", corners.len()),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    soup.push([corners[0], corners[k], corners[k + 1]]);
                }
                State::AfterLoop
            }
            (State::AfterLoop, "endfacet") => State::Solid,
            _ => return Err(unexpected()),
        };
    }
    if state != State::Outside {
        return Err(IoError::line(
            name,
            last_line,
            format!(
                "file ends where '{}' was expected (truncated?)",
                state.expected()
            ),
        ));
    }
    if soup.is_empty() {
        return Err(IoError::whole(
            name,
            "empty file (ASCII STL with no facets)",
        ));
    }
    Ok(soup)
}

fn parse_stl_vertex(args: &[&str], raw: &str, name: &str, line: usize) -> Result<Point3, IoError> {
    if args.len() != 3 {
        return Err(IoError::line(
            name,
            line,
            format!("expected 'vertex x y z', got '{}'", snippet(raw)),
        ));
    }
    let mut xyz = [0.0f64; 3];
    for (x, token) in xyz.iter_mut().zip(args) {
        *x = token.parse().map_err(|_| {
            IoError::line(
                name,
                line,
                format!("vertex coordinate \"{}\" is not a number", snippet(token)),
            )
        })?;
        if !x.is_finite() {
            return Err(IoError::line(
                name,
                line,
                format!(
                    "vertex coordinate \"{}\" is not a finite number",
                    snippet(token)
                ),
            ));
        }
    }
    Ok(Point3::new(xyz[0], xyz[1], xyz[2]))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::read_tri_mesh;

    /// An ASCII STL of `soup` (normals zero, as many exporters leave them).
    pub(crate) fn ascii_stl(soup: &[[Point3; 3]]) -> String {
        let mut s = String::from("solid patch\n");
        for t in soup {
            s.push_str("  facet normal 0 0 0\n    outer loop\n");
            for p in t {
                s.push_str(&format!("      vertex {:e} {:e} {:e}\n", p.x, p.y, p.z));
            }
            s.push_str("    endloop\n  endfacet\n");
        }
        s.push_str("endsolid patch\n");
        s
    }

    /// A binary STL of `soup` (as `f32`) whose header starts with `header`.
    pub(crate) fn binary_stl(soup: &[[Point3; 3]], header: &[u8]) -> Vec<u8> {
        let mut b = vec![0u8; 80];
        b[..header.len()].copy_from_slice(header);
        b.extend((soup.len() as u32).to_le_bytes());
        for t in soup {
            b.extend([0u8; 12]);
            for p in t {
                for x in p.iter() {
                    b.extend((*x as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    }

    fn err(text: &str) -> String {
        match read_tri_mesh(text.as_bytes(), "file.stl") {
            Ok(m) => panic!("expected an error, got {m:?}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn ascii_keywords_any_case_crlf_and_quads() {
        let text = "SOLID x\r\n facet normal 0 0 1\r\n  outer loop\r\n   vertex 0 0 0\r\n\
                    \tvertex 1 0 0\r\n   VERTEX 1 1 0\r\n   vertex 0 1 0\r\n  endloop\r\n \
                    endfacet\r\nendsolid\r\nsolid second\r\nendsolid";
        let m = read_tri_mesh(text.as_bytes(), "q.stl").unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn bad_ascii_names_file_and_line() {
        let good = ascii_stl(&[[
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ]]);
        let nan = good.replacen("vertex 1e0 0e0", "vertex NaN 0e0", 1);
        assert_eq!(
            err(&nan),
            "file.stl:5: vertex coordinate \"NaN\" is not a finite number"
        );
        let two = good.replacen("vertex 1e0 0e0 0e0", "vertex 1 0", 1);
        assert_eq!(
            err(&two),
            "file.stl:5: expected 'vertex x y z', got 'vertex 1 0'"
        );
        let word = good.replacen("vertex 1e0 0e0 0e0", "vertex 1 zero 0", 1);
        assert_eq!(
            err(&word),
            "file.stl:5: vertex coordinate \"zero\" is not a number"
        );
        let cut = &good[..good.find("endloop").unwrap()];
        assert_eq!(
            err(cut),
            "file.stl:7: file ends where 'vertex x y z' or 'endloop' was expected (truncated?)"
        );
        let no_end = good.replace("endsolid patch\n", "");
        assert_eq!(
            err(&no_end),
            "file.stl:9: file ends where 'facet normal' or 'endsolid' was expected (truncated?)"
        );
        let short = good.replacen("      vertex 0e0 1e0 0e0\n", "", 1);
        assert_eq!(
            err(&short),
            "file.stl:6: facet has 2 vertices; a triangle needs 3"
        );
        let wrong = good.replacen("outer loop", "inner loop", 1);
        assert_eq!(
            err(&wrong),
            "file.stl:3: expected 'outer loop', got 'inner loop'"
        );
        assert_eq!(
            err("solid empty\nendsolid empty\n"),
            "file.stl: empty file (ASCII STL with no facets)"
        );
        assert_eq!(err(""), "file.stl: empty file (no vertices or faces)");
    }
}
