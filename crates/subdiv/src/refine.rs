//! One uniform Catmull-Clark refinement step: the child level's topology and tags, and the
//! weights that make its vertices from the parent's (OpenSubdiv's `Vtr::QuadRefinement` and
//! `Far::PrimvarRefiner`).
//!
//! Numbering follows OpenSubdiv with vertices first: child vertices are the vertex points (one
//! per parent vertex), then the face points (one per parent face), then the edge points (one per
//! parent edge). An n-sided parent face has n quad children; child `j` is
//! (vertex point of corner `j`, edge point of edge `j`, face point, edge point of edge `j−1`),
//! rotated for quads so the vertex point stays at index `j`. Child edges are first the face
//! interior edges (face point → edge point, parent face by parent face), then the two halves of
//! each parent edge (edge point → vertex point of each end). Incidence lists are ordered so that
//! a manifold child vertex keeps its counter-clockwise order, as OpenSubdiv builds them.
//!
//! Sharpness decays (uniform or Chaikin, see [`crate::rules::crease`]); holes, non-manifold
//! flags and sharpness propagate from parent to child components. The child's tags and rules are
//! computed from the parent alone, so a child can be built with faces and tags only
//! ([`Refinement::with_topology`]): that is all evaluating the step needs, and the rest of its
//! relations (edges, incidences), which cost most of a level's time and memory, can wait until
//! something asks for them (OpenSubdiv's `Refinement::Options::_minimalTopology`).
//!
//! Masks are computed per vertex as OpenSubdiv's `PrimvarRefiner` computes them, with the
//! common cases short-cut: a smooth or dart vertex takes the smooth mask and a smooth edge the
//! ¼-¼ mask without gathering sharpness or face sizes.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::csr::{Csr, offsets_from_lengths};
use crate::mesh::to_u32;
use crate::options::{CreaseMethod, Options, TriangleRule};
use crate::rules::crease;
use crate::rules::masks::{self, EdgeMask, Mask, VertexNeighbourhood};
use crate::sparse::{CHUNK, Primvar, SparseRows, fill_rows};
use crate::topology::{Level, to_local};

/// A refinement step: the child level, and (built on first use) the weights of its vertices.
///
/// Direct refinement ([`Refinement::apply`]) computes each mask on the fly, as OpenSubdiv's
/// `PrimvarRefiner` does, so refining positions once never stores a weight; stencil tables and
/// face-varying data ask for the table ([`Refinement::weights`]), which is then kept.
#[derive(Debug)]
pub struct Refinement {
    /// The refined level.
    pub child: Level,
    /// Where each kind of child vertex starts.
    pub layout: ChildLayout,
    options: Options,
    weights: OnceLock<SparseRows>,
}

impl Clone for Refinement {
    fn clone(&self) -> Self {
        Self {
            child: self.child.clone(),
            layout: self.layout,
            options: self.options,
            weights: self
                .weights
                .get()
                .cloned()
                .map(OnceLock::from)
                .unwrap_or_default(),
        }
    }
}

/// Index ranges of the three kinds of child vertices: `[0, faces)` vertex points,
/// `[faces, edges)` face points, `[edges, total)` edge points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildLayout {
    /// Number of parent vertices = first face point.
    pub faces: usize,
    /// First edge point.
    pub edges: usize,
}

impl ChildLayout {
    fn new(parent: &Level) -> Self {
        Self {
            faces: parent.vertex_count,
            edges: parent.vertex_count + parent.face_count(),
        }
    }
    fn of_vertex(self, v: usize) -> u32 {
        to_u32(v)
    }
    fn of_face(self, f: usize) -> u32 {
        to_u32(self.faces + f)
    }
    fn of_edge(self, e: usize) -> u32 {
        to_u32(self.edges + e)
    }
}

impl Refinement {
    /// Refines the topology of `parent` once.
    #[must_use]
    pub fn new(parent: &Level, options: &Options) -> Self {
        Self::with_topology(parent, options, true)
    }

    /// Refines `parent` once; without `full`, the child gets its faces and tags only (what
    /// evaluating this step needs: OpenSubdiv's minimal last-level topology), and
    /// [`Self::full_child`] builds the rest.
    #[must_use]
    pub fn with_topology(parent: &Level, options: &Options, full: bool) -> Self {
        let layout = ChildLayout::new(parent);
        let child = child_level(parent, layout, options.crease_method, full);
        Self {
            child,
            layout,
            options: *options,
            weights: OnceLock::new(),
        }
    }

