//! Exact tests on single triangles and segments: zero area, triangle–triangle intersection,
//! closest points between segments, and the direction that parts two triangles.
//!
//! The intersection test is the classic reduction (Möller 1997; Guigue & Devillers 2003): two
//! triangles in general position meet exactly when an edge of one crosses the other, decided by
//! signs of 3×3 determinants (orientations); coplanar triangles are projected on their dominant
//! plane and tested with 2D orientations. The orientations come from Shewchuk's adaptive exact
//! predicates (`robust`), so coplanar and touching configurations, which flat cloth produces all
//! the time, are decided exactly. Touching counts as intersecting.
//!
//! Neighbouring triangles of a smooth surface are nearly coplanar, so the orientations of one
//! against the other's plane fall back to exact arithmetic, the slow path of the adaptive
//! predicates, although the triangles lie side by side. Three filters reject such pairs first,
//! each only when the triangles are strictly apart, so the answers are the same with or
//! without them: their boxes are disjoint; their projections on the line through their
//! centroids are disjoint by more than the projections' rounding (a dot product's error
//! bound, in plain floating point: no predicate); or a plane through an edge of one (and a
//! point off the triangle along its normal) has that triangle strictly on one side and the
//! other triangle strictly on the other. Any point off the edge's line makes such a plane, so
//! its rounding does not matter, and its orientations are well away from zero, the fast path.

use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::Triangle;
use robust::{Coord, Coord3D, orient2d, orient3d};

use crate::convert::{to_glam, to_vector};
use crate::{Point, Vector};

/// Whether a triangle has (numerically) zero area: twice its area is within rounding of zero
/// relative to its longest edge.
pub(crate) fn is_degenerate([a, b, c]: [DVec3; 3]) -> bool {
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    (b - a).cross(c - a).length() <= 4.0 * f64::EPSILON * longest
}

/// Whether two triangles intersect or touch (exactly, with adaptive predicates).
///
/// A zero-area triangle never intersects anything: the collision queries skip such triangles
/// and count them ([`crate::Hierarchy::degenerate_triangles`]).
#[must_use]
pub fn triangles_intersect(p: [Point; 3], q: [Point; 3]) -> bool {
    triangles_meet(p.map(|x| to_glam(&x)), q.map(|x| to_glam(&x)))
}

/// [`triangles_intersect`] on glam vectors.
pub(crate) fn triangles_meet(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    if boxes_apart(p, q)
        || centroids_apart(p, q)
        || edge_plane_separates(p, q)
        || edge_plane_separates(q, p)
    {
        return false;
    }
    triangles_meet_exact(p, q)
}

/// Whether two triangles lie apart along the line through their centroids by more than the
/// projections' rounding ([`apart_along`]).
fn centroids_apart(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let sum = |t: [DVec3; 3]| t[0] + t[1] + t[2];
    apart_along(sum(q) - sum(p), p, q)
}

/// Bound on the rounding of a projection `axis · x`, relative to `|axis| · |x|`: a dot
/// product of three terms is within γ₃ ≈ 3u of its exact value times that sum (Higham,
/// "Accuracy and Stability of Numerical Algorithms", §3.1; u = 2⁻⁵³), and the bound itself
/// and the shifted ends are rounded too; 8u covers all three.
const PROJECTION_ROUNDING: f64 = 4.0 * f64::EPSILON;

/// Whether the projections of `p` and `q` on `axis` are disjoint by more than their rounding:
/// a plane normal to `axis` then parts the two triangles (the separating axis theorem), and
/// `axis` itself may be any rounded direction.
fn apart_along(axis: DVec3, p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let size = axis.abs();
    let range = |t: [DVec3; 3]| {
        t.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), &x| {
                let along = axis.dot(x);
                let rounding = size.dot(x.abs()) * PROJECTION_ROUNDING;
                (low.min(along - rounding), high.max(along + rounding))
            })
    };
    let ((p_low, p_high), (q_low, q_high)) = (range(p), range(q));
    p_high < q_low || q_high < p_low
}

/// Whether the boxes of two triangles are disjoint (touching boxes are not).
fn boxes_apart(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let lo = |t: [DVec3; 3]| t[0].min(t[1]).min(t[2]);
    let hi = |t: [DVec3; 3]| t[0].max(t[1]).max(t[2]);
    hi(p).cmplt(lo(q)).any() || hi(q).cmplt(lo(p)).any()
}

