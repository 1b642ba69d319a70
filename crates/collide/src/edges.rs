//! Edge–edge proximity within one mesh: every pair of edges that share no vertex and come
//! closer than a distance, with their closest points, for the edge–edge repulsions of Bridson,
//! Fedkiw & Anderson 2002 (the vertex–face pairs come from [`Hierarchy::self_proximity`]).
//!
//! The self-traversal pairs faces whose boxes come within the distance of each other (no
//! normal-cone culling: a flat region can be closer to itself than a distance without
//! touching), and a pair of faces `(f, g)` tests the edges *owned* by `f` against those owned
//! by `g` (see [`crate::topology`]), so each pair of edges is tested once. Neighbouring faces
//! are most of those pairs, and an edge with an end on the other face is skipped there by the
//! rule below whatever the positions, so such edges are left out before any geometry (on the
//! 64² drape, a sixth of the query). The closest points between two segments are Ericson's
//! (*Real-Time Collision Detection*, §5.1.9).
//!
//! As the vertex–face pairs do ([`crate::local`]), a query may leave out the pairs the rest
//! shape holds that near: given the table of faces around each vertex, an edge is skipped
//! against another lying on a face around one of its ends (a face listed for that end, or one
//! using it). On a mesh finer than the distance, an edge within it of another in the rest shape
//! lies within the distance plus an edge length of each end, on the faces listed for that end
//! when the table was made a little farther out than the query (as the cloth's is, at 1.5
//! thicknesses); on a coarse mesh, only the edges of the faces around an end are skipped, which
//! are the pairs a fold within one or two faces brings together.

use crate::convert::{to_glam, to_vector};
use crate::error::CollideError;
use crate::hierarchy::{Hierarchy, check_distance, fresh};
use crate::proximity::LocalFaces;
use crate::traverse::self_pairs;
use crate::triangle::segment_closest;
use crate::{Point, Vector};

/// Two edges of a mesh closer than a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeProximity {
    /// The two edges, as indices into [`Hierarchy::edges`], the lower first.
    pub edges: [u32; 2],
    /// Where the closest points lie along each edge, from its low to its high vertex, in
    /// `[0, 1]`.
    pub parameters: [f64; 2],
    /// The distance between the closest points.
    pub distance: f64,
    /// The unit direction from the closest point on the first edge to the one on the second;
    /// when they coincide, the unit normal of the two edges' plane (zero for parallel edges).
    pub direction: Vector,
}

/// The closest points between segments `first` and `second`: their parameters along each
/// (0 at the first end, 1 at the second) and their distance. Parallel and zero-length segments
/// are handled; for parallel segments the parameters are one of the closest pairs.
#[must_use]
pub fn segments_closest_points(first: [Point; 2], second: [Point; 2]) -> ([f64; 2], f64) {
    let [p0, p1] = [to_glam(&first[0]), to_glam(&first[1])];
    let [q0, q1] = [to_glam(&second[0]), to_glam(&second[1])];
    let (s, u, distance) = segment_closest(p0, p1, q0, q1);
    ([s, u], distance)
}

/// Whether `edge` has an end among the corners of `face`; a quad, the common case, compares
/// its four corners with both ends without a branch.
fn touches(face: &[u32], [p, q]: [u32; 2]) -> bool {
    match <&[u32; 4]>::try_from(face) {
        Ok(quad) => quad.iter().fold(false, |hit, &v| hit | (v == p) | (v == q)),
        Err(_) => face.contains(&p) || face.contains(&q),
    }
}

