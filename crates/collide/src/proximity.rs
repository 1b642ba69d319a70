//! Proximity queries: the closest point of a mesh to each query point, or every face within a
//! distance, and the same for a mesh's own vertices against itself (DeRose, Kass & Truong 1998,
//! §5: every cloth vertex is tested against the body's hierarchy and against its own).
//!
//! Each query visits the faces whose boxes lie within the best distance so far (or within the
//! search radius), nearer boxes first (see the hierarchy's `boxes` module), comparing squared
//! distances so that no square root is taken until a face could win. Pruning only drops boxes
//! strictly farther (with a relative 10⁻¹² to spare for rounding) and ties go to the lowest
//! face, then the lowest triangle, so the answer is exactly the brute-force one. The
//! point–triangle projection is parry's (Ericson's Voronoi-region method).
//!
//! Queries come in runs, one run per thread at a time, usually in mesh order (the vertices of a
//! garment). A nearest-point query first tries the face that answered the previous query of its
//! run: it is close, so the search starts with nearly its final radius and climbs from that
//! face instead of descending from the root: about 30% fewer box tests than a plain descent
//! on a coherent set of queries. The seed only changes the order of the visits, never the
//! answer, so answers do not depend on how the queries are split between threads. A seed whose
//! box is out of reach (the query is far from where the previous one was answered, or the
//! previous queries found nothing and left an old seed) is not used: climbing from it would
//! test a box at every level, where a descent from the root stops at the root or its
//! children. Zero-area
//! triangles are rare, so the search ignores them and runs again without them only when one of
//! them won.
//!
//! A vertex of the mesh asking for the faces near it, excluding its own, climbs the same way
//! from the face that owns it, which lies next to it and is excluded anyway. It also skips the
//! faces around it on the surface that the caller lists ([`crate::local`]), whole subtrees of
//! them at a time, and climbs from the highest subtree around its own face that it skips.
//!
//! Self-proximity does not use the normal cones: they prove that a region cannot *touch*
//! itself, not that its vertices stay farther than a distance from its other faces (a finely
//! tessellated flat sheet has both), so only the exact zero-thickness queries cull with them.

use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{Triangle, TrianglePointLocation};
use rayon::prelude::*;

use crate::convert::{to_glam, to_point, to_vector};
use crate::error::CollideError;
use crate::hierarchy::{Hierarchy, Pending, check_distance, finite, fresh};
use crate::triangle::is_degenerate;
use crate::{Point, Vector};

/// The closest point of a mesh to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// The face it lies on.
    pub face: u32,
    /// The fan triangle of that face it lies on (index into [`Hierarchy::triangles`]).
    pub triangle: u32,
    /// The triangle's vertices.
    pub vertices: [u32; 3],
    /// Barycentric coordinates of the point on the triangle (they sum to 1).
    pub barycentric: [f64; 3],
    /// The closest point.
    pub point: Point,
    /// Its distance to the query point.
    pub distance: f64,
    /// The triangle's unit normal (right-handed around its vertices).
    pub normal: Vector,
}

/// For each vertex of a mesh, a sorted list of faces a self-proximity query skips: a CSR
/// table, made by [`Hierarchy::local_faces`]. The empty table (its default) lists nothing for
/// any vertex.
///
/// With the lists come, per vertex, the ranges of the depth-first face order of the hierarchy
/// that made the table (see `local`) in which every face is skipped, so that a query on that
/// hierarchy leaves out whole subtrees without testing their boxes; a hierarchy whose faces
/// lie in another order reads the lists alone.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LocalFaces {
    pub(crate) offsets: Vec<u32>,
    pub(crate) faces: Vec<u32>,
    /// CSR over vertices: ranges `[first, end)` of places in the depth-first order.
    pub(crate) range_offsets: Vec<u32>,
    pub(crate) ranges: Vec<[u32; 2]>,
    /// Per vertex, the node a query climbs from: the highest above the face that owns the
    /// vertex whose faces lie wholly in one range.
    pub(crate) starts: Vec<u32>,
    /// The fingerprint of the order the ranges refer to.
    pub(crate) order: u64,
}

