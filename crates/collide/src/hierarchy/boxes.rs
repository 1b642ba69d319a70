//! The boxes of the hierarchy, stored two to a record, and the descent of point queries.
//!
//! A query at an internal node compares its two children's boxes, so each internal node is one
//! record holding both children's boxes and references, as in parry's `Bvh` (a binary "wide"
//! BVH, Wald, Benthin & Boulos 2008). Record `i` is internal node `F + i`, so the records are in
//! the tree's level order and every child's record precedes its parent's. The boxes are single
//! precision, rounded outward: a record takes 60 bytes instead of 108, a box still contains its
//! faces, and distances to it remain lower bounds, so pruning stays exact; the box tests only
//! become a little looser, and every answer is decided by an exact test on the faces.
//!
//! A refit first rounds each vertex outward to a single-precision box (around its start and end
//! positions for a swept refit, loosened by the margin), so a face's box is the union of its
//! corners' boxes, rounded again only by the face's relative slack. Then it boxes every face,
//! and pulls, level by level and in parallel within a level: a record takes its leaf
//! children's face boxes and merges the two boxes of each internal child's record, which a
//! lower level has just finished. Each vertex is rounded once, each face boxed once and each
//! record written once; the vertices and the faces are boxed in vector registers where the
//! machine has AVX2 ([`Fit::boxes_into`]).
//!
//! Point queries descend depth first, nearer child first, pruning on a bound that the caller
//! may shrink as it finds closer faces; a query farther than the bound from the root's box
//! stops there, seed or not. A query that starts from a seed face (the answer to a
//! nearby query) instead climbs from the seed's record to the root, descending into each
//! sibling subtree whose box is within the bound: one box test per level where a descent from
//! the root needs two, and the faces near the seed come first. The seed may be a subtree whose
//! faces the caller knows to skip, and the caller may name other subtrees to leave out.

use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use crate::memory::heap;

/// Marks a child reference as a leaf: the rest of the bits are the face.
pub(crate) const LEAF: u32 = 1 << 31;

/// No record: the parent of the root.
const NONE: u32 = u32::MAX;

/// Records refit in a row by one thread.
const REFIT_RUN: usize = 1024;

/// Levels with fewer records than this are refit on one thread: a level of two runs is
/// worth splitting. The 64² drape's refined surface (16,641 vertices, 16,129 faces) then
/// refits its vertices and its three lowest levels on both cores, where at sixteen runs it
/// refit everything but its vertices on one: its swept refits, one a substep at the start of
/// its self queries and on the simulating thread, took 21–26 ms of the run instead of
/// 29–34 ms.
const PARALLEL_LEVEL: usize = 2 * REFIT_RUN;

/// A box as `[min x, min y, min z, max x, max y, max z]`, rounded outward to `f32`.
pub(crate) type SmallBox = [f32; 6];

/// The empty box, the identity of [`union`].
const EMPTY: SmallBox = [
    f32::INFINITY,
    f32::INFINITY,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
    f32::NEG_INFINITY,
];

/// One internal node: the boxes and references of its two children.
#[derive(Clone, Copy, Debug)]
struct Record {
    boxes: [SmallBox; 2],
    /// A child's record index, or `LEAF | face`.
    child: [u32; 2],
    /// The parent's record index, [`NONE`] at the root.
    parent: u32,
}

/// The boxes of every node of a hierarchy.
#[derive(Clone, Debug)]
pub(crate) struct Boxes {
    records: Vec<Record>,
    /// For each face, the record holding it and on which side: `record << 1 | side`.
    leaf_slot: Vec<u32>,
    /// The root's box (the only face's, for a one-face mesh).
    root: SmallBox,
    /// Each vertex's box at the last refit.
    vertices: Vec<SmallBox>,
    /// Each face's box at the last refit.
    faces: Vec<SmallBox>,
}