impl Hierarchy {
    /// The unique undirected edges of the fan triangles, as `[low, high]` vertex pairs, sorted.
    #[must_use]
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.topology.edges
    }

    /// Every pair of edges sharing no vertex whose closest points are within `distance`, at
    /// the positions of the last refit (the end positions of a swept refit), sorted by edges,
    /// except the pairs where one edge lies on a face around an end of the other: a face
    /// `skip` lists for that end ([`Hierarchy::local_faces`]), or one using it (see the module
    /// docs). With the empty table only the faces using an end count.
    ///
    /// # Errors
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn edge_proximity(
        &self,
        distance: f64,
        skip: &LocalFaces,
    ) -> Result<Vec<EdgeProximity>, CollideError> {
        fresh(|out| self.edge_proximity_into(distance, skip, out))
    }

    /// [`Hierarchy::edge_proximity`] into `out` (cleared first), reusing its allocation.
    ///
    /// # Errors
    /// As [`Hierarchy::edge_proximity`]; `out` is then left unchanged.
    pub fn edge_proximity_into(
        &self,
        distance: f64,
        skip: &LocalFaces,
        out: &mut Vec<EdgeProximity>,
    ) -> Result<(), CollideError> {
        check_distance("distance", distance)?;
        let users = self.vertex_faces();
        let edges = &self.topology.edges;
        // An edge with an end on the other face lies on a face around that end, as the other
        // edge lies on the other face: such pairs, and so every pair within one face, are
        // skipped before their geometry is looked at.
        let off = |e: u32, face: &[u32]| !touches(face, edges[e as usize]);
        let visit = |a: u32, b: u32, out: &mut Vec<EdgeProximity>| {
            if a == b {
                return;
            }
            let (f, g) = (a.min(b), a.max(b));
            let (face_f, face_g) = (self.topology.face(f), self.topology.face(g));
            let (mine, theirs) = (self.topology.owned_edges(f), self.topology.owned_edges(g));
            // Which of `theirs` have no end on `f`, a bit each, found once for the pair when
            // one of `mine` is to be tested (past the 64th, asked edge by edge).
            let mut theirs_off = None;
            for &e in mine.iter().filter(|&&e| off(e, face_g)) {
                let bits: u64 = *theirs_off.get_or_insert_with(|| {
                    theirs
                        .iter()
                        .take(64)
                        .enumerate()
                        .fold(0, |bits, (k, &o)| bits | u64::from(off(o, face_f)) << k)
                });
                let kept = |k: usize, o: u32| {
                    if k < 64 {
                        bits >> k & 1 == 1
                    } else {
                        off(o, face_f)
                    }
                };
                let others = theirs.iter().enumerate().filter(|&(k, &o)| kept(k, o));
                for (_, &o) in others {
                    let (e, o) = (e.min(o), e.max(o));
                    if let Some(near) = self.edges_near(e, o, distance)
                        && !self.edges_around(e, o, skip, users)
                    {
                        out.push(near);
                    }
                }
            }
        };
        out.clear();
        out.append(&mut self_pairs(self, None, true, distance, None, &visit));
        out.sort_unstable_by_key(|p| p.edges);
        Ok(())
    }

    /// Whether either of edges `e` and `o` lies on a face around an end of the other: one
    /// `skip` lists for that end, or one of `users`, the faces using each vertex.
    fn edges_around(&self, e: u32, o: u32, skip: &LocalFaces, users: &LocalFaces) -> bool {
        let edges = &self.topology.edges;
        let lies_on = |edge: [u32; 2], f: u32| {
            let face = self.topology.face(f);
            face.contains(&edge[0]) && face.contains(&edge[1])
        };
        let around = |edge: [u32; 2], other: [u32; 2]| {
            edge.iter().any(|&v| {
                let v = v as usize;
                users
                    .of(v)
                    .iter()
                    .chain(skip.of(v))
                    .any(|&f| lies_on(other, f))
            })
        };
        let (a, b) = (edges[e as usize], edges[o as usize]);
        around(a, b) || around(b, a)
    }

    /// Edges `e` and `o` (`e < o`) when they share no vertex and come within `distance`.
    fn edges_near(&self, e: u32, o: u32, distance: f64) -> Option<EdgeProximity> {
        let ([a0, a1], [b0, b1]) = (
            self.topology.edges[e as usize],
            self.topology.edges[o as usize],
        );
        if a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1 {
            return None;
        }
        let x = self.end();
        let [p0, p1, q0, q1] = [
            x[a0 as usize],
            x[a1 as usize],
            x[b0 as usize],
            x[b1 as usize],
        ];
        // Boxes farther apart along an axis than the distance hold segments farther apart too
        // (with a relative 10⁻¹² to spare for the rounding of the gap): most pairs a padded
        // face pair brings are rejected so, before the exact closest points.
        let gap = (q0.min(q1) - p0.max(p1)).max(p0.min(p1) - q0.max(q1));
        if gap.max_element() > distance * (1.0 + 1e-12) {
            return None;
        }
        let (s, u, d) = segment_closest(p0, p1, q0, q1);
        if d > distance {
            return None;
        }
        let gap = (q0 + (q1 - q0) * u) - (p0 + (p1 - p0) * s);
        let direction = if d > 0.0 {
            gap / d
        } else {
            (p1 - p0).cross(q1 - q0).normalize_or_zero()
        };
        Some(EdgeProximity {
            edges: [e, o],
            parameters: [s, u],
            distance: d,
            direction: to_vector(direction),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_and_touching_edges() {
        let p = |x: f64, y: f64, z: f64| Point::new(x, y, z);
        // Skew edges one apart, crossing above (0.5, 0).
        let (t, d) = segments_closest_points(
            [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0)],
            [p(0.5, -1.0, 1.0), p(0.5, 1.0, 1.0)],
        );
        assert_eq!((t, d), ([0.5, 0.5], 1.0));
        // Two separate triangles two apart along x: the edge pairs within 2.
        let positions = [
            p(0.0, 0.0, 0.0),
            p(1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(3.0, 0.0, 0.0),
            p(4.0, 0.0, 0.0),
            p(3.0, 1.0, 0.0),
        ];
        let h = Hierarchy::build(&positions, &[0, 3, 6], &[0, 1, 2, 3, 4, 5]).unwrap();
        let near = h.edge_proximity(2.0, &LocalFaces::default()).unwrap();
        let pairs: Vec<[[u32; 2]; 2]> = near
            .iter()
            .map(|n| n.edges.map(|e| h.edges()[e as usize]))
            .collect();
        // Vertex 1 at x = 1 is two from vertex 3 at x = 3; the other edges are farther.
        let expected = [
            [[0, 1], [3, 4]],
            [[0, 1], [3, 5]],
            [[1, 2], [3, 4]],
            [[1, 2], [3, 5]],
        ];
        assert_eq!(pairs, expected);
        let first = near[0];
        assert_eq!((first.distance, first.parameters), (2.0, [1.0, 0.0]));
        assert_eq!(first.direction, Vector::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn an_edge_is_not_near_the_edges_of_the_faces_at_its_ends() {
        // Two unit quads in a row along x. The opposite sides of one quad lie on a face using
        // each other's ends, as does its diagonal; the outer sides of the row, two apart, do
        // not.
        let p = |x: f64, y: f64| Point::new(x, y, 0.0);
        let positions = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, 0.0),
            p(0.0, 1.0),
            p(1.0, 1.0),
            p(2.0, 1.0),
        ];
        let h = Hierarchy::build(&positions, &[0, 4, 8], &[0, 1, 4, 3, 1, 2, 5, 4]).unwrap();
        let near = h.edge_proximity(2.0, &LocalFaces::default()).unwrap();
        let pairs: Vec<[[u32; 2]; 2]> = near
            .iter()
            .map(|n| n.edges.map(|e| h.edges()[e as usize]))
            .collect();
        assert_eq!(pairs, [[[0, 3], [2, 5]]]);
    }
}