    /// Whether the child has every relation, not only faces and tags.
    #[must_use]
    pub fn has_full_child(&self) -> bool {
        self.child.edge_count() > 0 || self.child.face_count() == 0
    }

    /// The child with every relation: a copy of a faces-and-tags child, completed from
    /// `parent` (the level this step refined).
    #[must_use]
    pub fn full_child(&self, parent: &Level) -> Level {
        let mut child = self.child.clone();
        if !self.has_full_child() {
            complete_child(parent, self.layout, &mut child);
        }
        child
    }

    /// The child's sharp edges that are neither boundary nor non-manifold, in edge order:
    /// its vertices and sharpness. Read off `parent` (the level this step refined), so a child
    /// with faces and tags only need not be completed: edges inside parent faces start smooth,
    /// half `k` of parent edge `e` joins `e`'s edge point to the vertex point of its end `k`
    /// (as [`Self::full_child`] numbers them), and lies on the boundary when `e` does.
    #[must_use]
    pub fn child_creases(&self, parent: &Level) -> Vec<([u32; 2], f32)> {
        let corners = parent.face_verts.items.len();
        let c = &self.child;
        (corners..c.edge_sharpness.len())
            .filter(|&i| crease::is_sharp(c.edge_sharpness[i]) && !c.edge_nonmanifold[i])
            .filter_map(|i| {
                let (e, k) = ((i - corners) / 2, (i - corners) % 2);
                let ends = [
                    self.layout.of_edge(e),
                    self.layout.of_vertex(parent.edge_verts[e][k] as usize),
                ];
                (!parent.is_boundary_edge(e)).then_some((ends, c.edge_sharpness[i]))
            })
            .collect()
    }

    /// One row per child vertex, over `parent` (the level this step refined). A column below
    /// the parent's vertex count names a parent vertex; a column `c` at or above it names the
    /// child vertex `c − parent vertex count`, always a face point (vertex and edge points use
    /// face points, as OpenSubdiv's masks do). Built on first call, then kept.
    pub fn weights(&self, parent: &Level) -> &SparseRows {
        self.weights
            .get_or_init(|| vertex_weights(parent, &self.child, self.layout, &self.options))
    }

    /// Computes the child level's values from the parent's (`parent_level` is the level this
    /// step refined): face points first, then vertex and edge points, each in parallel, with
    /// the masks computed on the fly.
    pub fn apply<T: Primvar>(&self, parent_level: &Level, parent: &[T], child: &mut [T]) {
        if let Some(w) = self.weights.get() {
            apply_two_phase(w, self.layout, parent, child);
            return;
        }
        let (p, c, layout, options) = (parent_level, &self.child, self.layout, &self.options);
        let face_points = to_u32(p.vertex_count + layout.faces);
        let centroid = |f: usize| {
            let fv = p.face_verts.row(f);
            let w = 1.0 / fv.len() as f64;
            let mut acc = T::zero();
            for &v in fv {
                acc.add_scaled(&parent[v as usize], w);
            }
            acc
        };
        two_phase(layout, parent, child, centroid, |i, s, g| {
            if i < layout.faces {
                vertex_row(p, c, options.crease_method, i, face_points, s, g);
            } else {
                edge_row(p, c, layout, options, i - layout.edges, face_points, s, g);
            }
        });
    }
}

/// Where a mask's weights go: a table row being written, or a value being accumulated.
trait RowSink {
    fn push(&mut self, col: u32, weight: f64);
}

/// Accumulates a row's weighted values directly (columns as in [`Refinement::weights`]).
struct Gather<'a, T> {
    parent: &'a [T],
    face_points: &'a [T],
    np: usize,
    first_face: usize,
    acc: T,
}

impl<T: Primvar> RowSink for Gather<'_, T> {
    fn push(&mut self, col: u32, weight: f64) {
        let col = col as usize;
        let v = if col < self.np {
            &self.parent[col]
        } else {
            &self.face_points[col - self.np - self.first_face]
        };
        self.acc.add_scaled(v, weight);
    }
}