/// What a refit boxes: the faces (CSR) and their vertices' motion.
pub(crate) struct Fit<'a> {
    pub(crate) face_offsets: &'a [u32],
    pub(crate) face_vertices: &'a [u32],
    pub(crate) start: &'a [DVec3],
    /// The end positions of a swept refit.
    pub(crate) end: Option<&'a [DVec3]>,
    pub(crate) margin: f64,
    /// Each face's box is loosened by this fraction of the sum of its extents.
    pub(crate) relative: f64,
}

impl Fit<'_> {
    /// The box of vertex `v`: around its start and end positions, loosened by the margin and
    /// rounded outward.
    #[inline]
    fn vertex(&self, v: usize) -> SmallBox {
        let pad = DVec3::splat(self.margin);
        let p = self.start[v];
        let (lo, hi) = self
            .end
            .map_or((p, p), |end| (p.min(end[v]), p.max(end[v])));
        outward(lo - pad, hi + pad)
    }

    /// Boxes `first..first + out.len()` into `out`: of the vertices, each as [`Fit::vertex`]
    /// makes it, or with `corners` (the vertices' boxes) of the faces, each as [`Fit::face`]
    /// makes it. In vector registers where the machine has AVX2 (through `pulp`, as the
    /// normal cones' scans): a vertex's three coordinates, or a box's three low and three
    /// high sides, in three lanes, the union and every operation of [`outward`] in their
    /// order, so the same bits.
    fn boxes_into(&self, corners: Option<&[SmallBox]>, first: usize, out: &mut [SmallBox]) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            return simd.vectorize(lanes::Boxing {
                simd,
                fit: self,
                corners,
                first,
                out,
            });
        }
        for (k, b) in (first..).zip(out) {
            *b = corners.map_or_else(|| self.vertex(k), |vertices| self.face(vertices, k));
        }
    }

    /// [`Fit::boxes_into`] of all `count` vertices, or faces with `corners`, into `out`: in
    /// runs of [`REFIT_RUN`] on the pool when there are [`PARALLEL_LEVEL`] or more.
    fn boxes_all(&self, corners: Option<&[SmallBox]>, count: usize, out: &mut Vec<SmallBox>) {
        out.resize(count, EMPTY);
        if count < PARALLEL_LEVEL {
            self.boxes_into(corners, 0, out);
        } else {
            out.par_chunks_mut(REFIT_RUN)
                .enumerate()
                .for_each(|(c, out)| self.boxes_into(corners, c * REFIT_RUN, out));
        }
    }

    /// The box of face `f`: the union of its corners' `vertices` boxes, loosened by
    /// [`Fit::relative`].
    #[inline]
    fn face(&self, vertices: &[SmallBox], f: usize) -> SmallBox {
        let corners =
            &self.face_vertices[self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize];
        let b = corners
            .iter()
            .fold(EMPTY, |b, &v| union(&b, &vertices[v as usize]));
        let (lo, hi) = widen(&b);
        let pad = DVec3::splat(self.relative * (hi - lo).element_sum());
        outward(lo - pad, hi + pad)
    }
}

/// A node still to visit: a record, with the squared distance from the query to its box.
pub(crate) type Pending = (u32, f64);

impl Default for Boxes {
    fn default() -> Self {
        Self {
            records: Vec::new(),
            leaf_slot: Vec::new(),
            root: EMPTY,
            vertices: Vec::new(),
            faces: Vec::new(),
        }
    }
}

impl Boxes {
    /// The records of the tree with internal nodes `children` over `faces` leaves, unfitted.
    pub(crate) fn new(faces: usize, children: &[[u32; 2]]) -> Self {
        let reference = |c: u32| match (c as usize).checked_sub(faces) {
            None => LEAF | c,
            Some(i) => i as u32,
        };
        let mut records: Vec<Record> = children
            .iter()
            .map(|&[a, b]| Record {
                boxes: [EMPTY; 2],
                child: [reference(a), reference(b)],
                parent: NONE,
            })
            .collect();
        let mut leaf_slot = vec![NONE; faces];
        for r in 0..records.len() {
            for (side, c) in records[r].child.into_iter().enumerate() {
                if c & LEAF != 0 {
                    leaf_slot[(c & !LEAF) as usize] = (r as u32) << 1 | side as u32;
                } else {
                    records[c as usize].parent = r as u32;
                }
            }
        }
        Self {
            records,
            leaf_slot,
            root: EMPTY,
            vertices: Vec::new(),
            faces: Vec::new(),
        }
    }

