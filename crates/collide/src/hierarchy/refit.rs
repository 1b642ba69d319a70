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
//!
//! The rounds of impulses after a continuous query move a few vertices and ask again over
//! the same step: a swept refit from the same starts and margin as the last one recomputes
//! only the boxes that the vertices whose ends changed enter, the same bits as refitting
//! every box. On the 64² drape the queries asked again moved 74 of 4096 control points, and
//! a fifth of the refined surface's swept refits moved nothing. A caller that knows which
//! ends moved, and that nothing refit the hierarchy since its own refit (the refit count is
//! unchanged), names them ([`Hierarchy::refit_swept_ends`]) and spares the comparison of
//! every start and end, four passes over the positions on the path of every query asked
//! again.

use parry3d_f64::math::Vector as DVec3;

use super::boxes::Fit;
use super::{
    Hierarchy, LastRefit, check_count, check_distance, check_positions, convert_into, finite, store,
};
use crate::Point;
use crate::ccd::CONTACT_SLACK;
use crate::convert::{to_glam, to_point};
use crate::distance_bounds::same_bits;
use crate::error::CollideError;
use crate::topology::Topology;

/// A swept refit recomputes only what moved when at most one vertex in this many did.
const PARTIAL_SHARE: usize = 4;

impl Hierarchy {
    /// Refits the boxes to `positions`, loosened by `margin`. When the last refit was static,
    /// with the same margin and the same positions to the bit (a body that holds still
    /// between substeps), the boxes are already these and are kept.
    ///
    /// # Errors
    /// [`CollideError::PositionCount`] when `positions` does not match the mesh,
    /// [`CollideError::NonFinitePosition`] for a NaN or infinite coordinate,
    /// [`CollideError::BadDistance`] for a negative or NaN margin.
    pub fn refit(&mut self, positions: &[Point], margin: f64) -> Result<(), CollideError> {
        check_distance("margin", margin)?;
        if !(self.last_refit == LastRefit::Static(margin) && same_positions(positions, &self.start))
        {
            convert_into(positions, self.vertex_count(), &mut self.start)?;
            self.end.clear();
            self.refit_boxes(margin);
            self.last_refit = LastRefit::Static(margin);
        }
        self.refits += 1;
        Ok(())
    }

    /// Refits the boxes around the motion from `start` to `end` (each vertex moving on a
    /// straight line), loosened by `margin`; the continuous queries read both. After a swept
    /// refit from the same `start` and `margin`, only the boxes of what moved are recomputed
    /// (see the module docs), when at most a quarter of the vertices did.
    ///
    /// # Errors
    /// As [`Hierarchy::refit`], for either array; the boxes are left as they were.
    pub fn refit_swept(
        &mut self,
        start: &[Point],
        end: &[Point],
        margin: f64,
    ) -> Result<(), CollideError> {
        check_distance("margin", margin)?;
        let count = self.vertex_count();
        check_positions(start, count)?;
        check_positions(end, count)?;
        if self.last_refit == LastRefit::Swept(margin) && same_positions(start, &self.start) {
            let moved: Vec<u32> = (0..count as u32)
                .filter(|&v| !same_bits(&end[v as usize], &to_point(self.end[v as usize])))
                .collect();
            self.move_ends(end, &moved, margin);
            return Ok(());
        }
        store(start, &mut self.start);
        store(end, &mut self.end);
        self.refit_boxes(margin);
        self.last_refit = LastRefit::Swept(margin);
        self.refits += 1;
        Ok(())
    }

    /// [`Hierarchy::refit_swept`] to `end` from the last swept refit's starts and margin, for
    /// a caller that knows which vertices' ends moved since: `moved` lists them (ascending,
    /// each once), and every other vertex's end must be that refit's, which a caller that made
    /// it and finds [`Hierarchy::refit_count`] unchanged since knows. The same bits as
    /// `refit_swept` then, without comparing every vertex's start and end (a query asked again
    /// after a round of impulses moves a few of thousands).
    ///
    /// # Errors
    /// [`CollideError::NotSwept`] when the last refit was not swept; as [`Hierarchy::refit`]
    /// for `end`'s length and the moved vertices' positions; the boxes are then left as they
    /// were.
    pub fn refit_swept_ends(&mut self, end: &[Point], moved: &[u32]) -> Result<(), CollideError> {
        let LastRefit::Swept(margin) = self.last_refit else {
            return Err(CollideError::NotSwept);
        };
        check_count(end, self.vertex_count())?;
        if let Some(&vertex) = moved.iter().find(|&&v| !finite(&end[v as usize])) {
            return Err(CollideError::NonFinitePosition {
                vertex: vertex as usize,
            });
        }
        self.move_ends(end, moved, margin);
        Ok(())
    }

