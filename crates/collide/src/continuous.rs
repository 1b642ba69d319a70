//! Continuous collision queries over a step: every vertex–triangle and edge–edge pair that
//! touches while the vertices move linearly from the start to the end positions of the last
//! swept refit ([`Hierarchy::refit_swept`]), within one mesh or between two (Bridson, Fedkiw &
//! Anderson 2002).
//!
//! The traversal pairs faces whose swept boxes overlap; a pair of faces `(f, g)` then tests the
//! vertices *owned* by `f` against the triangles of `g` (and the reverse) and the edges owned by
//! `f` against those owned by `g` (see [`crate::topology`]), so each pair of features is tested
//! once. Within one mesh, pairs of features sharing a vertex are skipped, the normal cones over
//! the step ([`crate::cones`]) clear whole smooth regions, and two faces around a vertex whose
//! star they clear are not tested against each other. Against a body, cloth only needs its
//! vertices kept out of the body's triangles ([`Hierarchy::vertex_impacts_with`]): the same
//! traversal with the vertex–triangle tests alone.

use parry3d_f64::math::Vector as DVec3;

use crate::ccd::{
    Path, apart_boxes, edge_edge_unboxed, faces_apart, swept, vertex_triangle_unboxed,
};
use crate::cones::{NormalCones, Stars};
use crate::hierarchy::Hierarchy;
use crate::traverse::{cross_pairs, self_pairs};

/// A vertex touching a triangle during the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexTriangleImpact {
    /// The vertex.
    pub vertex: u32,
    /// The fan triangle (index into [`Hierarchy::triangles`]).
    pub triangle: u32,
    /// First time of contact, as a fraction of the step in `[0, 1]`.
    pub time: f64,
    /// Barycentric coordinates of the contact on the triangle.
    pub barycentric: [f64; 3],
}

/// Two edges touching during the step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeEdgeImpact {
    /// The two edges, each as its end vertices `[low, high]`.
    pub edges: [[u32; 2]; 2],
    /// First time of contact, as a fraction of the step in `[0, 1]`.
    pub time: f64,
    /// Where along each edge, from its low to its high vertex, in `[0, 1]`.
    pub parameters: [f64; 2],
}

/// Everything that touches during a step, sorted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Impacts {
    /// Vertices of the first mesh against triangles of the second (of the mesh itself for a
    /// self query), sorted by vertex then triangle.
    pub vertex_triangle: Vec<VertexTriangleImpact>,
    /// Vertices of the second mesh against triangles of the first (empty for a self query).
    pub triangle_vertex: Vec<VertexTriangleImpact>,
    /// Edges of the first mesh against edges of the second (for a self query, the lower edge
    /// first), sorted by edges.
    pub edge_edge: Vec<EdgeEdgeImpact>,
}

enum Found {
    VertexTriangle(VertexTriangleImpact),
    TriangleVertex(VertexTriangleImpact),
    EdgeEdge(EdgeEdgeImpact),
}

impl Impacts {
    /// Refills the lists from what the traversal found, sorted, reusing their storage.
    fn refill(&mut self, found: Vec<Found>) {
        self.vertex_triangle.clear();
        self.triangle_vertex.clear();
        self.edge_edge.clear();
        for f in found {
            match f {
                Found::VertexTriangle(i) => self.vertex_triangle.push(i),
                Found::TriangleVertex(i) => self.triangle_vertex.push(i),
                Found::EdgeEdge(i) => self.edge_edge.push(i),
            }
        }
        for list in [&mut self.vertex_triangle, &mut self.triangle_vertex] {
            sort_vertex_triangle(list);
        }
        self.edge_edge.sort_unstable_by_key(|i| i.edges);
    }
}

/// Sorts vertex–triangle impacts by vertex, then triangle.
fn sort_vertex_triangle(list: &mut [VertexTriangleImpact]) {
    list.sort_unstable_by_key(|i| (i.vertex, i.triangle));
}

impl Hierarchy {
    /// Every vertex–triangle and edge–edge contact of the mesh with itself during the motion
    /// of the last swept refit, excluding pairs that share a vertex.
    #[must_use]
    pub fn self_impacts(&self) -> Impacts {
        let mut out = Impacts::default();
        self.self_impacts_into(&mut out);
        out
    }