    /// Recomputes every box bottom-up from `fit`. Internal nodes are stored level by level,
    /// level `k` being `level_offsets[k]..level_offsets[k + 1]`.
    pub(crate) fn refit(&mut self, level_offsets: &[u32], fit: &Fit<'_>) {
        fit.boxes_all(None, fit.start.len(), &mut self.vertices);
        fit.boxes_all(
            Some(&self.vertices),
            fit.face_offsets.len() - 1,
            &mut self.faces,
        );
        let face_boxes = &self.faces[..];
        let child_box = |c: u32, done: &[Record]| {
            if c & LEAF != 0 {
                face_boxes[(c & !LEAF) as usize]
            } else {
                let [a, b] = &done[c as usize].boxes;
                union(a, b)
            }
        };
        let fit_level = |done: &[Record], level: &mut [Record]| {
            let fit = |r: &mut Record| {
                let [a, b] = r.child;
                r.boxes = [child_box(a, done), child_box(b, done)];
            };
            if level.len() < PARALLEL_LEVEL {
                level.iter_mut().for_each(fit);
            } else {
                level.par_iter_mut().with_min_len(REFIT_RUN).for_each(fit);
            }
        };
        let records = &mut self.records;
        let small = records.len() < PARALLEL_LEVEL;
        let mut fit_all = || {
            for level in level_offsets.windows(2) {
                let (lo, hi) = (level[0] as usize, level[1] as usize);
                let (done, rest) = records.split_at_mut(lo);
                fit_level(done, &mut rest[..hi - lo]);
            }
        };
        // A small tree is refit in place; a large one enters the thread pool once for all its
        // levels, of which only the large lower ones are split.
        if small {
            fit_all();
        } else {
            rayon::scope(|_| fit_all());
        }
        self.fit_root();
    }

    /// Recomputes, after a refit from which only the vertices `moved` changed, the boxes those
    /// vertices enter: theirs, those of the `faces` around them, and those of every record
    /// above such a face. Every other box is a function of positions that did not change, so
    /// the boxes end as [`Boxes::refit`] from `fit` leaves them, bit for bit, at a cost that
    /// follows what moved.
    pub(crate) fn refit_moved(&mut self, fit: &Fit<'_>, moved: &[u32], faces: &[u32]) {
        for &v in moved {
            self.vertices[v as usize] = fit.vertex(v as usize);
        }
        let mut stale = vec![false; self.records.len()];
        for &f in faces {
            let face = fit.face(&self.vertices, f as usize);
            self.faces[f as usize] = face;
            let slot = self.leaf_slot[f as usize];
            if slot == NONE {
                continue;
            }
            let record = (slot >> 1) as usize;
            self.records[record].boxes[(slot & 1) as usize] = face;
            stale[record] = true;
        }
        // A child's record precedes its parent's, so one pass in order carries every change up;
        // it reads only the flags of the records that did not change.
        for r in 0..self.records.len() {
            if !stale[r] {
                continue;
            }
            let parent = self.records[r].parent;
            if parent == NONE {
                continue;
            }
            let [a, b] = &self.records[r].boxes;
            let merged = union(a, b);
            let side = usize::from(self.records[parent as usize].child[1] == r as u32);
            self.records[parent as usize].boxes[side] = merged;
            stale[parent as usize] = true;
        }
        self.fit_root();
    }

    /// The root's box from its record's two, or from the single face's when there is none.
    fn fit_root(&mut self) {
        self.root = match self.records.last() {
            Some(r) => union(&r.boxes[0], &r.boxes[1]),
            None => self.faces[0],
        };
    }