    /// The ends of the vertices `moved` lists taken from `end`, and the boxes they enter
    /// refit, or every box when more than a quarter of the vertices moved.
    fn move_ends(&mut self, end: &[Point], moved: &[u32], margin: f64) {
        self.refits += 1;
        if moved.len() * PARTIAL_SHARE > self.vertex_count() {
            store(end, &mut self.end);
            self.refit_boxes(margin);
            return;
        }
        for &v in moved {
            self.end[v as usize] = to_glam(&end[v as usize]);
        }
        let around = self.vertex_faces();
        let faces: Vec<u32> = moved
            .iter()
            .flat_map(|&v| around.of(v as usize))
            .copied()
            .collect();
        let fit = fit(&self.topology, &self.start, &self.end, margin);
        self.boxes.refit_moved(&fit, moved, &faces);
    }

    /// Refits every box from the current positions (both ends of a swept refit), each face's
    /// box loosened by `margin`.
    pub(super) fn refit_boxes(&mut self, margin: f64) {
        let fit = fit(&self.topology, &self.start, &self.end, margin);
        self.boxes.refit(&self.level_offsets, &fit);
    }
}

/// What a refit of `topology`'s faces boxes: the motion from `start` to `end` (a static refit
/// at `start` when `end` is empty), each vertex loosened by `margin`.
fn fit<'a>(topology: &'a Topology, start: &'a [DVec3], end: &'a [DVec3], margin: f64) -> Fit<'a> {
    Fit {
        face_offsets: &topology.face_offsets,
        face_vertices: &topology.face_vertices,
        start,
        end: (!end.is_empty()).then_some(end),
        margin,
        relative: CONTACT_SLACK,
    }
}

