//! Which points must be measured against a moving mesh again: lower bounds of their distances,
//! kept from one measurement to the next.
//!
//! The distance from a point to a mesh is 1-Lipschitz in the point, and moves by no more than
//! the largest displacement of the mesh's vertices while its triangles stay the same (every
//! point of a triangle moves by a convex combination of its vertices' displacements). So a
//! point measured at distance d, that has since moved by a while the mesh's vertices moved by
//! at most b, is still at least d − a − b away. A caller asking which points are within a
//! distance r of the mesh ([`Hierarchy::closest_points`], [`Hierarchy::signed_distances`])
//! need only measure again those whose bound is not past r, and of those only the ones that
//! moved or that the mesh moved under: the others' last answers still hold exactly. In a
//! drape most of the cloth hangs clear of the body and moves a fraction of a millimetre a
//! step, so most points skip most queries.
//!
//! The bounds are conservative in floating point: a bound counts as past r only when it
//! exceeds it by more than rounding could take back, and "has not moved" means the same bits.

use crate::Point;
use crate::convert::to_point;
use crate::hierarchy::Hierarchy;

/// Lower bounds of the distances of a set of points from a mesh, as of the points' and the
/// mesh's positions at the last [`DistanceBounds::stale`].
#[derive(Clone, Debug, Default)]
pub struct DistanceBounds {
    points: Vec<Point>,
    mesh: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    /// Each point's distance when last measured, less the motions since; what the caller
    /// passed to [`DistanceBounds::set`].
    bound: Vec<f64>,
}

impl DistanceBounds {
    /// Forgets every bound: the next [`DistanceBounds::stale`] lists every point.
    pub fn forget(&mut self) {
        self.points.clear();
    }

    /// Appends to `out` (cleared first) the indices of `points` whose last measurement may no
    /// longer tell whether they are within `distance` of `mesh` at its last refit: every point
    /// after [`DistanceBounds::forget`], or when the number of points or the mesh's triangles
    /// changed; else the points whose bound, less how far they moved and how far the mesh's
    /// vertices moved since the last call, is not past `distance`, except those that did not
    /// move over a mesh that did not move either. The caller measures the listed points and
    /// gives each a bound with [`DistanceBounds::set`]; the others keep theirs, lowered by the
    /// motions.
    pub fn stale(&mut self, mesh: &Hierarchy, points: &[Point], distance: f64, out: &mut Vec<u32>) {
        out.clear();
        let now = mesh.end();
        let comparable = !self.points.is_empty()
            && self.points.len() == points.len()
            && self.mesh.len() == now.len()
            && self.triangles == mesh.triangles();
        if comparable {
            let mut mesh_moved = 0.0_f64;
            let mut mesh_same = true;
            for (p, q) in self.mesh.iter_mut().zip(now) {
                let q = to_point(*q);
                mesh_moved = mesh_moved.max((q - *p).norm());
                mesh_same &= same_bits(p, &q);
                *p = q;
            }
            let clear = clear_of(distance);
            for (i, ((bound, p), q)) in self
                .bound
                .iter_mut()
                .zip(points)
                .zip(&mut self.points)
                .enumerate()
            {
                let same = same_bits(p, q);
                if same && mesh_same {
                    continue;
                }
                let lowered = *bound - (p - *q).norm() - mesh_moved;
                *q = *p;
                if lowered > clear {
                    *bound = lowered;
                } else {
                    *bound = f64::NEG_INFINITY;
                    out.push(i as u32);
                }
            }
        } else {
            self.points.clear();
            self.points.extend_from_slice(points);
            self.mesh.clear();
            self.mesh.extend(now.iter().map(|&q| to_point(q)));
            self.triangles.clear();
            self.triangles.extend_from_slice(mesh.triangles());
            self.bound.clear();
            self.bound.resize(points.len(), f64::NEG_INFINITY);
            out.extend(0..points.len() as u32);
        }
    }

    /// Point `i`, as listed by the last [`DistanceBounds::stale`], is at least `bound` from the
    /// mesh (its measured distance, or the radius a query found nothing within).
    pub fn set(&mut self, i: u32, bound: f64) {
        self.bound[i as usize] = bound;
    }

    /// Whether point `i`'s bound is past `distance` by more than rounding could take back, as
    /// of the last [`DistanceBounds::stale`]: the point is then farther than `distance` from
    /// the mesh.
    #[must_use]
    pub fn past(&self, i: u32, distance: f64) -> bool {
        self.bound[i as usize] > clear_of(distance)
    }

    /// Each point's bound: what [`DistanceBounds::set`] gave it, lowered by the motions since
    /// (negative infinity for a listed point not yet given one).
    #[must_use]
    pub fn bounds(&self) -> &[f64] {
        &self.bound
    }
}

/// `distance` with the margin a bound must pass it by: more than rounding could take back.
fn clear_of(distance: f64) -> f64 {
    distance + 1e-9 * (1.0 + distance.abs())
}

/// Whether two points are the same bits: a query answered at one is answered at the other.
/// Bitwise, since a signed zero is another number to the exact tests.
#[must_use]
pub fn same_bits(p: &Point, q: &Point) -> bool {
    (0..3).all(|k| p[k].to_bits() == q[k].to_bits())
}
