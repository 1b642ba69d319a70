//! Refitting: the boxes of every node recomputed bottom-up from the current positions, in O(n)
//! and in parallel level by level, leaving the tree untouched (DeRose, Kass & Truong 1998, §5:
//! the topology never changes, only the boxes).
//!
//! A swept refit boxes each face over a whole step (its corners at the start and at the end),
//! which contains the linearly moving face at every time in between, as continuous collision
//! needs (Bridson, Fedkiw & Anderson 2002, §6). The margin loosens every leaf box so that
//! features closer than it still pair up.

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector as DVec3;

use super::{Hierarchy, check_distance, convert_into};
use crate::Point;
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

    pub(super) fn refit_boxes(&mut self, margin: f64) {
        let mut boxes = std::mem::take(&mut self.boxes);
        self.fold_up_into(&mut boxes, |f| self.face_box(f, margin), |a, b| a.merged(b));
        self.boxes = boxes;
    }

    /// The box of face `f` over the start and end positions, loosened by `margin`.
    fn face_box(&self, f: u32, margin: f64) -> Aabb {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for positions in [&self.start[..], self.end()] {
            for &v in self.topology.face(f) {
                let p = positions[v as usize];
                lo = lo.min(p);
                hi = hi.max(p);
            }
            if !self.is_swept() {
                break;
            }
        }
        Aabb::new(lo - DVec3::splat(margin), hi + DVec3::splat(margin))
    }
}

#[cfg(test)]
mod tests {
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

    /// Every node's box equals the box of the points of the faces below it.
    fn assert_boxes_tight(h: &Hierarchy, margin: f64) {
        for node in 0..h.boxes.len() as u32 {
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
            let expected = Aabb::from_points(points).loosened(margin);
            assert_eq!(h.boxes[node as usize], expected, "node {node}");
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
        let root = h.boxes[h.root() as usize];
        assert_eq!(root.maxs, DVec3::new(8.25, 1.25, 16.25));
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
        assert_eq!(h.boxes[h.root() as usize].mins.z, -3.0);
        assert_eq!(h.boxes[h.root() as usize].maxs.z, 0.0);
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