/// Whether a plane through an edge of `p` and a point off `p` along its normal has the third
/// corner of `p` strictly on one side and all of `q` strictly on the other.
fn edge_plane_separates(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    let normal = (p[1] - p[0]).cross(p[2] - p[0]);
    (0..3).any(|i| {
        let (a, b, c) = (p[i], p[(i + 1) % 3], p[(i + 2) % 3]);
        let plane = [a, b, a + normal];
        let side = orient(plane, c);
        side != 0.0 && q.iter().all(|&x| orient(plane, x) == -side)
    })
}

/// [`triangles_meet`] without the filters.
fn triangles_meet_exact(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    if is_degenerate(p) || is_degenerate(q) {
        return false;
    }
    let side_of_p = q.map(|x| orient(p, x));
    if strictly_one_side(side_of_p) {
        return false;
    }
    let side_of_q = p.map(|x| orient(q, x));
    if strictly_one_side(side_of_q) {
        return false;
    }
    if side_of_p == [0.0; 3] {
        let axis = dominant_axis(p);
        return triangles_meet_2d(project(p, axis), project(q, axis));
    }
    (0..3).any(|i| {
        let j = (i + 1) % 3;
        segment_meets_triangle(p[i], p[j], side_of_q[i], side_of_q[j], q)
            || segment_meets_triangle(q[i], q[j], side_of_p[i], side_of_p[j], p)
    })
}

/// The sign of the orientation of `x` against the plane of `t` (0 when coplanar).
fn orient(t: [DVec3; 3], x: DVec3) -> f64 {
    let c = |v: DVec3| Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    orient3d(c(t[0]), c(t[1]), c(t[2]), c(x)).signum_or_zero()
}

trait SignumOrZero {
    fn signum_or_zero(self) -> Self;
}

impl SignumOrZero for f64 {
    fn signum_or_zero(self) -> f64 {
        if self == 0.0 { 0.0 } else { self.signum() }
    }
}

fn strictly_one_side(s: [f64; 3]) -> bool {
    s.iter().all(|&x| x > 0.0) || s.iter().all(|&x| x < 0.0)
}

/// Whether segment `ab`, whose ends lie on sides `sa`, `sb` of the plane of `t`, meets `t`.
fn segment_meets_triangle(a: DVec3, b: DVec3, sa: f64, sb: f64, t: [DVec3; 3]) -> bool {
    if sa * sb > 0.0 {
        return false;
    }
    if sa == 0.0 && sb == 0.0 {
        let axis = dominant_axis(t);
        let [a2, b2] = [a, b].map(|x| drop_axis(x, axis));
        let t2 = project(t, axis);
        return (0..3).any(|i| segments_meet_2d(a2, b2, t2[i], t2[(i + 1) % 3]))
            || point_in_triangle_2d(a2, t2);
    }
    // The line ab passes through t when it turns the same way around all three edges.
    let turns = [0, 1, 2].map(|i| orient([a, b, t[i]], t[(i + 1) % 3]));
    turns.iter().all(|&s| s >= 0.0) || turns.iter().all(|&s| s <= 0.0)
}

type V2 = [f64; 2];

/// The axis along which the normal of `t` is largest; dropping it keeps `t` non-degenerate.
fn dominant_axis([a, b, c]: [DVec3; 3]) -> usize {
    let n = (b - a).cross(c - a).abs();
    if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    }
}

fn drop_axis(v: DVec3, axis: usize) -> V2 {
    match axis {
        0 => [v.y, v.z],
        1 => [v.z, v.x],
        _ => [v.x, v.y],
    }
}

fn project(t: [DVec3; 3], axis: usize) -> [V2; 3] {
    t.map(|v| drop_axis(v, axis))
}

fn orient_2d(a: V2, b: V2, c: V2) -> f64 {
    let k = |v: V2| Coord { x: v[0], y: v[1] };
    orient2d(k(a), k(b), k(c)).signum_or_zero()
}

