//! Normal-cone culling for self-collision (Volino & Magnenat-Thalmann 1994; Provot 1997).
//!
//! A superface cannot touch itself when (1) some direction `a` sees every one of its triangles
//! from the front, i.e. its normals fit in a cone narrower than a half-space, and (2) its
//! boundary, projected along `a`, does not fold back. Then the projection along `a` maps every
//! triangle with positive orientation, and the number of triangles over a point of the plane is
//! the winding number of the projected boundary around it (a degree argument); a boundary that
//! winds once around a centre with every edge turning forward is a simple star-shaped curve, so
//! that number is 0 or 1 and no two triangles overlap. Two features touching would make two
//! triangles overlap near the contact, so the whole subtree is skipped.
//!
//! The direction tried is the superface's area-weighted mean normal (the sum of its triangles'
//! cross products), the axis of its normal cone; condition (1) is then a sign test per
//! triangle, with no square root. That sum needs no pass over the triangles: expanding
//! `(b - a) × (c - a) = a × b + b × c + c × a`, the terms of edges shared by two faces cancel,
//! so it is `Σ p × q` over the directed boundary edges `p → q` (Stokes' theorem for the
//! vector area), taken relative to a boundary vertex to keep its digits. Any direction would be
//! sound, since every triangle is then checked against it. The test runs lazily, top-down, on
//! the nodes the traversal visits: a smooth sheet is cleared by one linear pass at the root,
//! and a node that fails usually fails on its first few triangles, or before any of them on
//! its contour, which is checked first because it is shorter.
//!
//! Over a step every vertex moves linearly, so a triangle normal
//! `n(t) = (b(t) - a(t)) × (c(t) - a(t))` is quadratic in `t`; in the Bernstein basis its three
//! coefficients are `n(0)`, `((b0-a0)×(c1-a1) + (b1-a1)×(c0-a0)) / 2` and `n(1)`, and `n(t)` is
//! their combination with non-negative weights, so a direction seeing the three from the front
//! sees every `n(t)` (Tang, Curtis, Yoon & Manocha 2009 use the same trick). The contour test
//! likewise asks the three Bernstein coefficients of each edge's turn around the moving centre
//! to be positive, and the total turn, which can only change by whole turns and cannot change
//! while every edge turns forward, is checked at the start. A static refit has one coefficient.
//!
//! The boundary chains are topological (built once, see the hierarchy's build). Being star-shaped
//! around the centroid is a sufficient condition only, so the test clears what the coarsening
//! makes round: an S of four quads fails it even flat, a 2 × 2 square passes while its normals
//! do, and the build matches superfaces by roundness for that reason.

use std::f64::consts::{PI, TAU};

use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use crate::hierarchy::Hierarchy;

/// A normal counts as seen from the front when its angle to the axis is below 90° minus about
/// this many radians: culling must never be optimistic.
const MARGIN: f64 = 1e-6;

/// The Bernstein coefficients of the triangles' normals over the motion of the last refit,
/// computed from the positions where a test needs them (a cross product costs less than
/// storing and reloading it, and a smooth sheet needs each one once).
pub(crate) struct NormalCones {
    swept: bool,
}

impl NormalCones {
    /// The normal cones of `h` at its last refit.
    pub(crate) fn new(h: &Hierarchy) -> Self {
        Self {
            swept: h.is_swept(),
        }
    }

    /// Whether `each` holds for the normal coefficients of triangle `t`; stops at the first
    /// that fails.
    #[inline]
    fn all_of_triangle(&self, h: &Hierarchy, t: usize, each: impl Fn(DVec3) -> bool) -> bool {
        let [a0, b0, c0] = h.triangle_at(t, &h.start);
        let (e0, g0) = (b0 - a0, c0 - a0);
        if !self.swept {
            return each(e0.cross(g0));
        }
        let [a1, b1, c1] = h.triangle_at(t, h.end());
        let (e1, g1) = (b1 - a1, c1 - a1);
        each(e0.cross(g0)) && each((e0.cross(g1) + e1.cross(g0)) / 2.0) && each(e1.cross(g1))
    }

