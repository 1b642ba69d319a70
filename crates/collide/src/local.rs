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
//! per face the query reaches.

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
            .map(|v| self.reached(v as u32, &near, &users))
            .collect();
        let mut offsets = Vec::with_capacity(lists.len() + 1);
        offsets.push(0);
        let mut faces = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for list in lists {
            faces.extend(list);
            offsets.push(faces.len() as u32);
        }
        Ok(LocalFaces { offsets, faces })
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

    /// The faces using each vertex, sorted (the corners grouped by their vertex, in order).
    fn vertex_faces(&self) -> LocalFaces {
        let t = &self.topology;
        let (offsets, corners) = group_by_owner(&t.face_vertices, t.vertex_count);
        let corner_face: Vec<u32> = (0..t.face_count() as u32)
            .flat_map(|f| std::iter::repeat_n(f, t.face(f).len()))
            .collect();
        let faces = corners.iter().map(|&k| corner_face[k as usize]).collect();
        LocalFaces { offsets, faces }
    }
}