    /// [`Hierarchy::self_impacts`] into `out`, reusing its lists from step to step.
    pub fn self_impacts_into(&self, out: &mut Impacts) {
        out.refill(self.self_pairs_impacts(None));
    }

    /// [`Hierarchy::self_impacts_into`] once more, after a query that left its answers in
    /// `out`, when the swept refit since kept every start position and changed only the end
    /// positions of the vertices `moved` flags. The leaf pairs without a moved vertex are not
    /// traversed, and each feature pair without one keeps its answer, which the same straight
    /// paths cannot change; so `out` ends with the lists the full query gives, the same bits,
    /// at a cost that follows what moved. Rounds of impulses after the first move a few
    /// vertices each, and ask again of the whole mesh.
    ///
    /// # Panics
    /// If `moved` has fewer entries than the mesh has vertices.
    pub fn self_impacts_again(&self, moved: &[bool], out: &mut Impacts) {
        let dirty = self.nodes_moved(moved);
        let topology = &self.topology;
        let still = |v: &u32| !moved[*v as usize];
        let triangles = &topology.triangles;
        let unmoved = |found: &Found| match found {
            Found::VertexTriangle(i) | Found::TriangleVertex(i) => {
                still(&i.vertex) && triangles[i.triangle as usize].iter().all(still)
            }
            Found::EdgeEdge(i) => i.edges.iter().flatten().all(still),
        };
        let mut found = self.self_pairs_impacts(Some(&dirty));
        found.retain(|f| !unmoved(f));
        let kept = (out
            .vertex_triangle
            .iter()
            .copied()
            .map(Found::VertexTriangle))
        .chain(out.edge_edge.iter().copied().map(Found::EdgeEdge))
        .filter(unmoved);
        found.extend(kept);
        out.refill(found);
    }

    /// The self impacts of the leaf pairs a self walk visits (all, or with `dirty` those with a
    /// node that moved).
    fn self_pairs_impacts(&self, dirty: Option<&[bool]>) -> Vec<Found> {
        let cones = NormalCones::new(self);
        let stars = Stars::new(self, &cones);
        let visit = |a: u32, b: u32, out: &mut Vec<Found>| {
            let (f, g) = (a.min(b), a.max(b));
            // Faces sharing a vertex are parted by a cleared star around one they share;
            // faces sharing none, when they stay apart.
            if f != g
                && stars
                    .part(f, g)
                    .unwrap_or_else(|| self.faces_stay_apart(f, g))
            {
                return;
            }
            vertices_against_face(self, f, self, g, true, Found::VertexTriangle, out);
            if f != g {
                vertices_against_face(self, g, self, f, true, Found::VertexTriangle, out);
            }
            edges_against_edges(self, f, self, g, true, out);
        };
        self_pairs(self, Some(&cones), true, 0.0, dirty, &visit)
    }

    /// Whether faces `f` and `g`, which share no corner, stay apart over the step
    /// ([`faces_apart`]); faces of more than [`FACE_CORNERS`] corners are left to the tests.
    fn faces_stay_apart(&self, f: u32, g: u32) -> bool {
        let (a, b) = (self.topology.face(f), self.topology.face(g));
        if a.len() > FACE_CORNERS || b.len() > FACE_CORNERS {
            return false;
        }
        let mut corners = [[DVec3::ZERO; 2]; 2 * FACE_CORNERS];
        for (slot, &v) in corners.iter_mut().zip(a.iter().chain(b)) {
            *slot = path(self, v);
        }
        faces_apart(&corners[..a.len() + b.len()], a.len())
    }

    /// Every vertex–triangle and edge–edge contact between this mesh and `other` during the
    /// motions of their last swept refits.
    #[must_use]
    pub fn impacts_with(&self, other: &Hierarchy) -> Impacts {
        let mut out = Impacts::default();
        self.impacts_with_into(other, &mut out);
        out
    }

    /// [`Hierarchy::impacts_with`] into `out`, reusing its lists from step to step.
    pub fn impacts_with_into(&self, other: &Hierarchy, out: &mut Impacts) {
        let visit = |f: u32, g: u32, out: &mut Vec<Found>| {
            vertices_against_face(self, f, other, g, false, Found::VertexTriangle, out);
            vertices_against_face(other, g, self, f, false, Found::TriangleVertex, out);
            edges_against_edges(self, f, other, g, false, out);
        };
        out.refill(cross_pairs(self, other, &visit));
    }

