//! Target surfaces as a user hands them over: a triangle mesh read with [`read_tri_mesh`]'s
//! rules, then repaired where the intent is plain and checked where it is not, every
//! message naming the file's own place (1-based line of the `f` statement of an OBJ, facet
//! number of an STL, 1-based vertex numbers of the file).
//!
//! Repairs (counted in [`TargetRepairs`]): corners that coincide are welded (an OBJ
//! triangle soup, like STL, lists every triangle's own corners), triangles that collapse
//! under welding are dropped, and triangles listed against their neighbours' orientation
//! are turned (in each connected piece the larger part keeps its orientation).
//! Refused, naming the place: an edge with more than two triangles, a surface that cannot
//! be oriented (a Moebius band), zero-area triangles, more than one piece, no boundary.

use std::collections::HashMap;

use sv_geom::Point3;

use crate::obj::parse_obj;
use crate::reach::within_reach;
use crate::stl::{binary_stl_size, read_ascii_stl, read_binary_stl};
use crate::text::{decode, is_binary_char};
use crate::tri_mesh::{read_tri_mesh, weld_indexed, WELD_RELATIVE_TOLERANCE};
use crate::{IoError, TriMesh};

/// What reading a target repaired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct TargetRepairs {
    /// OBJ vertices merged into another one at the same place (STL corners are always
    /// welded and not counted).
    pub welded: usize,
    /// OBJ vertices no face uses (left out).
    pub unused: usize,
    /// Triangles dropped because their corners coincide after welding.
    pub dropped: usize,
    /// Triangles turned to the orientation of their neighbours.
    pub flipped: usize,
}

/// A target as read: the mesh (mm) and what was repaired.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetFile {
    /// The welded, consistently oriented triangle mesh.
    pub mesh: TriMesh,
    /// What was repaired.
    pub repairs: TargetRepairs,
}

/// Where a triangle came from, for messages.
#[derive(Clone, Copy, Debug)]
enum Place {
    /// The line of its `f` statement (OBJ).
    Line(usize),
    /// Its facet number, 1-based (STL).
    Facet(usize),
}

impl Place {
    fn describe(self) -> String {
        match self {
            Place::Line(n) => format!("the triangle on line {n}"),
            Place::Facet(n) => format!("facet {n}"),
        }
    }
}