fn triangles_meet_2d(p: [V2; 3], q: [V2; 3]) -> bool {
    (0..3).any(|i| (0..3).any(|j| segments_meet_2d(p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3])))
        || point_in_triangle_2d(p[0], q)
        || point_in_triangle_2d(q[0], p)
}

fn point_in_triangle_2d(x: V2, t: [V2; 3]) -> bool {
    let s = [0, 1, 2].map(|i| orient_2d(t[i], t[(i + 1) % 3], x));
    s.iter().all(|&v| v >= 0.0) || s.iter().all(|&v| v <= 0.0)
}

fn segments_meet_2d(a: V2, b: V2, c: V2, d: V2) -> bool {
    let (o1, o2) = (orient_2d(a, b, c), orient_2d(a, b, d));
    let (o3, o4) = (orient_2d(c, d, a), orient_2d(c, d, b));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    let within =
        |p: V2, q: V2, x: V2| (0..2).all(|k| p[k].min(q[k]) <= x[k] && x[k] <= p[k].max(q[k]));
    (o1 == 0.0 && within(a, b, c))
        || (o2 == 0.0 && within(a, b, d))
        || (o3 == 0.0 && within(c, d, a))
        || (o4 == 0.0 && within(c, d, b))
}

/// For two triangles that do not meet ([`triangles_intersect`]), the unit direction from the
/// closest point of `q` to the closest point of `p`: the plane through either point across
/// it has `p` on its side and `q` on the other, so moving the corners of `p` along it (or
/// any way whose component along it is not negative) and those of `q` against it keeps them
/// apart. `None` when they meet (or a triangle has zero area).
///
/// Two disjoint triangles are nearest at a corner of one and the other triangle, or at two
/// edges (Ericson, *Real-Time Collision Detection*, §5.2.8), so those fifteen pairs are tried.
#[must_use]
pub fn triangles_apart(p: [Point; 3], q: [Point; 3]) -> Option<Vector> {
    let (p, q) = (p.map(|x| to_glam(&x)), q.map(|x| to_glam(&x)));
    if is_degenerate(p) || is_degenerate(q) || triangles_meet(p, q) {
        return None;
    }
    let foot = |t: [DVec3; 3], x: DVec3| {
        Triangle::new(t[0], t[1], t[2])
            .project_local_point(x, true)
            .point
    };
    // Each candidate as (from q, to p).
    let corners = p
        .iter()
        .map(|&x| (foot(q, x), x))
        .chain(q.iter().map(|&y| (y, foot(p, y))));
    let edges = (0..3).flat_map(|i| {
        (0..3).map(move |j| {
            let (a0, a1, b0, b1) = (p[i], p[(i + 1) % 3], q[j], q[(j + 1) % 3]);
            let (s, u, _) = segment_closest(a0, a1, b0, b1);
            (b0 + (b1 - b0) * u, a0 + (a1 - a0) * s)
        })
    });
    let (from, to) = corners
        .chain(edges)
        .min_by(|a, b| (a.1 - a.0).length().total_cmp(&(b.1 - b.0).length()))?;
    let direction = (to - from).normalize_or_zero();
    (direction != DVec3::ZERO).then(|| to_vector(direction))
}

