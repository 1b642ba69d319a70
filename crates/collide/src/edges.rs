//! Edge–edge proximity within one mesh: every pair of edges that share no vertex and come
//! closer than a distance, with their closest points, for the edge–edge repulsions of Bridson,
//! Fedkiw & Anderson 2002 (the vertex–face pairs come from [`Hierarchy::self_proximity`]).
//!
//! The self-traversal pairs faces whose boxes come within the distance of each other (no
//! normal-cone culling: a flat region can be closer to itself than a distance without
//! touching), and a pair of faces `(f, g)` tests the edges *owned* by `f` against those owned
//! by `g` (see [`crate::topology`]), so each pair of edges is tested once. The closest points
//! between two segments are Ericson's (*Real-Time Collision Detection*, §5.1.9).

use crate::convert::{to_glam, to_vector};
use crate::error::CollideError;
use crate::hierarchy::{Hierarchy, check_distance, fresh};
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

impl Hierarchy {
    /// The unique undirected edges of the fan triangles, as `[low, high]` vertex pairs, sorted.
    #[must_use]
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.topology.edges
    }

    /// Every pair of edges sharing no vertex whose closest points are within `distance`, at
    /// the positions of the last refit (the end positions of a swept refit), sorted by edges.
    ///
    /// # Errors
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn edge_proximity(&self, distance: f64) -> Result<Vec<EdgeProximity>, CollideError> {
        fresh(|out| self.edge_proximity_into(distance, out))
    }

    /// [`Hierarchy::edge_proximity`] into `out` (cleared first), reusing its allocation.
    ///
    /// # Errors
    /// As [`Hierarchy::edge_proximity`]; `out` is then left unchanged.
    pub fn edge_proximity_into(
        &self,
        distance: f64,
        out: &mut Vec<EdgeProximity>,
    ) -> Result<(), CollideError> {
        check_distance("distance", distance)?;
        let visit = |a: u32, b: u32, out: &mut Vec<EdgeProximity>| {
            let (f, g) = (a.min(b), a.max(b));
            let (mine, theirs) = (self.topology.owned_edges(f), self.topology.owned_edges(g));
            for (i, &e) in mine.iter().enumerate() {
                let theirs = if f == g { &theirs[i + 1..] } else { theirs };
                for &o in theirs {
                    out.extend(self.edges_near(e.min(o), e.max(o), distance));
                }
            }
        };
        out.clear();
        out.append(&mut self_pairs(self, None, true, distance, None, &visit));
        out.sort_unstable_by_key(|p| p.edges);
        Ok(())
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
        let near = h.edge_proximity(2.0).unwrap();
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
}
