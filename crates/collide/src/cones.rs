//! Normal-cone culling for self-collision (Volino & Magnenat-Thalmann 1994; Provot 1997).
//!
//! A superface cannot touch itself when (1) some direction `a` sees every one of its triangles
//! from the front, i.e. its normals fit in a cone narrower than a half-space, and (2) its
//! boundary, projected along `a`, does not fold back. Then the projection along `a` maps every
//! triangle with positive orientation, and the number of triangles over a point of the plane is
//! the winding number of the projected boundary around it (a degree argument); a boundary that
//! winds once around a centre with every edge turning forward is a simple star-shaped curve, so
//! that number is 0 or 1 and no two triangles overlap. Two features touching would make two
//! triangles overlap near the contact, so the whole subtree is skipped.
//!
//! The direction tried is the superface's area-weighted mean normal (the sum of its triangles'
//! cross products), the axis of its normal cone; condition (1) is then a sign test per
//! triangle, with no square root. That sum needs no pass over the triangles: expanding
//! `(b - a) × (c - a) = a × b + b × c + c × a`, the terms of edges shared by two faces cancel,
//! so it is `Σ p × q` over the directed boundary edges `p → q` (Stokes' theorem for the
//! vector area), taken relative to a boundary vertex to keep its digits. Any direction would be
//! sound, since every triangle is then checked against it: over a step the axis is the vector
//! area of the superface at the step's middle, `Σ (p0 + p1) × (q0 + q1)`, one cross product a
//! boundary edge, where the sum of the normals' three Bernstein coefficients (below) took
//! four; the two differ only in how much the middle coefficient counts. The same pass sums the
//! boundary's vertices for the contour's centre. The test runs lazily, top-down, on
//! the nodes the traversal visits: a smooth sheet is cleared by one linear pass at the root,
//! and a node that fails usually fails on its first few triangles, or before any of them on
//! its contour, which is checked first because it is shorter. The pass takes four triangles
//! at a time in vector registers where the machine has AVX2 (through `pulp`, as the cloth's
//! block product), and the contour four edges, each lane making the scalar test's
//! products, sums and comparisons in its order, so the same answers: the 64² drape's run
//! makes 3.6% fewer instructions.
//!
//! Over a step every vertex moves linearly, so a triangle normal
//! `n(t) = (b(t) - a(t)) × (c(t) - a(t))` is quadratic in `t`; in the Bernstein basis its three
//! coefficients are `n(0)`, `((b0-a0)×(c1-a1) + (b1-a1)×(c0-a0)) / 2` and `n(1)`, and `n(t)` is
//! their combination with non-negative weights, so a direction seeing the three from the front
//! sees every `n(t)` (Tang, Curtis, Yoon & Manocha 2009 use the same trick). The contour test
//! likewise asks the three Bernstein coefficients of each edge's turn around the moving centre
//! to be positive, and the winding number, which cannot change while every edge turns forward,
//! is checked at the start: with every edge turning forward by less than half a turn, it is
//! the number of edges that pass the ray from the centre along one axis, a sign test each
//! rather than an angle. A static refit has one coefficient.
//!
//! The same test clears a vertex's star, the faces around it ([`Stars`]), which the
//! hierarchy has no node for: two nodes the cones did not clear overlap along the seam
//! between them, and the faces that meet across it are tested pair by pair for the features
//! they do not share (a crease closing is such a pair). When the star of a vertex two faces
//! share is cleared, neither can touch the other.
//!
//! **A failed test remembers why.** A node or star that fails on a triangle whose normals
//! the axis does not see keeps that triangle as its witness in the hierarchy, and its next
//! test (the next query, after the next refit) tries the witness first: the test is a
//! conjunction over the triangles, so one that still fails decides it, with no contour and no
//! scan, and one that passes now costs one triangle more before the whole test. The answer is
//! the same either way; only the work differs. Over the 64² drape's run the failing tests
//! scanned 68 triangles each before their first failure, and folds stay where they are from
//! one substep to the next: the tests took 15% fewer instructions, the run 1.8% fewer
//! (`docs/BENCHMARKS.md`). Which failing triangle a parallel scan at the root finds first may
//! depend on the threads; the answers do not.
//!
//! The boundary chains are topological (built once, see the hierarchy's build). Being star-shaped
//! around the centroid is a sufficient condition only, so the test clears what the coarsening
//! makes round: an S of four quads fails it even flat, a 2 × 2 square passes while its normals
//! do, and the build matches superfaces by roundness for that reason.

use std::sync::atomic::{AtomicU8, AtomicU32, Ordering::Relaxed};

use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use crate::hierarchy::Hierarchy;
use crate::memory::heap;
use crate::topology::Topology;

/// A normal counts as seen from the front when its angle to the axis is below 90° minus about
/// this many radians: culling must never be optimistic.
const MARGIN: f64 = 1e-6;

/// The Bernstein coefficients of the triangles' normals over the motion of the last refit,
/// computed from the positions where a test needs them (a cross product costs less than
/// storing and reloading it, and a smooth sheet needs each one once).
pub(crate) struct NormalCones {
    swept: bool,
    /// The machine's AVX2, when it has it, for scans four triangles at a time.
    #[cfg(target_arch = "x86_64")]
    simd: Option<pulp::x86::V3>,
}

/// What a superface's normals must face: its axis `a`, seen from the front by a normal `n`
/// when `n · a > 0` and the angle between them is below 90° minus [`MARGIN`].
#[derive(Clone, Copy)]
struct Front {
    axis: DVec3,
    axis_len2: f64,
    cos2: f64,
}

impl Front {
    fn new(axis: DVec3) -> Self {
        Self {
            axis,
            axis_len2: axis.length_squared(),
            cos2: MARGIN.sin().powi(2),
        }
    }