/// Read a target surface: [`read_tri_mesh`], then the repairs and checks of the module
/// documentation.
pub fn read_target(bytes: &[u8], name: &str) -> Result<TargetFile, IoError> {
    // the plain reader's errors (syntax, numbers, truncation) come first
    let plain = read_tri_mesh(bytes, name)?;
    let (corners, places, numbers) = located_soup(bytes, name, &plain)?;
    // corner `k` of soup triangle `t` as the file names it
    let corner_name = |t: usize, k: usize| match numbers.get(t) {
        Some(n) => format!("vertex {}", n[k]),
        None => format!("corner {} of {}", k + 1, places[t].describe()),
    };
    // the surface's size, the weld tolerance and areas are finite numbers: no vertex far out
    for (t, tri) in corners.iter().enumerate() {
        for (k, p) in tri.iter().enumerate() {
            within_reach(name, p, || corner_name(t, k))?;
        }
    }
    let (mut mesh, first, dropped) = weld_indexed(&corners, WELD_RELATIVE_TOLERANCE);
    // the file's vertex number of every welded vertex (its first occurrence)
    let vertex_name: Vec<String> = first.iter().map(|&(t, k)| corner_name(t, k)).collect();
    let kept: Vec<Place> = places
        .iter()
        .enumerate()
        .filter(|(t, _)| !dropped.contains(t))
        .map(|(_, p)| *p)
        .collect();
    // STL always lists every triangle's own corners: welding them is reading it, not a
    // repair; an OBJ that repeats its vertices is a soup
    let mut used = vec![false; plain.vertices.len()];
    plain
        .triangles
        .iter()
        .flatten()
        .for_each(|&v| used[v] = true);
    let used = used.iter().filter(|&&u| u).count();
    let (welded, unused) = if numbers.is_empty() {
        (0, 0)
    } else {
        (
            used.saturating_sub(mesh.vertices.len()),
            plain.vertices.len() - used,
        )
    };
    let mut repairs = TargetRepairs {
        welded,
        unused,
        dropped: dropped.len(),
        flipped: 0,
    };
    if mesh.triangles.is_empty() {
        return Err(IoError::whole(
            name,
            "every triangle is degenerate (its corners coincide)",
        ));
    }
    // zero area
    let (lo, hi) = mesh
        .vertices
        .iter()
        .fold((mesh.vertices[0], mesh.vertices[0]), |(a, b), p| {
            (a.inf(p), b.sup(p))
        });
    let diag = (hi - lo).norm();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| mesh.vertices[i]);
        if 0.5 * (b - a).cross(&(c - a)).norm() <= 1e-12 * diag * diag {
            return Err(IoError::whole(
                name,
                format!(
                    "{} has zero area (its corners are collinear)",
                    kept[t].describe()
                ),
            ));
        }
    }
    // edges: at most two triangles each
    let mut edges: HashMap<(usize, usize), Vec<(usize, bool)>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((t, a < b));
        }
    }
    let mut keys: Vec<&(usize, usize)> = edges.keys().collect();
    keys.sort_unstable();
    for key in keys {
        let users = &edges[key];
        if users.len() > 2 {
            let list: Vec<String> = users.iter().map(|&(t, _)| kept[t].describe()).collect();
            return Err(IoError::whole(
                name,
                format!(
                    "the edge from {} to {} has {} triangles ({}); a surface has at most two on an edge",
                    vertex_name[key.0],
                    vertex_name[key.1],
                    users.len(),
                    list.join(", ")
                ),
            ));
        }
    }
    // orientation: breadth first over the pieces, turning what disagrees
    let n = mesh.triangles.len();
    let mut flip: Vec<Option<bool>> = vec![None; n];
    let mut neighbours: Vec<Vec<(usize, bool)>> = vec![Vec::new(); n];
    for users in edges.values() {
        if let [(s, ds), (t, dt)] = users[..] {
            // same direction along the shared edge: the two disagree
            neighbours[s].push((t, ds == dt));
            neighbours[t].push((s, ds == dt));
        }
    }
    let mut pieces = 0;
    for seed in 0..n {
        if flip[seed].is_some() {
            continue;
        }
        pieces += 1;
        if pieces > 1 {
            return Err(IoError::whole(
                name,
                format!(
                    "{} is not connected to {} (the target must be one piece)",
                    kept[seed].describe(),
                    kept[0].describe()
                ),
            ));
        }
        flip[seed] = Some(false);
        let mut queue = std::collections::VecDeque::from([seed]);
        let mut members = vec![seed];
        while let Some(s) = queue.pop_front() {
            let fs = flip[s].unwrap_or(false);
            for &(t, disagree) in &neighbours[s] {
                let want = fs ^ disagree;
                match flip[t] {
                    None => {
                        flip[t] = Some(want);
                        queue.push_back(t);
                        members.push(t);
                    }
                    Some(f) if f != want => {
                        return Err(IoError::whole(
                            name,
                            format!(
                                "the surface cannot be oriented (a Moebius band): {} and {} cannot face the same side",
                                kept[s].describe(),
                                kept[t].describe()
                            ),
                        ));
                    }
                    Some(_) => {}
                }
            }
        }
        let turned = members.iter().filter(|&&t| flip[t] == Some(true)).count();
        if 2 * turned > members.len() {
            for &t in &members {
                flip[t] = flip[t].map(|f| !f);
            }
        }
    }
    for (t, f) in flip.iter().enumerate() {
        if *f == Some(true) {
            mesh.triangles[t].swap(1, 2);
            repairs.flipped += 1;
        }
    }
    if edges.values().all(|u| u.len() == 2) {
        return Err(IoError::whole(
            name,
            "the surface is closed (no boundary edge); a target is a patch with a boundary",
        ));
    }
    Ok(TargetFile { mesh, repairs })
}

/// Every triangle's corners, its place in the file, and (OBJ) the file's 1-based vertex
/// numbers of its corners.
type Located = (Vec<[Point3; 3]>, Vec<Place>, Vec<[usize; 3]>);

