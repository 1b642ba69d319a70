//! Refitting: the boxes of every node recomputed bottom-up from the current positions, in O(n)
//! and in parallel level by level, leaving the tree untouched (DeRose, Kass & Truong 1998, §5:
//! the topology never changes, only the boxes).
//!
//! A swept refit boxes each face over a whole step (its corners at the start and at the end),
//! which contains the linearly moving face at every time in between, as continuous collision
//! needs (Bridson, Fedkiw & Anderson 2002, §6). The margin loosens every leaf box so that
//! features closer than it still pair up, and so does the contact tolerance of the exact
//! tests ([`CONTACT_SLACK`] times the sum of the face box's extents): two faces whose boxes so
//! loosened overlap are those the exact tests could call touching, and a traversal compares
//! the stored boxes as they are.

use super::boxes::Fit;
use super::{Hierarchy, check_distance, convert_into};
use crate::Point;
use crate::ccd::CONTACT_SLACK;
use crate::error::CollideError;

impl Hierarchy {
    /// Refits the boxes to `positions`, loosened by `margin`.
    ///
    /// # Errors
    /// [`CollideError::PositionCount`] when `positions` does not match the mesh,
    /// [`CollideError::NonFinitePosition`] for a NaN or infinite coordinate,
    /// [`CollideError::BadDistance`] for a negative or NaN margin.
    pub fn refit(&mut self, positions: &[Point], margin: f64) -> Result<(), CollideError> {
        check_distance("margin", margin)?;
        convert_into(positions, self.vertex_count(), &mut self.start)?;
        self.end.clear();
        self.refit_boxes(margin);
        Ok(())
    }

    /// Refits the boxes around the motion from `start` to `end` (each vertex moving on a
    /// straight line), loosened by `margin`; the continuous queries read both.
    ///
    /// # Errors
    /// As [`Hierarchy::refit`], for either array.
    pub fn refit_swept(
        &mut self,
        start: &[Point],
        end: &[Point],
        margin: f64,
    ) -> Result<(), CollideError> {
        check_distance("margin", margin)?;
        let count = self.vertex_count();
        convert_into(start, count, &mut self.start)?;
        convert_into(end, count, &mut self.end)?;
        self.refit_boxes(margin);
        Ok(())
    }

    /// Refits every box from the current positions (both ends of a swept refit), each face's
    /// box loosened by `margin`.
    pub(super) fn refit_boxes(&mut self, margin: f64) {
        let fit = Fit {
            face_offsets: &self.topology.face_offsets,
            face_vertices: &self.topology.face_vertices,
            start: &self.start,
            end: (!self.end.is_empty()).then_some(&self.end[..]),
            margin,
            relative: CONTACT_SLACK,
        };
        self.boxes.refit(&self.level_offsets, &fit);
    }
}

#[cfg(test)]
mod tests {
    use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
    use parry3d_f64::math::Vector as DVec3;

    use super::*;

    fn strip() -> (Vec<Point>, Vec<u32>, Vec<u32>) {
        let positions = (0..10)
            .map(|i| Point::new((i / 2) as f64, (i % 2) as f64, 0.0))
            .collect();
        let mut corners = Vec::new();
        for q in 0..4u32 {
            corners.extend([2 * q, 2 * q + 2, 2 * q + 3, 2 * q + 1]);
        }
        (positions, vec![0, 4, 8, 12, 16], corners)
    }

    /// Every node's box contains the box of the points of the faces below it, and exceeds it
    /// by no more than the outward rounding to single precision and the contact tolerance.
    fn assert_boxes_tight(h: &Hierarchy, margin: f64) {
        for node in 0..=h.root() {
            let mut faces = Vec::new();
            let mut stack = vec![node];
            while let Some(n) = stack.pop() {
                match h.node_children(n) {
                    None => faces.push(n),
                    Some(c) => stack.extend(c),
                }
            }
            let points = faces
                .iter()
                .flat_map(|&f| h.topology.face(f))
                .flat_map(|&v| [h.start[v as usize], h.end()[v as usize]]);
            let exact = Aabb::from_points(points).loosened(margin);
            let got = h.node_box(node);
            let contact = 2.0 * CONTACT_SLACK * (exact.maxs - exact.mins).element_sum();
            let slack = |x: DVec3| x.abs() * 1e-6 + DVec3::splat(1e-30 + contact);
            assert!(
                got.mins.cmple(exact.mins).all() && got.maxs.cmpge(exact.maxs).all(),
                "node {node}: {got:?} does not contain {exact:?}"
            );
            assert!(
                (exact.mins - got.mins).cmple(slack(exact.mins)).all()
                    && (got.maxs - exact.maxs).cmple(slack(exact.maxs)).all(),
                "node {node}: {got:?} is loose around {exact:?}"
            );
        }
    }

    #[test]
    fn refit_follows_the_positions() {
        let (p, o, c) = strip();
        let mut h = Hierarchy::build(&p, &o, &c).unwrap();
        let moved: Vec<Point> = p
            .iter()
            .map(|q| Point::new(q.x * 2.0, q.y, q.x * q.x))
            .collect();
        h.refit(&moved, 0.25).unwrap();
        assert_boxes_tight(&h, 0.25);
        let root = h.node_box(h.root());
        assert!((root.maxs - DVec3::new(8.25, 1.25, 16.25)).length() < 1e-5);
        // The largest coordinate is the root's far corner in z (16 plus the margin).
        assert!((h.largest_coordinate() - 16.25).abs() < 1e-5);
    }

    #[test]
    fn swept_refit_covers_start_and_end() {
        let (p, o, c) = strip();
        let mut h = Hierarchy::build(&p, &o, &c).unwrap();
        let end: Vec<Point> = p
            .iter()
            .map(|q| q + crate::Vector::new(0.0, 0.0, -3.0))
            .collect();
        h.refit_swept(&p, &end, 0.0).unwrap();
        assert_boxes_tight(&h, 0.0);
        let root = h.node_box(h.root());
        // Loosened by the contact tolerance: 2e-10 of the face's extents (1 + 1 + 3).
        assert!((root.mins.z + 3.0).abs() < 1e-6 && root.maxs.z.abs() < 1e-8);
        // An end twice as far out reaches x = 8 (and z = -6): the sweep counts, not only the
        // start (x = 4).
        h.refit_swept(&p, &end.iter().map(|q| q * 2.0).collect::<Vec<_>>(), 0.0)
            .unwrap();
        assert!((h.largest_coordinate() - 8.0).abs() < 1e-5);
        h.refit(&p, 0.0).unwrap();
        assert!((h.largest_coordinate() - 4.0).abs() < 1e-5);
    }

    #[test]
    fn refit_rejects_bad_positions() {
        let (mut p, o, c) = strip();
        let mut h = Hierarchy::build(&p, &o, &c).unwrap();
        assert_eq!(
            h.refit(&p[..3], 0.0).unwrap_err(),
            CollideError::PositionCount {
                expected: 10,
                given: 3
            }
        );
        assert!(matches!(
            h.refit(&p, -1.0),
            Err(CollideError::BadDistance { .. })
        ));
        p[7].y = f64::NAN;
        assert_eq!(
            h.refit(&p, 0.0).unwrap_err(),
            CollideError::NonFinitePosition { vertex: 7 }
        );
        assert_eq!(
            Hierarchy::build(&p, &o, &c).unwrap_err(),
            CollideError::NonFinitePosition { vertex: 7 }
        );
    }
}