/// Applies a table whose columns reach into the child face points (see
/// [`Refinement::weights`]); shared by vertex and face-varying data.
pub(crate) fn apply_two_phase<T: Primvar>(
    w: &SparseRows,
    layout: ChildLayout,
    parent: &[T],
    child: &mut [T],
) {
    two_phase(
        layout,
        parent,
        child,
        |f| w.gather(layout.faces + f, parent),
        |i, _, g| {
            let (cols, ws) = w.row(i);
            for (&col, &wt) in cols.iter().zip(ws) {
                g.push(col, wt);
            }
        },
    );
}

/// The shared two-phase evaluation: every face point (`face_point(f)`), then every vertex and
/// edge point in parallel, `row(child vertex, scratch, sink)` pushing its weights into a
/// [`Gather`] that reads parent values and the fresh face points.
fn two_phase<T: Primvar>(
    layout: ChildLayout,
    parent: &[T],
    child: &mut [T],
    face_point: impl Fn(usize) -> T + Sync,
    row: impl Fn(usize, &mut Scratch, &mut Gather<'_, T>) + Sync,
) {
    let (vertex_points, rest) = child.split_at_mut(layout.faces);
    let (face_points, edge_points) = rest.split_at_mut(layout.edges - layout.faces);
    face_points
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(k, out)| {
            for (i, d) in out.iter_mut().enumerate() {
                *d = face_point(k * CHUNK + i);
            }
        });
    let face_points = &*face_points;
    let fill = |first: usize, out: &mut [T]| {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each_init(Scratch::default, |s, (k, out)| {
                for (i, d) in out.iter_mut().enumerate() {
                    let mut g = Gather {
                        parent,
                        face_points,
                        np: parent.len(),
                        first_face: layout.faces,
                        acc: T::zero(),
                    };
                    row(first + k * CHUNK + i, s, &mut g);
                    *d = g.acc;
                }
            });
    };
    fill(0, vertex_points);
    fill(layout.edges, edge_points);
}

/// The child level: faces and tags, and with `full` every other relation too.
fn child_level(p: &Level, layout: ChildLayout, method: CreaseMethod, full: bool) -> Level {
    let corners = p.face_verts.items.len();
    let mut c = Level {
        vertex_count: p.vertex_count + p.face_count() + p.edge_count(),
        face_verts: Csr {
            offsets: (0..=corners)
                .into_par_iter()
                .map(|i| to_u32(4 * i))
                .collect(),
            items: child_face_verts(p, layout),
        },
        ..Level::default()
    };
    child_tags(p, layout, method, &mut c);
    if full {
        complete_child(p, layout, &mut c);
    }
    c
}

/// Child `j` of parent face `f` is the quad at its corner `j`: (vertex point of corner `j`,
/// edge point of edge `j`, face point, edge point of edge `j − 1`), rotated for quads so that
/// the vertex point stays at index `j`. `quad(j)` gives those four for child `j`; the children
/// of a parent face are written into `out` (four slots each).
#[inline]
fn fill_child_quads(n: usize, out: &mut [u32], quad: impl Fn(usize) -> [u32; 4]) {
    for (j, slots) in out.chunks_exact_mut(4).enumerate() {
        // Quads keep the vertex point at index j; other polygons put it first.
        let rot = if n == 4 { j } else { 0 };
        for (k, &x) in quad(j).iter().enumerate() {
            slots[(k + rot) & 3] = x;
        }
    }
}

/// Runs `fill(f, slots)` on every parent face in parallel, `slots` being the four entries of
/// each of its child quads in a child-face table.
fn per_parent_face(p: &Level, out: &mut [u32], fill: impl Fn(usize, &mut [u32]) + Sync) {
    let offsets: Vec<u32> = p.face_verts.offsets.iter().map(|&o| 4 * o).collect();
    let mut unit = vec![(); out.len()];
    fill_rows(&offsets, out, &mut unit, |f, slots, _| fill(f, slots));
}