    /// The box of `node` of a tree over `faces` faces whose root is `root`.
    #[cfg(test)]
    pub(crate) fn node_box(
        &self,
        node: u32,
        faces: u32,
        root: u32,
    ) -> parry3d_f64::bounding_volume::Aabb {
        let b = if node == root {
            self.root
        } else if node < faces {
            let slot = self.leaf_slot[node as usize];
            self.records[(slot >> 1) as usize].boxes[(slot & 1) as usize]
        } else {
            let [a, b] = &self.records[(node - faces) as usize].boxes;
            union(a, b)
        };
        let (lo, hi) = widen(&b);
        parry3d_f64::bounding_volume::Aabb::new(lo, hi)
    }

    /// The root's box.
    pub(crate) fn root_box(&self) -> SmallBox {
        self.root
    }

    /// The distance from `q` to the root's box, 0 inside it.
    pub(crate) fn root_distance(&self, q: DVec3) -> f64 {
        distance2(&self.root, q).sqrt()
    }

    /// The references and boxes of the two children of record `r`: a child's record index,
    /// or `LEAF | face`.
    pub(crate) fn record(&self, r: u32) -> ([u32; 2], &[SmallBox; 2]) {
        let record = &self.records[r as usize];
        (record.child, &record.boxes)
    }

    /// Whether there are no records (a one-face mesh).
    pub(crate) fn is_single_face(&self) -> bool {
        self.records.is_empty()
    }

    /// Heap bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        heap(&self.records) + heap(&self.leaf_slot) + heap(&self.vertices)
    }

    /// The squared distance from `q` to the box of face `f` (0 inside).
    pub(crate) fn face_distance2(&self, f: u32, q: DVec3) -> f64 {
        match self.leaf_slot.get(f as usize) {
            Some(&slot) if slot != NONE => distance2(
                &self.records[(slot >> 1) as usize].boxes[(slot & 1) as usize],
                q,
            ),
            _ => distance2(&self.root, q),
        }
    }

    /// Calls `leaf(face)` for every face whose box is within squared distance `bound` of `q`,
    /// nearer faces first; `leaf` returns the bound from then on, which may only shrink. With
    /// a `seed` (a reference: `LEAF | face`, or a record), whose faces the caller has already
    /// considered, the walk climbs from it (see the module docs) and skips its faces. Records
    /// for which `skip(record)` holds are left out with every face below them. `stack` is
    /// scratch space.
    pub(crate) fn visit_near(
        &self,
        q: DVec3,
        mut bound: f64,
        seed: Option<u32>,
        stack: &mut Vec<Pending>,
        skip: impl Fn(u32) -> bool,
        mut leaf: impl FnMut(u32) -> f64,
    ) {
        if distance2(&self.root, q) > bound {
            return;
        }
        let Some(root) = self.records.len().checked_sub(1) else {
            if seed.is_none() {
                leaf(0);
            }
            return;
        };
        let Some(seed) = seed else {
            if !skip(root as u32) {
                self.descend(root as u32, q, bound, stack, &skip, &mut leaf);
            }
            return;
        };
        let (mut side, mut record) = match self.slot(seed) {
            Some(slot) => (slot & 1, slot >> 1),
            None => return,
        };
        loop {
            let r = &self.records[record as usize];
            let other = (1 - side) as usize;
            if distance2(&r.boxes[other], q) <= bound {
                let c = r.child[other];
                if c & LEAF != 0 {
                    bound = leaf(c & !LEAF);
                } else if !skip(c) {
                    bound = self.descend(c, q, bound, stack, &skip, &mut leaf);
                }
            }
            if r.parent == NONE {
                return;
            }
            let parent = &self.records[r.parent as usize];
            side = u32::from(parent.child[1] == record);
            record = r.parent;
        }
    }

    /// Where the parent's record holds the node `node` refers to (`LEAF | face`, or a record):
    /// `record << 1 | side`; `None` for the root (the only face of a one-face mesh, which no
    /// record holds, or the last record).
    fn slot(&self, node: u32) -> Option<u32> {
        if node & LEAF != 0 {
            let slot = self.leaf_slot[(node & !LEAF) as usize];
            (slot != NONE).then_some(slot)
        } else {
            let parent = self.records[node as usize].parent;
            (parent != NONE)
                .then(|| parent << 1 | u32::from(self.records[parent as usize].child[1] == node))
        }
    }

    /// The record holding the node `node` refers to (`LEAF | face`, or a record); `None` for
    /// the root.
    pub(crate) fn parent(&self, node: u32) -> Option<u32> {
        self.slot(node).map(|slot| slot >> 1)
    }

    /// Visits the faces below `record` within `bound` of `q`, depth first and nearer child
    /// first, leaving out the records `skip` names; returns the bound at the end.
    fn descend(
        &self,
        mut record: u32,
        q: DVec3,
        mut bound: f64,
        stack: &mut Vec<Pending>,
        skip: &impl Fn(u32) -> bool,
        leaf: &mut impl FnMut(u32) -> f64,
    ) -> f64 {
        stack.clear();
        loop {
            let r = &self.records[record as usize];
            let (d0, d1) = (distance2(&r.boxes[0], q), distance2(&r.boxes[1], q));
            let ((near, dn), (far, df)) = if d1 < d0 {
                ((r.child[1], d1), (r.child[0], d0))
            } else {
                ((r.child[0], d0), (r.child[1], d1))
            };
            let mut next = None;
            if dn <= bound {
                if near & LEAF != 0 {
                    bound = leaf(near & !LEAF);
                } else if !skip(near) {
                    next = Some(near);
                }
            }
            if df <= bound {
                if far & LEAF != 0 {
                    bound = leaf(far & !LEAF);
                } else if !skip(far) {
                    match next {
                        None => next = Some(far),
                        Some(_) => stack.push((far, df)),
                    }
                }
            }
            record = match next {
                Some(c) => c,
                None => loop {
                    match stack.pop() {
                        None => return bound,
                        Some((c, d)) if d <= bound => break c,
                        Some(_) => {}
                    }
                },
            };
        }
    }
}