impl LocalFaces {
    /// The faces listed for vertex `v`, sorted; none beyond the table.
    #[must_use]
    pub fn of(&self, v: usize) -> &[u32] {
        match self.offsets.get(v..v + 2) {
            Some(&[first, end]) => &self.faces[first as usize..end as usize],
            _ => &[],
        }
    }

    /// The ranges of the depth-first order of `h` in which every face is skipped for vertex
    /// `v`, and the node of `h` its query climbs from: none when `h` orders its faces
    /// otherwise than the hierarchy that made the table.
    pub(crate) fn ranges_of(&self, v: usize, h: &Hierarchy) -> Option<(&[[u32; 2]], u32)> {
        match self.range_offsets.get(v..v + 2) {
            Some(&[first, end]) if self.order == h.order_fingerprint() => {
                Some((&self.ranges[first as usize..end as usize], self.starts[v]))
            }
            _ => None,
        }
    }

    /// How many vertex–face pairs the table lists.
    #[must_use]
    pub fn pair_count(&self) -> usize {
        self.faces.len()
    }
}

/// For each query, every face within a distance: a CSR table of [`Closest`] hits, each the
/// nearest point of one face, sorted by face.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Neighbours {
    offsets: Vec<u32>,
    hits: Vec<Closest>,
}