fn child_face_verts(p: &Level, layout: ChildLayout) -> Vec<u32> {
    let mut items = vec![0u32; 4 * p.face_verts.items.len()];
    per_parent_face(p, &mut items, |f, slots| {
        let range = p.face_verts.range(f);
        let (fv, fe) = (&p.face_verts.items[range.clone()], &p.face_edges[range]);
        let n = fv.len();
        let face_point = layout.of_face(f);
        fill_child_quads(n, slots, |j| {
            let jp = if j == 0 { n - 1 } else { j - 1 };
            [
                layout.of_vertex(fv[j] as usize),
                layout.of_edge(fe[j] as usize),
                face_point,
                layout.of_edge(fe[jp] as usize),
            ]
        });
    });
    items
}

fn child_face_edges(p: &Level) -> Vec<u32> {
    let corners = p.face_verts.items.len();
    let half = |e: u32, k: usize| to_u32(corners + 2 * e as usize + k);
    let mut items = vec![0u32; 4 * corners];
    per_parent_face(p, &mut items, |f, slots| {
        let range = p.face_verts.range(f);
        let (fv, fe) = (
            &p.face_verts.items[range.clone()],
            &p.face_edges[range.clone()],
        );
        let n = fv.len();
        // Which half of an edge touches corner j; a degenerate edge (only in level 0) runs
        // from the corner it leads to the corner it trails, like the face.
        let corner_in_edge = |e: u32, j: usize, degenerate_end: usize| {
            let [a, b] = p.edge_verts[e as usize];
            if a == b {
                degenerate_end
            } else {
                usize::from(a != fv[j])
            }
        };
        fill_child_quads(n, slots, |j| {
            let jp = if j == 0 { n - 1 } else { j - 1 };
            [
                half(fe[j], corner_in_edge(fe[j], j, 0)),
                to_u32(range.start + j),
                to_u32(range.start + jp),
                half(fe[jp], corner_in_edge(fe[jp], j, 1)),
            ]
        });
    });
    items
}

/// Adds every relation but face → vertices to a child level built with faces and tags only.
fn complete_child(p: &Level, layout: ChildLayout, c: &mut Level) {
    let corners = p.face_verts.items.len();
    let corner_face = corner_faces(p);
    c.face_edges = child_face_edges(p);
    // Edges: interior edges of faces (face point → edge point), then halves of parent edges.
    c.edge_verts = (0..corners + 2 * p.edge_count())
        .into_par_iter()
        .map(|i| {
            if i < corners {
                [
                    layout.of_face(corner_face[i] as usize),
                    layout.of_edge(p.face_edges[i] as usize),
                ]
            } else {
                let (e, k) = ((i - corners) / 2, (i - corners) % 2);
                [
                    layout.of_edge(e),
                    layout.of_vertex(p.edge_verts[e][k] as usize),
                ]
            }
        })
        .collect();
    child_edge_faces(p, &corner_face, c);
    child_vertex_faces(p, layout, c);
    child_vertex_edges(p, layout, c);
}

/// `value(f)` for every corner of `p`, `f` being the corner's face.
fn per_corner<T: Copy + Default + Send>(p: &Level, value: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let mut out = vec![T::default(); p.face_verts.items.len()];
    let mut unit = vec![(); out.len()];
    fill_rows(&p.face_verts.offsets, &mut out, &mut unit, |f, row, _| {
        row.fill(value(f));
    });
    out
}

/// The face of every corner of `p` (the inverse of its face offsets).
fn corner_faces(p: &Level) -> Vec<u32> {
    per_corner(p, to_u32)
}

/// The child quad at corner `j` of parent face `f`.
fn child_face(p: &Level, f: usize, j: usize) -> u32 {
    to_u32(p.face_verts.offsets[f] as usize + j)
}

/// Builds a CSR relation with a parallel per-item array (local indices, or `()` for none), row
/// by row in parallel.
fn relation<B: Clone + Default + Send>(
    rows: usize,
    length: impl Fn(usize) -> usize + Sync,
    fill: impl Fn(usize, &mut [u32], &mut [B]) + Sync,
) -> (Csr, Vec<B>) {
    let offsets = offsets_from_lengths(rows, length);
    let total = *offsets.last().expect("offsets start at 0") as usize;
    let (mut items, mut local) = (vec![0u32; total], vec![B::default(); total]);
    fill_rows(&offsets, &mut items, &mut local, fill);
    (Csr { offsets, items }, local)
}