    #[inline]
    fn sees(&self, n: DVec3) -> bool {
        let d = n.dot(self.axis);
        d > 0.0 && d * d > self.cos2 * n.length_squared() * self.axis_len2
    }
}

impl NormalCones {
    /// The normal cones of `h` at its last refit.
    pub(crate) fn new(h: &Hierarchy) -> Self {
        Self {
            swept: h.is_swept(),
            #[cfg(target_arch = "x86_64")]
            simd: pulp::x86::V3::try_new(),
        }
    }

    /// The first of `triangles`, in their order, with a normal coefficient that `front` does
    /// not see. Four at a time in vector registers where the machine has AVX2, each lane
    /// computing what [`Self::all_of_triangle`] computes, operation for operation, so the
    /// same answer.
    fn first_unseen(
        &self,
        h: &Hierarchy,
        front: Front,
        mut triangles: impl Iterator<Item = usize>,
    ) -> Option<usize> {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = self.simd {
            return simd.vectorize(lanes::Scan {
                simd,
                cones: self,
                h,
                front,
                triangles,
            });
        }
        triangles.find(|&t| !self.all_of_triangle(h, t, |n| front.sees(n)))
    }

    /// Whether the `boundary` chain, projected along `axis`, winds exactly once around its
    /// moving centroid with every edge turning forward at every time of the step; `sums` are
    /// its vertices' sums at the start and at the end (see [`Self::boundary_axis`]). Every
    /// edge turns forward by less than half a turn, so the curve winds once when it passes
    /// the ray from the centre along the first axis once. Four edges at a time in vector
    /// registers where the machine has AVX2, each lane computing what [`Contour::edge`]
    /// computes.
    fn contour_does_not_fold(
        &self,
        h: &Hierarchy,
        boundary: &[[u32; 2]],
        axis: DVec3,
        sums: [DVec3; 2],
    ) -> bool {
        if boundary.is_empty() {
            return false;
        }
        let contour = Contour::new(axis, sums, boundary.len());
        let (mut passes, mut rest) = (0, boundary);
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = self.simd {
            let (fours, tail) = boundary.split_at(boundary.len() / 4 * 4);
            let Some(n) = simd.vectorize(lanes::Edges {
                simd,
                contour,
                h,
                edges: fours,
            }) else {
                return false;
            };
            (passes, rest) = (n, tail);
        }
        for &edge in rest {
            match contour.edge(h, edge) {
                None => return false,
                Some(passing) => passes += usize::from(passing),
            }
        }
        passes == 1
    }

    /// Whether `each` holds for the normal coefficients of triangle `t`; stops at the first
    /// that fails.
    #[inline]
    fn all_of_triangle(&self, h: &Hierarchy, t: usize, each: impl Fn(DVec3) -> bool) -> bool {
        let [a0, b0, c0] = h.triangle_at(t, &h.start);
        let (e0, g0) = (b0 - a0, c0 - a0);
        if !self.swept {
            return each(e0.cross(g0));
        }
        let [a1, b1, c1] = h.triangle_at(t, h.end());
        let (e1, g1) = (b1 - a1, c1 - a1);
        each(e0.cross(g0)) && each((e0.cross(g1) + e1.cross(g0)) / 2.0) && each(e1.cross(g1))
    }

    /// The axis a superface's normals are tested against, from its `boundary` chain (see the
    /// module docs): its vector area `Σ p × q` at the start for a static refit, and for a swept
    /// one at the middle of the step, `Σ (p0 + p1) × (q0 + q1)` (the sum of the Bernstein
    /// coefficients of its normals with the middle one counted twice: one cross product an
    /// edge rather than four), relative to the first boundary vertex. Also the sums of the
    /// boundary's vertices at the start and at the end, for the contour's centre.
    fn boundary_axis(&self, h: &Hierarchy, boundary: &[[u32; 2]]) -> (DVec3, [DVec3; 2]) {
        let Some(&[origin, _]) = boundary.first() else {
            return (DVec3::ZERO, [DVec3::ZERO; 2]);
        };
        let (start, end) = (&h.start[..], h.end());
        let o = origin as usize;
        if !self.swept {
            let (axis, sum) =
                boundary
                    .iter()
                    .fold((DVec3::ZERO, DVec3::ZERO), |(axis, sum), &[p, q]| {
                        let (p, q) = (start[p as usize], start[q as usize]);
                        (axis + (p - start[o]).cross(q - start[o]), sum + p)
                    });
            return (axis, [sum; 2]);
        }
        let middle = |p: u32| start[p as usize] + end[p as usize] - (start[o] + end[o]);
        boundary.iter().fold(
            (DVec3::ZERO, [DVec3::ZERO; 2]),
            |(axis, [s0, s1]), &[p, q]| {
                let sums = [s0 + start[p as usize], s1 + end[p as usize]];
                (axis + middle(p).cross(middle(q)), sums)
            },
        )
    }

    /// Whether no two features below `node` can touch during the step (see the module docs).
    ///
    /// A large node's faces are checked in parallel, in fixed chunks.
    pub(crate) fn cannot_self_collide(&self, h: &Hierarchy, node: u32) -> bool {
        let (faces, boundary) = (h.leaves_below(node), h.node_boundary(node));
        self.superface_cannot_self_collide(h, faces, boundary, node as usize)
    }