impl Neighbours {
    /// Number of queries.
    #[must_use]
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether there were no queries.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The faces near query `i`, sorted by face.
    #[must_use]
    pub fn of(&self, i: usize) -> &[Closest] {
        &self.hits[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// All hits, query after query.
    #[must_use]
    pub fn hits(&self) -> &[Closest] {
        &self.hits
    }

    /// Refills the table with the hits of `count` queries, in parallel, reusing its storage.
    /// `query(i, stack, hits)` appends the hits of query `i`; runs of queries share a stack and
    /// a hit list, concatenated in query order, so the table does not depend on the threads.
    fn fill(&mut self, count: usize, query: impl Fn(usize, &mut Stack, &mut Vec<Closest>) + Sync) {
        let runs: Vec<(Vec<u32>, Vec<Closest>)> = (0..count)
            .into_par_iter()
            .with_min_len(QUERY_RUN)
            .fold(
                || (Vec::new(), Vec::new(), Vec::new()),
                |(mut counts, mut hits, mut stack), i| {
                    let before = hits.len();
                    query(i, &mut stack, &mut hits);
                    hits[before..].sort_unstable_by_key(|c| c.face);
                    counts.push((hits.len() - before) as u32);
                    (counts, hits, stack)
                },
            )
            .map(|(counts, hits, _)| (counts, hits))
            .collect();
        self.offsets.clear();
        self.offsets.reserve(count + 1);
        self.offsets.push(0);
        self.hits.clear();
        self.hits
            .reserve(runs.iter().map(|(_, hits)| hits.len()).sum());
        for (counts, hits) in runs {
            for c in counts {
                let last = *self.offsets.last().unwrap_or(&0);
                self.offsets.push(last + c);
            }
            self.hits.extend(hits);
        }
    }
}

/// Queries handled in a row by one thread, sharing a traversal stack.
const QUERY_RUN: usize = 256;

/// The traversal stack of a query.
type Stack = Vec<Pending>;

/// The best candidate of a nearest-point search so far, and the distance to beat.
type Best = (Option<Candidate>, f64);

/// What a run of nearest-point queries on one thread reuses from query to query.
#[derive(Default)]
struct Scratch {
    stack: Stack,
    /// The face that answered the previous query.
    seed: Option<u32>,
}

/// The nearest point found so far on one triangle, before it becomes a [`Closest`].
#[derive(Clone, Copy)]
struct Candidate {
    distance: f64,
    face: u32,
    triangle: usize,
    point: DVec3,
    location: TrianglePointLocation,
}

impl Hierarchy {
    /// For each query point, the closest point of the mesh within `max_distance` (which may be
    /// infinite), at the positions of the last refit. Zero-area triangles are skipped.
    ///
    /// # Errors
    /// [`CollideError::NonFiniteQuery`] for a NaN or infinite query point,
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn closest_points(
        &self,
        queries: &[Point],
        max_distance: f64,
    ) -> Result<Vec<Option<Closest>>, CollideError> {
        fresh(|out| self.closest_points_into(queries, max_distance, out))
    }

    /// [`Hierarchy::closest_points`] into `out` (cleared first), reusing its allocation from
    /// step to step.
    ///
    /// # Errors
    /// As [`Hierarchy::closest_points`]; `out` is then left unchanged.
    pub fn closest_points_into(
        &self,
        queries: &[Point],
        max_distance: f64,
        out: &mut Vec<Option<Closest>>,
    ) -> Result<(), CollideError> {
        self.closest_points_from(queries, max_distance, |_| None, out)
    }

    /// [`Hierarchy::closest_points_into`] with a face near each query, `seeds[i]` for
    /// `queries[i]` (the face of its last answer, for points that moved little since), tried
    /// first in place of the previous query's: the walk then starts with a radius about the
    /// answer's. The answers are the same bits with any seeds, or none (see
    /// [`Hierarchy::nearest`]).
    ///
    /// # Errors
    /// As [`Hierarchy::closest_points`]; `out` is then left unchanged.
    ///
    /// # Panics
    /// When `seeds` and `queries` differ in length, or a seed is not a face of the mesh.
    pub fn closest_points_seeded_into(
        &self,
        queries: &[Point],
        max_distance: f64,
        seeds: &[Option<u32>],
        out: &mut Vec<Option<Closest>>,
    ) -> Result<(), CollideError> {
        self.assert_seeds(queries, seeds);
        self.closest_points_from(queries, max_distance, |i| seeds[i], out)
    }

    /// Panics unless there is a seed per query and each names a face of the mesh.
    pub(crate) fn assert_seeds(&self, queries: &[Point], seeds: &[Option<u32>]) {
        assert_eq!(seeds.len(), queries.len(), "a seed per query");
        assert!(
            seeds
                .iter()
                .flatten()
                .all(|&f| (f as usize) < self.face_count()),
            "seeds are faces of the mesh"
        );
    }

    /// The closest points of `queries` within `max_distance` into `out`, query `i` trying
    /// `seed(i)` first when it names a face, else the face of the previous query's answer.
    pub(crate) fn closest_points_from(
        &self,
        queries: &[Point],
        max_distance: f64,
        seed: impl Fn(usize) -> Option<u32> + Sync,
        out: &mut Vec<Option<Closest>>,
    ) -> Result<(), CollideError> {
        check_distance("max_distance", max_distance)?;
        check_queries(queries)?;
        queries
            .par_iter()
            .enumerate()
            .with_min_len(QUERY_RUN)
            .map_init(Scratch::default, |scratch, (i, q)| {
                scratch.seed = seed(i).or(scratch.seed);
                self.nearest(to_glam(q), max_distance, scratch)
            })
            .collect_into_vec(out);
        Ok(())
    }

    /// For each query point, every face with a point within `distance`.
    ///
    /// # Errors
    /// As [`Hierarchy::closest_points`].
    pub fn faces_within(
        &self,
        queries: &[Point],
        distance: f64,
    ) -> Result<Neighbours, CollideError> {
        fresh(|out| self.faces_within_into(queries, distance, out))
    }

    /// [`Hierarchy::faces_within`] into `out`, reusing its storage from step to step.
    ///
    /// # Errors
    /// As [`Hierarchy::closest_points`]; `out` is then left unchanged.
    pub fn faces_within_into(
        &self,
        queries: &[Point],
        distance: f64,
        out: &mut Neighbours,
    ) -> Result<(), CollideError> {
        check_distance("distance", distance)?;
        check_queries(queries)?;
        out.fill(queries.len(), |i, stack, hits| {
            let q = to_glam(&queries[i]);
            self.within(q, distance, None, (&[], |_| false), stack, hits);
        });
        Ok(())
    }

    /// For each vertex of the mesh, every face within `distance` that does not use the vertex
    /// and that `skip` does not list for it ([`Hierarchy::local_faces`]; the empty table skips
    /// nothing).
    ///
    /// # Errors
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn self_proximity(
        &self,
        distance: f64,
        skip: &LocalFaces,
    ) -> Result<Neighbours, CollideError> {
        fresh(|out| self.self_proximity_into(distance, skip, out))
    }

    /// [`Hierarchy::self_proximity`] into `out`, reusing its storage from step to step.
    ///
    /// # Errors
    /// As [`Hierarchy::self_proximity`]; `out` is then left unchanged.
    pub fn self_proximity_into(
        &self,
        distance: f64,
        skip: &LocalFaces,
        out: &mut Neighbours,
    ) -> Result<(), CollideError> {
        check_distance("distance", distance)?;
        out.fill(self.vertex_count(), |v, stack, hits| {
            let owner = self.topology.vertex_owner[v];
            let (ranges, seed) = match skip.ranges_of(v, self) {
                Some((ranges, start)) => (ranges, (start != u32::MAX).then_some(start)),
                None => (&[][..], (owner != u32::MAX).then_some(owner)),
            };
            let skipped = skip.of(v);
            let v = v as u32;
            let excluded =
                |f: u32| self.topology.face(f).contains(&v) || skipped.binary_search(&f).is_ok();
            self.within(
                self.end()[v as usize],
                distance,
                seed,
                (ranges, excluded),
                stack,
                hits,
            );
        });
        Ok(())
    }

    /// The closest point to `q` within `limit`.
    ///
    /// The face that answered the previous query of the same run is tried first: queries come
    /// in mesh order, so it is usually close to the answer and the descent starts with a tight
    /// radius. The descent then visits nearer boxes first and prunes on the best distance so
    /// far; faces are compared by `(distance, face)`, so ties go to the lowest face and the seed
    /// never changes the answer. Zero-area triangles are rare, so the search first ignores them
    /// and is redone without them only when one of them won.
    fn nearest(&self, q: DVec3, limit: f64, scratch: &mut Scratch) -> Option<Closest> {
        let best = match self.nearest_candidate(q, limit, scratch, false) {
            Some(c) if is_degenerate(self.triangle_at(c.triangle, self.end())) => {
                self.nearest_candidate(q, limit, scratch, true)
            }
            found => found,
        };
        // A query with nothing within reach keeps the last seed for the next one.
        scratch.seed = best.map(|c| c.face).or(scratch.seed);
        best.map(|c| self.closest(c))
    }

    /// [`Hierarchy::nearest`], skipping zero-area triangles when `strict`.
    fn nearest_candidate(
        &self,
        q: DVec3,
        limit: f64,
        scratch: &mut Scratch,
        strict: bool,
    ) -> Option<Candidate> {
        let mut best: Best = (None, limit);
        // A seed out of reach (the answer to a query near another part of the mesh, or the
        // last one found before a run of queries far from the mesh) would only make the walk
        // climb every level: a plain descent from the root, which prunes at the root's
        // children, is cheaper then.
        let seed = scratch
            .seed
            .filter(|&f| self.boxes().face_distance2(f, q) <= prune_bound(limit));
        if let Some(f) = seed {
            self.consider(&mut best, f, q, strict);
        }
        let bound = prune_bound(best.1);
        self.visit_near(q, bound, seed, &mut scratch.stack, &[], |f| {
            self.consider(&mut best, f, q, strict);
            prune_bound(best.1)
        });
        best.0
    }

    /// Makes face `f` the best when one of its triangles is nearer to `q` (ties to the lowest
    /// face, then triangle), skipping zero-area triangles when `strict`.
    #[inline(always)]
    fn consider(&self, best: &mut Best, f: u32, q: DVec3, strict: bool) {
        for t in self.topology.face_triangles(f) {
            if let Some(c) = self.project_within(f, t, q, best.1)
                && best
                    .0
                    .is_none_or(|b| (c.distance, c.face) < (b.distance, b.face))
                && !(strict && is_degenerate(self.triangle_at(t, self.end())))
            {
                *best = (Some(c), c.distance);
            }
        }
    }

    /// Appends every face within `distance` of `q` that is not excluded to `hits`: a face is
    /// excluded when it lies in one of the ranges of the depth-first order or `excluded` holds
    /// for it, and the ranges must list excluded faces only. The walk climbs from `seed`, a
    /// node whose faces are all excluded, when there is one.
    fn within(
        &self,
        q: DVec3,
        distance: f64,
        seed: Option<u32>,
        (ranges, excluded): (&[[u32; 2]], impl Fn(u32) -> bool),
        stack: &mut Stack,
        hits: &mut Vec<Closest>,
    ) {
        let bound = prune_bound(distance);
        self.visit_near(q, bound, seed, stack, ranges, |f| {
            if !excluded(f) {
                hits.extend(
                    self.closest_on_face(f, q, distance)
                        .map(|c| self.closest(c)),
                );
            }
            bound
        });
    }

    /// The projection of `q` on fan triangle `t` of face `f`, whatever its area.
    ///
    /// Only when it lies within `limit`: the squared distance is compared first, and the square
    /// root (exactly the one of [`DVec3::length`]) taken only for the survivors.
    #[inline(always)]
    fn project_within(&self, f: u32, t: usize, q: DVec3, limit: f64) -> Option<Candidate> {
        let [a, b, c] = self.triangle_at(t, self.end());
        let (projection, location) =
            Triangle::new(a, b, c).project_local_point_and_get_location(q, false);
        let squared = (q - projection.point).length_squared();
        if squared > prune_bound(limit) {
            return None;
        }
        let distance = squared.sqrt();
        (distance <= limit).then_some(Candidate {
            distance,
            face: f,
            triangle: t,
            point: projection.point,
            location,
        })
    }

    /// The closest point of face `f` to `q` within `limit` over its non-degenerate triangles
    /// (the lowest triangle on ties).
    fn closest_on_face(&self, f: u32, q: DVec3, limit: f64) -> Option<Candidate> {
        let mut best: Option<Candidate> = None;
        for t in self.topology.face_triangles(f) {
            if let Some(c) = self.project_within(f, t, q, limit)
                && best.is_none_or(|b| c.distance < b.distance)
                && !is_degenerate(self.triangle_at(t, self.end()))
            {
                best = Some(c);
            }
        }
        best
    }

    /// The full answer for a candidate.
    fn closest(&self, c: Candidate) -> Closest {
        let [a, b, d] = self.triangle_at(c.triangle, self.end());
        Closest {
            face: c.face,
            triangle: c.triangle as u32,
            vertices: self.topology.triangles[c.triangle],
            barycentric: c
                .location
                .barycentric_coordinates()
                .unwrap_or([1.0, 0.0, 0.0]),
            point: to_point(c.point),
            distance: c.distance,
            normal: to_vector((b - a).cross(d - a).normalize()),
        }
    }
}

/// The squared box distance beyond which a node cannot hold a point within `radius`, loosened
/// by a relative 1e-12 so that rounding never prunes a tie.
fn prune_bound(radius: f64) -> f64 {
    let r = radius * (1.0 + 1e-12);
    r * r
}

/// Checks that query points are finite.
fn check_queries(queries: &[Point]) -> Result<(), CollideError> {
    match queries.iter().position(|p| !finite(p)) {
        Some(point) => Err(CollideError::NonFiniteQuery { point }),
        None => Ok(()),
    }
}
