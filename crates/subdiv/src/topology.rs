//! Connectivity tables of one refinement level, after OpenSubdiv's `Vtr::Level`.
//!
//! A [`Level`] holds the face→vertex and face→edge relations, edge→vertex and edge→face,
//! vertex→face and vertex→edge, all flat (CSR offsets + `u32` items), plus the per-component
//! tags that subdivision needs: sharpness (single precision, as OpenSubdiv), boundary and
//! non-manifold flags, holes and each vertex's [`Rule`].
//!
//! Around a manifold vertex, faces and edges are ordered counter-clockwise: face `i` lies
//! between edge `i` (its leading edge, leaving the vertex) and edge `i + 1`; on a boundary the
//! order starts at the boundary edge that leads its face. Limit tangents depend on this order.
//!
//! Level 0 is built from a [`Mesh`] here ([`Level::from_mesh`]): edges are numbered in order of
//! first appearance walking the faces, non-manifold edges (more than two faces, or two faces
//! that disagree on orientation) and vertices (bow-ties, isolated vertices, anything that cannot
//! be ordered) are found, and OpenSubdiv's sharpening is applied (`TopologyRefinerFactory`):
//! boundary and non-manifold edges become infinitely sharp, as do non-manifold vertices except
//! on an interior non-manifold crease, and topological corners with edge-and-corner boundaries.
//! Child levels are built by [`crate::refine`].
//!
//! Degenerate faces (a vertex repeated, accepted only with
//! [`Validation::allow_degenerate_faces`](crate::Validation)) are read as OpenSubdiv reads them
//! (`Vtr::Level::completeTopologyFromFaceVertices`, `populateLocalIndices`): two equal
//! consecutive corners make a new *degenerate edge* (both ends the same vertex) each time, and
//! an edge a face uses twice gets a second instance; all are non-manifold, so infinitely sharp,
//! and their vertices non-manifold corners. Such a vertex lists the face once per corner and a
//! degenerate edge twice in a row, as its end 0 then its end 1 ([`Level::end_in_edge`]), which
//! is how every child relation tells the two halves of a degenerate edge apart
//! (`Vtr::QuadRefinement`). Child levels have no degenerate edges, only parallel ones.
//!
//! Local indices (a vertex's or edge's place in a face) are `u16`, as OpenSubdiv's
//! `LocalIndex`: half the memory of the two largest per-incidence tables.

use rayon::prelude::*;

use crate::csr::{Csr, group_into};
use crate::mesh::{Mesh, to_u32};
use crate::options::BoundaryInterpolation;
use crate::rules::crease::{self, INFINITE, Rule};

/// A corner or edge position within a face as a local index (`u16`, as OpenSubdiv's
/// `LocalIndex`); [`Mesh`] bounds face sizes accordingly.
#[inline]
pub(crate) fn to_local(n: usize) -> u16 {
    u16::try_from(n).expect("face larger than Mesh allows")
}

/// One level of a refinement hierarchy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Level {
    /// Number of vertices.
    pub(crate) vertex_count: usize,
    /// Face → vertices (counter-clockwise loops).
    pub(crate) face_verts: Csr,
    /// Face → edges, parallel to `face_verts`: edge `j` joins corners `j` and `j + 1`.
    pub(crate) face_edges: Vec<u32>,
    /// Edge → its two vertices.
    pub(crate) edge_verts: Vec<[u32; 2]>,
    /// Edge → incident faces.
    pub(crate) edge_faces: Csr,
    /// Position of the edge within each incident face, parallel to `edge_faces.items`.
    pub(crate) edge_face_local: Vec<u16>,
    /// Vertex → incident faces (ordered around manifold vertices).
    pub(crate) vert_faces: Csr,
    /// Corner index of the vertex within each incident face, parallel to `vert_faces.items`.
    pub(crate) vert_face_local: Vec<u16>,
    /// Vertex → incident edges (ordered around manifold vertices).
    pub(crate) vert_edges: Csr,
    /// Edge sharpness (0 smooth, ≥ 10 infinite).
    pub(crate) edge_sharpness: Vec<f32>,
    /// Vertex sharpness.
    pub(crate) vertex_sharpness: Vec<f32>,
    /// Non-manifold edges.
    pub(crate) edge_nonmanifold: Vec<bool>,
    /// Non-manifold vertices.
    pub(crate) vertex_nonmanifold: Vec<bool>,
    /// Hole faces.
    pub(crate) face_hole: Vec<bool>,
    /// The rule of each vertex.
    pub(crate) vertex_rule: Vec<Rule>,
}