fn child_edge_faces(p: &Level, corner_face: &[u32], c: &mut Level) {
    let corners = p.face_verts.items.len();
    let length = |i: usize| {
        if i < corners {
            2
        } else {
            p.edge_faces.range((i - corners) / 2).len()
        }
    };
    (c.edge_faces, c.edge_face_local) =
        relation(corners + 2 * p.edge_count(), length, |i, faces, local| {
            if i < corners {
                // The interior edge between child quads j and j + 1 of a parent face.
                let f = corner_face[i] as usize;
                let range = p.face_verts.range(f);
                let (n, j) = (range.len(), i - range.start);
                let jn = (j + 1) % n;
                let (l0, l1) = if n == 4 { (jn, (jn + 2) % 4) } else { (1, 2) };
                faces.copy_from_slice(&[child_face(p, f, j), child_face(p, f, jn)]);
                local.copy_from_slice(&[to_local(l0), to_local(l1)]);
                return;
            }
            // Half k of parent edge e: in each parent face, the child quad at that end.
            let (e, k) = ((i - corners) / 2, (i - corners) % 2);
            let [a, b] = p.edge_verts[e];
            let end = [a, b][k];
            for (slot, idx) in p.edge_faces.range(e).enumerate() {
                let (pf, l) = (
                    p.edge_faces.items[idx] as usize,
                    p.edge_face_local[idx] as usize,
                );
                let fr = p.face_verts.range(pf);
                let n = fr.len();
                let of_edge = if a == b {
                    k
                } else {
                    usize::from(p.face_verts.items[fr.start + l] != end)
                };
                faces[slot] = child_face(p, pf, (l + of_edge) % n);
                local[slot] = to_local(if n == 4 {
                    l
                } else if of_edge == 1 {
                    3
                } else {
                    0
                });
            }
        });
}

fn child_vertex_faces(p: &Level, layout: ChildLayout, c: &mut Level) {
    let (nv, nf) = (p.vertex_count, p.face_count());
    debug_assert_eq!((layout.faces, layout.edges), (nv, nv + nf));
    let length = |i: usize| {
        if i < nv {
            p.vert_faces.range(i).len()
        } else if i < nv + nf {
            p.face_verts.range(i - nv).len()
        } else {
            2 * p.edge_faces.range(i - nv - nf).len()
        }
    };
    (c.vert_faces, c.vert_face_local) =
        relation(nv + nf + p.edge_count(), length, |i, faces, local| {
            if i < nv {
                for (slot, k) in p.vert_faces.range(i).enumerate() {
                    let (f, l) = (
                        p.vert_faces.items[k] as usize,
                        p.vert_face_local[k] as usize,
                    );
                    let quad = p.face_verts.range(f).len() == 4;
                    faces[slot] = child_face(p, f, l);
                    local[slot] = to_local(if quad { l } else { 0 });
                }
            } else if i < nv + nf {
                let f = i - nv;
                let n = faces.len();
                for j in 0..n {
                    faces[j] = child_face(p, f, j);
                    local[j] = to_local(if n == 4 { (j + 2) % 4 } else { 2 });
                }
            } else {
                // Per parent face of the edge: the quad after the edge, then the one before it.
                for (slot, k) in p.edge_faces.range(i - nv - nf).enumerate() {
                    let (f, l) = (
                        p.edge_faces.items[k] as usize,
                        p.edge_face_local[k] as usize,
                    );
                    let n = p.face_verts.range(f).len();
                    let l1 = (l + 1) % n;
                    faces[2 * slot] = child_face(p, f, l1);
                    local[2 * slot] = to_local(if n == 4 { l } else { 3 });
                    faces[2 * slot + 1] = child_face(p, f, l);
                    local[2 * slot + 1] = to_local(if n == 4 { l1 } else { 1 });
                }
            }
        });
}

