//! The faces around each vertex on the surface: those within a distance of it that the surface
//! joins to it without leaving that distance, as opposed to another layer that happens to lie
//! as near.
//!
//! Cloth repulsion acts on every vertex within the thickness of a face (Bridson, Fedkiw &
//! Anderson 2002, §7.1). On a mesh whose edges are shorter than the thickness, a vertex lies
//! that near the faces a few rings around it in the rest shape, and repelling them fights the
//! elastic forces that hold the rest shape. PhysBAM, the library of Bridson et al., omits the
//! point–face pairs near each other in the collision-free start positions
//! (`TRIANGLE_REPULSIONS::Turn_Off_Repulsions_Based_On_Current_Proximity`); ARCSim (Narain,
//! Samii & O'Brien 2012) skips only adjacent pairs and remeshes to keep its edges long.
//! Distance alone would also silence two layers modelled nearer than the distance (a hem
//! turned back, two panels laid on each other), which must go on repelling:
//! [`Hierarchy::local_faces`] keeps, of the faces within the distance, only those reached from
//! the vertex's own faces through faces within the distance, each sharing a vertex with the
//! one before. On a flat or gently curved sheet that is every face within the distance (the
//! straight path from the vertex to the nearest point of such a face stays within it, and
//! the faces it crosses share vertices one after the next); another layer is reached only
//! through a crease within the distance of the vertex.
//!
//! The table is built once, at the rest positions, and [`Hierarchy::self_proximity`] skips
//! the faces it lists before projecting on them: a sorted slice per vertex and a binary search
//! per face the query reaches. On a mesh finer than the distance, though, the faces around a
//! vertex are most of what lies near it, and finding them box by box only to skip them was
//! most of the query's time (half of it on a rolled sheet of 100k triangles with edges a
//! little shorter than the distance). The faces below a node of the hierarchy are
//! contiguous in its depth-first order, so the table also keeps, per vertex, the ranges of
//! that order in which every face is skipped, and the query leaves out, untested, every node
//! whose faces lie in one range; it climbs from the highest such node above the vertex's own
//! face. The ranges refer to the order of the hierarchy that made the table, which a
//! fingerprint identifies; a hierarchy that orders its faces otherwise reads the lists alone.

use rayon::prelude::*;

use crate::error::CollideError;
use crate::hierarchy::Hierarchy;
use crate::proximity::{LocalFaces, Neighbours};
use crate::topology::group_by_owner;

impl Hierarchy {
    /// For each vertex, the faces around it on the surface (see the module docs of
    /// `local`): those not using it within `distance` of it at the positions of the last
    /// refit, reached from its own faces through faces within `distance` of it, each sharing
    /// a vertex with the one before. Call it at the rest positions, and pass the table to
    /// [`Hierarchy::self_proximity`] to skip these pairs.
    ///
    /// # Errors
    /// [`CollideError::BadDistance`] for a negative or NaN distance.
    pub fn local_faces(&self, distance: f64) -> Result<LocalFaces, CollideError> {
        let near = self.self_proximity(distance, &LocalFaces::default())?;
        let users = self.vertex_faces();
        let lists: Vec<Vec<u32>> = (0..self.vertex_count())
            .into_par_iter()
            .map(|v| self.reached(v as u32, &near, users))
            .collect();
        let ranges: Vec<Vec<[u32; 2]>> = lists
            .par_iter()
            .enumerate()
            .map(|(v, list)| self.skipped_ranges(list, users.of(v)))
            .collect();
        let starts = ranges
            .par_iter()
            .zip(&self.topology.vertex_owner)
            .map(|(ranges, &owner)| {
                if owner == u32::MAX {
                    owner
                } else {
                    self.highest_within(owner, ranges)
                }
            })
            .collect();
        let (offsets, faces) = concatenate(lists);
        let (range_offsets, ranges) = concatenate(ranges);
        Ok(LocalFaces {
            offsets,
            faces,
            range_offsets,
            ranges,
            starts,
            order: self.order_fingerprint(),
        })
    }

    /// The ranges `[first, end)` of the depth-first face order, two faces long or more, in
    /// which every face is one of `listed` or `own` (those using the vertex), which a query of
    /// the vertex skips.
    fn skipped_ranges(&self, listed: &[u32], own: &[u32]) -> Vec<[u32; 2]> {
        let mut places: Vec<u32> = listed
            .iter()
            .chain(own)
            .map(|&f| self.leaf_position(f))
            .collect();
        places.sort_unstable();
        places.dedup();
        let mut ranges: Vec<[u32; 2]> = Vec::new();
        for p in places {
            match ranges.last_mut() {
                Some(last) if last[1] == p => last[1] = p + 1,
                _ => ranges.push([p, p + 1]),
            }
        }
        ranges.retain(|&[a, b]| b - a >= 2);
        ranges
    }