    /// The vertices of this mesh touching triangles of `other` during the motions of their
    /// last swept refits, sorted by vertex then triangle: the part of
    /// [`Hierarchy::impacts_with`] that keeps cloth vertices out of a body, without the
    /// edge–edge tests or the body's vertices.
    #[must_use]
    pub fn vertex_impacts_with(&self, other: &Hierarchy) -> Vec<VertexTriangleImpact> {
        let mut out = Vec::new();
        self.vertex_impacts_with_into(other, &mut out);
        out
    }

    /// [`Hierarchy::vertex_impacts_with`] into `out` (cleared first), reusing its allocation.
    pub fn vertex_impacts_with_into(&self, other: &Hierarchy, out: &mut Vec<VertexTriangleImpact>) {
        let visit = |f: u32, g: u32, out: &mut Vec<VertexTriangleImpact>| {
            vertices_against_face(self, f, other, g, false, |i| i, out);
        };
        out.clear();
        out.append(&mut cross_pairs(self, other, &visit));
        sort_vertex_triangle(out);
    }
}

/// Most corners of a face [`Hierarchy::faces_stay_apart`] looks at.
const FACE_CORNERS: usize = 8;

/// The path of vertex `v` of `h` over the step: `[start, end]`.
fn path(h: &Hierarchy, v: u32) -> Path {
    [h.start[v as usize], h.end()[v as usize]]
}

/// The vertices owned by face `f` of `hv` against the triangles of face `g` of `ht`. Each
/// triangle is boxed once for all the vertices (see [`crate::ccd`]), and not at all when `f`
/// owns none (a vertex belongs to the first of its faces).
fn vertices_against_face<T>(
    hv: &Hierarchy,
    f: u32,
    ht: &Hierarchy,
    g: u32,
    same_mesh: bool,
    wrap: fn(VertexTriangleImpact) -> T,
    out: &mut Vec<T>,
) {
    let owned = hv.topology.owned_vertices(f);
    if owned.is_empty() {
        return;
    }
    for t in ht.topology.face_triangles(g) {
        let corners = ht.topology.triangles[t];
        let triangle = corners.map(|c| path(ht, c));
        let around = swept(&triangle);
        for &v in owned {
            if same_mesh && corners.contains(&v) {
                continue;
            }
            let p = path(hv, v);
            if apart_boxes(swept(&[p]), around) {
                continue;
            }
            if let Some((time, barycentric)) = vertex_triangle_unboxed(p, triangle) {
                out.push(wrap(VertexTriangleImpact {
                    vertex: v,
                    triangle: t as u32,
                    time,
                    barycentric,
                }));
            }
        }
    }
}

/// The edges owned by face `f` of `ha` against those owned by face `g` of `hb`; within one
/// face, each unordered pair once. Each edge of `f` is boxed once for all those of `g`.
fn edges_against_edges(
    ha: &Hierarchy,
    f: u32,
    hb: &Hierarchy,
    g: u32,
    same_mesh: bool,
    out: &mut Vec<Found>,
) {
    let (mine, theirs) = (ha.topology.owned_edges(f), hb.topology.owned_edges(g));
    for (i, &ea) in mine.iter().enumerate() {
        let theirs = if same_mesh && f == g {
            &theirs[i + 1..]
        } else {
            theirs
        };
        let a = ha.topology.edges[ea as usize];
        let path_a = a.map(|v| path(ha, v));
        let box_a = swept(&path_a);
        for &eb in theirs {
            let b = hb.topology.edges[eb as usize];
            if same_mesh && a.iter().any(|v| b.contains(v)) {
                continue;
            }
            let path_b = b.map(|v| path(hb, v));
            if apart_boxes(box_a, swept(&path_b)) {
                continue;
            }
            // Within one mesh the lower edge goes first, so the same pair always gives the
            // same bits whichever face owns which edge.
            let (edges, found) = if same_mesh && b < a {
                ([b, a], edge_edge_unboxed(path_b, path_a))
            } else {
                ([a, b], edge_edge_unboxed(path_a, path_b))
            };
            if let Some((time, parameters)) = found {
                out.push(Found::EdgeEdge(EdgeEdgeImpact {
                    edges,
                    time,
                    parameters,
                }));
            }
        }
    }
}