    /// Whether no two features of `faces`, whose boundary chain is `boundary`, can touch
    /// during the step; `slot` is where the hierarchy keeps the superface's witness.
    fn superface_cannot_self_collide(
        &self,
        h: &Hierarchy,
        faces: &[u32],
        boundary: &[[u32; 2]],
        slot: usize,
    ) -> bool {
        let (axis, sums) = self.boundary_axis(h, boundary);
        let front = Front::new(axis);
        let seen = |t: usize| self.all_of_triangle(h, t, |n| front.sees(n));
        if front.axis_len2 <= 0.0 || h.witnesses.get(slot).is_some_and(|t| !seen(t)) {
            return false;
        }
        // The root holds every triangle: check them in memory order, a chunk per task, each
        // chunk a plain loop.
        let unseen = || {
            if faces.len() == h.face_count() {
                let triangles = h.triangle_count();
                (0..triangles.div_ceil(CHUNK))
                    .into_par_iter()
                    .find_map_any(|c| {
                        self.first_unseen(h, front, c * CHUNK..triangles.min((c + 1) * CHUNK))
                    })
            } else {
                let chunk_unseen = |chunk: &[u32]| {
                    let triangles = chunk.iter().flat_map(|&f| h.topology.face_triangles(f));
                    self.first_unseen(h, front, triangles)
                };
                if faces.len() <= CHUNK {
                    chunk_unseen(faces)
                } else {
                    faces.par_chunks(CHUNK).find_map_any(chunk_unseen)
                }
            }
        };
        // The contour costs a pass over the boundary, the normals one over the faces: the
        // cheaper test goes first.
        if !self.contour_does_not_fold(h, boundary, axis.normalize(), sums) {
            return false;
        }
        match unseen() {
            None => true,
            Some(t) => {
                h.witnesses.set(slot, t);
                false
            }
        }
    }
}

/// The stars of a mesh's vertices (the faces around each) that the normal cones clear over the
/// step, each tested on first ask and remembered for the rest of the query. Two faces that
/// share a vertex both lie in its star, so when that star is cleared no feature of one can
/// touch a feature of the other (see the module docs).
///
/// A self query reaches such neighbours wherever two nodes the cones did not clear meet: their
/// boxes overlap along the seam between them down to its faces. On the 64² drape seven in ten
/// face pairs the continuous self queries tested were neighbours; a star is tested once for
/// all the pairs around its vertex.
pub(crate) struct Stars<'a> {
    h: &'a Hierarchy,
    cones: &'a NormalCones,
    /// Per vertex: [`UNKNOWN`], [`CLEARED`] or [`NOT_CLEARED`].
    known: Vec<AtomicU8>,
}

const UNKNOWN: u8 = 0;
const CLEARED: u8 = 1;
const NOT_CLEARED: u8 = 2;

impl<'a> Stars<'a> {
    /// The stars of `h`'s vertices over its last refit, none tested yet.
    pub(crate) fn new(h: &'a Hierarchy, cones: &'a NormalCones) -> Self {
        Self {
            h,
            cones,
            known: (0..h.vertex_count())
                .map(|_| AtomicU8::new(UNKNOWN))
                .collect(),
        }
    }

    /// For faces `f` and `g` that share a vertex, whether they cannot touch because the star
    /// of one they share is cleared (the shared corners tried in `f`'s order); `None` for
    /// faces that share none.
    pub(crate) fn part(&self, f: u32, g: u32) -> Option<bool> {
        let other = self.h.topology.face(g);
        let mut shared = false;
        for &v in self.h.topology.face(f) {
            if other.contains(&v) {
                if self.cleared(v) {
                    return Some(true);
                }
                shared = true;
            }
        }
        shared.then_some(false)
    }

    /// Whether the star of `v` is cleared. The answer is a function of the positions alone,
    /// so two threads that test the same star at once store the same value.
    fn cleared(&self, v: u32) -> bool {
        let known = &self.known[v as usize];
        match known.load(Relaxed) {
            CLEARED => true,
            NOT_CLEARED => false,
            _ => {
                let faces = self.h.vertex_faces().of(v as usize);
                let mut boundary = [[0; 2]; STAR_EDGES];
                let cleared =
                    star_boundary(&self.h.topology, v, faces, &mut boundary).is_some_and(|len| {
                        let slot = Witnesses::star(self.h, v as usize);
                        self.cones.superface_cannot_self_collide(
                            self.h,
                            faces,
                            &boundary[..len],
                            slot,
                        )
                    });
                known.store(if cleared { CLEARED } else { NOT_CLEARED }, Relaxed);
                cleared
            }
        }
    }
}

/// Per node and per vertex star of a hierarchy (see [`Witnesses::star`]): the triangle that
/// last failed its normal-cone test, plus one (0 for none). Written by the queries' threads
/// with relaxed atomics; a value only orders the work of the next test (see the module docs).
#[derive(Debug, Default)]
pub(crate) struct Witnesses(Vec<AtomicU32>);

impl Clone for Witnesses {
    fn clone(&self) -> Self {
        Self(
            self.0
                .iter()
                .map(|w| AtomicU32::new(w.load(Relaxed)))
                .collect(),
        )
    }
}

impl Witnesses {
    /// No witness yet for any node or star of `h`.
    pub(crate) fn of(h: &Hierarchy) -> Self {
        let slots = Self::star(h, h.vertex_count());
        Self((0..slots).map(|_| AtomicU32::new(0)).collect())
    }

    /// The slot of vertex `v`'s star in `h`, after its nodes'.
    fn star(h: &Hierarchy, v: usize) -> usize {
        h.face_count() + h.children.len() + v
    }

    fn get(&self, slot: usize) -> Option<usize> {
        (self.0[slot].load(Relaxed) as usize).checked_sub(1)
    }

    fn set(&self, slot: usize, triangle: usize) {
        self.0[slot].store(triangle as u32 + 1, Relaxed);
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        heap(&self.0)
    }
}

/// Most boundary edges a star is tested with; a vertex with more (twenty-odd quads around
/// it) is left to the exact tests.
const STAR_EDGES: usize = 48;