impl Level {
    /// Number of vertices.
    #[must_use]
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Face → vertices (counter-clockwise loops).
    #[must_use]
    pub fn face_verts(&self) -> &Csr {
        &self.face_verts
    }

    /// Edge → its two vertices.
    #[must_use]
    pub fn edge_verts(&self) -> &[[u32; 2]] {
        &self.edge_verts
    }

    /// Edge → incident faces.
    #[must_use]
    pub fn edge_faces(&self) -> &Csr {
        &self.edge_faces
    }

    /// Vertex → incident faces (ordered around manifold vertices).
    #[must_use]
    pub fn vert_faces(&self) -> &Csr {
        &self.vert_faces
    }

    /// Vertex → incident edges (ordered around manifold vertices).
    #[must_use]
    pub fn vert_edges(&self) -> &Csr {
        &self.vert_edges
    }

    /// Edge sharpness (0 smooth, ≥ 10 infinite).
    #[must_use]
    pub fn edge_sharpness(&self) -> &[f32] {
        &self.edge_sharpness
    }

    /// Vertex sharpness.
    #[must_use]
    pub fn vertex_sharpness(&self) -> &[f32] {
        &self.vertex_sharpness
    }

    /// Non-manifold edges.
    #[must_use]
    pub fn edge_nonmanifold(&self) -> &[bool] {
        &self.edge_nonmanifold
    }

    /// Non-manifold vertices.
    #[must_use]
    pub fn vertex_nonmanifold(&self) -> &[bool] {
        &self.vertex_nonmanifold
    }

    /// Hole faces.
    #[must_use]
    pub fn face_hole(&self) -> &[bool] {
        &self.face_hole
    }

    /// Number of faces.
    #[must_use]
    #[inline]
    pub fn face_count(&self) -> usize {
        self.face_verts.rows()
    }

    /// Number of edges.
    #[must_use]
    #[inline]
    pub fn edge_count(&self) -> usize {
        self.edge_verts.len()
    }

    /// Edges with a single face.
    #[must_use]
    #[inline]
    pub fn is_boundary_edge(&self, e: usize) -> bool {
        self.edge_faces.range(e).len() < 2
    }

    /// The vertex at the far end of edge `e` from `v`.
    #[must_use]
    #[inline]
    pub fn other_end(&self, e: u32, v: u32) -> u32 {
        let [a, b] = self.edge_verts[e as usize];
        if a == v { b } else { a }
    }

    /// Builds level 0 from a validated mesh: topology, non-manifold detection, tags and
    /// OpenSubdiv's boundary and non-manifold sharpening.
    #[must_use]
    pub fn from_mesh(mesh: &Mesh) -> Self {
        let mut level = Self {
            vertex_count: mesh.vertex_count(),
            face_verts: Csr {
                offsets: mesh.face_offsets().to_vec(),
                items: mesh.face_vertices().to_vec(),
            },
            ..Self::default()
        };
        level.build_edges();
        level.build_incidence();
        level.orient_vertices();
        level.apply_tags(mesh);
        level
    }

