//! Connectivity of a quad mesh needed by the optimiser and the report: any valence, any
//! number of boundary loops.

use std::collections::HashMap;

use sv_frame::QuadMesh;

use crate::SurfaceError;

/// An interior vertex with its faces in cyclic order (any valence >= 3).
#[derive(Clone, Debug)]
pub(crate) struct Star {
    pub(crate) vertex: usize,
    /// `(face, corner)` pairs in cyclic order around the vertex.
    pub(crate) faces: Vec<(usize, usize)>,
}

pub(crate) struct Topology {
    pub(crate) boundary: Vec<bool>,
    /// The corners of the layout ([`QuadMesh::corners`]): they stay where they start.
    pub(crate) corner: Vec<bool>,
    /// Interior vertices with a closed fan.
    pub(crate) stars: Vec<Star>,
    /// Consecutive vertices `(a, b, c)` along a mesh polyline through a regular vertex `b`
    /// (interior with four faces, or on the boundary with two).
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
        let mut count = vec![0usize; nv];
        let mut boundary_nb: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for face in &mesh.faces {
            for k in 0..4 {
                count[face[k]] += 1;
                let (a, b) = (face[k], face[(k + 1) % 4]);
                if !edge_face.contains_key(&(b, a)) {
                    boundary[a] = true;
                    boundary[b] = true;
                    boundary_nb[a].push(b);
                    boundary_nb[b].push(a);
                }
            }
        }
        let stars: Vec<Star> = mesh
            .interior_fans()
            .into_iter()
            .filter(|(v, _)| !boundary[*v])
            .map(|(vertex, faces)| Star { vertex, faces })
            .collect();
        // in vertex order (the order of the optimiser's rows)
        let mut star_at = vec![None; nv];
        for (i, s) in stars.iter().enumerate() {
            star_at[s.vertex] = Some(i);
        }
        let mut triples = Vec::new();
        for v in 0..nv {
            match star_at[v].map(|i| &stars[i]) {
                Some(s) if s.faces.len() == 4 => {
                    let nb: Vec<usize> = s
                        .faces
                        .iter()
                        .map(|&(f, k)| mesh.faces[f][(k + 1) % 4])
                        .collect();
                    triples.push([nb[0], v, nb[2]]);
                    triples.push([nb[1], v, nb[3]]);
                }
                _ if boundary[v] && count[v] == 2 && boundary_nb[v].len() == 2 => {
                    triples.push([boundary_nb[v][0], v, boundary_nb[v][1]]);
                }
                _ => {}
            }
        }
        let corner = mesh.corners();
        Ok(Self {
            boundary,
            corner,
            stars,
            triples,
        })
    }
}
