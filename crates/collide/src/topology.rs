//! Connectivity tables of a polygon mesh, built once per topology.
//!
//! Faces arrive as CSR (`face_offsets`, `face_vertices`), the layout of `tailor_subdiv::Mesh`.
//! Each polygon `v0 v1 … vk` is fan-triangulated into `(v0, vi, vi+1)`, so face `f` owns the
//! triangles `face_offsets[f] - 2f .. face_offsets[f+1] - 2(f+1)`; the exact tests run on those
//! triangles and their edges (polygon edges and fan diagonals).
//!
//! For continuous collision every vertex and every edge is *owned* by the first face that uses it
//! (Bridson, Fedkiw & Anderson 2002 test each vertex–triangle and edge–edge pair once): a pair of
//! leaves `(f, g)` then tests the features owned by `f` against those of `g`, and no pair of
//! features is ever tested twice.

use crate::error::CollideError;
use crate::memory::heap;

/// Validated faces with their fan triangles, edges and feature owners. All tables are flat.
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    pub(crate) vertex_count: usize,
    pub(crate) face_offsets: Vec<u32>,
    pub(crate) face_vertices: Vec<u32>,
    /// Fan triangles, in face order.
    pub(crate) triangles: Vec<[u32; 3]>,
    /// The face each triangle belongs to.
    pub(crate) triangle_face: Vec<u32>,
    /// Unique undirected triangle edges `[low, high]`, sorted.
    pub(crate) edges: Vec<[u32; 2]>,
    /// How many triangles use each edge (2 everywhere on a closed manifold).
    pub(crate) edge_triangle_count: Vec<u32>,
    /// Pairs of distinct faces sharing an edge, `f < g`, sorted and unique.
    pub(crate) adjacency: Vec<[u32; 2]>,
    /// The face owning each vertex (the first that uses it), `u32::MAX` for an unused one.
    pub(crate) vertex_owner: Vec<u32>,
    /// CSR: the vertices each face owns.
    pub(crate) owned_vertex_offsets: Vec<u32>,
    pub(crate) owned_vertices: Vec<u32>,
    /// CSR: the edges (indices into `edges`) each face owns.
    pub(crate) owned_edge_offsets: Vec<u32>,
    pub(crate) owned_edges: Vec<u32>,
    /// How many fan triangles every face has, when all faces have the same size (a triangle
    /// or quad mesh): the triangles of a face then follow from its index alone.
    uniform_fan: Option<u32>,
}

