//! Continuous collision between linearly moving points (Provot 1997; Bridson, Fedkiw & Anderson,
//! "Robust treatment of collisions, contact and friction for cloth animation", SIGGRAPH 2002,
//! §4).
//!
//! Over a step every vertex moves on a straight line, `x(t) = x0 + t (x1 - x0)`, `t ∈ [0, 1]`.
//! A vertex can only hit a triangle, or an edge another edge, at a time when the four points
//! are coplanar: a root of the cubic `((x1 - x0) × (x2 - x0)) · (x3 - x0)`. The roots in
//! `[0, 1]` are isolated robustly: the cubic is split at the roots of its derivative into
//! monotone pieces, a piece whose ends differ in sign is bisected to machine precision, and a
//! piece end where the cubic (nearly) vanishes without a sign change, a grazing contact, is kept
//! too. At each candidate time, earliest first, the points are checked to be actually touching
//! (vertex within a tolerance of the triangle, or of each other's segment for edges).
//!
//! Degenerate motions are handled: when the four points stay coplanar for the whole step (the
//! cubic vanishes identically: parallel or coplanar motion), first contact can only begin at
//! `t = 0` or when a vertex crosses the line of an edge, so those times are the candidates,
//! with the collinear case (a vertex crossing an edge's end) one level further down. A zero-area
//! triangle at the contact time is tested as its three edges.

use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::Triangle;

use crate::Point;
use crate::convert::to_glam;
use crate::triangle::{is_degenerate, segment_closest};

/// Features closer than this fraction of the problem's size count as touching.
const TOUCH: f64 = 1e-10;

/// How much the traversal loosens boxes (relative to their diagonals) so that features within
/// the touching tolerance still pair up: the problem's size is at most the two boxes' diagonals.
pub(crate) const CONTACT_SLACK: f64 = 2.0 * TOUCH;

/// A cubic (or lower) polynomial vanishing below this fraction of its natural scale counts as
/// identically zero.
const FLAT: f64 = 1e-13;

/// The earliest time in `[0, 1]` at which a moving vertex touches a moving triangle, with the
/// barycentric coordinates of the contact on the triangle.
///
/// `vertex` and each corner of `triangle` are `[start, end]` positions.
#[must_use]
pub fn vertex_triangle_impact(
    vertex: [Point; 2],
    triangle: [[Point; 2]; 3],
) -> Option<(f64, [f64; 3])> {
    let g = |p: [Point; 2]| p.map(|x| to_glam(&x));
    vertex_triangle(g(vertex), triangle.map(g))
}

/// The earliest time in `[0, 1]` at which two moving edges touch, with the parameters of the
/// contact along each (0 at the first end, 1 at the second).
///
/// Each end of each edge is `[start, end]` positions.
#[must_use]
pub fn edge_edge_impact(
    first: [[Point; 2]; 2],
    second: [[Point; 2]; 2],
) -> Option<(f64, [f64; 2])> {
    let g = |p: [Point; 2]| p.map(|x| to_glam(&x));
    edge_edge(first.map(g), second.map(g))
}

/// A point moving linearly: `[start, end]`.
type Path = [DVec3; 2];

fn at(p: Path, t: f64) -> DVec3 {
    p[0] + (p[1] - p[0]) * t
}

/// [`vertex_triangle_impact`] on glam vectors.
pub(crate) fn vertex_triangle(p: Path, tri: [Path; 3]) -> Option<(f64, [f64; 3])> {
    let scale = size(&[p, tri[0], tri[1], tri[2]]);
    let touch = TOUCH * scale;
    let test = |t: f64| {
        let q = at(p, t);
        let corners = tri.map(|c| at(c, t));
        point_triangle(q, corners)
            .filter(|(d, _)| *d <= touch)
            .map(|(_, w)| (t, w))
    };
    let cubic = coplanarity(tri[0], tri[1], tri[2], p);
    let mut times = Vec::new();
    if is_flat(&cubic, scale.powi(3)) {
        times.push(0.0);
        for i in 0..3 {
            vertex_line_times(p, [tri[i], tri[(i + 1) % 3]], scale, &mut times);
        }
    } else {
        roots_in_unit(&cubic, &mut times);
    }
    earliest(times, test)
}