fn child_vertex_edges(p: &Level, layout: ChildLayout, c: &mut Level) {
    let (nv, nf) = (p.vertex_count, p.face_count());
    debug_assert_eq!((layout.faces, layout.edges), (nv, nv + nf));
    let corners = p.face_verts.items.len();
    let half = |e: usize, k: usize| to_u32(corners + 2 * e + k);
    let length = |i: usize| {
        if i < nv {
            p.vert_edges.range(i).len()
        } else if i < nv + nf {
            p.face_verts.range(i - nv).len()
        } else {
            2 + p.edge_faces.range(i - nv - nf).len()
        }
    };
    let (edges, _) = relation(nv + nf + p.edge_count(), length, |i, out, _: &mut [()]| {
        if i < nv {
            let edges = p.vert_edges.row(i);
            for (k, (slot, &e)) in out.iter_mut().zip(edges).enumerate() {
                *slot = half(e as usize, p.end_in_edge(to_u32(i), edges, k));
            }
        } else if i < nv + nf {
            let r = p.face_verts.range(i - nv);
            let n = r.len();
            for (j, slot) in out.iter_mut().enumerate() {
                *slot = to_u32(r.start + (j + n - 1) % n);
            }
        } else {
            // (edge half, face edge, edge half, face edges...), the first half being the one
            // the first incident face reaches first (OpenSubdiv's counter-clockwise order).
            let e = i - nv - nf;
            let faces = p.edge_faces.range(e);
            let face_edge = |idx: usize| {
                let (f, l) = (
                    p.edge_faces.items[idx] as usize,
                    p.edge_face_local[idx] as usize,
                );
                let corner = p.face_verts.offsets[f] as usize + l;
                (to_u32(corner), p.face_verts.items[corner])
            };
            if faces.is_empty() {
                out.copy_from_slice(&[half(e, 0), half(e, 1)]);
                return;
            }
            let (first, corner) = face_edge(faces.start);
            let [a, b] = p.edge_verts[e];
            let forward = corner == a && a != b;
            let (a, b) = if forward {
                (half(e, 1), half(e, 0))
            } else {
                (half(e, 0), half(e, 1))
            };
            out[..3].copy_from_slice(&[a, first, b]);
            for (k, idx) in faces.skip(1).enumerate() {
                out[3 + k] = face_edge(idx).0;
            }
        }
    });
    c.vert_edges = edges;
}

/// Sharpness, non-manifold flags, holes and rules of the child level, from the parent alone (so
/// a child with faces only gets them too).
fn child_tags(p: &Level, layout: ChildLayout, method: CreaseMethod, c: &mut Level) {
    let corners = p.face_verts.items.len();
    let (nv, nf, ne) = (p.vertex_count, p.face_count(), p.edge_count());
    // Edges inside parent faces start smooth; the halves of parent edge e are at
    // corners + 2e + (end of e they touch).
    c.edge_sharpness = vec![0.0; corners + 2 * ne];
    let halves = &mut c.edge_sharpness[corners..];
    if method == CreaseMethod::Uniform {
        halves
            .par_chunks_mut(2)
            .zip(&p.edge_sharpness)
            .for_each(|(h, &s)| h.fill(crease::decrement(s)));
    } else {
        // Chaikin: each half depends on the other sharp edges at its end vertex.
        let (mut parent_s, mut child_s) = (Vec::new(), Vec::new());
        for v in 0..nv {
            let edges = p.vert_edges.row(v);
            parent_s.clear();
            parent_s.extend(edges.iter().map(|&e| p.edge_sharpness[e as usize]));
            if !parent_s.iter().any(|&s| crease::is_sharp(s)) {
                continue;
            }
            child_s.resize(parent_s.len(), 0.0);
            crease::subdivide_edges_around_vertex(method, &parent_s, &mut child_s);
            for (i, (&e, &s)) in edges.iter().zip(&child_s).enumerate() {
                halves[2 * e as usize + p.end_in_edge(to_u32(v), edges, i)] = s;
            }
        }
    }
    c.vertex_sharpness = p
        .vertex_sharpness
        .iter()
        .map(|&s| crease::decrement(s))
        .collect();
    c.vertex_sharpness.resize(nv + nf + ne, 0.0);
    c.edge_nonmanifold = vec![false; corners];
    c.edge_nonmanifold
        .extend(p.edge_nonmanifold.iter().flat_map(|&n| [n, n]));
    c.vertex_nonmanifold = p.vertex_nonmanifold.clone();
    c.vertex_nonmanifold.resize(layout.edges, false);
    c.vertex_nonmanifold.extend_from_slice(&p.edge_nonmanifold);
    c.face_hole = per_corner(p, |f| p.face_hole[f]);
    c.vertex_rule = child_rules(p, c);
}

