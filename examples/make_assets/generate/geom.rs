//! Triangle soups and the two queries the generator needs: where a ray crosses a surface
//! (Möller & Trumbore 1997) and how far a point is from it (closest point on a triangle,
//! Ericson, *Real-Time Collision Detection*, §5.1.5).

use nalgebra::{Point3, Vector3};

/// A point in metres.
pub type P = Point3<f64>;
/// A direction or displacement.
pub type V = Vector3<f64>;

/// Triangles of a quad surface, each quad split along its 0–2 diagonal, with bounding boxes.
pub struct Soup {
    /// Corner positions of every triangle.
    pub triangles: Vec<[P; 3]>,
    /// Lower and upper corner of each triangle's bounding box, as plain arrays (cheap to test).
    boxes: Vec<[[f64; 3]; 2]>,
}

impl Soup {
    /// Splits every face of `faces` (quads or triangles) over `positions` into triangles.
    pub fn from_faces<F: AsRef<[u32]>>(positions: &[P], faces: impl Iterator<Item = F>) -> Self {
        let mut triangles = Vec::new();
        for f in faces {
            let f = f.as_ref();
            for k in 1..f.len() - 1 {
                triangles.push([f[0], f[k], f[k + 1]].map(|v| positions[v as usize]));
            }
        }
        let boxes = triangles
            .iter()
            .map(|t| {
                let (lo, hi) = (t[0].inf(&t[1]).inf(&t[2]), t[0].sup(&t[1]).sup(&t[2]));
                [lo.coords.into(), hi.coords.into()]
            })
            .collect();
        Self { triangles, boxes }
    }

    /// Distances along `dir` (unit) from `origin` to the crossings with the surface within
    /// `reach`, sorted.
    pub fn crossings(&self, origin: P, dir: V, reach: f64) -> Vec<f64> {
        let (o, d): ([f64; 3], [f64; 3]) = (origin.coords.into(), dir.into());
        let mut hits: Vec<f64> = self
            .triangles
            .iter()
            .zip(&self.boxes)
            .filter(|(_, b)| segment_meets_box(o, d, reach, b))
            .filter_map(|(t, _)| ray_triangle(origin, dir, t))
            .filter(|&t| t <= reach)
            .collect();
        hits.sort_by(f64::total_cmp);
        hits
    }

    /// The smallest distance from `p` to the surface.
    pub fn distance(&self, p: P) -> f64 {
        let q: [f64; 3] = p.coords.into();
        let mut best = f64::INFINITY;
        for (t, [lo, hi]) in self.triangles.iter().zip(&self.boxes) {
            let gap = (0..3)
                .map(|a| (lo[a] - q[a]).max(q[a] - hi[a]).max(0.0).powi(2))
                .sum::<f64>();
            if gap < best * best {
                best = best.min((p - closest_on_triangle(p, t)).norm());
            }
        }
        best
    }
}

/// Whether `o + t d`, `t ∈ [0, reach]`, meets the box `[lo, hi]` (slab test).
fn segment_meets_box(o: [f64; 3], d: [f64; 3], reach: f64, [lo, hi]: &[[f64; 3]; 2]) -> bool {
    let (mut t0, mut t1) = (0.0_f64, reach);
    for a in 0..3 {
        if d[a].abs() < 1e-300 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return false;
            }
        } else {
            let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    t0 <= t1
}

/// The ray parameter `t > 0` where `origin + t dir` crosses triangle `t`, if it does.
fn ray_triangle(origin: P, dir: V, [a, b, c]: &[P; 3]) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let h = dir.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(&h) / det;
    let q = s.cross(&e1);
    let v = dir.dot(&q) / det;
    let t = e2.dot(&q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// The point of triangle `[a, b, c]` closest to `p`, by Voronoi region.
fn closest_on_triangle(p: P, [a, b, c]: &[P; 3]) -> P {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// The volume enclosed by closed, consistently oriented faces (divergence theorem); positive
/// when they face outward.
pub fn volume(soup: &Soup) -> f64 {
    soup.triangles
        .iter()
        .map(|[a, b, c]| a.coords.dot(&b.coords.cross(&c.coords)) / 6.0)
        .sum()
}