    /// The faces of `near` (within the distance of `v`, sorted) that `v`'s own faces reach
    /// through faces of `near`, each sharing a vertex with the one before; `users` lists the
    /// faces using each vertex.
    fn reached(&self, v: u32, near: &Neighbours, users: &LocalFaces) -> Vec<u32> {
        let candidates = near.of(v as usize);
        let mut joined = vec![false; candidates.len()];
        let mut pending: Vec<u32> = users.of(v as usize).to_vec();
        while let Some(f) = pending.pop() {
            for &corner in self.topology.face(f) {
                for &g in users.of(corner as usize) {
                    if let Ok(i) = candidates.binary_search_by_key(&g, |c| c.face)
                        && !joined[i]
                    {
                        joined[i] = true;
                        pending.push(g);
                    }
                }
            }
        }
        candidates
            .iter()
            .zip(&joined)
            .filter_map(|(c, &joined)| joined.then_some(c.face))
            .collect()
    }

    /// The faces using each vertex, sorted (the corners grouped by their vertex, in order):
    /// a function of the topology, made once, on first use.
    pub(crate) fn vertex_faces(&self) -> &LocalFaces {
        self.vertex_faces.get_or_init(|| {
            let t = &self.topology;
            let (offsets, corners) = group_by_owner(&t.face_vertices, t.vertex_count);
            let corner_face: Vec<u32> = (0..t.face_count() as u32)
                .flat_map(|f| std::iter::repeat_n(f, t.face(f).len()))
                .collect();
            let faces = corners.iter().map(|&k| corner_face[k as usize]).collect();
            LocalFaces {
                offsets,
                faces,
                ..LocalFaces::default()
            }
        })
    }
}

/// Lists laid end to end as a CSR table: the offsets and the items.
fn concatenate<T>(lists: Vec<Vec<T>>) -> (Vec<u32>, Vec<T>) {
    let mut offsets = Vec::with_capacity(lists.len() + 1);
    offsets.push(0);
    let mut items = Vec::with_capacity(lists.iter().map(Vec::len).sum());
    for list in lists {
        items.extend(list);
        offsets.push(items.len() as u32);
    }
    (offsets, items)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Point;

    /// A mesh of one face, which no record of the hierarchy holds (the face is the root): the
    /// table is made, and a self-proximity query with it finds nothing, the face being each
    /// corner's own.
    #[test]
    fn a_single_face_makes_a_table() {
        let (p, o, c) = crate::hierarchy::grid(1, 1);
        let mut h = Hierarchy::build(&p, &o, &c).unwrap();
        let local = h.local_faces(0.5).unwrap();
        h.refit(&p, 0.0).unwrap();
        let near = h.self_proximity(0.5, &local).unwrap();
        assert!((0..4).all(|v| near.of(v).is_empty()));
    }

    #[test]
    fn a_hierarchy_in_another_order_reads_the_lists_alone_and_finds_the_same() {
        // A 24 × 24 grid of quads on the unit square, its right half then laid back over the
        // left 0.05 above it.
        let n = 24u32;
        let flat: Vec<Point> = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| Point::new(f64::from(i), f64::from(j), 0.0)))
            .map(|p| Point::from(p.coords / f64::from(n)))
            .collect();
        let mut offsets = vec![0];
        let mut corners = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                corners.extend([v, v + 1, v + n + 2, v + n + 1]);
                offsets.push(corners.len() as u32);
            }
        }
        let mut h = Hierarchy::build(&flat, &offsets, &corners).unwrap();
        let local = h.local_faces(0.15).unwrap();
        assert!(local.ranges.len() > flat.len(), "whole subtrees to skip");
        let folded: Vec<Point> = flat
            .iter()
            .map(|p| {
                if p.x > 0.5 {
                    Point::new(1.0 - p.x, p.y, 0.05)
                } else {
                    *p
                }
            })
            .collect();
        h.refit(&folded, 0.0).unwrap();
        let other_order = LocalFaces {
            order: !local.order,
            ..local.clone()
        };
        let fast = h.self_proximity(0.1, &local).unwrap();
        assert!(fast.hits().len() > flat.len(), "the layers find each other");
        assert_eq!(fast, h.self_proximity(0.1, &other_order).unwrap());
    }
}