    /// Numbers the edges in order of first appearance and fills `face_edges`, flagging edges
    /// shared by more than two faces or by two faces of opposite winding as non-manifold.
    ///
    /// Degenerate faces follow `Vtr::Level::completeTopologyFromFaceVertices`: two equal
    /// consecutive corners make a new degenerate edge each time, and an edge a face already
    /// uses gets a second instance; both are non-manifold.
    fn build_edges(&mut self) {
        let nv = self.vertex_count;
        // Each vertex keeps the edges it starts (as the smaller index); at most two per corner.
        let mut corners = vec![0u32; nv];
        for &v in &self.face_verts.items {
            corners[v as usize] += 2;
        }
        let mut slots = Csr::with_counts(corners);
        let mut fill = vec![0u32; nv];
        let mut edge_face_count: Vec<u32> = Vec::new();
        let mut edge_last_face: Vec<u32> = Vec::new();
        self.face_edges = vec![0; self.face_verts.items.len()];
        for f in 0..self.face_count() {
            let range = self.face_verts.range(f);
            let fv = &self.face_verts.items[range.clone()];
            let fi = to_u32(f);
            for j in 0..fv.len() {
                let (a, b) = (fv[j], fv[(j + 1) % fv.len()]);
                let (lo, hi) = (a.min(b), a.max(b));
                let start = slots.offsets[lo as usize] as usize;
                let known = &slots.items[start..start + fill[lo as usize] as usize];
                let found = (a != b)
                    .then(|| {
                        known.iter().copied().find(|&e| {
                            let [p, q] = self.edge_verts[e as usize];
                            p.max(q) == hi
                        })
                    })
                    .flatten();
                let mut nonmanifold = a == b;
                let existing = found.filter(|&e| {
                    let ei = e as usize;
                    if edge_last_face[ei] == fi {
                        // The face repeats this edge: both instances are non-manifold.
                        self.edge_nonmanifold[ei] = true;
                        nonmanifold = true;
                        return false;
                    }
                    if edge_face_count[ei] > 1 || self.edge_verts[ei][0] == a {
                        self.edge_nonmanifold[ei] = true;
                    }
                    true
                });
                let e = match existing {
                    Some(e) => {
                        edge_face_count[e as usize] += 1;
                        edge_last_face[e as usize] = fi;
                        e
                    }
                    None => {
                        let e = to_u32(self.edge_verts.len());
                        self.edge_verts.push([a, b]);
                        self.edge_nonmanifold.push(nonmanifold);
                        edge_face_count.push(1);
                        edge_last_face.push(fi);
                        if a != b {
                            slots.items[start + fill[lo as usize] as usize] = e;
                            fill[lo as usize] += 1;
                        }
                        e
                    }
                };
                self.face_edges[range.start + j] = e;
            }
        }
    }

    /// Fills edge→faces, vertex→faces and vertex→edges in the order OpenSubdiv first builds
    /// them (faces in face order, edges in edge order): each a stable grouping of the corners
    /// or edges by their edge or vertex.
    fn build_incidence(&mut self) {
        let (nv, ne) = (self.vertex_count, self.edge_count());
        // Every corner as (its face, its place in the face, its index in the flat tables).
        let corners = (0..self.face_count()).flat_map(|f| {
            let range = self.face_verts.range(f);
            let start = range.start;
            range.map(move |corner| (to_u32(f), to_local(corner - start), corner))
        });
        let mut in_faces = Vec::new();
        let by_edge = corners
            .clone()
            .map(|(f, j, corner)| (self.face_edges[corner], (f, j)));
        group_into(ne, by_edge, &mut self.edge_faces.offsets, &mut in_faces);
        (self.edge_faces.items, self.edge_face_local) = in_faces.iter().copied().unzip();
        let by_vertex = corners.map(|(f, j, corner)| (self.face_verts.items[corner], (f, j)));
        group_into(nv, by_vertex, &mut self.vert_faces.offsets, &mut in_faces);
        (self.vert_faces.items, self.vert_face_local) = in_faces.into_iter().unzip();
        let ends = self.edge_verts.iter().enumerate();
        self.vert_edges = Csr::group_by(
            nv,
            ends.flat_map(|(e, &[a, b])| [(a, to_u32(e)), (b, to_u32(e))]),
        );
    }