/// [`Fit::boxes_into`] in vector registers.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use std::arch::x86_64::{__m128, __m256d, _CMP_GT_OQ, _CMP_LT_OQ};

    use parry3d_f64::math::Vector as DVec3;
    use pulp::x86::V3;

    use super::{Fit, SmallBox};

    /// What [`Fit::boxes_into`] boxes: the vertices, or with `corners` the faces.
    pub(super) struct Boxing<'a, 'b> {
        pub(super) simd: V3,
        pub(super) fit: &'a Fit<'b>,
        pub(super) corners: Option<&'a [SmallBox]>,
        pub(super) first: usize,
        pub(super) out: &'a mut [SmallBox],
    }

    impl pulp::NullaryFnOnce for Boxing<'_, '_> {
        type Output = ();

        #[inline(always)]
        fn call(self) {
            let Self {
                simd,
                fit,
                corners,
                first,
                out,
            } = self;
            match corners {
                None => vertex_boxes(simd, fit, first, out),
                Some(vertices) => face_boxes(simd, fit, vertices, first, out),
            }
        }
    }

    /// [`Fit::vertex`] of vertices `first..` into `out`.
    #[inline(always)]
    fn vertex_boxes(simd: V3, fit: &Fit, first: usize, out: &mut [SmallBox]) {
        let avx = simd.avx;
        let pad = avx._mm256_set1_pd(fit.margin);
        for (v, b) in (first..).zip(out) {
            let p = coordinates(simd, fit.start[v]);
            let (lo, hi) = match fit.end {
                Some(end) => {
                    let q = coordinates(simd, end[v]);
                    (avx._mm256_min_pd(p, q), avx._mm256_max_pd(p, q))
                }
                None => (p, p),
            };
            *b = padded(simd, lo, hi, pad);
        }
    }

    /// [`Fit::face`] of faces `first..` into `out`, from their corners' `vertices` boxes.
    #[inline(always)]
    fn face_boxes(simd: V3, fit: &Fit, vertices: &[SmallBox], first: usize, out: &mut [SmallBox]) {
        let (sse, avx) = (simd.sse, simd.avx);
        let offsets = fit.face_offsets;
        for (f, b) in (first..).zip(out) {
            let corners = &fit.face_vertices[offsets[f] as usize..offsets[f + 1] as usize];
            // The union's `a < b ? a : b` and `a > b ? a : b` are `minps` and `maxps`, the
            // accumulated box first, zeros and all.
            let mut lo = sse._mm_set1_ps(f32::INFINITY);
            let mut hi = sse._mm_set1_ps(f32::NEG_INFINITY);
            for &v in corners {
                let (low, high) = sides(simd, &vertices[v as usize]);
                lo = sse._mm_min_ps(lo, low);
                hi = sse._mm_max_ps(hi, high);
            }
            let (lo, hi) = (avx._mm256_cvtps_pd(lo), avx._mm256_cvtps_pd(hi));
            let extent: [f64; 4] = pulp::cast(avx._mm256_sub_pd(hi, lo));
            let pad = avx._mm256_set1_pd(fit.relative * (extent[0] + extent[1] + extent[2]));
            *b = padded(simd, lo, hi, pad);
        }
    }

    /// A box's low sides and its high sides, each in lanes 0–2 (lane 3 unspecified): two
    /// loads of four and a shuffle.
    #[inline(always)]
    fn sides(simd: V3, b: &SmallBox) -> (__m128, __m128) {
        let low: __m128 = pulp::cast(<[f32; 4]>::try_from(&b[..4]).expect("four sides"));
        let high: __m128 = pulp::cast(<[f32; 4]>::try_from(&b[2..]).expect("four sides"));
        (low, simd.avx._mm_permute_ps::<0b00_11_10_01>(high))
    }

    /// The box from `lo` to `hi` (lanes 0–2) loosened by `pad` and rounded outward, as
    /// [`super::outward`] of `lo − pad` and `hi + pad`.
    #[inline(always)]
    fn padded(simd: V3, lo: __m256d, hi: __m256d, pad: __m256d) -> SmallBox {
        let avx = simd.avx;
        let lo: [f32; 4] = pulp::cast(rounded::<false>(simd, avx._mm256_sub_pd(lo, pad)));
        let hi: [f32; 4] = pulp::cast(rounded::<true>(simd, avx._mm256_add_pd(hi, pad)));
        [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]]
    }

    /// `p` in lanes 0–2 (lane 3 zero).
    #[inline(always)]
    fn coordinates(simd: V3, p: DVec3) -> __m256d {
        simd.avx._mm256_set_pd(0.0, p.z, p.y, p.x)
    }

    /// `|x| ε + tiny` in each lane, what [`super::outward`] moves a value by.
    #[inline(always)]
    fn nudge(simd: V3, x: __m256d) -> __m256d {
        let avx = simd.avx;
        let magnitude = avx._mm256_andnot_pd(avx._mm256_set1_pd(-0.0), x);
        avx._mm256_mul_pd(magnitude, avx._mm256_set1_pd(super::EPS))
    }

    /// [`super::outward`]'s `down` (`UP` false) or `up` in each lane.
    #[inline(always)]
    fn rounded<const UP: bool>(simd: V3, x: __m256d) -> std::arch::x86_64::__m128 {
        let avx = simd.avx;
        let tiny = avx._mm256_set1_pd(super::TINY);
        let (y, limit) = if UP {
            let y = avx._mm256_add_pd(avx._mm256_add_pd(x, nudge(simd, x)), tiny);
            (y, -super::BIG)
        } else {
            let y = avx._mm256_sub_pd(avx._mm256_sub_pd(x, nudge(simd, x)), tiny);
            (y, super::BIG)
        };
        let limit = avx._mm256_set1_pd(limit);
        let inside = if UP {
            avx._mm256_cmp_pd::<_CMP_GT_OQ>(y, limit)
        } else {
            avx._mm256_cmp_pd::<_CMP_LT_OQ>(y, limit)
        };
        avx._mm256_cvtpd_ps(avx._mm256_blendv_pd(limit, y, inside))
    }
}

