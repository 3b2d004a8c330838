//! Connectivity of a quad mesh needed by the optimiser and the report.

use std::collections::HashMap;

use sv_frame::QuadMesh;

use crate::SurfaceError;

/// An interior valence-4 vertex with its faces in cyclic order.
#[derive(Clone, Debug)]
pub(crate) struct Star {
    pub(crate) vertex: usize,
    /// `(face, corner)` pairs in cyclic order around the vertex.
    pub(crate) faces: [(usize, usize); 4],
}

pub(crate) struct Topology {
    pub(crate) boundary: Vec<bool>,
    /// Boundary vertices with a single face (grid corners).
    pub(crate) corner: Vec<bool>,
    pub(crate) stars: Vec<Star>,
    /// Consecutive vertices `(a, b, c)` along a grid polyline through `b`.
    pub(crate) triples: Vec<[usize; 3]>,
}

impl Topology {
    pub(crate) fn new(mesh: &QuadMesh) -> Result<Self, SurfaceError> {
        let nv = mesh.vertices.len();
        let mut edge_face: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..4 {
                if face[k] >= nv {
                    return Err(SurfaceError::InvalidParameter(format!(
                        "face {f} uses vertex {}, but there are only {nv} vertices",
                        face[k]
                    )));
                }
                if edge_face
                    .insert((face[k], face[(k + 1) % 4]), (f, k))
                    .is_some()
                {
                    return Err(SurfaceError::InvalidParameter(format!(
                        "edge ({}, {}) of face {f} is non-manifold or inconsistently oriented",
                        face[k],
                        face[(k + 1) % 4]
                    )));
                }
            }
        }
        let mut boundary = vec![false; nv];
        let mut corners: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nv];
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..4 {
                corners[face[k]].push((f, k));
                let (a, b) = (face[k], face[(k + 1) % 4]);
                if !edge_face.contains_key(&(b, a)) {
                    boundary[a] = true;
                    boundary[b] = true;
                }
            }
        }
        let mut stars = Vec::new();
        let mut triples = Vec::new();
        for v in 0..nv {
            let cs = &corners[v];
            if !boundary[v] && cs.len() == 4 {
                let mut order = [cs[0]; 4];
                let mut ok = true;
                for s in 1..4 {
                    let (f, k) = order[s - 1];
                    let next = mesh.faces[f][(k + 1) % 4];
                    match edge_face.get(&(next, v)) {
                        Some(&(g, m)) => order[s] = (g, (m + 1) % 4),
                        None => ok = false,
                    }
                }
                if ok {
                    stars.push(Star {
                        vertex: v,
                        faces: order,
                    });
                    // neighbours in cyclic order: next of each corner
                    let nb = order.map(|(f, k)| mesh.faces[f][(k + 1) % 4]);
                    triples.push([nb[0], v, nb[2]]);
                    triples.push([nb[1], v, nb[3]]);
                }
            } else if boundary[v] && cs.len() == 2 {
                // the two boundary neighbours
                let mut nb = Vec::new();
                for &(f, k) in cs {
                    let face = mesh.faces[f];
                    let (next, prev) = (face[(k + 1) % 4], face[(k + 3) % 4]);
                    if !edge_face.contains_key(&(next, v)) {
                        nb.push(next);
                    }
                    if !edge_face.contains_key(&(v, prev)) {
                        nb.push(prev);
                    }
                }
                if nb.len() == 2 {
                    triples.push([nb[0], v, nb[1]]);
                }
            }
        }
        let corner = (0..nv)
            .map(|v| boundary[v] && corners[v].len() == 1)
            .collect();
        Ok(Self {
            boundary,
            corner,
            stars,
            triples,
        })
    }
}