/// The rule of every child vertex, counting its sharp edges through the parent: a vertex
/// point has one half of each parent edge at its vertex, an edge point the two halves of its
/// edge, and edges inside parent faces are smooth, so face points are smooth (what
/// [`Level::assign_rules`] finds on the full child).
fn child_rules(p: &Level, c: &Level) -> Vec<crease::Rule> {
    let corners = p.face_verts.items.len();
    let (nv, nf) = (p.vertex_count, p.face_count());
    let halves = &c.edge_sharpness[corners..];
    // Sharp halves counted at their end vertex, edge by edge (a degenerate edge's two halves
    // both count at its one vertex, as its vertex lists it twice).
    let mut sharp_at = vec![0u32; nv];
    for (e, &[a, b]) in p.edge_verts.iter().enumerate() {
        for (k, v) in [a, b].into_iter().enumerate() {
            if crease::is_sharp(halves[2 * e + k]) {
                sharp_at[v as usize] += 1;
            }
        }
    }
    let mut rules = vec![crease::Rule::Smooth; c.vertex_count];
    let (vertex_points, rest) = rules.split_at_mut(nv);
    let edge_points = &mut rest[nf..];
    vertex_points
        .par_chunks_mut(CHUNK)
        .zip(sharp_at.par_chunks(CHUNK))
        .zip(c.vertex_sharpness.par_chunks(CHUNK))
        .for_each(|((out, sharp), s)| {
            for ((r, &n), &s) in out.iter_mut().zip(sharp).zip(s) {
                *r = crease::Rule::of(s, n as usize);
            }
        });
    edge_points
        .par_chunks_mut(CHUNK)
        .zip(halves.par_chunks(2 * CHUNK))
        .for_each(|(out, h)| {
            for (r, h) in out.iter_mut().zip(h.chunks_exact(2)) {
                let n = usize::from(crease::is_sharp(h[0])) + usize::from(crease::is_sharp(h[1]));
                *r = crease::Rule::of(0.0, n);
            }
        });
    rules
}

/// The weights of every child vertex (see [`Refinement::weights`]), built in parallel.
fn vertex_weights(p: &Level, c: &Level, layout: ChildLayout, options: &Options) -> SparseRows {
    let np = p.vertex_count;
    let face_points = to_u32(np + layout.faces);
    let (nv, nf) = (p.vertex_count, p.face_count());
    // Every row has a fixed length from the topology (weights a rule does not use are zero),
    // so the table is filled in place, in parallel.
    let length = |i: usize| {
        if i < nv {
            p.vert_faces.range(i).len() + p.vert_edges.range(i).len() + 1
        } else if i < nv + nf {
            p.face_verts.range(i - nv).len()
        } else {
            2 + p.edge_faces.range(i - nv - nf).len()
        }
    };
    thread_local! {
        static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
    }
    SparseRows::from_lengths(nv + nf + p.edge_count(), length, |i, cols, weights| {
        SCRATCH.with_borrow_mut(|s| {
            let mut row = Row {
                cols,
                weights,
                next: 0,
            };
            if i < nv {
                vertex_row(p, c, options.crease_method, i, face_points, s, &mut row);
            } else if i < nv + nf {
                let fv = p.face_verts.row(i - nv);
                let w = 1.0 / fv.len() as f64;
                for &v in fv {
                    row.push(v, w);
                }
            } else {
                edge_row(p, c, layout, options, i - nv - nf, face_points, s, &mut row);
            }
            debug_assert_eq!(row.next, row.cols.len());
        });
    })
}

/// A row being written in place.
struct Row<'a> {
    cols: &'a mut [u32],
    weights: &'a mut [f64],
    next: usize,
}

impl RowSink for Row<'_> {
    fn push(&mut self, col: u32, weight: f64) {
        self.cols[self.next] = col;
        self.weights[self.next] = weight;
        self.next += 1;
    }
}

