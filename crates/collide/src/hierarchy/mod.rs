//! The coarsening hierarchy of DeRose, Kass & Truong (1998, §5): a binary tree over the faces of
//! a polygon mesh whose shape depends only on the topology.
//!
//! Nodes are numbered so that a flat, bottom-up pass is a plain loop: leaves `0..F` are the faces
//! (node `f` is face `f`), internal node `F + i` has children `children[i]`, and internal nodes are
//! stored level by level, so every child precedes its parent and the root is the last node. All
//! per-node data (boxes, leaf counts, boundary chains) are flat arrays indexed by node, and a
//! depth-first numbering of the faces makes the faces below any node one contiguous slice.
//! [`build`] makes the tree, [`refit`] the boxes.

pub(crate) mod boxes;
mod build;
mod refit;

use std::hash::{Hash, Hasher};
use std::sync::OnceLock;

use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use crate::Point;
use crate::cones::Witnesses;
use crate::convert::to_glam;
use crate::error::CollideError;
use crate::memory::heap;
use crate::proximity::LocalFaces;
use crate::topology::Topology;

use boxes::Boxes;
use boxes::LEAF;
pub(crate) use boxes::Pending;

/// Below this many nodes a level is refit on one thread.
const PARALLEL_MIN: usize = 512;

/// A coarsening hierarchy over a polygon mesh, with the boxes of its last refit.
///
/// Build it once per topology with [`Hierarchy::build`], then call [`Hierarchy::refit`] (or
/// [`Hierarchy::refit_swept`] for continuous queries) whenever the vertices move. Queries read
/// the positions of the last refit.
#[derive(Clone, Debug)]
pub struct Hierarchy {
    pub(crate) topology: Topology,
    /// Children of internal node `F + i`.
    pub(crate) children: Vec<[u32; 2]>,
    /// Internal nodes of level `k` are `F + level_offsets[k] .. F + level_offsets[k + 1]`.
    pub(crate) level_offsets: Vec<u32>,
    /// Number of faces below each node.
    pub(crate) leaf_counts: Vec<u32>,
    /// The faces in depth-first order: node `n` covers `leaf_order[leaf_first[n]..][..leaf_counts[n]]`.
    leaf_order: Vec<u32>,
    leaf_first: Vec<u32>,
    /// The places `[first, end)` in `leaf_order` of the faces below each internal node, by
    /// record (node `F + i` is record `i`).
    record_spans: Vec<[u32; 2]>,
    /// A hash of `leaf_order`.
    order_fingerprint: u64,
    /// The faces using each vertex, made on first use (see [`Hierarchy::vertex_faces`]).
    pub(crate) vertex_faces: OnceLock<LocalFaces>,
    /// CSR over nodes: the directed boundary edges of each node's faces (see [`build`]).
    pub(crate) boundary_offsets: Vec<u32>,
    pub(crate) boundary: Vec<[u32; 2]>,
    /// The box of every node, from the last refit (see [`boxes`]).
    boxes: Boxes,
    /// Positions of the last refit; for a swept refit, at the start of the step.
    pub(crate) start: Vec<DVec3>,
    /// Positions at the end of the step of a swept refit; empty after a static refit.
    end: Vec<DVec3>,
    /// The kind and margin of the last refit.
    last_refit: LastRefit,
    /// How many refits this value has had (see [`Hierarchy::refit_count`]).
    refits: u64,
    /// The triangle that last failed each node's and each vertex star's normal-cone test
    /// (see [`crate::cones`]).
    pub(crate) witnesses: Witnesses,
}

/// What the last refit boxed, with the margin it loosened the boxes by: a refit like it from
/// the same positions leaves the boxes as they are.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LastRefit {
    Static(f64),
    Swept(f64),
}

