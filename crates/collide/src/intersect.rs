//! Self-intersecting face pairs: faces that share no vertex and whose fan triangles cross, as
//! `tailor check` reports them.
//!
//! The candidate pairs come from the self-traversal with normal-cone culling
//! ([`crate::cones`]): a smooth region is cleared without pairing its faces. Each candidate
//! is then decided exactly by [`crate::triangles_intersect`] on every pair of fan triangles.

use crate::cones::NormalCones;
use crate::hierarchy::Hierarchy;
use crate::traverse::self_pairs;
use crate::triangle::triangles_meet;

impl Hierarchy {
    /// Every pair of faces `[f, g]` (`f < g`, sorted) that share no vertex and whose triangles
    /// intersect or touch, at the positions of the last refit (the end positions of a swept
    /// refit). Zero-area triangles are skipped.
    #[must_use]
    pub fn self_intersections(&self) -> Vec<[u32; 2]> {
        let cones = NormalCones::new(self);
        let visit = |a: u32, b: u32, out: &mut Vec<[u32; 2]>| {
            let (f, g) = (a.min(b), a.max(b));
            if self.topology.faces_share_vertex(f, g) {
                return;
            }
            let crosses = self.topology.face_triangles(f).any(|s| {
                let p = self.triangle_at(s, self.end());
                self.topology
                    .face_triangles(g)
                    .any(|t| triangles_meet(p, self.triangle_at(t, self.end())))
            });
            if crosses {
                out.push([f, g]);
            }
        };
        let mut pairs = self_pairs(self, Some(&cones), false, 0.0, None, &visit);
        pairs.sort_unstable();
        pairs
    }
}