/// [`edge_edge_impact`] on glam vectors.
pub(crate) fn edge_edge(e: [Path; 2], f: [Path; 2]) -> Option<(f64, [f64; 2])> {
    let scale = size(&[e[0], e[1], f[0], f[1]]);
    let touch = TOUCH * scale;
    let test = |t: f64| {
        let (s, u, d) = segment_closest(at(e[0], t), at(e[1], t), at(f[0], t), at(f[1], t));
        (d <= touch).then_some((t, [s, u]))
    };
    let cubic = coplanarity(e[0], e[1], f[0], f[1]);
    let mut times = Vec::new();
    if is_flat(&cubic, scale.powi(3)) {
        times.push(0.0);
        for (p, segment) in [(e[0], f), (e[1], f), (f[0], e), (f[1], e)] {
            vertex_line_times(p, segment, scale, &mut times);
        }
    } else {
        roots_in_unit(&cubic, &mut times);
    }
    earliest(times, test)
}

/// The first candidate time (ascending) at which `test` finds contact.
fn earliest<R>(mut times: Vec<f64>, test: impl Fn(f64) -> Option<R>) -> Option<R> {
    times.sort_unstable_by(f64::total_cmp);
    times.into_iter().find_map(test)
}

/// The largest distance between the points involved, start or end, from the first one's start.
fn size(paths: &[Path]) -> f64 {
    let origin = paths[0][0];
    paths
        .iter()
        .flatten()
        .map(|&x| (x - origin).length())
        .fold(f64::MIN_POSITIVE, f64::max)
}

fn is_flat(poly: &[f64], scale: f64) -> bool {
    poly.iter().all(|c| c.abs() <= FLAT * scale)
}

/// Coefficients (ascending powers of t) of `((b - a) × (c - a)) · (d - a)` along the motion.
fn coplanarity(a: Path, b: Path, c: Path, d: Path) -> [f64; 4] {
    let rel = |x: Path| (x[0] - a[0], (x[1] - x[0]) - (a[1] - a[0]));
    let ((e1, d1), (e2, d2), (e3, d3)) = (rel(b), rel(c), rel(d));
    let n0 = e1.cross(e2);
    let n1 = e1.cross(d2) + d1.cross(e2);
    let n2 = d1.cross(d2);
    [
        n0.dot(e3),
        n0.dot(d3) + n1.dot(e3),
        n1.dot(d3) + n2.dot(e3),
        n2.dot(d3),
    ]
}

/// Candidate times at which moving point `p` crosses the line of moving segment `s`: roots of
/// the components of `(s1 - s0) × (p - s0)`; when that vanishes identically (collinear motion),
/// the times `p` passes either end.
fn vertex_line_times(p: Path, s: [Path; 2], scale: f64, times: &mut Vec<f64>) {
    let rel = |x: Path| (x[0] - s[0][0], (x[1] - x[0]) - (s[0][1] - s[0][0]));
    let ((e0, de), (w0, dw)) = (rel(s[1]), rel(p));
    let coefficients = [e0.cross(w0), e0.cross(dw) + de.cross(w0), de.cross(dw)];
    let components = |c: [DVec3; 3]| (0..3).map(move |k| [c[0][k], c[1][k], c[2][k], 0.0]);
    if components(coefficients).all(|poly| is_flat(&poly, scale * scale)) {
        for end in s {
            let (x0, dx) = (p[0] - end[0], (p[1] - p[0]) - (end[1] - end[0]));
            for poly in components([x0, dx, DVec3::ZERO]) {
                roots_in_unit(&poly, times);
            }
        }
    } else {
        for poly in components(coefficients) {
            roots_in_unit(&poly, times);
        }
    }
}

