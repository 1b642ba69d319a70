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
//! flags and sharpness propagate from parent to child components.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::mesh::to_u32;
use crate::options::{CreaseMethod, Options};
use crate::rules::crease;
use crate::rules::masks::{self, EdgeMask, Mask, VertexNeighbourhood};
use crate::sparse::{CHUNK, Primvar, SparseRows, fill_rows, offsets_from_lengths};
use crate::topology::{Csr, Level};

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
        let layout = ChildLayout::new(parent);
        let child = child_topology(parent, layout, options.crease_method);
        Self {
            child,
            layout,
            options: *options,
            weights: OnceLock::new(),
        }
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
        let face_point = |f: usize| to_u32(p.vertex_count + layout.faces + f);
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
                vertex_row(p, c, options.crease_method, i, &face_point, s, g);
            } else {
                edge_row(p, c, layout, options, i - layout.edges, &face_point, s, g);
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

/// The child level's topology and tags.
fn child_topology(p: &Level, layout: ChildLayout, method: CreaseMethod) -> Level {
    let corners = p.face_verts.items.len();
    let (nv, nf, ne) = (p.vertex_count, p.face_count(), p.edge_count());
    let corner_face = corner_faces(p);
    let half = |e: usize, k: usize| to_u32(corners + 2 * e + k);
    let mut c = Level {
        vertex_count: nv + nf + ne,
        face_verts: Csr {
            offsets: (0..=corners)
                .into_par_iter()
                .map(|i| to_u32(4 * i))
                .collect(),
            items: vec![0; 4 * corners],
        },
        face_edges: vec![0; 4 * corners],
        ..Level::default()
    };
    // Faces: child i is the quad at corner i of its parent face.
    c.face_verts
        .items
        .par_chunks_mut(4)
        .zip(c.face_edges.par_chunks_mut(4))
        .enumerate()
        .for_each(|(i, (cv, ce))| {
            let f = corner_face[i] as usize;
            let range = p.face_verts.range(f);
            let (n, j) = (range.len(), i - range.start);
            let jp = (j + n - 1) % n;
            let fv = &p.face_verts.items[range.clone()];
            let fe = &p.face_edges[range.clone()];
            let corner_in_edge = |e: u32| usize::from(p.edge_verts[e as usize][0] != fv[j]);
            let verts = [
                layout.of_vertex(fv[j] as usize),
                layout.of_edge(fe[j] as usize),
                layout.of_face(f),
                layout.of_edge(fe[jp] as usize),
            ];
            let edges = [
                half(fe[j] as usize, corner_in_edge(fe[j])),
                to_u32(range.start + j),
                to_u32(range.start + jp),
                half(fe[jp] as usize, corner_in_edge(fe[jp])),
            ];
            // Quads keep the vertex point at index j; other polygons put it first.
            let rot = if n == 4 { j } else { 0 };
            for k in 0..4 {
                cv[(k + rot) % 4] = verts[k];
                ce[(k + rot) % 4] = edges[k];
            }
        });
    // Edges: interior edges of faces (face point → edge point), then halves of parent edges.
    c.edge_verts = (0..corners + 2 * ne)
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
    child_edge_faces(p, &corner_face, &mut c);
    child_vertex_faces(p, layout, &mut c);
    child_vertex_edges(p, layout, &mut c);
    child_tags(p, layout, method, &mut c);
    c
}

/// The face of every corner of `p` (the inverse of its face offsets).
fn corner_faces(p: &Level) -> Vec<u32> {
    let mut out = vec![0u32; p.face_verts.items.len()];
    let mut unit = vec![(); out.len()];
    fill_rows(&p.face_verts.offsets, &mut out, &mut unit, |f, row, _| {
        row.fill(to_u32(f))
    });
    out
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
                local.copy_from_slice(&[to_u32(l0), to_u32(l1)]);
                return;
            }
            // Half k of parent edge e: in each parent face, the child quad at that end.
            let (e, k) = ((i - corners) / 2, (i - corners) % 2);
            let end = p.edge_verts[e][k];
            for (slot, idx) in p.edge_faces.range(e).enumerate() {
                let (pf, l) = (
                    p.edge_faces.items[idx] as usize,
                    p.edge_face_local[idx] as usize,
                );
                let fr = p.face_verts.range(pf);
                let n = fr.len();
                let of_edge = usize::from(p.face_verts.items[fr.start + l] != end);
                faces[slot] = child_face(p, pf, (l + of_edge) % n);
                local[slot] = to_u32(if n == 4 {
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
                    local[slot] = to_u32(if quad { l } else { 0 });
                }
            } else if i < nv + nf {
                let f = i - nv;
                let n = faces.len();
                for j in 0..n {
                    faces[j] = child_face(p, f, j);
                    local[j] = to_u32(if n == 4 { (j + 2) % 4 } else { 2 });
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
                    local[2 * slot] = to_u32(if n == 4 { l } else { 3 });
                    faces[2 * slot + 1] = child_face(p, f, l);
                    local[2 * slot + 1] = to_u32(if n == 4 { l1 } else { 1 });
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
            for (slot, &e) in out.iter_mut().zip(p.vert_edges.row(i)) {
                *slot = half(
                    e as usize,
                    usize::from(p.edge_verts[e as usize][0] != to_u32(i)),
                );
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
            let forward = corner == p.edge_verts[e][0];
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

/// Sharpness, non-manifold flags, holes and rules of the child level.
fn child_tags(p: &Level, layout: ChildLayout, method: CreaseMethod, c: &mut Level) {
    let corners = p.face_verts.items.len();
    let (nv, nf, ne) = (p.vertex_count, p.face_count(), p.edge_count());
    c.edge_sharpness = vec![0.0; corners + 2 * ne];
    let mut parent_s = Vec::new();
    let mut child_s = Vec::new();
    for v in 0..nv {
        let edges = p.vert_edges.row(v);
        parent_s.clear();
        parent_s.extend(edges.iter().map(|&e| p.edge_sharpness[e as usize]));
        if !parent_s.iter().any(|&s| crease::is_sharp(s)) {
            continue;
        }
        child_s.resize(parent_s.len(), 0.0);
        crease::subdivide_edges_around_vertex(method, &parent_s, &mut child_s);
        for (&e, &s) in edges.iter().zip(&child_s) {
            let k = usize::from(p.edge_verts[e as usize][0] != to_u32(v));
            c.edge_sharpness[corners + 2 * e as usize + k] = s;
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
    c.face_hole = (0..nf)
        .flat_map(|f| std::iter::repeat_n(p.face_hole[f], p.face_verts.range(f).len()))
        .collect();
    c.assign_rules();
}

/// The weights of every child vertex (see [`Refinement::weights`]), built in parallel.
fn vertex_weights(p: &Level, c: &Level, layout: ChildLayout, options: &Options) -> SparseRows {
    let np = p.vertex_count;
    let face_point = |f: usize| to_u32(np + layout.faces + f);
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
                vertex_row(p, c, options.crease_method, i, &face_point, s, &mut row);
            } else if i < nv + nf {
                let fv = p.face_verts.row(i - nv);
                let w = 1.0 / fv.len() as f64;
                for &v in fv {
                    row.push(v, w);
                }
            } else {
                edge_row(p, c, layout, options, i - nv - nf, &face_point, s, &mut row);
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

#[allow(clippy::too_many_arguments)]
fn edge_row(
    p: &Level,
    c: &Level,
    layout: ChildLayout,
    options: &Options,
    e: usize,
    face_point: &dyn Fn(usize) -> u32,
    s: &mut Scratch,
    out: &mut impl RowSink,
) {
    let faces = p.edge_faces.row(e);
    s.sizes.clear();
    s.sizes
        .extend(faces.iter().map(|&f| p.face_verts.range(f as usize).len()));
    let child_rule = c.vertex_rule[layout.of_edge(e) as usize];
    masks::edge_point(
        options.triangle_rule,
        p.edge_sharpness[e],
        child_rule,
        &s.sizes,
        &mut s.edge,
    );
    // The ends first, then the face points, in OpenSubdiv's order of operations.
    for v in p.edge_verts[e] {
        out.push(v, s.edge.vertex);
    }
    for (k, &f) in faces.iter().enumerate() {
        out.push(
            face_point(f as usize),
            s.edge.faces.get(k).copied().unwrap_or(0.0),
        );
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

fn vertex_row(
    p: &Level,
    c: &Level,
    method: CreaseMethod,
    v: usize,
    face_point: &dyn Fn(usize) -> u32,
    s: &mut Scratch,
    out: &mut impl RowSink,
) {
    let edges = p.vert_edges.row(v);
    let corners = p.face_verts.items.len();
    s.parent_s.clear();
    s.parent_s
        .extend(edges.iter().map(|&e| p.edge_sharpness[e as usize]));
    s.child_s.clear();
    s.child_s.extend(edges.iter().map(|&e| {
        let k = usize::from(p.edge_verts[e as usize][0] != to_u32(v));
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
    // Smaller weights first, as OpenSubdiv applies them: faces, edges, then the vertex.
    for (k, &f) in p.vert_faces.row(v).iter().enumerate() {
        out.push(
            face_point(f as usize),
            s.mask.faces.get(k).copied().unwrap_or(0.0),
        );
    }
    for (k, &e) in edges.iter().enumerate() {
        out.push(
            p.other_end(e, to_u32(v)),
            s.mask.edges.get(k).copied().unwrap_or(0.0),
        );
    }
    out.push(to_u32(v), s.mask.vertex);
}