impl Hierarchy {
    /// Builds the hierarchy of a polygon mesh given as CSR faces, and refits it at `positions`.
    ///
    /// The tree depends on the topology, except where pieces with no neighbour left are paired
    /// by where they lie at `positions`, so pass a representative pose such as the rest pose;
    /// the tree stays valid for any later positions.
    ///
    /// # Errors
    /// [`CollideError`] when there are no faces, the CSR tables are inconsistent, a face is
    /// shorter than a triangle, repeats a vertex or names a missing vertex, or a position is not
    /// finite.
    pub fn build(
        positions: &[Point],
        face_offsets: &[u32],
        face_vertices: &[u32],
    ) -> Result<Self, CollideError> {
        let topology = Topology::new(positions.len(), face_offsets, face_vertices)?;
        let start = to_glam_checked(positions, positions.len())?;
        let tree = build::coarsen(&topology, &start);
        let mut hierarchy = Self {
            topology,
            children: tree.children,
            level_offsets: tree.level_offsets,
            leaf_counts: Vec::new(),
            leaf_order: Vec::new(),
            leaf_first: Vec::new(),
            record_spans: Vec::new(),
            order_fingerprint: 0,
            vertex_faces: OnceLock::new(),
            boundary_offsets: Vec::new(),
            boundary: Vec::new(),
            boxes: Boxes::default(),
            start,
            end: Vec::new(),
            last_refit: LastRefit::Static(0.0),
            refits: 0,
            witnesses: Witnesses::default(),
        };
        hierarchy.leaf_counts = hierarchy.fold_up(|_| 1, |a, b| a + b);
        hierarchy.order_leaves();
        (hierarchy.boundary_offsets, hierarchy.boundary) = build::boundary_chains(&hierarchy);
        hierarchy.boxes = Boxes::new(hierarchy.face_count(), &hierarchy.children);
        hierarchy.refit_boxes(0.0);
        hierarchy.witnesses = Witnesses::of(&hierarchy);
        Ok(hierarchy)
    }