    /// The sum of the normal coefficients of the triangles below `node`, from its boundary
    /// (see the module docs): `Σ p × q` at the start and at the end, and the Bernstein middle
    /// term `Σ (p0 × q1 + p1 × q0) / 2` of a swept refit, relative to the first boundary vertex.
    fn boundary_axis(&self, h: &Hierarchy, node: u32) -> DVec3 {
        let boundary = h.node_boundary(node);
        let Some(&[origin, _]) = boundary.first() else {
            return DVec3::ZERO;
        };
        let rel = |x: &[DVec3], v: u32| x[v as usize] - x[origin as usize];
        let (start, end) = (&h.start[..], h.end());
        boundary.iter().fold(DVec3::ZERO, |sum, &[p, q]| {
            let (p0, q0) = (rel(start, p), rel(start, q));
            if !self.swept {
                return sum + p0.cross(q0);
            }
            let (p1, q1) = (rel(end, p), rel(end, q));
            sum + p0.cross(q0) + (p0.cross(q1) + p1.cross(q0)) / 2.0 + p1.cross(q1)
        })
    }

    /// Whether no two features below `node` can touch during the step (see the module docs).
    ///
    /// A large node's faces are checked in parallel, in fixed chunks.
    pub(crate) fn cannot_self_collide(&self, h: &Hierarchy, node: u32) -> bool {
        let faces = h.leaves_below(node);
        let axis = self.boundary_axis(h, node);
        let (axis_len2, cos2) = (axis.length_squared(), (MARGIN).sin().powi(2));
        let front = |n: &DVec3| {
            let d = n.dot(axis);
            d > 0.0 && d * d > cos2 * n.length_squared() * axis_len2
        };
        let seen = |t: usize| self.all_of_triangle(h, t, |n| front(&n));
        // The root holds every triangle: check them in memory order, a chunk per task, each
        // chunk a plain loop.
        let all_seen = || {
            if faces.len() == h.face_count() {
                let triangles = h.triangle_count();
                (0..triangles.div_ceil(CHUNK))
                    .into_par_iter()
                    .all(|c| (c * CHUNK..triangles.min((c + 1) * CHUNK)).all(seen))
            } else {
                let chunk_seen = |chunk: &[u32]| {
                    chunk
                        .iter()
                        .all(|&f| h.topology.face_triangles(f).all(seen))
                };
                if faces.len() <= CHUNK {
                    chunk_seen(faces)
                } else {
                    faces.par_chunks(CHUNK).all(chunk_seen)
                }
            }
        };
        // The contour costs a pass over the boundary, the normals one over the faces: the
        // cheaper test goes first.
        axis_len2 > 0.0 && contour_does_not_fold(h, node, axis.normalize()) && all_seen()
    }
}

/// Faces a thread sums or checks in a row.
const CHUNK: usize = 8192;