/// The boundary chain of the star of `v` made of `faces` into `edges`, returning its length,
/// or `None` when it has more than [`STAR_EDGES`] edges. An edge at `v` of one face cancels
/// the opposite edge of the next around it; an edge away from `v` is kept even when another
/// face of the star has it the other way (a fold of the mesh's own making): one of the two
/// then turns backwards and the contour test fails, which is safe.
fn star_boundary(
    topology: &Topology,
    v: u32,
    faces: &[u32],
    edges: &mut [[u32; 2]; STAR_EDGES],
) -> Option<usize> {
    let mut len = 0;
    for &f in faces {
        let corners = topology.face(f);
        for (i, &p) in corners.iter().enumerate() {
            let q = corners[if i + 1 == corners.len() { 0 } else { i + 1 }];
            if (p == v || q == v)
                && let Some(k) = edges[..len].iter().position(|&e| e == [q, p])
            {
                len -= 1;
                edges[k] = edges[len];
                continue;
            }
            *edges.get_mut(len)? = [p, q];
            len += 1;
        }
    }
    Some(len)
}

/// Faces a thread sums or checks in a row.
const CHUNK: usize = 8192;

/// A boundary chain projected along an axis, for [`NormalCones::contour_does_not_fold`]: the
/// plane's two axes and the chain's centroid in it at the start and at the end of the step.
#[derive(Clone, Copy)]
struct Contour {
    u: DVec3,
    w: DVec3,
    centres: [[f64; 2]; 2],
}

impl Contour {
    /// The projection of a chain of `len` vertices whose sums at the start and at the end are
    /// `sums` along `axis`.
    fn new(axis: DVec3, sums: [DVec3; 2], len: usize) -> Self {
        let (u, w) = axis.any_orthonormal_pair();
        let mut contour = Self {
            u,
            w,
            centres: [[0.0; 2]; 2],
        };
        contour.centres = sums.map(|sum| contour.flat(sum / len as f64));
        contour
    }

    fn flat(&self, p: DVec3) -> [f64; 2] {
        [p.dot(self.u), p.dot(self.w)]
    }

    /// `p` in the plane relative to the centre at the start (`k` = 0) or the end (1).
    fn relative(&self, p: DVec3, k: usize) -> [f64; 2] {
        let (q, c) = (self.flat(p), self.centres[k]);
        [q[0] - c[0], q[1] - c[1]]
    }

    /// Edge `p → q` of the chain: `None` when it does not turn forward around the centre at
    /// every time of the step (after a static refit the end is the start, and its turn is the
    /// only one), else whether it passes the ray from the centre along the plane's first axis,
    /// going from below that axis to on or above it.
    #[inline]
    fn edge(&self, h: &Hierarchy, [p, q]: [u32; 2]) -> Option<bool> {
        let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
        let (p0, q0) = (
            self.relative(h.start[p as usize], 0),
            self.relative(h.start[q as usize], 0),
        );
        if cross(p0, q0) <= 0.0 {
            return None;
        }
        if h.is_swept() {
            let (p1, q1) = (
                self.relative(h.end()[p as usize], 1),
                self.relative(h.end()[q as usize], 1),
            );
            let later = [(cross(p0, q1) + cross(p1, q0)) / 2.0, cross(p1, q1)];
            if later.iter().any(|&k| k <= 0.0) {
                return None;
            }
        }
        Some(p0[1] < 0.0 && q0[1] >= 0.0)
    }
}