    /// Orders faces and edges counter-clockwise around every vertex that touches no
    /// non-manifold edge; a vertex that cannot be ordered is non-manifold
    /// (`Vtr::Level::orderVertexFacesAndEdges`).
    fn orient_vertices(&mut self) {
        self.vertex_nonmanifold = vec![false; self.vertex_count];
        for (e, &[a, b]) in self.edge_verts.iter().enumerate() {
            if self.edge_nonmanifold[e] {
                self.vertex_nonmanifold[a as usize] = true;
                self.vertex_nonmanifold[b as usize] = true;
            }
        }
        let mut faces = Vec::new();
        let mut edges = Vec::new();
        for v in 0..self.vertex_count {
            if self.vertex_nonmanifold[v] {
                continue;
            }
            if self.order_vertex(v, &mut faces, &mut edges) {
                let fr = self.vert_faces.range(v);
                for (slot, &f) in fr.zip(&faces) {
                    self.vert_faces.items[slot] = f;
                    self.vert_face_local[slot] = self.corner_of(f as usize, to_u32(v));
                }
                let er = self.vert_edges.range(v);
                self.vert_edges.items[er].copy_from_slice(&edges);
            } else {
                self.vertex_nonmanifold[v] = true;
            }
        }
    }

    /// The corner index of vertex `v` in face `f`.
    fn corner_of(&self, f: usize, v: u32) -> u16 {
        let fv = self.face_verts.row(f);
        to_local(fv.iter().position(|&x| x == v).expect("vertex not in face"))
    }

    fn order_vertex(&self, v: usize, faces: &mut Vec<u32>, edges: &mut Vec<u32>) -> bool {
        let v_faces = self.vert_faces.row(v);
        let v_edges = self.vert_edges.row(v);
        let (nf, ne) = (v_faces.len(), v_edges.len());
        faces.clear();
        edges.clear();
        if nf == 0 || ne < 2 || ne > nf + 1 {
            return false;
        }
        let vi = to_u32(v);
        let leading = |f: u32| {
            let c = self.corner_of(f as usize, vi) as usize;
            (
                c,
                self.face_edges[self.face_verts.offsets[f as usize] as usize + c],
            )
        };
        let (mut face, mut corner, mut edge);
        if ne == nf {
            face = v_faces[0];
            (corner, edge) = leading(face);
        } else {
            // Start at the boundary edge that leads its face.
            let start = v_edges.iter().find_map(|&e| {
                let ef = self.edge_faces.row(e as usize);
                (ef.len() == 1 && leading(ef[0]).1 == e).then_some(ef[0])
            });
            let Some(f) = start else { return false };
            face = f;
            (corner, edge) = leading(face);
        }
        faces.push(face);
        edges.push(edge);
        let first = edge;
        while edges.len() < ne {
            let fr = self.face_verts.range(face as usize);
            let prev = if corner == 0 {
                fr.len() - 1
            } else {
                corner - 1
            };
            let next = self.face_edges[fr.start + prev];
            if next == edge || next == first {
                return false;
            }
            edges.push(next);
            if faces.len() < nf {
                let ef = self.edge_faces.row(next as usize);
                if ef.is_empty() || (ef.len() == 1 && ef[0] == face) {
                    return false;
                }
                face = if ef[0] == face { ef[1] } else { ef[0] };
                let fe = &self.face_edges[self.face_verts.range(face as usize)];
                corner = fe
                    .iter()
                    .position(|&x| x == next)
                    .expect("edge not in face");
                faces.push(face);
            }
            edge = next;
        }
        // A bow-tie can pass the walk with the right counts but other faces left out (faces
        // never repeat a vertex, so each incident face is listed once).
        v_faces.iter().all(|f| faces.contains(f))
    }