    /// Heap bytes held by the hierarchy: its topology tables, tree, boxes and the positions of
    /// the last refit (capacities, not lengths). Grows linearly with the face count.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.topology.memory_bytes()
            + heap(&self.children)
            + heap(&self.level_offsets)
            + heap(&self.leaf_counts)
            + heap(&self.leaf_order)
            + heap(&self.leaf_first)
            + heap(&self.record_spans)
            + self
                .vertex_faces
                .get()
                .map_or(0, |t| heap(&t.offsets) + heap(&t.faces))
            + heap(&self.boundary_offsets)
            + heap(&self.boundary)
            + self.boxes.memory_bytes()
            + heap(&self.start)
            + heap(&self.end)
            + self.witnesses.memory_bytes()
    }

    /// Number of faces (leaves).
    #[must_use]
    pub fn face_count(&self) -> usize {
        self.topology.face_count()
    }

    /// Number of fan triangles the faces split into.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.topology.triangles.len()
    }

    /// How many refits of any kind this value has had. A caller that refit it and finds the
    /// count unchanged later knows the boxes and positions are still those of its own refit,
    /// without comparing them (see [`Hierarchy::refit_swept_ends`]).
    #[must_use]
    pub fn refit_count(&self) -> u64 {
        self.refits
    }

    /// Number of vertices the mesh was built with.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.topology.vertex_count
    }

    /// The largest magnitude of a coordinate in the root's box, as of the last refit (its
    /// margin and sweep included): a bound on every coordinate of the faces, and so the scale
    /// of what rounding their positions (to write them as `f32`, say) can move them by.
    #[must_use]
    pub fn largest_coordinate(&self) -> f64 {
        let root = self.boxes.root_box();
        root.iter()
            .fold(0.0, |m: f64, &c| m.max(f64::from(c.abs())))
    }

    /// The distance from `q` to the box around every face at the last refit (its margin and
    /// sweep included, rounded outward), 0 inside it: a lower bound of `q`'s distance to the
    /// mesh, and for a point outside the box of a closed mesh, of its signed distance, as
    /// nothing of the mesh lies outside it. One box test, where the closest point of a query
    /// far from the mesh searches many of its faces. NaN for a point that is not finite, which
    /// bounds nothing (the queries that measure report such a point as an error).
    #[must_use]
    pub fn box_distance(&self, q: &Point) -> f64 {
        if finite(q) {
            self.boxes.root_distance(to_glam(q))
        } else {
            f64::NAN
        }
    }

    /// Number of levels above the leaves: about `log2` of the face count.
    #[must_use]
    pub fn depth(&self) -> usize {
        self.level_offsets.len() - 1
    }

    /// The fan triangles (vertex triples, counter-clockwise as the faces), in face order.
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.topology.triangles
    }

    /// The face each fan triangle belongs to; the triangles come face by face, in face order.
    #[must_use]
    pub fn triangle_faces(&self) -> &[u32] {
        &self.topology.triangle_face
    }

    /// Number of fan triangles of zero area at the positions of the last refit; the exact tests
    /// skip them.
    #[must_use]
    pub fn degenerate_triangles(&self) -> usize {
        (0..self.triangle_count())
            .into_par_iter()
            .filter(|&t| crate::triangle::is_degenerate(self.triangle_at(t, self.end())))
            .count()
    }

    /// Whether the last refit was swept (its end positions differ from its start).
    pub(crate) fn is_swept(&self) -> bool {
        !self.end.is_empty()
    }

    /// The current positions: those of a static refit, or the end of a swept one.
    pub(crate) fn end(&self) -> &[DVec3] {
        if self.is_swept() {
            &self.end
        } else {
            &self.start
        }
    }

    /// Numbers the faces depth-first, so the faces below any node are contiguous.
    fn order_leaves(&mut self) {
        let faces = self.face_count();
        self.leaf_first = vec![0; faces + self.children.len()];
        for (i, &[a, b]) in self.children.iter().enumerate().rev() {
            let first = self.leaf_first[faces + i];
            self.leaf_first[a as usize] = first;
            self.leaf_first[b as usize] = first + self.leaf_counts[a as usize];
        }
        self.leaf_order = vec![0; faces];
        for f in 0..faces {
            self.leaf_order[self.leaf_first[f] as usize] = f as u32;
        }
        self.record_spans = (faces..faces + self.children.len())
            .map(|n| [self.leaf_first[n], self.leaf_first[n] + self.leaf_counts[n]])
            .collect();
        let mut hasher = std::hash::DefaultHasher::new();
        self.leaf_order.hash(&mut hasher);
        self.order_fingerprint = hasher.finish();
    }

    /// Calls `leaf(face)` for every face whose box (at the last refit) is within squared
    /// distance `bound` of `q`, except those below the node `seed` (which the caller has
    /// considered already; the walk climbs from it) and below the nodes whose faces lie wholly
    /// within one of the `skipped` ranges of the depth-first order
    /// ([`Hierarchy::leaf_position`]), nearer faces first; `leaf` returns the bound from then
    /// on, which may only shrink. `stack` is scratch space, reused from query to query.
    pub(crate) fn visit_near(
        &self,
        q: DVec3,
        bound: f64,
        seed: Option<u32>,
        stack: &mut Vec<Pending>,
        skipped: &[[u32; 2]],
        leaf: impl FnMut(u32) -> f64,
    ) {
        let skip = |record: u32| self.within_ranges(record, skipped);
        let seed = seed.map(|node| self.reference(node));
        self.boxes.visit_near(q, bound, seed, stack, skip, leaf);
    }

    /// Whether the faces below record `record` lie wholly within one of `ranges` of the
    /// depth-first order.
    #[inline(always)]
    fn within_ranges(&self, record: u32, ranges: &[[u32; 2]]) -> bool {
        let [first, end] = self.record_spans[record as usize];
        ranges.iter().any(|&[a, b]| a <= first && end <= b)
    }

    /// The reference to node `node` in the boxes' records: `LEAF | face`, or a record.
    fn reference(&self, node: u32) -> u32 {
        let faces = self.face_count() as u32;
        if node < faces {
            LEAF | node
        } else {
            node - faces
        }
    }

    /// The highest node above face `f` (itself included) whose faces lie wholly within one of
    /// `ranges` of the depth-first order.
    pub(crate) fn highest_within(&self, f: u32, ranges: &[[u32; 2]]) -> u32 {
        let mut node = LEAF | f;
        while let Some(parent) = self.boxes.parent(node)
            && self.within_ranges(parent, ranges)
        {
            node = parent;
        }
        self.node_id(node) as u32
    }

    /// The node (face `f`, or `F + i` for record `i`) a reference in the boxes' records names:
    /// the inverse of [`Self::reference`].
    #[inline(always)]
    pub(crate) fn node_id(&self, reference: u32) -> usize {
        if reference & LEAF != 0 {
            (reference & !LEAF) as usize
        } else {
            self.face_count() + reference as usize
        }
    }

    /// Per node (faces, then records, as [`Self::node_id`] numbers them), whether a vertex
    /// below it is one that `moved` flags: the faces around each moved vertex and the records
    /// above them, climbing until a record already marked, so the cost follows what moved.
    ///
    /// # Panics
    /// If `moved` has fewer entries than the mesh has vertices.
    pub(crate) fn nodes_moved(&self, moved: &[bool]) -> Vec<bool> {
        let faces = self.face_count();
        let mut marked = vec![false; faces + self.children.len()];
        let around = self.vertex_faces();
        for v in (0..self.vertex_count()).filter(|&v| moved[v]) {
            for &f in around.of(v) {
                if std::mem::replace(&mut marked[f as usize], true) {
                    continue;
                }
                let mut node = LEAF | f;
                while let Some(record) = self.boxes.parent(node)
                    && !std::mem::replace(&mut marked[faces + record as usize], true)
                {
                    node = record;
                }
            }
        }
        marked
    }

    /// The place of face `f` in the depth-first order, where the faces below any node are
    /// contiguous.
    pub(crate) fn leaf_position(&self, f: u32) -> u32 {
        self.leaf_first[f as usize]
    }

    /// A fingerprint of the depth-first order of the faces: two hierarchies with the same
    /// fingerprint place the faces alike.
    pub(crate) fn order_fingerprint(&self) -> u64 {
        self.order_fingerprint
    }

    /// The boxes at the last refit.
    pub(crate) fn boxes(&self) -> &Boxes {
        &self.boxes
    }

    /// The box of `node` at the last refit.
    #[cfg(test)]
    pub(crate) fn node_box(&self, node: u32) -> parry3d_f64::bounding_volume::Aabb {
        self.boxes
            .node_box(node, self.face_count() as u32, self.root())
    }

    /// The faces below `node`.
    pub(crate) fn leaves_below(&self, node: u32) -> &[u32] {
        let n = node as usize;
        let first = self.leaf_first[n] as usize;
        &self.leaf_order[first..first + self.leaf_counts[n] as usize]
    }

    /// The node id of the root.
    pub(crate) fn root(&self) -> u32 {
        (self.face_count() + self.children.len() - 1) as u32
    }

    /// The children of `node`, or `None` for a leaf.
    #[cfg(test)]
    pub(crate) fn node_children(&self, node: u32) -> Option<[u32; 2]> {
        let f = self.face_count() as u32;
        (node >= f).then(|| self.children[(node - f) as usize])
    }

    /// The boundary chain of `node`.
    pub(crate) fn node_boundary(&self, node: u32) -> &[[u32; 2]] {
        let n = node as usize;
        &self.boundary[self.boundary_offsets[n] as usize..self.boundary_offsets[n + 1] as usize]
    }

    /// The corners of fan triangle `t` at `positions`.
    pub(crate) fn triangle_at(&self, t: usize, positions: &[DVec3]) -> [DVec3; 3] {
        let [a, b, c] = self.topology.triangles[t];
        [
            positions[a as usize],
            positions[b as usize],
            positions[c as usize],
        ]
    }

    /// Computes one value per node bottom-up: `leaf(f)` for face `f`, then `merge` of the two
    /// children, one level at a time, each level in parallel. O(n); the result does not depend
    /// on the thread count.
    pub(crate) fn fold_up<T: Copy + Send + Sync>(
        &self,
        leaf: impl Fn(u32) -> T + Sync,
        merge: impl Fn(&T, &T) -> T + Sync,
    ) -> Vec<T> {
        let faces = self.face_count();
        let mut out: Vec<T> = (0..faces as u32)
            .into_par_iter()
            .with_min_len(PARALLEL_MIN)
            .map(&leaf)
            .collect();
        out.resize(faces + self.children.len(), out[0]);
        for level in self.level_offsets.windows(2) {
            let (lo, hi) = (level[0] as usize, level[1] as usize);
            let (done, rest) = out.split_at_mut(faces + lo);
            rest[..hi - lo]
                .par_iter_mut()
                .with_min_len(PARALLEL_MIN)
                .zip(&self.children[lo..hi])
                .for_each(|(o, &[a, b])| *o = merge(&done[a as usize], &done[b as usize]));
        }
        out
    }
}