/// [`outward`]'s relative slack: a unit in the last place of `f32`, relative.
const EPS: f64 = f32::EPSILON as f64;
/// More than half the smallest `f32` subnormal (1.4e-45), the most that rounding to nearest
/// moves a value that small: [`outward`]'s slack beyond the relative one.
const TINY: f64 = 2e-45;
/// The largest finite `f32`.
const BIG: f64 = f32::MAX as f64;

/// `lo..hi` rounded outward to single precision.
///
/// Rounding to nearest moves a value by at most half a unit in the last place of `f32`, at
/// most `2⁻²⁴` of it, or half the smallest subnormal; widening by `2⁻²³` of the value plus a
/// subnormal first leaves the rounded value on the safe side, without branches. Values beyond
/// the range of `f32` go to its largest finite values or to infinity, still on the safe side.
fn outward(lo: DVec3, hi: DVec3) -> SmallBox {
    let down = |x: f64| {
        let y = x - x.abs() * EPS - TINY;
        (if y < BIG { y } else { BIG }) as f32
    };
    let up = |x: f64| {
        let y = x + x.abs() * EPS + TINY;
        (if y > -BIG { y } else { -BIG }) as f32
    };
    [
        down(lo.x),
        down(lo.y),
        down(lo.z),
        up(hi.x),
        up(hi.y),
        up(hi.z),
    ]
}