/// The weights of edge point `e`: its two ends, then the face point (column
/// `face_points + f`) of each incident face `f`.
#[allow(clippy::too_many_arguments)]
fn edge_row(
    p: &Level,
    c: &Level,
    layout: ChildLayout,
    options: &Options,
    e: usize,
    face_points: u32,
    s: &mut Scratch,
    out: &mut impl RowSink,
) {
    let faces = p.edge_faces.row(e);
    let sharpness = p.edge_sharpness[e];
    let (vertex, face_weights) = if !crease::is_sharp(sharpness)
        && (options.triangle_rule == TriangleRule::Catmark || faces.len() != 2)
    {
        // The smooth mask, the common case, needs no face sizes.
        let f = if faces.len() == 2 {
            0.25
        } else {
            0.5 / faces.len() as f64
        };
        (0.25, FaceWeights::All(f))
    } else {
        s.sizes.clear();
        s.sizes
            .extend(faces.iter().map(|&f| p.face_verts.range(f as usize).len()));
        let child_rule = c.vertex_rule[layout.of_edge(e) as usize];
        masks::edge_point(
            options.triangle_rule,
            sharpness,
            child_rule,
            &s.sizes,
            &mut s.edge,
        );
        (s.edge.vertex, FaceWeights::Each(&s.edge.faces))
    };
    // The ends first, then the face points, in OpenSubdiv's order of operations.
    for v in p.edge_verts[e] {
        out.push(v, vertex);
    }
    for (k, &f) in faces.iter().enumerate() {
        out.push(face_points + f, face_weights.get(k));
    }
}

/// The face (or edge) weights of a mask: one for all, or each its own (missing ones zero).
enum FaceWeights<'a> {
    All(f64),
    Each(&'a [f64]),
}

impl FaceWeights<'_> {
    #[inline]
    fn get(&self, k: usize) -> f64 {
        match self {
            Self::All(w) => *w,
            Self::Each(ws) => ws.get(k).copied().unwrap_or(0.0),
        }
    }
}

#[derive(Default)]
struct Scratch {
    mask: Mask,
    blend: Mask,
    edge: EdgeMask,
    sizes: Vec<usize>,
    parent_s: Vec<f32>,
    child_s: Vec<f32>,
}

/// The weights of vertex point `v`: the face point (column `face_points + f`) of each incident
/// face `f`, the far end of each incident edge, then `v` itself.
fn vertex_row(
    p: &Level,
    c: &Level,
    method: CreaseMethod,
    v: usize,
    face_points: u32,
    s: &mut Scratch,
    out: &mut impl RowSink,
) {
    let edges = p.vert_edges.row(v);
    let vi = to_u32(v);
    let (vertex, face_weights, edge_weights) = if p.vertex_rule[v].is_smooth() {
        // Smooth and dart vertices take the smooth mask whatever their child's rule, and
        // need no sharpness (the common case).
        let n = p.vert_faces.range(v).len() as f64;
        let w = 1.0 / (n * n);
        ((n - 2.0) / n, FaceWeights::All(w), FaceWeights::All(w))
    } else {
        let corners = p.face_verts.items.len();
        s.parent_s.clear();
        s.parent_s
            .extend(edges.iter().map(|&e| p.edge_sharpness[e as usize]));
        s.child_s.clear();
        s.child_s.extend(edges.iter().enumerate().map(|(i, &e)| {
            let k = p.end_in_edge(vi, edges, i);
            c.edge_sharpness[corners + 2 * e as usize + k]
        }));
        let hood = VertexNeighbourhood {
            faces: p.vert_faces.range(v).len(),
            parent_rule: p.vertex_rule[v],
            child_rule: c.vertex_rule[v],
            parent_sharpness: p.vertex_sharpness[v],
            child_sharpness: c.vertex_sharpness[v],
            parent_edges: &s.parent_s,
            child_edges: &s.child_s,
        };
        masks::vertex_point(method, &hood, &mut s.mask, &mut s.blend);
        (
            s.mask.vertex,
            FaceWeights::Each(&s.mask.faces),
            FaceWeights::Each(&s.mask.edges),
        )
    };
    // Smaller weights first, as OpenSubdiv applies them: faces, edges, then the vertex.
    for (k, &f) in p.vert_faces.row(v).iter().enumerate() {
        out.push(face_points + f, face_weights.get(k));
    }
    for (k, &e) in edges.iter().enumerate() {
        out.push(p.other_end(e, vi), edge_weights.get(k));
    }
    out.push(vi, vertex);
}