/// Runs a query that fills a buffer (an `_into` variant) on a new one and returns it.
pub(crate) fn fresh<T: Default>(
    into: impl FnOnce(&mut T) -> Result<(), CollideError>,
) -> Result<T, CollideError> {
    let mut out = T::default();
    into(&mut out)?;
    Ok(out)
}

/// Converts positions to glam, checking their count and that they are finite.
pub(crate) fn to_glam_checked(
    positions: &[Point],
    expected: usize,
) -> Result<Vec<DVec3>, CollideError> {
    let mut out = Vec::new();
    convert_into(positions, expected, &mut out)?;
    Ok(out)
}

/// Converts positions to glam into `out` (reusing its allocation), checking their count and
/// that they are finite.
pub(crate) fn convert_into(
    positions: &[Point],
    expected: usize,
    out: &mut Vec<DVec3>,
) -> Result<(), CollideError> {
    check_positions(positions, expected)?;
    store(positions, out);
    Ok(())
}

/// Converts positions already checked to glam into `out`, reusing its allocation.
pub(crate) fn store(positions: &[Point], out: &mut Vec<DVec3>) {
    out.clear();
    out.extend(positions.iter().map(to_glam));
}

/// Checks that there are `expected` positions and that they are finite.
pub(crate) fn check_positions(positions: &[Point], expected: usize) -> Result<(), CollideError> {
    check_count(positions, expected)?;
    match positions.iter().position(|p| !finite(p)) {
        Some(vertex) => Err(CollideError::NonFinitePosition { vertex }),
        None => Ok(()),
    }
}