    /// Applies the mesh's tags and OpenSubdiv's sharpening rules, then assigns vertex rules
    /// (`TopologyRefinerFactoryBase::prepareComponentTagsAndSharpness`).
    fn apply_tags(&mut self, mesh: &Mesh) {
        let options = mesh.options;
        self.edge_sharpness = vec![0.0; self.edge_count()];
        self.vertex_sharpness = vec![0.0; self.vertex_count];
        self.face_hole = vec![false; self.face_count()];
        for c in mesh.creases() {
            let [a, b] = c.vertices;
            if let Some(e) = self.find_edge(a, b) {
                self.edge_sharpness[e] = c.sharpness as f32;
            }
        }
        for c in mesh.corners() {
            self.vertex_sharpness[c.vertex as usize] = c.sharpness as f32;
        }
        for &h in mesh.holes() {
            self.face_hole[h as usize] = true;
        }
        // With boundary interpolation `none`, boundary edges the user did not make infinitely
        // sharp turn their vertices' faces into holes (RULES.md, "Boundaries").
        let explicit_infinite: Vec<bool> = self
            .edge_sharpness
            .iter()
            .map(|&s| crease::is_infinite(s))
            .collect();
        for e in 0..self.edge_count() {
            if self.is_boundary_edge(e) || self.edge_nonmanifold[e] {
                self.edge_sharpness[e] = INFINITE;
            }
        }
        for v in 0..self.vertex_count {
            let edges = self.vert_edges.row(v);
            let count =
                |pred: &dyn Fn(usize) -> bool| edges.iter().filter(|&&e| pred(e as usize)).count();
            let boundary = count(&|e| self.is_boundary_edge(e));
            let nonmanifold = count(&|e| self.edge_nonmanifold[e]);
            let faces = self.vert_faces.range(v).len();
            let topological_corner = faces == 1 && edges.len() == 2;
            if topological_corner && options.boundary == BoundaryInterpolation::EdgeAndCorner {
                self.vertex_sharpness[v] = INFINITE;
            } else if self.vertex_nonmanifold[v] {
                let nonmanifold_crease = nonmanifold == 2 && boundary == 0 && faces > edges.len();
                if !nonmanifold_crease {
                    self.vertex_sharpness[v] = INFINITE;
                }
            }
            let open_boundary = edges
                .iter()
                .any(|&e| self.is_boundary_edge(e as usize) && !explicit_infinite[e as usize]);
            if options.boundary == BoundaryInterpolation::None && open_boundary {
                for &f in self.vert_faces.row(v) {
                    self.face_hole[f as usize] = true;
                }
            }
        }
        self.assign_rules();
    }

    /// Recomputes every vertex's rule from the current sharpness values.
    pub(crate) fn assign_rules(&mut self) {
        self.vertex_rule = (0..self.vertex_count)
            .into_par_iter()
            .map(|v| {
                let sharp = self
                    .vert_edges
                    .row(v)
                    .iter()
                    .filter(|&&e| crease::is_sharp(self.edge_sharpness[e as usize]))
                    .count();
                Rule::of(self.vertex_sharpness[v], sharp)
            })
            .collect();
    }

    /// The edge joining `a` and `b`, if any; for `a == b`, the first degenerate edge at `a`
    /// (`Vtr::Level::findEdge`).
    #[must_use]
    pub fn find_edge(&self, a: u32, b: u32) -> Option<usize> {
        self.vert_edges
            .row(a as usize)
            .iter()
            .map(|&e| e as usize)
            .find(|&e| {
                let [p, q] = self.edge_verts[e];
                if a == b { p == q } else { p == b || q == b }
            })
    }