/// Pushes the roots in `[0, 1]` of the polynomial `poly` (ascending powers, degree ≤ 3), and
/// the places where it grazes zero without changing sign. An identically zero polynomial has
/// no isolated roots and pushes nothing.
pub(crate) fn roots_in_unit(poly: &[f64; 4], times: &mut Vec<f64>) {
    let scale = poly.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if scale == 0.0 {
        return;
    }
    let eval = |t: f64| ((poly[3] * t + poly[2]) * t + poly[1]) * t + poly[0];
    let mut cuts = vec![0.0];
    cuts.extend(
        quadratic_roots(3.0 * poly[3], 2.0 * poly[2], poly[1]).filter(|t| *t > 0.0 && *t < 1.0),
    );
    cuts.push(1.0);
    cuts.sort_unstable_by(f64::total_cmp);
    let graze = 1e-14 * scale;
    for &t in &cuts {
        if eval(t).abs() <= graze {
            times.push(t);
        }
    }
    for piece in cuts.windows(2) {
        let (mut lo, mut hi) = (piece[0], piece[1]);
        let (flo, fhi) = (eval(lo), eval(hi));
        if flo == 0.0 || fhi == 0.0 || (flo > 0.0) == (fhi > 0.0) {
            continue;
        }
        loop {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if (eval(mid) > 0.0) == (flo > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        times.push(lo);
    }
}

/// Real roots of `a t² + b t + c` (fewer when degenerate), computed without cancellation.
fn quadratic_roots(a: f64, b: f64, c: f64) -> impl Iterator<Item = f64> {
    let mut roots = [f64::NAN; 2];
    if a == 0.0 {
        if b != 0.0 {
            roots[0] = -c / b;
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            roots[0] = q / a;
            if q != 0.0 {
                roots[1] = c / q;
            }
        }
    }
    roots.into_iter().filter(|r| r.is_finite())
}

/// Distance from `q` to the triangle and barycentric coordinates of the closest point; a
/// zero-area triangle is treated as its three edges.
fn point_triangle(q: DVec3, corners: [DVec3; 3]) -> Option<(f64, [f64; 3])> {
    let [a, b, c] = corners;
    if !is_degenerate(corners) {
        let (projection, location) =
            Triangle::new(a, b, c).project_local_point_and_get_location(q, false);
        let weights = location.barycentric_coordinates()?;
        return Some(((q - projection.point).length(), weights));
    }
    (0..3)
        .map(|i| {
            let j = (i + 1) % 3;
            let (_, u, d) = segment_closest(q, q, corners[i], corners[j]);
            let mut w = [0.0; 3];
            w[i] = 1.0 - u;
            w[j] = u;
            (d, w)
        })
        .min_by(|x, y| x.0.total_cmp(&y.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(p: DVec3) -> Path {
        [p, p]
    }

    fn moving(p: DVec3, v: DVec3) -> Path {
        [p, p + v]
    }

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    fn floor() -> [Path; 3] {
        [
            still(v(0.0, 0.0, 0.0)),
            still(v(1.0, 0.0, 0.0)),
            still(v(0.0, 1.0, 0.0)),
        ]
    }

    #[test]
    fn vertex_falling_through_a_triangle() {
        // From z = 0.3 down to z = -0.7: contact at t = 0.3, above (0.2, 0.25).
        let (t, w) =
            vertex_triangle(moving(v(0.2, 0.25, 0.3), v(0.0, 0.0, -1.0)), floor()).unwrap();
        assert!((t - 0.3).abs() < 1e-12);
        assert!((w[1] - 0.2).abs() < 1e-9 && (w[2] - 0.25).abs() < 1e-9);
    }

    #[test]
    fn vertex_missing_a_triangle() {
        // Crosses the plane outside the hypotenuse x + y = 1.
        assert_eq!(
            vertex_triangle(moving(v(0.6, 0.6, 0.3), v(0.0, 0.0, -1.0)), floor()),
            None
        );
        // Stops short of the plane.
        assert_eq!(
            vertex_triangle(moving(v(0.2, 0.2, 0.3), v(0.0, 0.0, -0.29)), floor()),
            None
        );
    }

    #[test]
    fn rotating_triangle_hits_a_still_vertex() {
        // The triangle's third corner swings from z = -1 to z = 1 while the vertex waits at
        // (0.1, 0.1, 0.05): the plane through the x axis passes it when the corner's height
        // reaches 0.05 · 1 / 0.1 = 0.5, i.e. t = 0.75.
        let tri = [
            still(v(0.0, 0.0, 0.0)),
            still(v(1.0, 0.0, 0.0)),
            [v(0.0, 1.0, -1.0), v(0.0, 1.0, 1.0)],
        ];
        let (t, _) = vertex_triangle(still(v(0.1, 0.1, 0.05)), tri).unwrap();
        assert!((t - 0.75).abs() < 1e-9, "{t}");
    }

    #[test]
    fn coplanar_vertex_sliding_into_a_triangle() {
        // In the triangle's plane, from x = -1 to x = 1 along y = 0.25: enters at x = 0, t = 0.5.
        let (t, w) =
            vertex_triangle(moving(v(-1.0, 0.25, 0.0), v(2.0, 0.0, 0.0)), floor()).unwrap();
        assert!((t - 0.5).abs() < 1e-9, "{t}");
        assert!((w[2] - 0.25).abs() < 1e-9);
        // Same plane, parallel to the hypotenuse and outside: never touches.
        assert_eq!(
            vertex_triangle(moving(v(2.0, 0.0, 0.0), v(-1.0, 1.0, 0.0)), floor()),
            None
        );
    }

    #[test]
    fn parallel_motion_keeps_its_distance() {
        // Vertex and triangle move together: no contact, and no contact at t = 0 either.
        let d = v(0.3, -0.2, 0.5);
        let tri = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)].map(|x| moving(x, d));
        assert_eq!(vertex_triangle(moving(v(0.2, 0.2, 0.1), d), tri), None);
        // Resting on the triangle from the start: contact at t = 0.
        assert_eq!(
            vertex_triangle(moving(v(0.2, 0.2, 0.0), d), tri).map(|r| r.0),
            Some(0.0)
        );
    }

    #[test]
    fn degenerate_triangle_is_tested_as_edges() {
        // A triangle collapsed onto the segment (0,0,0)–(1,0,0), hit by a vertex at t = 0.4.
        let tri = [
            still(v(0.0, 0.0, 0.0)),
            still(v(1.0, 0.0, 0.0)),
            still(v(0.5, 0.0, 0.0)),
        ];
        let (t, _) = vertex_triangle(moving(v(0.25, 0.0, 0.4), v(0.0, 0.0, -1.0)), tri).unwrap();
        assert!((t - 0.4).abs() < 1e-9, "{t}");
    }

    #[test]
    fn crossing_edges() {
        // Edge along x at z = 0; edge along y falls from z = 1 to z = -1, crossing at t = 0.5.
        let e = [still(v(-1.0, 0.0, 0.0)), still(v(1.0, 0.0, 0.0))];
        let f = [
            moving(v(0.3, -1.0, 1.0), v(0.0, 0.0, -2.0)),
            moving(v(0.3, 1.0, 1.0), v(0.0, 0.0, -2.0)),
        ];
        let (t, [s, u]) = edge_edge(e, f).unwrap();
        assert!((t - 0.5).abs() < 1e-12);
        assert!((s - 0.65).abs() < 1e-9 && (u - 0.5).abs() < 1e-9);
        // Same fall, but the falling edge is shifted past the first edge's end.
        let g = f.map(|p| p.map(|x| x + v(2.0, 0.0, 0.0)));
        assert_eq!(edge_edge(e, g), None);
    }

    #[test]
    fn parallel_and_collinear_edges() {
        let e = [still(v(0.0, 0.0, 0.0)), still(v(1.0, 0.0, 0.0))];
        // A parallel edge approaching sideways in the same plane meets at t = 0.25.
        let f = [
            moving(v(0.5, 1.0, 0.0), v(0.0, -4.0, 0.0)),
            moving(v(1.5, 1.0, 0.0), v(0.0, -4.0, 0.0)),
        ];
        let (t, _) = edge_edge(e, f).unwrap();
        assert!((t - 0.25).abs() < 1e-9, "{t}");
        // A collinear edge sliding along the line reaches the first one's end at t = 0.5.
        let g = [
            moving(v(2.0, 0.0, 0.0), v(-2.0, 0.0, 0.0)),
            moving(v(3.0, 0.0, 0.0), v(-2.0, 0.0, 0.0)),
        ];
        let (t, [s, u]) = edge_edge(e, g).unwrap();
        assert!((t - 0.5).abs() < 1e-9, "{t}");
        assert!((s - 1.0).abs() < 1e-9 && u.abs() < 1e-9);
        // A parallel edge moving parallel to it never meets it.
        let h = [
            moving(v(0.0, 1.0, 0.0), v(1.0, 0.0, 0.0)),
            moving(v(1.0, 1.0, 0.0), v(1.0, 0.0, 0.0)),
        ];
        assert_eq!(edge_edge(e, h), None);
    }

    #[test]
    fn roots_of_known_cubics() {
        let mut r = Vec::new();
        // (t - 0.2)(t - 0.5)(t - 0.9) = t³ - 1.6t² + 0.73t - 0.09.
        roots_in_unit(&[-0.09, 0.73, -1.6, 1.0], &mut r);
        r.sort_unstable_by(f64::total_cmp);
        assert_eq!(r.len(), 3);
        for (got, want) in r.iter().zip([0.2, 0.5, 0.9]) {
            assert!((got - want).abs() < 1e-12, "{got}");
        }
        // A double root at t = 0.5 (grazing): (t - 0.5)² = t² - t + 0.25.
        r.clear();
        roots_in_unit(&[0.25, -1.0, 1.0, 0.0], &mut r);
        assert_eq!(r, vec![0.5]);
        // No root in [0, 1], and the zero polynomial.
        r.clear();
        roots_in_unit(&[1.0, 0.0, 1.0, 0.0], &mut r);
        roots_in_unit(&[0.0; 4], &mut r);
        assert!(r.is_empty());
    }
}