/// Whether the boundary of `node`, projected along `axis`, winds exactly once around its moving
/// centroid with every edge turning forward at every time of the step.
fn contour_does_not_fold(h: &Hierarchy, node: u32, axis: DVec3) -> bool {
    let boundary = h.node_boundary(node);
    if boundary.is_empty() {
        return false;
    }
    let (u, w) = axis.any_orthonormal_pair();
    let flat = |p: DVec3| [p.dot(u), p.dot(w)];
    let centre = |positions: &[DVec3]| {
        let sum = boundary
            .iter()
            .fold(DVec3::ZERO, |s, e| s + positions[e[0] as usize]);
        flat(sum / boundary.len() as f64)
    };
    let (c0, c1) = (centre(&h.start), centre(h.end()));
    let rel = |p: DVec3, c: [f64; 2]| {
        let q = flat(p);
        [q[0] - c[0], q[1] - c[1]]
    };
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let mut total = 0.0;
    for &[p, q] in boundary {
        let (p0, q0) = (rel(h.start[p as usize], c0), rel(h.start[q as usize], c0));
        let (p1, q1) = (rel(h.end()[p as usize], c1), rel(h.end()[q as usize], c1));
        let turns = [
            cross(p0, q0),
            (cross(p0, q1) + cross(p1, q0)) / 2.0,
            cross(p1, q1),
        ];
        if turns.iter().any(|&k| k <= 0.0) {
            return false;
        }
        total += turns[0].atan2(p0[0] * q0[0] + p0[1] * q0[1]);
    }
    (total - TAU).abs() < PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Point;

    /// An `n × n` grid of quads over the unit square lifted by `height(x, y)`.
    fn sheet(n: u32, height: impl Fn(f64, f64) -> f64) -> Hierarchy {
        let s = 1.0 / n as f64;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 * s, j as f64 * s);
                positions.push(Point::new(x, y, height(x, y)));
            }
        }
        let (mut offsets, mut corners) = (vec![0], Vec::new());
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                corners.extend([v, v + 1, v + n + 2, v + n + 1]);
                offsets.push(corners.len() as u32);
            }
        }
        Hierarchy::build(&positions, &offsets, &corners).unwrap()
    }

    #[test]
    fn gently_curved_sheet_is_culled_at_the_root() {
        let h = sheet(8, |x, y| 0.2 * (x * 3.0).sin() * y);
        let cones = NormalCones::new(&h);
        assert!(cones.cannot_self_collide(&h, h.root()));
    }

    #[test]
    fn steep_but_unfolded_sheet_is_culled_and_a_folded_one_is_not() {
        // Bent up at x = 0.5 with slope 4 (76°): still seen from one side.
        let bent = sheet(8, |x, _| if x < 0.5 { 0.0 } else { (x - 0.5) * 4.0 });
        assert!(NormalCones::new(&bent).cannot_self_collide(&bent, bent.root()));
        // Folded back over itself like a taco, round a half-cylinder hinge of radius 0.1: the
        // normals sweep half a turn.
        let mut folded = sheet(20, |_, _| 0.0);
        let hinge = |x: f64, y: f64| {
            if x <= 0.4 {
                Point::new(x, y, 0.0)
            } else if x <= 0.6 {
                let (s, c) = ((x - 0.4) / 0.2 * PI).sin_cos();
                Point::new(0.4 + 0.1 * s, y, 0.1 - 0.1 * c)
            } else {
                Point::new(1.0 - x, y, 0.2)
            }
        };
        let positions: Vec<Point> = folded.start.iter().map(|p| hinge(p.x, p.y)).collect();
        folded.refit(&positions, 0.0).unwrap();
        assert!(!NormalCones::new(&folded).cannot_self_collide(&folded, folded.root()));
    }

    #[test]
    fn spiral_whose_projection_overlaps_is_not() {
        // A flat strip that winds 1.5 turns around the origin like a helix ramp: every normal
        // points nearly up, yet the strip passes over itself.
        let turns = 60;
        let mut positions = Vec::new();
        for i in 0..=turns {
            let a = i as f64 / turns as f64 * 3.0 * PI;
            let (s, c) = a.sin_cos();
            let z = 0.01 * a;
            positions.push(Point::new(c, s, z));
            positions.push(Point::new(2.0 * c, 2.0 * s, z));
        }
        let (mut offsets, mut corners) = (vec![0], Vec::new());
        for i in 0..turns {
            corners.extend([2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2]);
            offsets.push(corners.len() as u32);
        }
        let h = Hierarchy::build(&positions, &offsets, &corners).unwrap();
        let cones = NormalCones::new(&h);
        assert!(!cones.cannot_self_collide(&h, h.root()));
    }

    #[test]
    fn a_flip_during_the_step_is_not_culled() {
        let mut h = sheet(4, |_, _| 0.0);
        let start: Vec<Point> = h
            .start
            .iter()
            .map(|&p| crate::convert::to_point(p))
            .collect();
        // Turn the sheet upside down over the step (mirror x): normals swing through the plane.
        let end: Vec<Point> = start
            .iter()
            .map(|p| Point::new(1.0 - p.x, p.y, p.z))
            .collect();
        h.refit_swept(&start, &end, 0.0).unwrap();
        assert!(!NormalCones::new(&h).cannot_self_collide(&h, h.root()));
        // The same sheet merely translated is still culled.
        let shifted: Vec<Point> = start
            .iter()
            .map(|p| Point::new(p.x + 0.3, p.y, p.z + 1.0))
            .collect();
        h.refit_swept(&start, &shifted, 0.0).unwrap();
        assert!(NormalCones::new(&h).cannot_self_collide(&h, h.root()));
    }
}