/// The corners of a box in double precision.
fn widen(b: &SmallBox) -> (DVec3, DVec3) {
    (
        DVec3::new(b[0].into(), b[1].into(), b[2].into()),
        DVec3::new(b[3].into(), b[4].into(), b[5].into()),
    )
}

/// The box around two boxes.
fn union(a: &SmallBox, b: &SmallBox) -> SmallBox {
    let mut out = [0.0; 6];
    for k in 0..3 {
        out[k] = if a[k] < b[k] { a[k] } else { b[k] };
        out[k + 3] = if a[k + 3] > b[k + 3] {
            a[k + 3]
        } else {
            b[k + 3]
        };
    }
    out
}

/// The squared distance from `q` to box `b` (0 inside).
fn distance2(b: &SmallBox, q: DVec3) -> f64 {
    let (lo, hi) = widen(b);
    (lo - q).max(q - hi).max(DVec3::ZERO).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Start and end positions of `n` vertices whose coordinates have either sign, from
    /// subnormal to beyond the range of `f32`, zeros of both signs among them.
    fn motion(n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
        let values = [
            0.0,
            -0.0,
            0.1,
            -0.1,
            1e-40,
            -1e-310,
            3.4e38,
            -3.5e38,
            1e300,
            123_456.789,
            7e-3,
        ];
        let at = |k: usize| values[k % values.len()];
        let start = (0..n)
            .map(|k| DVec3::new(at(k), at(3 * k + 1), at(7 * k + 2)))
            .collect();
        let end = (0..n)
            .map(|k| DVec3::new(at(5 * k + 3), at(k + 4), -at(2 * k)))
            .collect();
        (start, end)
    }

    /// The vertex boxes in vector registers are [`Fit::vertex`]'s to the bit, static and
    /// swept, with and without a margin, for coordinates of either sign from subnormal to
    /// beyond the range of `f32`, zeros of both signs included.
    #[test]
    fn vertex_boxes_in_lanes_are_the_scalar_ones() {
        let (start, end) = motion(97);
        let bits = |b: &SmallBox| b.map(f32::to_bits);
        for (swept, margin) in [(false, 0.0), (false, 1e-3), (true, 0.0), (true, 2.5e-3)] {
            let fit = Fit {
                face_offsets: &[],
                face_vertices: &[],
                start: &start,
                end: swept.then_some(&end[..]),
                margin,
                relative: 0.0,
            };
            let mut out = vec![EMPTY; start.len() - 5];
            fit.boxes_into(None, 5, &mut out);
            for (k, b) in out.iter().enumerate() {
                assert_eq!(bits(b), bits(&fit.vertex(5 + k)), "vertex {}", 5 + k);
            }
        }
    }

    #[test]
    fn outward_rounding_contains_the_box() {
        let values = [
            0.1,
            1e-40,
            1e-310,
            3.4e38,
            3.5e38,
            1e300,
            123_456.789,
            7e-3,
            0.0,
            f64::INFINITY,
        ];
        for x in values.into_iter().flat_map(|x| [x, -x]) {
            let (lo, hi) = widen(&outward(DVec3::splat(x), DVec3::splat(x)));
            assert!(lo.x <= x && x <= hi.x, "{x}");
        }
        // Representable corners move out by about one unit in the last place.
        let unit = outward(DVec3::ZERO, DVec3::ONE);
        assert!(unit[..3].iter().all(|&x| x <= 0.0 && x > -1e-40));
        assert!(
            unit[3..]
                .iter()
                .all(|&x| (1.0..=1.0 + 3.0 * f32::EPSILON).contains(&x))
        );
        let d = distance2(&unit, DVec3::new(2.0, 0.5, -1.0));
        assert!(d <= 2.0 && d > 2.0 - 1e-6);
    }

    /// The face boxes in vector registers are [`Fit::face`]'s to the bit: triangles, quads
    /// and pentagons over the boxes of corners whose coordinates have either sign, from
    /// subnormal to beyond the range of `f32`, with and without relative slack.
    #[test]
    fn face_boxes_in_lanes_are_the_scalar_ones() {
        let (start, end) = motion(41);
        // Faces of three, four and five corners, each vertex in several.
        let (mut face_offsets, mut face_vertices) = (vec![0u32], Vec::new());
        for f in 0..60u32 {
            let corners = 3 + f % 3;
            face_vertices.extend((0..corners).map(|k| (f * 7 + k * 11) % 41));
            face_offsets.push(face_vertices.len() as u32);
        }
        let bits = |b: &SmallBox| b.map(f32::to_bits);
        for (relative, margin) in [(0.0, 0.0), (1e-3, 0.0), (2f64.powi(-20), 2.5e-3)] {
            let fit = Fit {
                face_offsets: &face_offsets,
                face_vertices: &face_vertices,
                start: &start,
                end: Some(&end),
                margin,
                relative,
            };
            let vertices: Vec<SmallBox> = (0..start.len()).map(|v| fit.vertex(v)).collect();
            let mut out = vec![EMPTY; 60 - 4];
            fit.boxes_into(Some(&vertices), 4, &mut out);
            for (k, b) in out.iter().enumerate() {
                assert_eq!(bits(b), bits(&fit.face(&vertices, 4 + k)), "face {}", 4 + k);
            }
        }
    }

    #[test]
    fn records_follow_the_tree() {
        // Faces 0..4; internal nodes 4 = (0, 1), 5 = (2, 3), 6 = (4, 5) the root.
        let b = Boxes::new(4, &[[0, 1], [2, 3], [4, 5]]);
        let children: Vec<[u32; 2]> = b.records.iter().map(|r| r.child).collect();
        assert_eq!(children, [[LEAF, LEAF | 1], [LEAF | 2, LEAF | 3], [0, 1]]);
        let parents: Vec<u32> = b.records.iter().map(|r| r.parent).collect();
        assert_eq!(parents, [2, 2, NONE]);
        assert_eq!(b.leaf_slot, [0, 1, 2, 3]);
    }
}