/// The triangle scan of [`NormalCones::first_unseen`] and the contour test of
/// [`NormalCones::contour_does_not_fold`] in AVX registers, through `pulp` (as the cloth's
/// block product): four triangles or four edges in the four lanes, every product, sum and
/// comparison of [`NormalCones::all_of_triangle`] and [`Front::sees`], or of
/// [`Contour::edge`], in the same order (no fused multiply-adds; `/ 2` as `* 0.5`, both
/// exact), so each lane's answer is the scalar one.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use std::arch::x86_64::{__m256d, _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ};

    use parry3d_f64::math::Vector as DVec3;
    use pulp::x86::V3;

    use super::{Contour, Front, Hierarchy, NormalCones};

    /// A coordinate of four points, one a lane.
    type Four = [__m256d; 3];

    pub(super) struct Scan<'a, I> {
        pub(super) simd: V3,
        pub(super) cones: &'a NormalCones,
        pub(super) h: &'a Hierarchy,
        pub(super) front: Front,
        pub(super) triangles: I,
    }

    impl<I: Iterator<Item = usize>> pulp::NullaryFnOnce for Scan<'_, I> {
        type Output = Option<usize>;

        #[inline(always)]
        fn call(self) -> Option<usize> {
            let Self {
                simd,
                cones,
                h,
                front,
                mut triangles,
            } = self;
            let mut group = [0; 4];
            loop {
                let mut n = 0;
                while n < 4 {
                    let Some(t) = triangles.next() else { break };
                    group[n] = t;
                    n += 1;
                }
                if n < 4 {
                    return group[..n]
                        .iter()
                        .copied()
                        .find(|&t| !cones.all_of_triangle(h, t, |normal| front.sees(normal)));
                }
                let seen = seen_by(simd, h, cones.swept, &front, group);
                if seen != 0b1111 {
                    return Some(group[(!seen).trailing_zeros() as usize]);
                }
            }
        }
    }

    /// Which of the four triangles `group` have every normal coefficient seen by `front`: bit
    /// `k` for `group[k]`. (Plain functions marked to inline rather than closures: a closure
    /// is compiled without the vector units its caller enables.)
    #[inline(always)]
    fn seen_by(simd: V3, h: &Hierarchy, swept: bool, front: &Front, group: [usize; 4]) -> i32 {
        let avx = simd.avx;
        let corners = group.map(|t| h.topology.triangles[t]);
        let start = &h.start[..];
        let a0 = corner(simd, start, &corners, 0);
        let e0 = minus(simd, corner(simd, start, &corners, 1), a0);
        let g0 = minus(simd, corner(simd, start, &corners, 2), a0);
        let mut seen = sees(simd, front, cross(simd, e0, g0));
        if swept {
            let end = h.end();
            let a1 = corner(simd, end, &corners, 0);
            let e1 = minus(simd, corner(simd, end, &corners, 1), a1);
            let g1 = minus(simd, corner(simd, end, &corners, 2), a1);
            let (p, q) = (cross(simd, e0, g1), cross(simd, e1, g0));
            let half = avx._mm256_set1_pd(0.5);
            let middle = [
                avx._mm256_mul_pd(avx._mm256_add_pd(p[0], q[0]), half),
                avx._mm256_mul_pd(avx._mm256_add_pd(p[1], q[1]), half),
                avx._mm256_mul_pd(avx._mm256_add_pd(p[2], q[2]), half),
            ];
            seen = avx._mm256_and_pd(seen, sees(simd, front, middle));
            seen = avx._mm256_and_pd(seen, sees(simd, front, cross(simd, e1, g1)));
        }
        avx._mm256_movemask_pd(seen)
    }

    /// Corner `k` of the four triangles `corners` at `positions`.
    #[inline(always)]
    fn corner(simd: V3, positions: &[DVec3], corners: &[[u32; 3]; 4], k: usize) -> Four {
        points(simd, positions, corners.map(|c| c[k]))
    }

    /// The four points `indices` of `positions`.
    #[inline(always)]
    fn points(simd: V3, positions: &[DVec3], indices: [u32; 4]) -> Four {
        let avx = simd.avx;
        let p = indices.map(|i| positions[i as usize]);
        [
            avx._mm256_set_pd(p[3].x, p[2].x, p[1].x, p[0].x),
            avx._mm256_set_pd(p[3].y, p[2].y, p[1].y, p[0].y),
            avx._mm256_set_pd(p[3].z, p[2].z, p[1].z, p[0].z),
        ]
    }

    #[inline(always)]
    fn minus(simd: V3, p: Four, q: Four) -> Four {
        let avx = simd.avx;
        [
            avx._mm256_sub_pd(p[0], q[0]),
            avx._mm256_sub_pd(p[1], q[1]),
            avx._mm256_sub_pd(p[2], q[2]),
        ]
    }

    /// glam's `cross`: (y r.z − r.y z, z r.x − r.z x, x r.y − r.x y).
    #[inline(always)]
    fn cross(simd: V3, e: Four, g: Four) -> Four {
        let avx = simd.avx;
        [
            avx._mm256_sub_pd(avx._mm256_mul_pd(e[1], g[2]), avx._mm256_mul_pd(g[1], e[2])),
            avx._mm256_sub_pd(avx._mm256_mul_pd(e[2], g[0]), avx._mm256_mul_pd(g[2], e[0])),
            avx._mm256_sub_pd(avx._mm256_mul_pd(e[0], g[1]), avx._mm256_mul_pd(g[0], e[1])),
        ]
    }

    /// glam's `dot`: (x r.x + y r.y) + z r.z.
    #[inline(always)]
    fn dot(simd: V3, a: Four, b: Four) -> __m256d {
        let avx = simd.avx;
        avx._mm256_add_pd(
            avx._mm256_add_pd(avx._mm256_mul_pd(a[0], b[0]), avx._mm256_mul_pd(a[1], b[1])),
            avx._mm256_mul_pd(a[2], b[2]),
        )
    }

    /// [`Front::sees`] in each lane: all ones where it holds.
    #[inline(always)]
    fn sees(simd: V3, front: &Front, n: Four) -> __m256d {
        let avx = simd.avx;
        let d = dot(simd, n, broadcast(simd, front.axis));
        let bound = avx._mm256_mul_pd(
            avx._mm256_mul_pd(avx._mm256_set1_pd(front.cos2), dot(simd, n, n)),
            avx._mm256_set1_pd(front.axis_len2),
        );
        avx._mm256_and_pd(
            avx._mm256_cmp_pd::<_CMP_GT_OQ>(d, avx._mm256_setzero_pd()),
            avx._mm256_cmp_pd::<_CMP_GT_OQ>(avx._mm256_mul_pd(d, d), bound),
        )
    }

    /// The contour test of [`NormalCones::contour_does_not_fold`] on `edges`, four at a time
    /// (their count a multiple of four): `None` when one turns backward, else how many pass
    /// the ray. Each lane makes [`Contour::edge`]'s operations in its order.
    pub(super) struct Edges<'a> {
        pub(super) simd: V3,
        pub(super) contour: Contour,
        pub(super) h: &'a Hierarchy,
        pub(super) edges: &'a [[u32; 2]],
    }

    impl pulp::NullaryFnOnce for Edges<'_> {
        type Output = Option<usize>;

        #[inline(always)]
        fn call(self) -> Option<usize> {
            let Self {
                simd,
                contour,
                h,
                edges,
            } = self;
            let avx = simd.avx;
            let zero = avx._mm256_setzero_pd();
            let [c0, c1] = contour.centres;
            let plane = Plane {
                axes: [broadcast(simd, contour.u), broadcast(simd, contour.w)],
                centres: [
                    [avx._mm256_set1_pd(c0[0]), avx._mm256_set1_pd(c0[1])],
                    [avx._mm256_set1_pd(c1[0]), avx._mm256_set1_pd(c1[1])],
                ],
            };
            let (start, swept) = (&h.start[..], h.is_swept());
            let mut passes = 0;
            for four in edges.chunks_exact(4) {
                let (p, q) = (
                    [four[0][0], four[1][0], four[2][0], four[3][0]],
                    [four[0][1], four[1][1], four[2][1], four[3][1]],
                );
                let (p0, q0) = (
                    relative(simd, &plane, points(simd, start, p), 0),
                    relative(simd, &plane, points(simd, start, q), 0),
                );
                let mut backward = avx._mm256_cmp_pd::<_CMP_LE_OQ>(turn(simd, p0, q0), zero);
                if swept {
                    let end = h.end();
                    let (p1, q1) = (
                        relative(simd, &plane, points(simd, end, p), 1),
                        relative(simd, &plane, points(simd, end, q), 1),
                    );
                    let middle = avx._mm256_mul_pd(
                        avx._mm256_add_pd(turn(simd, p0, q1), turn(simd, p1, q0)),
                        avx._mm256_set1_pd(0.5),
                    );
                    backward = avx._mm256_or_pd(
                        backward,
                        avx._mm256_or_pd(
                            avx._mm256_cmp_pd::<_CMP_LE_OQ>(middle, zero),
                            avx._mm256_cmp_pd::<_CMP_LE_OQ>(turn(simd, p1, q1), zero),
                        ),
                    );
                }
                if avx._mm256_movemask_pd(backward) != 0 {
                    return None;
                }
                let passing = avx._mm256_and_pd(
                    avx._mm256_cmp_pd::<_CMP_LT_OQ>(p0[1], zero),
                    avx._mm256_cmp_pd::<_CMP_GE_OQ>(q0[1], zero),
                );
                passes += avx._mm256_movemask_pd(passing).count_ones() as usize;
            }
            Some(passes)
        }
    }

    /// The plane's axes and the centre at the start and at the end, each in every lane.
    struct Plane {
        axes: [Four; 2],
        centres: [[__m256d; 2]; 2],
    }

    /// `a` in every lane.
    #[inline(always)]
    fn broadcast(simd: V3, a: DVec3) -> Four {
        let avx = simd.avx;
        [
            avx._mm256_set1_pd(a.x),
            avx._mm256_set1_pd(a.y),
            avx._mm256_set1_pd(a.z),
        ]
    }

    /// [`Contour::relative`] in each lane.
    #[inline(always)]
    fn relative(simd: V3, plane: &Plane, p: Four, k: usize) -> [__m256d; 2] {
        let avx = simd.avx;
        [
            avx._mm256_sub_pd(dot(simd, p, plane.axes[0]), plane.centres[k][0]),
            avx._mm256_sub_pd(dot(simd, p, plane.axes[1]), plane.centres[k][1]),
        ]
    }

    /// The turn `a₀ b₁ − a₁ b₀` in each lane.
    #[inline(always)]
    fn turn(simd: V3, a: [__m256d; 2], b: [__m256d; 2]) -> __m256d {
        let avx = simd.avx;
        avx._mm256_sub_pd(avx._mm256_mul_pd(a[0], b[1]), avx._mm256_mul_pd(a[1], b[0]))
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::Point;

    /// An `n × n` grid of quads over the unit square lifted by `height(x, y)`.
    fn sheet(n: u32, height: impl Fn(f64, f64) -> f64) -> Hierarchy {
        let s = 1.0 / n as f64;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 * s, j as f64 * s);
                positions.push(Point::new(x, y, height(x, y)));
            }
        }
        let (mut offsets, mut corners) = (vec![0], Vec::new());
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                corners.extend([v, v + 1, v + n + 2, v + n + 1]);
                offsets.push(corners.len() as u32);
            }
        }
        Hierarchy::build(&positions, &offsets, &corners).unwrap()
    }

    /// A crumpled sheet refit over three motions, waving over a step, turning half a turn in
    /// its plane (its normals' ends face up, their middle coefficient down) and at rest, with
    /// the normal cones of each refit in vector lanes and one at a time.
    fn for_each_motion(mut test: impl FnMut(&Hierarchy, &NormalCones, &NormalCones)) {
        let mut h = sheet(12, |x, y| 0.03 * (7.0 * x).sin() * (5.0 * y).cos());
        let start: Vec<Point> = h
            .start
            .iter()
            .map(|&p| crate::convert::to_point(p))
            .collect();
        let wave = |p: &Point| {
            Point::new(
                p.x + 0.05 * (9.0 * p.y).sin(),
                p.y,
                p.z + 0.2 * (11.0 * p.x).cos(),
            )
        };
        let half_turn = |p: &Point| Point::new(1.0 - p.x, 1.0 - p.y, p.z);
        let ends: [Option<Vec<Point>>; 3] = [
            Some(start.iter().map(wave).collect()),
            Some(start.iter().map(half_turn).collect()),
            None,
        ];
        for end in ends {
            match end {
                Some(end) => h.refit_swept(&start, &end, 0.0).unwrap(),
                None => h.refit(&start, 0.0).unwrap(),
            }
            let lanes = NormalCones::new(&h);
            let one = NormalCones {
                swept: lanes.swept,
                #[cfg(target_arch = "x86_64")]
                simd: None,
            };
            test(&h, &lanes, &one);
        }
    }

    /// The scan four triangles at a time answers as the scalar one, triangle for triangle,
    /// against axes that see every normal, some, or none, and tilted to just inside and just
    /// outside the margin.
    #[test]
    fn four_triangles_at_a_time_answer_as_one_at_a_time() {
        let (mut compared, mut unseen) = (0, [0; 2]);
        for_each_motion(|h, lanes, one| {
            // Axes at an angle to the first triangle's normal just short of 90° minus the
            // margin, and just past it.
            let n = {
                let [a, b, c] = h.triangle_at(0, &h.start);
                (b - a).cross(c - a).normalize()
            };
            let (u, _) = n.any_orthonormal_pair();
            let tilt = |angle: f64| n * angle.cos() + u * angle.sin();
            let axes = [
                DVec3::Z,
                -DVec3::Z,
                DVec3::new(0.3, -0.2, 1.0),
                DVec3::new(1.0, 0.0, 0.2),
                tilt(PI / 2.0 - 1.1 * MARGIN),
                tilt(PI / 2.0 - 0.9 * MARGIN),
            ];
            for axis in axes {
                let front = Front::new(axis);
                let triangles = h.triangle_count();
                for first in 0..triangles {
                    for len in [1, 3, 4, 5, 9, 40] {
                        let range = first..triangles.min(first + len);
                        let expect = range
                            .clone()
                            .find(|&t| !one.all_of_triangle(h, t, |n| front.sees(n)));
                        assert_eq!(one.first_unseen(h, front, range.clone()), expect);
                        assert_eq!(lanes.first_unseen(h, front, range), expect);
                        compared += 1;
                        unseen[usize::from(expect.is_some())] += 1;
                    }
                }
            }
        });
        assert!(
            compared > 10_000 && unseen.iter().all(|&k| k > 1_000),
            "{unseen:?}"
        );
    }

    /// The contour test four edges at a time answers as the scalar one on every node's
    /// boundary and every vertex star's, projected along axes that keep some contours simple
    /// and fold others.
    #[test]
    fn four_edges_at_a_time_answer_as_one_at_a_time() {
        let mut answers = [0; 2];
        for_each_motion(|h, lanes, one| {
            let mut boundaries: Vec<Vec<[u32; 2]>> = (0..h.children.len() as u32)
                .map(|i| h.node_boundary(h.face_count() as u32 + i).to_vec())
                .collect();
            for v in 0..h.vertex_count() as u32 {
                let mut edges = [[0; 2]; STAR_EDGES];
                let faces = h.vertex_faces().of(v as usize);
                if let Some(len) = star_boundary(&h.topology, v, faces, &mut edges) {
                    boundaries.push(edges[..len].to_vec());
                }
            }
            for boundary in &boundaries {
                let (axis, sums) = one.boundary_axis(h, boundary);
                for axis in [axis, DVec3::Z, DVec3::new(1.0, 0.2, 0.1), -axis] {
                    let axis = axis.normalize();
                    let expect = one.contour_does_not_fold(h, boundary, axis, sums);
                    assert_eq!(lanes.contour_does_not_fold(h, boundary, axis, sums), expect);
                    answers[usize::from(expect)] += 1;
                }
            }
        });
        assert!(answers.iter().all(|&k| k > 500), "{answers:?}");
    }

    #[test]
    fn gently_curved_sheet_is_culled_at_the_root() {
        let h = sheet(8, |x, y| 0.2 * (x * 3.0).sin() * y);
        let cones = NormalCones::new(&h);
        assert!(cones.cannot_self_collide(&h, h.root()));
    }

    #[test]
    fn steep_but_unfolded_sheet_is_culled_and_a_folded_one_is_not() {
        // Bent up at x = 0.5 with slope 4 (76°): still seen from one side.
        let bent = sheet(8, |x, _| if x < 0.5 { 0.0 } else { (x - 0.5) * 4.0 });
        assert!(NormalCones::new(&bent).cannot_self_collide(&bent, bent.root()));
        // Folded back over itself like a taco, round a half-cylinder hinge of radius 0.1: the
        // normals sweep half a turn.
        let mut folded = sheet(20, |_, _| 0.0);
        let hinge = |x: f64, y: f64| {
            if x <= 0.4 {
                Point::new(x, y, 0.0)
            } else if x <= 0.6 {
                let (s, c) = ((x - 0.4) / 0.2 * PI).sin_cos();
                Point::new(0.4 + 0.1 * s, y, 0.1 - 0.1 * c)
            } else {
                Point::new(1.0 - x, y, 0.2)
            }
        };
        let positions: Vec<Point> = folded.start.iter().map(|p| hinge(p.x, p.y)).collect();
        folded.refit(&positions, 0.0).unwrap();
        assert!(!NormalCones::new(&folded).cannot_self_collide(&folded, folded.root()));
    }

    #[test]
    fn spiral_whose_projection_overlaps_is_not() {
        // A flat strip that winds 1.5 turns around the origin like a helix ramp: every normal
        // points nearly up, yet the strip passes over itself.
        let turns = 60;
        let mut positions = Vec::new();
        for i in 0..=turns {
            let a = i as f64 / turns as f64 * 3.0 * PI;
            let (s, c) = a.sin_cos();
            let z = 0.01 * a;
            positions.push(Point::new(c, s, z));
            positions.push(Point::new(2.0 * c, 2.0 * s, z));
        }
        let (mut offsets, mut corners) = (vec![0], Vec::new());
        for i in 0..turns {
            corners.extend([2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2]);
            offsets.push(corners.len() as u32);
        }
        let h = Hierarchy::build(&positions, &offsets, &corners).unwrap();
        let cones = NormalCones::new(&h);
        assert!(!cones.cannot_self_collide(&h, h.root()));
    }

    /// The positions of `h`'s last refit (the start of a swept one).
    fn start_positions(h: &Hierarchy) -> Vec<Point> {
        h.start
            .iter()
            .map(|&p| crate::convert::to_point(p))
            .collect()
    }

    #[test]
    fn a_flip_during_the_step_is_not_culled() {
        let mut h = sheet(4, |_, _| 0.0);
        let start = start_positions(&h);
        // Turn the sheet upside down over the step (mirror x): normals swing through the plane.
        let end: Vec<Point> = start
            .iter()
            .map(|p| Point::new(1.0 - p.x, p.y, p.z))
            .collect();
        h.refit_swept(&start, &end, 0.0).unwrap();
        assert!(!NormalCones::new(&h).cannot_self_collide(&h, h.root()));
        // The same sheet merely translated is still culled.
        let shifted: Vec<Point> = start
            .iter()
            .map(|p| Point::new(p.x + 0.3, p.y, p.z + 1.0))
            .collect();
        h.refit_swept(&start, &shifted, 0.0).unwrap();
        assert!(NormalCones::new(&h).cannot_self_collide(&h, h.root()));
    }

    /// The stars of every vertex of a gently waving sheet are cleared, those at its rim and
    /// corners too; a crease closing to 170° over the step leaves the stars along it, whose
    /// faces lie on both sides, to the exact tests, and clears the others, those of the half
    /// that turns rigidly too.
    #[test]
    fn stars_are_cleared_on_a_waving_sheet_and_not_across_a_closing_crease() {
        let n = 8;
        let mut h = sheet(n, |_, _| 0.0);
        let start = start_positions(&h);
        let waved: Vec<Point> = start
            .iter()
            .map(|p| Point::new(p.x, p.y, 0.1 * (3.0 * p.x + 2.0 * p.y).sin()))
            .collect();
        h.refit_swept(&start, &waved, 0.0).unwrap();
        let cones = NormalCones::new(&h);
        let stars = Stars::new(&h, &cones);
        assert!((0..h.vertex_count() as u32).all(|v| stars.cleared(v)));

        let (s, c) = (170f64.to_radians().sin(), 170f64.to_radians().cos());
        let creased: Vec<Point> = start
            .iter()
            .map(|p| {
                if p.x <= 0.5 {
                    *p
                } else {
                    let r = p.x - 0.5;
                    Point::new(0.5 + r * c, p.y, r * s)
                }
            })
            .collect();
        h.refit_swept(&start, &creased, 0.0).unwrap();
        let cones = NormalCones::new(&h);
        let stars = Stars::new(&h, &cones);
        for (v, p) in start.iter().enumerate() {
            let cleared = stars.cleared(v as u32);
            assert_eq!(cleared, p.x != 0.5, "vertex {v} at {p}");
        }
    }

    /// A failed test keeps its witness and tries it first next time; the answers, for every
    /// node and every star, stay those of a hierarchy that remembers nothing, as an inner
    /// vertex of a sheet is dragged across its neighbours and back, the sheet rests flat (the
    /// witnesses now pass), folds, folds further, opens, folds across the other way and waves.
    #[test]
    fn remembered_failures_change_no_answer() {
        let n = 12;
        let fold = |x0: f64, degrees: f64, along_x: bool| {
            let (s, c) = degrees.to_radians().sin_cos();
            move |p: &Point| {
                let (u, w) = if along_x { (p.x, p.y) } else { (p.y, p.x) };
                let (u, z) = if u <= x0 {
                    (u, 0.0)
                } else {
                    (x0 + (u - x0) * c, (u - x0) * s)
                };
                if along_x {
                    Point::new(u, w, z)
                } else {
                    Point::new(w, u, z)
                }
            }
        };
        let rest = sheet(n, |_, _| 0.0);
        let flat = start_positions(&rest);
        let pose = |f: &dyn Fn(&Point) -> Point| flat.iter().map(f).collect::<Vec<_>>();
        // One inner vertex dragged across its neighbours turns its faces over while the rim
        // stays square: the nodes around it fail on their normals, not their contour.
        let dragged = |by: f64| {
            move |p: &Point| {
                let near = |a: f64| (a - 0.5).abs() < 1e-9;
                if near(p.x) && near(p.y) {
                    Point::new(p.x + by, p.y + 0.5 * by, 0.01)
                } else {
                    *p
                }
            }
        };
        let poses = [
            flat.clone(),
            pose(&dragged(0.3)),
            pose(&dragged(0.35)),
            flat.clone(),
            flat.clone(),
            pose(&fold(0.5, 120.0, true)),
            pose(&fold(0.5, 170.0, true)),
            pose(&fold(0.45, 175.0, true)),
            flat.clone(),
            flat.clone(),
            pose(&fold(0.3, 160.0, false)),
            pose(&|p: &Point| Point::new(p.x, p.y, 0.1 * (5.0 * p.x + 3.0 * p.y).sin())),
            pose(&fold(0.3, 165.0, false)),
        ];
        let mut remembering = rest.clone();
        let mut failures = 0;
        for step in poses.windows(2) {
            remembering.refit_swept(&step[0], &step[1], 0.0).unwrap();
            let mut fresh = sheet(n, |_, _| 0.0);
            fresh.refit_swept(&step[0], &step[1], 0.0).unwrap();
            let (cones, fresh_cones) = (NormalCones::new(&remembering), NormalCones::new(&fresh));
            let nodes = remembering.face_count() + remembering.children.len();
            for node in 0..nodes as u32 {
                let answer = cones.cannot_self_collide(&remembering, node);
                assert_eq!(
                    answer,
                    fresh_cones.cannot_self_collide(&fresh, node),
                    "node {node}"
                );
                failures += usize::from(!answer);
            }
            let (stars, fresh_stars) = (
                Stars::new(&remembering, &cones),
                Stars::new(&fresh, &fresh_cones),
            );
            for v in 0..remembering.vertex_count() as u32 {
                assert_eq!(stars.cleared(v), fresh_stars.cleared(v), "star {v}");
            }
        }
        assert!(failures > 0, "no test failed");
        let remembered =
            (0..remembering.witnesses.0.len()).filter(|&k| remembering.witnesses.get(k).is_some());
        assert!(remembered.count() > 0, "nothing was remembered");
    }
}