/// Closest points between segments `p0 p1` and `q0 q1` (Ericson, *Real-Time Collision
/// Detection*, §5.1.9): the parameters `(s, u)` in `[0, 1]` along each and the distance.
/// Parallel and zero-length segments are handled.
pub(crate) fn segment_closest(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64, f64) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, u) = if a <= f64::MIN_POSITIVE && e <= f64::MIN_POSITIVE {
        (0.0, 0.0)
    } else if a <= f64::MIN_POSITIVE {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= f64::MIN_POSITIVE {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut u = (b * s + f) / e;
            if u < 0.0 {
                u = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if u > 1.0 {
                u = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, u)
        }
    };
    let distance = ((p0 + d1 * s) - (q0 + d2 * u)).length();
    (s, u, distance)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [DVec3; 3] {
        [a, b, c].map(DVec3::from_array)
    }

    const FLOOR: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];

    fn floor() -> [DVec3; 3] {
        t(FLOOR[0], FLOOR[1], FLOOR[2])
    }

    #[test]
    fn piercing_triangle_intersects() {
        let wall = t([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.0]);
        assert!(triangles_meet(floor(), wall));
        assert!(triangles_meet(wall, floor()));
    }

    #[test]
    fn separated_and_near_miss_triangles_do_not() {
        let above = t([0.0, 0.0, 1e-12], [1.0, 0.0, 1e-12], [0.0, 1.0, 1.0]);
        assert!(!triangles_meet(floor(), above));
        // Crosses the floor's plane, but outside its hypotenuse x + y = 2.
        let beside = t([1.5, 1.5, -1.0], [1.5, 1.5, 1.0], [3.0, 3.0, 0.0]);
        assert!(!triangles_meet(floor(), beside));
    }

    #[test]
    fn touching_counts() {
        // A vertex resting exactly on the floor, and an edge lying on it.
        let tip = t([0.5, 0.5, 0.0], [0.5, 0.0, 1.0], [0.0, 0.5, 1.0]);
        assert!(triangles_meet(floor(), tip));
        let edge_down = t([0.5, 0.1, 0.0], [0.1, 0.5, 0.0], [0.3, 0.3, 1.0]);
        assert!(triangles_meet(floor(), edge_down));
    }

    #[test]
    fn coplanar_cases() {
        let overlapping = t([1.0, 1.0, 0.0], [3.0, 1.0, 0.0], [1.0, 3.0, 0.0]);
        assert!(triangles_meet(floor(), overlapping));
        let disjoint = t([1.1, 1.1, 0.0], [3.0, 1.1, 0.0], [1.1, 3.0, 0.0]);
        assert!(!triangles_meet(floor(), disjoint));
        let inside = t([0.1, 0.1, 0.0], [0.5, 0.1, 0.0], [0.1, 0.5, 0.0]);
        assert!(triangles_meet(floor(), inside) && triangles_meet(inside, floor()));
    }

    #[test]
    fn degenerate_triangles_are_skipped() {
        let sliver = t([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [0.5, 0.5, 0.0]);
        assert!(is_degenerate(sliver));
        assert!(!triangles_meet(floor(), sliver));
        assert!(!is_degenerate(floor()));
    }

    /// Random pairs of small triangles near one plane, side by side, overlapping or touching
    /// (corners on a coarse grid, so that shared vertices, edges and coplanar contacts come
    /// often): the filters never change the answer, and they do reject.
    #[test]
    fn filters_keep_the_exact_answer() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = |k: u64| (xorshift(&mut state) % k) as f64;
        let (mut rejected, mut meeting) = (0, 0);
        for _ in 0..20_000 {
            let mut corner = || DVec3::new(next(5), next(5), next(3) * 0.5) * 0.25;
            let (p, q) = (
                [corner(), corner(), corner()],
                [corner(), corner(), corner()],
            );
            let exact = triangles_meet_exact(p, q);
            assert_eq!(triangles_meet(p, q), exact, "{p:?} {q:?}");
            meeting += usize::from(exact);
            let filtered = boxes_apart(p, q) || centroids_apart(p, q) || edge_plane_separates(p, q);
            rejected += usize::from(filtered && !is_degenerate(p) && !is_degenerate(q));
        }
        assert!(rejected > 1000 && meeting > 1000, "{rejected} {meeting}");
    }

    /// Random pairs of triangles in a unit cube: for those apart, neither triangle reaches past
    /// the plane the direction makes, and moving each triangle's corners its own way along it
    /// never makes them meet.
    #[test]
    fn the_direction_apart_parts_the_triangles() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut unit = || (xorshift(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
        let mut apart = 0;
        for _ in 0..4000 {
            let mut corner = || Point::new(unit(), unit(), unit());
            let (p, q) = (
                [corner(), corner(), corner()],
                [corner(), corner(), corner()],
            );
            let direction = triangles_apart(p, q);
            assert_eq!(
                direction.is_none(),
                triangles_intersect(p, q),
                "{p:?} {q:?}"
            );
            let Some(n) = direction else { continue };
            apart += 1;
            assert!((n.norm() - 1.0).abs() < 1e-12);
            // The gap along n: p's lowest corner above q's highest.
            let along = |t: &[Point; 3]| t.map(|x| x.coords.dot(&n));
            let low = along(&p).into_iter().fold(f64::INFINITY, f64::min);
            let high = along(&q).into_iter().fold(f64::NEG_INFINITY, f64::max);
            assert!(low >= high - 1e-12, "{p:?} {q:?}: {low} < {high}");
            // Each corner of p moved by a random amount with no component against n, each
            // of q with none along it.
            let mut moved = |t: [Point; 3], sign: f64| {
                t.map(|x| {
                    let d = Vector::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 0.2;
                    let along = d.dot(&n) * sign;
                    x + if along < 0.0 {
                        d - n * (along * sign)
                    } else {
                        d
                    }
                })
            };
            let (p2, q2) = (moved(p, 1.0), moved(q, -1.0));
            assert!(
                !triangles_intersect(p2, q2),
                "{p:?} {q:?} moved to {p2:?} {q2:?}"
            );
        }
        assert!(apart > 1000, "{apart}");
    }

    /// The next state of Marsaglia's xorshift generator (2003), a test's random numbers.
    fn xorshift(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    /// Triangles touching where their projections on the line through their centroids meet,
    /// their projections there equal in exact arithmetic but not as rounded: a corner `c` of
    /// `p`, the highest of `p` along that line, lies on an edge `c ± e` of `q` at right angles
    /// to it, `q`'s third corner beyond. Every coordinate is a multiple of 2⁻³⁰ of at most 37
    /// significant bits, so `c ± e` and the line are exact and `c` lies exactly on the edge,
    /// while the projections' products need up to 69 bits and round. They touch, and the
    /// centroid filter must not part them: without its allowance for rounding it parts
    /// about one in five.
    #[test]
    fn triangles_touching_across_the_centroid_line_meet() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut int = |bits: u32| (xorshift(&mut state) >> (64 - bits)) as i64 - (1 << (bits - 1));
        let dot = |a: [i64; 3], b: [i64; 3]| {
            (0..3)
                .map(|k| i128::from(a[k]) * i128::from(b[k]))
                .sum::<i128>()
        };
        let point = |a: [i64; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64) / 2f64.powi(30);
        let mut touching = 0;
        for _ in 0..20_000 {
            let mut corner = |bits| [int(bits), int(bits), int(bits)];
            let (c, p1, p2, beyond, w) =
                (corner(30), corner(30), corner(30), corner(30), corner(4));
            // The centroids' difference, three times over: `c + e` and `c - e` sum to `2c`.
            let line: [i64; 3] = std::array::from_fn(|k| c[k] + beyond[k] - p1[k] - p2[k]);
            let e = [
                line[1] * w[2] - line[2] * w[1],
                line[2] * w[0] - line[0] * w[2],
                line[0] * w[1] - line[1] * w[0],
            ];
            let top = dot(line, c);
            if e == [0; 3]
                || dot(line, p1) >= top
                || dot(line, p2) >= top
                || dot(line, beyond) <= top
            {
                continue;
            }
            let shifted = |s: i64| std::array::from_fn(|k| c[k] + s * e[k]);
            let p = [point(c), point(p1), point(p2)];
            let q = [point(shifted(1)), point(beyond), point(shifted(-1))];
            assert!(triangles_meet_exact(p, q), "{p:?} {q:?}");
            assert!(triangles_meet(p, q), "{p:?} {q:?}");
            touching += 1;
        }
        assert!(touching > 5000, "{touching}");
    }

    #[test]
    fn segment_closest_points() {
        let x = |v: f64| DVec3::new(v, 0.0, 0.0);
        // Skew segments: along x at z = 0 and along y at z = 1, crossing above (0.5, 0).
        let (s, u, d) = segment_closest(
            x(0.0),
            x(1.0),
            DVec3::new(0.5, -1.0, 1.0),
            DVec3::new(0.5, 1.0, 1.0),
        );
        assert_eq!((s, u, d), (0.5, 0.5, 1.0));
        // Parallel overlapping segments one apart.
        let (_, _, d) = segment_closest(
            x(0.0),
            x(2.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(3.0, 1.0, 0.0),
        );
        assert_eq!(d, 1.0);
        // A zero-length segment against a segment.
        let (s, u, d) = segment_closest(DVec3::Y, DVec3::Y, x(-1.0), x(1.0));
        assert_eq!((s, u, d), (0.0, 0.5, 1.0));
    }
}
