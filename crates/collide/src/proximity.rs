//! Proximity queries: the closest point of a mesh to each query point, or every face within a
//! distance, and the same for a mesh's own vertices against itself (DeRose, Kass & Truong 1998,
//! §5: every cloth vertex is tested against the body's hierarchy and against its own).
//!
//! Each query descends the hierarchy nearest child first and prunes a node whose box lies
//! farther than the best distance so far (or than the search radius). Pruning is strict and
//! ties go to the lowest face, then the lowest triangle, so the answer is exactly the
//! brute-force one. The point–triangle projection is parry's (Ericson's Voronoi-region method).
//! Queries run in parallel over query points; each answer depends only on its point.
//!
//! Self-proximity does not use the normal cones: they prove that a region cannot *touch*
//! itself, not that its vertices stay farther than a distance from its other faces (a finely
//! tessellated flat sheet has both), so only the exact zero-thickness queries cull with them.

use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::Triangle;
use rayon::prelude::*;

use crate::convert::{to_glam, to_point, to_vector};
use crate::error::CollideError;
use crate::hierarchy::{Hierarchy, check_distance};
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

/// For each query, every face within a distance: a CSR table of [`Closest`] hits, each the
/// nearest point of one face, sorted by face.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Neighbours {
    offsets: Vec<u32>,
    hits: Vec<Closest>,
}

impl Neighbours {
    fn from_lists(lists: Vec<Vec<Closest>>) -> Self {
        let mut offsets = Vec::with_capacity(lists.len() + 1);
        offsets.push(0);
        let mut hits = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for list in lists {
            hits.extend(list);
            offsets.push(hits.len() as u32);
        }
        Self { offsets, hits }
    }

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
        check_distance("max_distance", max_distance)?;
        let queries = checked_queries(queries)?;
        Ok(queries
            .par_iter()
            .map(|&q| self.nearest(q, max_distance, |_| false))
            .collect())
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
        check_distance("distance", distance)?;
        let queries = checked_queries(queries)?;
        let lists = queries
            .par_iter()
            .map(|&q| self.within(q, distance, |_| false))
            .collect();
        Ok(Neighbours::from_lists(lists))
    }

    /// For each vertex of the mesh, every face within `distance` that does not use the vertex.
    ///
    /// # Errors
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn self_proximity(&self, distance: f64) -> Result<Neighbours, CollideError> {
        check_distance("distance", distance)?;
        let lists = (0..self.vertex_count() as u32)
            .into_par_iter()
            .map(|v| {
                let incident = |f: u32| self.topology.face(f).contains(&v);
                self.within(self.end()[v as usize], distance, incident)
            })
            .collect();
        Ok(Neighbours::from_lists(lists))
    }

    /// The closest point to `q` within `limit` over faces not `excluded`.
    pub(crate) fn nearest(
        &self,
        q: DVec3,
        limit: f64,
        excluded: impl Fn(u32) -> bool,
    ) -> Option<Closest> {
        let mut best: Option<Closest> = None;
        let mut radius = limit;
        let mut stack = Vec::with_capacity(64);
        stack.push((self.root(), self.box_distance(self.root(), q)));
        while let Some((node, distance)) = stack.pop() {
            if distance > radius {
                continue;
            }
            match self.node_children(node) {
                None if excluded(node) => {}
                None => {
                    if let Some(c) = self.closest_on_face(node, q)
                        && c.distance <= radius
                        && best.is_none_or(|b| (c.distance, c.face) < (b.distance, b.face))
                    {
                        radius = c.distance;
                        best = Some(c);
                    }
                }
                Some([a, b]) => {
                    let (da, db) = (self.box_distance(a, q), self.box_distance(b, q));
                    let (near, far) = if da <= db {
                        ((a, da), (b, db))
                    } else {
                        ((b, db), (a, da))
                    };
                    stack.extend([far, near].into_iter().filter(|x| x.1 <= radius));
                }
            }
        }
        best
    }

    /// Every face within `distance` of `q` that is not `excluded`, sorted by face.
    fn within(&self, q: DVec3, distance: f64, excluded: impl Fn(u32) -> bool) -> Vec<Closest> {
        let mut hits = Vec::new();
        let mut stack = Vec::with_capacity(64);
        stack.push(self.root());
        while let Some(node) = stack.pop() {
            if self.box_distance(node, q) > distance {
                continue;
            }
            match self.node_children(node) {
                None if !excluded(node) => hits.extend(
                    self.closest_on_face(node, q)
                        .filter(|c| c.distance <= distance),
                ),
                None => {}
                Some(children) => stack.extend(children),
            }
        }
        hits.sort_unstable_by_key(|c| c.face);
        hits
    }

    fn box_distance(&self, node: u32, q: DVec3) -> f64 {
        let b = &self.boxes[node as usize];
        (b.mins - q).max(q - b.maxs).max(DVec3::ZERO).length()
    }

    /// The closest point of face `f` to `q` over its non-degenerate triangles (the lowest
    /// triangle on ties).
    pub(crate) fn closest_on_face(&self, f: u32, q: DVec3) -> Option<Closest> {
        let mut best: Option<(f64, usize, DVec3, [f64; 3])> = None;
        for t in self.topology.face_triangles(f) {
            let corners = self.triangle_at(t, self.end());
            if is_degenerate(corners) {
                continue;
            }
            let [a, b, c] = corners;
            let (projection, location) =
                Triangle::new(a, b, c).project_local_point_and_get_location(q, false);
            let distance = (q - projection.point).length();
            if best.is_none_or(|b| distance < b.0) {
                let weights = location
                    .barycentric_coordinates()
                    .unwrap_or([1.0, 0.0, 0.0]);
                best = Some((distance, t, projection.point, weights));
            }
        }
        best.map(|(distance, t, point, barycentric)| {
            let [a, b, c] = self.triangle_at(t, self.end());
            Closest {
                face: f,
                triangle: t as u32,
                vertices: self.topology.triangles[t],
                barycentric,
                point: to_point(point),
                distance,
                normal: to_vector((b - a).cross(c - a).normalize()),
            }
        })
    }
}

/// Converts query points, checking that they are finite.
fn checked_queries(queries: &[Point]) -> Result<Vec<DVec3>, CollideError> {
    if let Some(point) = queries
        .iter()
        .position(|p| !p.coords.iter().all(|c| c.is_finite()))
    {
        return Err(CollideError::NonFiniteQuery { point });
    }
    Ok(queries.iter().map(to_glam).collect())
}