/// Checks that a position array has `expected` entries.
pub(crate) fn check_count(positions: &[Point], expected: usize) -> Result<(), CollideError> {
    if positions.len() == expected {
        Ok(())
    } else {
        Err(CollideError::PositionCount {
            expected,
            given: positions.len(),
        })
    }
}

/// Whether every coordinate of `p` is finite.
pub(crate) fn finite(p: &Point) -> bool {
    p.coords.iter().all(|c| c.is_finite())
}

/// Checks that a distance parameter is a number `>= 0` (infinity allowed).
pub(crate) fn check_distance(what: &'static str, value: f64) -> Result<(), CollideError> {
    if value >= 0.0 {
        Ok(())
    } else {
        Err(CollideError::BadDistance { what, value })
    }
}

/// For tests: `copies` detached `n × n` grids of unit quads, the first in the plane z = 0,
/// each next one 10 above.
#[cfg(test)]
pub(crate) fn grid(n: u32, copies: u32) -> (Vec<Point>, Vec<u32>, Vec<u32>) {
    let (mut positions, mut offsets, mut corners) = (Vec::new(), vec![0], Vec::new());
    for copy in 0..copies {
        let base = positions.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                positions.push(Point::new(i as f64, j as f64, 10.0 * copy as f64));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = base + j * (n + 1) + i;
                corners.extend([v, v + 1, v + n + 2, v + n + 1]);
                offsets.push(corners.len() as u32);
            }
        }
    }
    (positions, offsets, corners)
}