    /// Which end of its `i`-th incident edge (`vert_edges.row(v)[i]`) vertex `v` is: 0 or 1
    /// (OpenSubdiv's vertex-edge local index). A degenerate edge, whose ends are both `v`, is
    /// listed twice in a row: end 0, then end 1.
    #[must_use]
    #[inline]
    pub fn end_in_edge(&self, v: u32, edges: &[u32], i: usize) -> usize {
        let [a, b] = self.edge_verts[edges[i] as usize];
        if a == b {
            usize::from(i > 0 && edges[i - 1] == edges[i])
        } else {
            usize::from(a != v)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Point;

    fn grid(n: usize) -> Mesh {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(Point::new(i as f64, j as f64, 0.0));
            }
        }
        let idx = |i: usize, j: usize| to_u32(j * (n + 1) + i);
        let faces: Vec<[u32; 4]> = (0..n)
            .flat_map(|j| {
                (0..n).map(move |i| [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)])
            })
            .collect();
        Mesh::from_polygons(p, &faces).unwrap()
    }

    #[test]
    fn grid_topology_counts_and_order() {
        let level = Level::from_mesh(&grid(2));
        assert_eq!(level.edge_count(), 12);
        assert_eq!(level.vertex_count, 9);
        // The centre vertex is interior, valence 4, ordered so that face i lies between
        // edge i and edge i + 1.
        let v = 4;
        let faces = level.vert_faces.row(v);
        let edges = level.vert_edges.row(v);
        assert_eq!(faces.len(), 4);
        for i in 0..4 {
            let f = faces[i] as usize;
            let fe = &level.face_edges[level.face_verts.range(f)];
            assert!(fe.contains(&edges[i]) && fe.contains(&edges[(i + 1) % 4]));
        }
        assert!(level.vertex_nonmanifold.iter().all(|&n| !n));
        assert_eq!(level.vertex_rule[v], Rule::Smooth);
        assert_eq!(level.vertex_rule[1], Rule::Crease);
        assert_eq!(level.vertex_rule[0], Rule::Crease);
    }

    #[test]
    fn bow_tie_is_non_manifold() {
        let p = vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(-1.0, 0.0, 0.0),
            Point::new(0.0, -1.0, 0.0),
        ];
        let mesh = Mesh::from_polygons(p, &[[0u32, 1, 2], [0, 3, 4]]).unwrap();
        let level = Level::from_mesh(&mesh);
        assert!(level.vertex_nonmanifold[0]);
        assert_eq!(level.vertex_sharpness[0], INFINITE);
        assert_eq!(level.vertex_rule[0], Rule::Corner);
    }

    #[test]
    fn repeated_corner_is_a_degenerate_nonmanifold_edge() {
        // Two quads sharing edge 1-2; the first repeats vertex 2, as in
        // `catmark_nonman_quadpole8` (`f 4 3 5 5`).
        let p = (0..5).map(|i| Point::new(f64::from(i), 0.0, 0.0)).collect();
        let faces = vec![0, 1, 2, 2, 1, 3, 4, 2];
        let allow = crate::mesh::Validation {
            allow_degenerate_faces: true,
        };
        let mesh = Mesh::from_flat_with(p, vec![0, 4, 8], faces, allow).unwrap();
        let level = Level::from_mesh(&mesh);
        assert_eq!(
            level.edge_verts,
            [[0, 1], [1, 2], [2, 2], [2, 0], [1, 3], [3, 4], [4, 2]]
        );
        assert!(level.edge_nonmanifold[2]);
        assert_eq!(level.find_edge(2, 2), Some(2));
        // Vertex 2 sees face 0 twice and the degenerate edge twice, as end 0 then end 1.
        assert_eq!(level.vert_faces.row(2), [0, 0, 1]);
        assert_eq!(level.vert_face_local[level.vert_faces.range(2)], [2, 3, 3]);
        let edges = level.vert_edges.row(2);
        assert_eq!(edges, [1, 2, 2, 3, 6]);
        let ends: Vec<usize> = (0..edges.len())
            .map(|i| level.end_in_edge(2, edges, i))
            .collect();
        assert_eq!(ends, [1, 0, 1, 0, 1]);
        assert!(level.vertex_nonmanifold[2]);
        assert_eq!(level.vertex_rule[2], Rule::Corner);
    }
}