/// Whether `positions` are those `stored`, every coordinate the same bits.
fn same_positions(positions: &[Point], stored: &[DVec3]) -> bool {
    positions.len() == stored.len()
        && positions
            .iter()
            .zip(stored)
            .all(|(p, &q)| same_bits(p, &to_point(q)))
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

    /// The boxes of every node of `h`, as bits.
    fn box_bits(h: &Hierarchy) -> Vec<[u64; 6]> {
        (0..=h.root())
            .map(|n| {
                let b = h.node_box(n);
                let (lo, hi) = (b.mins.to_array(), b.maxs.to_array());
                [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(f64::to_bits)
            })
            .collect()
    }

    /// Node by node, as bits, the boxes of `h` are those of a new hierarchy of the 12 × 12
    /// grid refit swept from `start` to `end` with `margin`.
    fn assert_boxes_of_a_whole_refit(h: &Hierarchy, start: &[Point], end: &[Point], margin: f64) {
        let (_, offsets, corners) = crate::hierarchy::grid(12, 1);
        let mut fresh = Hierarchy::build(start, &offsets, &corners).unwrap();
        fresh.refit_swept(start, end, margin).unwrap();
        let (got, want) = (box_bits(h), box_bits(&fresh));
        let differs = (0..want.len()).find(|&n| got[n] != want[n]);
        assert_eq!(differs, None, "a node's box differs from a whole refit's");
    }

    /// A static refit at the positions and margin of the last one keeps its boxes, and a
    /// moved vertex, another margin or a swept refit in between gives the boxes of a whole
    /// refit.
    #[test]
    fn a_static_refit_at_the_last_positions_keeps_the_boxes_a_change_refits() {
        let (start, offsets, corners) = crate::hierarchy::grid(12, 1);
        let fresh = |positions: &[Point], margin: f64| {
            let mut h = Hierarchy::build(&start, &offsets, &corners).unwrap();
            h.refit_swept(&start, positions, margin).unwrap();
            h.refit(positions, margin).unwrap();
            box_bits(&h)
        };
        let mut h = Hierarchy::build(&start, &offsets, &corners).unwrap();
        let posed = lifted(&start, &[5, 60, 130], 0.25);
        h.refit(&posed, 0.1).unwrap();
        let count = h.refit_count();
        h.refit(&posed, 0.1).unwrap();
        assert_eq!(box_bits(&h), fresh(&posed, 0.1));
        assert_eq!(h.refit_count(), count + 1, "a kept refit still counts");
        let mut nudged = posed.clone();
        nudged[60].x += 0.5;
        h.refit(&nudged, 0.1).unwrap();
        assert_eq!(box_bits(&h), fresh(&nudged, 0.1));
        h.refit(&nudged, 0.2).unwrap();
        assert_eq!(box_bits(&h), fresh(&nudged, 0.2));
        // Swept from the same positions to others, then static at the first again.
        h.refit_swept(&nudged, &posed, 0.2).unwrap();
        h.refit(&nudged, 0.2).unwrap();
        assert!(!h.is_swept());
        assert_eq!(box_bits(&h), fresh(&nudged, 0.2));
    }

    /// `end` with the vertices `moved` lists lifted by `dz` and moved sideways a third of it.
    fn lifted(end: &[Point], moved: &[u32], dz: f64) -> Vec<Point> {
        let mut end = end.to_vec();
        for &v in moved {
            end[v as usize].z += dz;
            end[v as usize].x -= dz / 3.0;
        }
        end
    }

    /// A swept refit after one from the same starts, with a few ends moved, leaves every box
    /// as a refit of a new hierarchy does; so does one after a static refit in between, or
    /// with another margin, and bad positions are refused on either path.
    #[test]
    fn a_swept_refit_after_a_few_ends_moved_gives_the_boxes_of_a_whole_refit() {
        let (start, offsets, corners) = crate::hierarchy::grid(12, 1);
        let whole = |h: &Hierarchy, end: &[Point], margin: f64| {
            assert_boxes_of_a_whole_refit(h, &start, end, margin);
        };
        let mut h = Hierarchy::build(&start, &offsets, &corners).unwrap();
        let first = lifted(&start, &[0, 7, 80, 168], 0.5);
        h.refit_swept(&start, &first, 0.1).unwrap();
        whole(&h, &first, 0.1);
        // Vertex 80 again, and two more (169 vertices: at most a quarter may move).
        let again = lifted(&first, &[80, 3, 100], -2.0);
        h.refit_swept(&start, &again, 0.1).unwrap();
        whole(&h, &again, 0.1);
        // Nothing moved.
        h.refit_swept(&start, &again, 0.1).unwrap();
        whole(&h, &again, 0.1);
        // Another margin, then a static refit in between.
        let third = lifted(&again, &[5], 1.0);
        h.refit_swept(&start, &third, 0.2).unwrap();
        whole(&h, &third, 0.2);
        h.refit(&start, 0.0).unwrap();
        let fourth = lifted(&third, &[6], 1.0);
        h.refit_swept(&start, &fourth, 0.2).unwrap();
        whole(&h, &fourth, 0.2);
        // A bad end is refused where only a few ends changed, and the boxes stay.
        let mut bad = fourth.clone();
        bad[9].y = f64::INFINITY;
        assert_eq!(
            h.refit_swept(&start, &bad, 0.2).unwrap_err(),
            CollideError::NonFinitePosition { vertex: 9 }
        );
        let fifth = lifted(&fourth, &[9], 1.0);
        h.refit_swept(&start, &fifth, 0.2).unwrap();
        whole(&h, &fifth, 0.2);
    }

    /// Ends moved by a caller that lists them give the boxes of a whole refit, a few or more
    /// than a quarter of the vertices at once; each refit counts; a static last refit and a
    /// bad moved end are refused, the boxes left as they were.
    #[test]
    fn ends_moved_by_list_give_the_boxes_of_a_whole_refit() {
        let (start, offsets, corners) = crate::hierarchy::grid(12, 1);
        let whole =
            |h: &Hierarchy, end: &[Point]| assert_boxes_of_a_whole_refit(h, &start, end, 0.1);
        let mut h = Hierarchy::build(&start, &offsets, &corners).unwrap();
        assert_eq!(
            h.refit_swept_ends(&start, &[]).unwrap_err(),
            CollideError::NotSwept
        );
        h.refit_swept(&start, &start, 0.1).unwrap();
        let count = h.refit_count();
        let few = [3, 40, 41, 168];
        let first = lifted(&start, &few, 0.7);
        h.refit_swept_ends(&first, &few).unwrap();
        whole(&h, &first);
        assert_eq!(h.refit_count(), count + 1);
        // More than a quarter of the 169 vertices.
        let many: Vec<u32> = (0..169).filter(|v| v % 3 != 1).collect();
        let second = lifted(&first, &many, -0.4);
        h.refit_swept_ends(&second, &many).unwrap();
        whole(&h, &second);
        // A bad moved end, then a good one.
        let mut bad = second.clone();
        bad[41].x = f64::NAN;
        assert_eq!(
            h.refit_swept_ends(&bad, &[41]).unwrap_err(),
            CollideError::NonFinitePosition { vertex: 41 }
        );
        whole(&h, &second);
        assert_eq!(
            h.refit_swept_ends(&second[1..], &[]).unwrap_err(),
            CollideError::PositionCount {
                expected: 169,
                given: 168
            }
        );
        let third = lifted(&second, &[41], 0.2);
        h.refit_swept_ends(&third, &[41]).unwrap();
        whole(&h, &third);
        h.refit(&start, 0.0).unwrap();
        assert_eq!(
            h.refit_swept_ends(&third, &[41]).unwrap_err(),
            CollideError::NotSwept
        );
    }
}