fn located_soup(bytes: &[u8], name: &str, plain: &TriMesh) -> Result<Located, IoError> {
    if binary_stl_size(bytes) == Some(bytes.len()) {
        let soup = read_binary_stl(bytes, name)?;
        let places = (1..=soup.len()).map(Place::Facet).collect();
        return Ok((soup, places, Vec::new()));
    }
    let text = decode(bytes);
    let first_word = text
        .trim_start_matches('\u{feff}')
        .split_whitespace()
        .next()
        .unwrap_or("");
    if !text.contains(is_binary_char) && first_word.eq_ignore_ascii_case("solid") {
        let soup = read_ascii_stl(&text, name)?;
        let places = (1..=soup.len()).map(Place::Facet).collect();
        return Ok((soup, places, Vec::new()));
    }
    let data = parse_obj(&text, name, "an OBJ or STL")?;
    let mut soup = Vec::new();
    let mut places = Vec::new();
    let mut numbers = Vec::new();
    for face in &data.faces {
        let v = &face.vertices;
        for k in 1..v.len().saturating_sub(1) {
            let tri = [v[0], v[k], v[k + 1]];
            soup.push(tri.map(|i| plain.vertices[i]));
            places.push(Place::Line(face.line));
            numbers.push(tri.map(|i| i + 1));
        }
    }
    Ok((soup, places, numbers))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 1 strip of squares as an OBJ triangle soup (every triangle its own corners).
    fn soup_obj(flip_last: bool) -> String {
        let quads = [[0.0, 0.0], [300.0, 0.0]];
        let mut s = String::new();
        let mut n = 0;
        let mut faces = Vec::new();
        for q in quads {
            let c = [
                [q[0], q[1]],
                [q[0] + 300.0, q[1]],
                [q[0] + 300.0, q[1] + 300.0],
                [q[0], q[1] + 300.0],
            ];
            for tri in [[0, 1, 2], [0, 2, 3]] {
                for &k in &tri {
                    s.push_str(&format!("v {} {} 0\n", c[k][0], c[k][1]));
                }
                faces.push([n + 1, n + 2, n + 3]);
                n += 3;
            }
        }
        for (i, f) in faces.iter().enumerate() {
            if flip_last && i == 3 {
                s.push_str(&format!("f {} {} {}\n", f[0], f[2], f[1]));
            } else {
                s.push_str(&format!("f {} {} {}\n", f[0], f[1], f[2]));
            }
        }
        s
    }

    #[test]
    fn obj_triangle_soup_is_welded_and_oriented() {
        let t = read_target(soup_obj(true).as_bytes(), "soup.obj").unwrap();
        assert_eq!(t.mesh.vertices.len(), 6);
        assert_eq!(t.mesh.triangles.len(), 4);
        assert_eq!(t.repairs.welded, 12 - 6);
        assert_eq!(t.repairs.flipped, 1);
        // every triangle now faces +Z
        for tri in &t.mesh.triangles {
            let [a, b, c] = tri.map(|i| t.mesh.vertices[i]);
            assert!((b - a).cross(&(c - a)).z > 0.0);
        }
    }

    #[test]
    fn vertices_no_face_uses_are_left_out_not_welded() {
        // the soup plus two vertices no face names, one of them far off
        let text = format!("{}v 5 5 5\nv 1e7 0 0\n", soup_obj(true));
        let t = read_target(text.as_bytes(), "soup.obj").unwrap();
        assert_eq!(t.mesh.vertices.len(), 6);
        assert_eq!((t.repairs.welded, t.repairs.unused), (12 - 6, 2));
        let clean = read_target(soup_obj(true).as_bytes(), "soup.obj").unwrap();
        assert_eq!(clean.repairs.unused, 0);
    }

    /// The error reading `text` as `t.obj`.
    fn error_of(text: &str) -> String {
        read_target(text.as_bytes(), "t.obj")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn bad_targets_name_the_line() {
        // a third triangle on the edge between vertices 2 and 3 (file numbers)
        let text =
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 1\nf 1 2 3\nf 1 3 4\nf 3 2 5\nf 2 3 5\n";
        let e = error_of(text);
        assert!(e.starts_with("t.obj: the edge from vertex 2 to vertex 3 has 3 triangles (the triangle on line 6, the triangle on line 8, the triangle on line 9)"), "{e}");
        let text = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n";
        let e = error_of(text);
        assert_eq!(
            e,
            "t.obj: the triangle on line 6 has zero area (its corners are collinear)"
        );
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\nf 4 5 6\n";
        let e = error_of(text);
        assert_eq!(e, "t.obj: the triangle on line 8 is not connected to the triangle on line 7 (the target must be one piece)");
        let tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
        let e = error_of(tetra);
        assert!(e.contains("closed"), "{e}");
    }

    /// A vertex at 1e308 overflowed the bounding box, the zero-area check passed on NaN and
    /// the target was read, its areas infinite.
    #[test]
    fn a_vertex_far_out_is_refused_not_read_as_nan() {
        let text = "v 0 0 0\nv 1 0 0\nv 1e308 -1e308 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
        let e = error_of(text);
        assert_eq!(e, "t.obj: vertex 3 at (1e308, -1e308, 0) is farther than 1e12 mm from the origin (a corrupt number, or not in mm?)");
        // site coordinates (a UTM northing in mm) are read
        let text = "v 0 5e9 0\nv 1 5e9 0\nv 1 5000000001 0\nf 1 2 3\n";
        assert!(read_target(text.as_bytes(), "t.obj").is_ok());
    }
}