impl Topology {
    /// Validates the CSR faces against `vertex_count` and builds every table.
    pub(crate) fn new(
        vertex_count: usize,
        face_offsets: &[u32],
        face_vertices: &[u32],
    ) -> Result<Self, CollideError> {
        validate(vertex_count, face_offsets, face_vertices)?;
        let face_count = face_offsets.len() - 1;
        let mut triangles = Vec::with_capacity(face_vertices.len() - 2 * face_count);
        let mut triangle_face = Vec::with_capacity(triangles.capacity());
        for f in 0..face_count {
            let corners = &face_vertices[face_offsets[f] as usize..face_offsets[f + 1] as usize];
            for pair in corners[1..].windows(2) {
                triangles.push([corners[0], pair[0], pair[1]]);
                triangle_face.push(f as u32);
            }
        }

        // Every triangle edge with the face using it, bucketed by its lower vertex (a counting
        // sort) and sorted within each bucket, which groups the users of one edge, lowest face
        // first, so the first user is the owner.
        let mut bucket = vec![0u32; vertex_count + 1];
        for [a, b, c] in &triangles {
            for low in [a.min(b), b.min(c), c.min(a)] {
                bucket[*low as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            bucket[v + 1] += bucket[v];
        }
        let mut cursor = bucket.clone();
        let mut uses: Vec<([u32; 2], u32)> = vec![([0, 0], 0); 3 * triangles.len()];
        for (t, &[a, b, c]) in triangles.iter().enumerate() {
            for (p, q) in [(a, b), (b, c), (c, a)] {
                let slot = &mut cursor[p.min(q) as usize];
                uses[*slot as usize] = ([p.min(q), p.max(q)], triangle_face[t]);
                *slot += 1;
            }
        }
        for w in bucket.windows(2) {
            uses[w[0] as usize..w[1] as usize].sort_unstable();
        }
        let mut edges = Vec::new();
        let mut edge_triangle_count = Vec::new();
        let mut edge_owner = Vec::new();
        let mut adjacency = Vec::new();
        for group in uses.chunk_by(|x, y| x.0 == y.0) {
            edges.push(group[0].0);
            edge_triangle_count.push(group.len() as u32);
            edge_owner.push(group[0].1);
            for pair in group.windows(2) {
                if pair[0].1 != pair[1].1 {
                    adjacency.push([pair[0].1, pair[1].1]);
                }
            }
        }
        adjacency.sort_unstable();
        adjacency.dedup();

        let mut vertex_owner = vec![u32::MAX; vertex_count];
        for f in 0..face_count {
            for &v in &face_vertices[face_offsets[f] as usize..face_offsets[f + 1] as usize] {
                let owner = &mut vertex_owner[v as usize];
                if *owner == u32::MAX {
                    *owner = f as u32;
                }
            }
        }
        let (owned_vertex_offsets, owned_vertices) = group_by_owner(&vertex_owner, face_count);
        let (owned_edge_offsets, owned_edges) = group_by_owner(&edge_owner, face_count);
        // The tables live as long as the mesh: give back what growing them left over.
        for table in [&mut edges, &mut adjacency] {
            table.shrink_to_fit();
        }
        edge_triangle_count.shrink_to_fit();
        Ok(Self {
            vertex_count,
            face_offsets: face_offsets.to_vec(),
            face_vertices: face_vertices.to_vec(),
            triangles,
            triangle_face,
            edges,
            edge_triangle_count,
            adjacency,
            vertex_owner,
            owned_vertex_offsets,
            owned_vertices,
            owned_edge_offsets,
            owned_edges,
            uniform_fan: uniform_fan(face_offsets),
        })
    }

    /// Heap bytes held by the tables.
    pub(crate) fn memory_bytes(&self) -> usize {
        heap(&self.face_offsets)
            + heap(&self.face_vertices)
            + heap(&self.triangles)
            + heap(&self.triangle_face)
            + heap(&self.edges)
            + heap(&self.edge_triangle_count)
            + heap(&self.adjacency)
            + heap(&self.vertex_owner)
            + heap(&self.owned_vertex_offsets)
            + heap(&self.owned_vertices)
            + heap(&self.owned_edge_offsets)
            + heap(&self.owned_edges)
    }

    /// Number of faces.
    pub(crate) fn face_count(&self) -> usize {
        self.face_offsets.len() - 1
    }

    /// The corners of face `f`.
    pub(crate) fn face(&self, f: u32) -> &[u32] {
        let f = f as usize;
        &self.face_vertices[self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize]
    }

    /// The indices of the fan triangles of face `f`.
    pub(crate) fn face_triangles(&self, f: u32) -> std::ops::Range<usize> {
        match self.uniform_fan {
            Some(k) => (f * k) as usize..((f + 1) * k) as usize,
            None => face_triangle_range(&self.face_offsets, f as usize),
        }
    }

    /// The vertices face `f` owns.
    pub(crate) fn owned_vertices(&self, f: u32) -> &[u32] {
        let f = f as usize;
        let range =
            self.owned_vertex_offsets[f] as usize..self.owned_vertex_offsets[f + 1] as usize;
        &self.owned_vertices[range]
    }

    /// The edges (indices into `edges`) face `f` owns.
    pub(crate) fn owned_edges(&self, f: u32) -> &[u32] {
        let f = f as usize;
        let range = self.owned_edge_offsets[f] as usize..self.owned_edge_offsets[f + 1] as usize;
        &self.owned_edges[range]
    }

    /// Whether two faces share at least one vertex. Two quads, the common case, compare all
    /// sixteen corner pairs without a branch.
    pub(crate) fn faces_share_vertex(&self, f: u32, g: u32) -> bool {
        let (face, other) = (self.face(f), self.face(g));
        if let (Ok(a), Ok(b)) = (<&[u32; 4]>::try_from(face), <&[u32; 4]>::try_from(other)) {
            return a.iter().fold(false, |shared, v| {
                shared | b.iter().fold(false, |s, w| s | (v == w))
            });
        }
        face.iter().any(|v| other.contains(v))
    }
}

/// The triangles of face `f` under fan triangulation.
fn face_triangle_range(face_offsets: &[u32], f: usize) -> std::ops::Range<usize> {
    face_offsets[f] as usize - 2 * f..face_offsets[f + 1] as usize - 2 * (f + 1)
}

/// The number of fan triangles of every face, if all faces have the same number of corners
/// and the triangle count fits in `u32`.
fn uniform_fan(face_offsets: &[u32]) -> Option<u32> {
    let corners = face_offsets[1] - face_offsets[0];
    let triangles = u32::try_from((face_offsets.len() - 1) * (corners as usize - 2)).ok()?;
    let uniform = face_offsets.windows(2).all(|w| w[1] - w[0] == corners);
    (uniform && triangles < u32::MAX).then_some(corners - 2)
}

/// Groups item indices by owner (counting sort); owners `u32::MAX` (none) are left out.
///
/// The stable counting sort of `tailor_subdiv::csr`, which the rest of the workspace builds
/// its tables with; this crate takes positions and faces and depends on no other crate of the
/// workspace, so it keeps its own.
pub(crate) fn group_by_owner(owner: &[u32], owners: usize) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = vec![0u32; owners + 1];
    for &o in owner.iter().filter(|&&o| o != u32::MAX) {
        offsets[o as usize + 1] += 1;
    }
    for i in 0..owners {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut items = vec![0u32; offsets[owners] as usize];
    for (item, &o) in owner.iter().enumerate().filter(|&(_, &o)| o != u32::MAX) {
        items[cursor[o as usize] as usize] = item as u32;
        cursor[o as usize] += 1;
    }
    (offsets, items)
}

fn validate(
    vertex_count: usize,
    face_offsets: &[u32],
    face_vertices: &[u32],
) -> Result<(), CollideError> {
    if face_offsets.len() < 2 {
        return Err(CollideError::Empty);
    }
    let bad = CollideError::BadOffsets {
        corners: face_vertices.len(),
    };
    if face_offsets[0] != 0 || *face_offsets.last().unwrap_or(&0) as usize != face_vertices.len() {
        return Err(bad);
    }
    for (face, w) in face_offsets.windows(2).enumerate() {
        if w[1] < w[0] {
            return Err(bad);
        }
        let corners = &face_vertices[w[0] as usize..w[1] as usize];
        if corners.len() < 3 {
            return Err(CollideError::TooFewVertices {
                face,
                corners: corners.len(),
            });
        }
        for (i, &vertex) in corners.iter().enumerate() {
            if vertex as usize >= vertex_count {
                return Err(CollideError::VertexOutOfRange {
                    face,
                    vertex,
                    count: vertex_count,
                });
            }
            if corners[..i].contains(&vertex) {
                return Err(CollideError::RepeatedVertex { face, vertex });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad and a pentagon sharing the edge 1–2.
    fn quad_and_pentagon() -> Topology {
        Topology::new(7, &[0, 4, 9], &[0, 1, 2, 3, 1, 4, 5, 6, 2]).unwrap()
    }

    #[test]
    fn fans_polygons_into_triangles() {
        let t = quad_and_pentagon();
        assert_eq!(
            t.triangles,
            vec![[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 6], [1, 6, 2]]
        );
        assert_eq!(t.face_triangles(0), 0..2);
        assert_eq!(t.face_triangles(1), 2..5);
        assert_eq!(t.triangle_face, vec![0, 0, 1, 1, 1]);
        assert_eq!(t.uniform_fan, None);
        // Two quads: the triangles of a face follow from its index.
        let quads = Topology::new(6, &[0, 4, 8], &[0, 1, 4, 3, 1, 2, 5, 4]).unwrap();
        assert_eq!(quads.uniform_fan, Some(2));
        assert_eq!(quads.face_triangles(1), 2..4);
        assert_eq!(quads.triangle_face, vec![0, 0, 1, 1]);
    }

    #[test]
    fn edges_owners_and_adjacency() {
        let t = quad_and_pentagon();
        // 4 + 5 polygon edges, one shared, plus 1 + 2 diagonals.
        assert_eq!(t.edges.len(), 4 + 5 - 1 + 3);
        let shared = t.edges.iter().position(|e| *e == [1, 2]).unwrap();
        assert_eq!(t.edge_triangle_count[shared], 2);
        assert!(t.owned_edges(0).contains(&(shared as u32)));
        assert_eq!(
            t.owned_edges(0).len() + t.owned_edges(1).len(),
            t.edges.len()
        );
        assert_eq!(t.adjacency, vec![[0, 1]]);
        assert_eq!(t.owned_vertices(0), &[0, 1, 2, 3]);
        assert_eq!(t.owned_vertices(1), &[4, 5, 6]);
        assert!(t.faces_share_vertex(0, 1));
    }

    /// Every pair of faces of a 4 × 4 grid of quads with a triangle and a pentagon beside it
    /// shares a vertex exactly when their corner sets meet: quads against quads, quads against
    /// the others, each way round, a face against itself.
    #[test]
    fn faces_share_a_vertex_exactly_when_their_corners_meet() {
        let (mut offsets, mut corners) = (vec![0], Vec::new());
        for j in 0..4u32 {
            for i in 0..4 {
                let v = j * 5 + i;
                corners.extend([v, v + 1, v + 6, v + 5]);
                offsets.push(corners.len() as u32);
            }
        }
        corners.extend([4, 25, 9]);
        offsets.push(corners.len() as u32);
        corners.extend([9, 25, 26, 27, 14]);
        offsets.push(corners.len() as u32);
        let t = Topology::new(28, &offsets, &corners).unwrap();
        let faces = offsets.len() as u32 - 1;
        let mut shared = 0;
        for f in 0..faces {
            for g in 0..faces {
                let expect = t.face(f).iter().any(|v| t.face(g).contains(v));
                assert_eq!(t.faces_share_vertex(f, g), expect, "faces {f} and {g}");
                shared += usize::from(expect);
            }
        }
        assert!(shared > 100 && shared < (faces * faces) as usize);
    }

    #[test]
    fn rejects_bad_faces() {
        assert_eq!(
            Topology::new(3, &[0], &[]).unwrap_err(),
            CollideError::Empty
        );
        assert_eq!(
            Topology::new(3, &[0, 2], &[0, 1]).unwrap_err(),
            CollideError::TooFewVertices {
                face: 0,
                corners: 2
            }
        );
        assert_eq!(
            Topology::new(3, &[0, 3], &[0, 1, 3]).unwrap_err(),
            CollideError::VertexOutOfRange {
                face: 0,
                vertex: 3,
                count: 3
            }
        );
        assert_eq!(
            Topology::new(3, &[0, 3], &[0, 1, 1]).unwrap_err(),
            CollideError::RepeatedVertex { face: 0, vertex: 1 }
        );
        assert_eq!(
            Topology::new(3, &[0, 4], &[0, 1, 2]).unwrap_err(),
            CollideError::BadOffsets { corners: 3 }
        );
    }
}
