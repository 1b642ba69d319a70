//! Catmull-Clark masks, after OpenSubdiv's `Sdc::Scheme<SCHEME_CATMARK>`.
//!
//! A mask gives the weight of a vertex's own position, of the far end of each incident edge and
//! of each incident face, in the order of the vertex's edges and faces. For refinement, face
//! weights apply to the new face points (face centres); for limit masks they apply to the vertex
//! diagonally opposite in each incident quad.
//!
//! Refinement (Catmull & Clark 1978; DeRose, Kass & Truong 1998, section 3):
//! - face point: the centroid;
//! - edge point: ¼ of each end and ¼ of each adjacent face point; ½ of each end on a crease,
//!   blended by the sharpness when a semi-sharp edge decays to smooth in this step;
//! - vertex point: `(n−2)/n V + 1/n² ΣE + 1/n² ΣF` (smooth and dart), `¾ V + ⅛ (E_a + E_b)`
//!   (crease), `V` (corner), blended when the rule changes between parent and child.
//!
//! Limit (Halstead, Kass & DeRose 1993; Biermann et al. 2000 for the crease cross-tangent):
//! positions `(n² V + 4 ΣE + ΣQ) / (n(n+5))`, `⅔ V + ⅙ (E_a + E_b)` on creases, `V` at corners;
//! tangent masks exactly as OpenSubdiv writes them (`Far::PrimvarRefiner::Limit`).

use std::f64::consts::PI;

use super::crease::{self, Rule};
use crate::options::{CreaseMethod, TriangleRule};

/// Weights of a vertex, its incident edges' far ends and its incident faces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mask {
    /// Weight of the vertex itself (or the two edge ends for an edge mask: see [`EdgeMask`]).
    pub vertex: f64,
    /// One weight per incident edge (far end), possibly empty.
    pub edges: Vec<f64>,
    /// One weight per incident face, possibly empty.
    pub faces: Vec<f64>,
}

impl Mask {
    fn set(&mut self, vertex: f64, edges: usize, faces: usize) {
        self.vertex = vertex;
        self.edges.clear();
        self.edges.resize(edges, 0.0);
        self.faces.clear();
        self.faces.resize(faces, 0.0);
    }

    /// `self = p * self + (1 − p) * other`, where missing weights count as zero.
    fn blend(&mut self, p: f64, other: &Self) {
        let c = 1.0 - p;
        self.vertex = p * self.vertex + c * other.vertex;
        blend_weights(&mut self.edges, p, c, &other.edges);
        blend_weights(&mut self.faces, p, c, &other.faces);
    }
}

fn blend_weights(dst: &mut Vec<f64>, p: f64, c: f64, src: &[f64]) {
    if src.is_empty() {
        dst.iter_mut().for_each(|w| *w *= p);
    } else if dst.is_empty() {
        dst.extend(src.iter().map(|w| c * w));
    } else {
        dst.iter_mut()
            .zip(src)
            .for_each(|(d, s)| *d = p * *d + c * s);
    }
}

/// The weights of an edge point: both ends share `vertex`, each incident face point gets its
/// entry in `faces` (empty for a crease).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EdgeMask {
    /// Weight of each of the two end vertices.
    pub vertex: f64,
    /// One weight per incident face point.
    pub faces: Vec<f64>,
}

/// The edge-point mask (`ComputeEdgeVertexMask` with the parent rule from the edge sharpness
/// and the child rule of the new vertex, as `Far::PrimvarRefiner` calls it).
///
/// `face_sizes` lists the vertex count of each incident face (the triangle rule needs it).
pub fn edge_point(
    triangle_rule: TriangleRule,
    sharpness: f32,
    child_rule: Rule,
    face_sizes: &[usize],
    mask: &mut EdgeMask,
) {
    if crease::is_sharp(sharpness) && child_rule == Rule::Crease {
        mask.vertex = 0.5;
        mask.faces.clear();
        return;
    }
    smooth_edge_point(triangle_rule, face_sizes, mask);
    if crease::is_sharp(sharpness) {
        // A crease decaying to smooth: blend the crease mask in by the parent sharpness.
        let p = f64::from(sharpness);
        let c = 1.0 - p;
        mask.vertex = p * 0.5 + c * mask.vertex;
        mask.faces.iter_mut().for_each(|w| *w *= c);
    }
}

fn smooth_edge_point(triangle_rule: TriangleRule, face_sizes: &[usize], mask: &mut EdgeMask) {
    mask.faces.clear();
    let n = face_sizes.len();
    let tri = |i: usize| face_sizes[i] == 3;
    if triangle_rule == TriangleRule::Smooth && n == 2 && (tri(0) || tri(1)) {
        // OpenSubdiv mimics Hbr's order of operations here.
        const TRI_EDGE_WEIGHT: f64 = 0.470;
        let w = |i| if tri(i) { TRI_EDGE_WEIGHT } else { 0.25 };
        let f = 0.5 * (w(0) + w(1));
        mask.vertex = 0.5 * (1.0 - 2.0 * f);
        mask.faces.extend([f, f]);
    } else {
        mask.vertex = 0.25;
        let f = if n == 2 { 0.25 } else { 0.5 / n as f64 };
        mask.faces.resize(n, f);
    }
}

/// Everything the vertex-point mask needs to know about a vertex and its child.
#[derive(Clone, Copy, Debug)]
pub struct VertexNeighbourhood<'a> {
    /// Number of incident faces.
    pub faces: usize,
    /// Rule of the parent vertex.
    pub parent_rule: Rule,
    /// Rule of its child vertex.
    pub child_rule: Rule,
    /// Sharpness of the parent vertex.
    pub parent_sharpness: f32,
    /// Sharpness of the child vertex.
    pub child_sharpness: f32,
    /// Sharpness of each incident edge, in the vertex's edge order.
    pub parent_edges: &'a [f32],
    /// Sharpness of each child edge at the child vertex, in the same order.
    pub child_edges: &'a [f32],
}

/// The vertex-point mask (`ComputeVertexVertexMask`), face weights for face points.
///
/// `scratch` holds the child-rule mask when the two rules must be blended.
pub fn vertex_point(
    method: CreaseMethod,
    v: &VertexNeighbourhood<'_>,
    mask: &mut Mask,
    scratch: &mut Mask,
) {
    if v.parent_rule.is_smooth() {
        smooth_vertex_point(v.faces, v.parent_edges.len(), mask);
        return;
    }
    rule_vertex_point(v.parent_rule, v.faces, v.parent_edges, mask);
    if v.child_rule == v.parent_rule {
        return;
    }
    rule_vertex_point(v.child_rule, v.faces, v.child_edges, scratch);
    let p = crease::fractional_weight_at_vertex(
        method,
        v.parent_sharpness,
        v.child_sharpness,
        v.parent_edges,
        v.child_edges,
    );
    mask.blend(f64::from(p), scratch);
}

fn rule_vertex_point(rule: Rule, faces: usize, edges: &[f32], mask: &mut Mask) {
    match rule {
        Rule::Smooth | Rule::Dart => smooth_vertex_point(faces, edges.len(), mask),
        Rule::Crease => {
            let [a, b] = crease::sharp_edge_pair(edges);
            mask.set(0.75, edges.len(), 0);
            mask.edges[a] = 0.125;
            mask.edges[b] = 0.125;
        }
        Rule::Corner => mask.set(1.0, 0, 0),
    }
}

fn smooth_vertex_point(faces: usize, edges: usize, mask: &mut Mask) {
    debug_assert_eq!(faces, edges, "smooth rules need a manifold interior vertex");
    let n = faces as f64;
    let w = 1.0 / (n * n);
    mask.set((n - 2.0) / n, edges, faces);
    mask.edges.fill(w);
    mask.faces.fill(w);
}

/// Limit position mask of a vertex whose neighbourhood is all quads (`ComputeVertexLimitMask`);
/// face weights apply to the vertex opposite in each quad.
pub fn limit_position(rule: Rule, faces: usize, edges: &[f32], mask: &mut Mask) {
    match rule {
        Rule::Smooth | Rule::Dart if faces == 2 => mask.set(1.0, 0, 0),
        Rule::Smooth | Rule::Dart => {
            let n = faces as f64;
            let (v, e, f) = if faces == 4 {
                (4.0 / 9.0, 1.0 / 9.0, 1.0 / 36.0)
            } else {
                let f = 1.0 / (n * (n + 5.0));
                let e = 4.0 * f;
                (1.0 - n * (e + f), e, f)
            };
            mask.set(v, edges.len(), faces);
            mask.edges.fill(e);
            mask.faces.fill(f);
        }
        Rule::Crease => {
            let [a, b] = crease::sharp_edge_pair(edges);
            mask.set(2.0 / 3.0, edges.len(), 0);
            mask.edges[a] = 1.0 / 6.0;
            mask.edges[b] = 1.0 / 6.0;
        }
        Rule::Corner => mask.set(1.0, 0, 0),
    }
}

/// Limit tangent masks (`ComputeVertexLimitMask` with tangents); the limit normal is
/// `normalize(tan1 × tan2)`. Face weights apply to the vertex opposite in each quad.
pub fn limit_tangents(rule: Rule, faces: usize, edges: &[f32], tan1: &mut Mask, tan2: &mut Mask) {
    let n_edges = edges.len();
    match rule {
        Rule::Smooth | Rule::Dart if faces != 2 => smooth_tangents(faces, tan1, tan2),
        Rule::Crease => {
            let [a, b] = crease::sharp_edge_pair(edges);
            crease_tangents(faces, n_edges, a, b, tan1, tan2);
        }
        _ => {
            tan1.set(-1.0, n_edges, 0);
            tan2.set(-1.0, n_edges, 0);
            tan1.edges[0] = 1.0;
            tan2.edges[1] = 1.0;
        }
    }
}

fn smooth_tangents(n: usize, tan1: &mut Mask, tan2: &mut Mask) {
    tan1.set(0.0, n, n);
    tan2.set(0.0, n, n);
    if n == 4 {
        tan1.edges.copy_from_slice(&[4.0, 0.0, -4.0, 0.0]);
        tan1.faces.copy_from_slice(&[1.0, -1.0, -1.0, 1.0]);
        tan2.edges.copy_from_slice(&[0.0, 4.0, 0.0, -4.0]);
        tan2.faces.copy_from_slice(&[1.0, 1.0, -1.0, -1.0]);
        return;
    }
    let theta = 2.0 * PI / n as f64;
    let (cos_t, cos_half) = (theta.cos(), (theta * 0.5).cos());
    let lambda = 5.0 / 16.0 + (cos_t + cos_half * (2.0 * (9.0 + cos_t)).sqrt()) / 16.0;
    let face_scale = 1.0 / (4.0 * lambda - 1.0);
    for i in 0..n {
        let (ci, cj) = ((i as f64 * theta).cos(), ((i + 1) as f64 * theta).cos());
        tan1.edges[i] = 4.0 * ci;
        tan1.faces[i] = face_scale * (ci + cj);
    }
    // tan2 is tan1 rotated by one position around the vertex.
    for i in 0..n {
        tan2.edges[i] = tan1.edges[(i + n - 1) % n];
        tan2.faces[i] = tan1.faces[(i + n - 1) % n];
    }
}

fn crease_tangents(
    faces: usize,
    edges: usize,
    a: usize,
    b: usize,
    tan1: &mut Mask,
    tan2: &mut Mask,
) {
    // Along the crease, towards the leading crease edge.
    tan1.set(0.0, edges, faces);
    tan1.edges[a] = 0.5;
    tan1.edges[b] = -0.5;
    // Across the faces in the counter-clockwise span from the leading to the trailing edge.
    tan2.set(0.0, edges, faces);
    let interior = b - a - 1;
    if interior == 1 {
        tan2.vertex = -4.0 / 6.0;
        tan2.edges[a] = -1.0 / 6.0;
        tan2.edges[a + 1] = 4.0 / 6.0;
        tan2.edges[b] = -1.0 / 6.0;
        tan2.faces[a] = 1.0 / 6.0;
        tan2.faces[a + 1] = 1.0 / 6.0;
    } else if interior > 1 {
        let k = (interior + 1) as f64;
        let theta = PI / k;
        let (cos_t, sin_t) = (theta.cos(), theta.sin());
        let denom = 1.0 / (k * (3.0 + cos_t));
        let r = (cos_t + 1.0) / sin_t;
        tan2.vertex = 4.0 * r * (cos_t - 1.0) * denom;
        let crease_w = -r * (1.0 + 2.0 * cos_t) * denom;
        tan2.edges[a] = crease_w;
        tan2.edges[b] = crease_w;
        tan2.faces[a] = sin_t * denom;
        for i in 1..=interior {
            let (si, sj) = ((i as f64 * theta).sin(), ((i + 1) as f64 * theta).sin());
            tan2.edges[a + i] = 4.0 * si * denom;
            tan2.faces[a + i] = (si + sj) * denom;
        }
    } else {
        tan2.vertex = -6.0;
        tan2.edges[a] = 3.0;
        tan2.edges[b] = 3.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(m: &Mask) -> f64 {
        m.vertex + m.edges.iter().sum::<f64>() + m.faces.iter().sum::<f64>()
    }

    #[test]
    fn smooth_vertex_weights_match_the_paper() {
        // Valence 3: (n-2)/n = 1/3, 1/9 for each edge end and face point.
        let mut m = Mask::default();
        smooth_vertex_point(3, 3, &mut m);
        assert!((m.vertex - 1.0 / 3.0).abs() < 1e-15);
        assert!(
            m.edges
                .iter()
                .chain(&m.faces)
                .all(|&w| (w - 1.0 / 9.0).abs() < 1e-15)
        );
        assert!((sum(&m) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn semi_sharp_vertex_blends_by_sharpness() {
        // A corner of sharpness 0.25 over a smooth valence-4 vertex: 0.25 corner + 0.75 smooth.
        let (mut m, mut s) = (Mask::default(), Mask::default());
        let zero = [0.0f32; 4];
        let v = VertexNeighbourhood {
            faces: 4,
            parent_rule: Rule::Corner,
            child_rule: Rule::Smooth,
            parent_sharpness: 0.25,
            child_sharpness: 0.0,
            parent_edges: &zero,
            child_edges: &zero,
        };
        vertex_point(CreaseMethod::Uniform, &v, &mut m, &mut s);
        assert!((m.vertex - (0.25 + 0.75 * 0.5)).abs() < 1e-15);
        assert!(m.faces.iter().all(|&w| (w - 0.75 / 16.0).abs() < 1e-15));
        assert!((sum(&m) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn edge_masks_sum_to_one() {
        let mut m = EdgeMask::default();
        for (rule, s) in [
            (Rule::Smooth, 0.0),
            (Rule::Smooth, 0.3),
            (Rule::Crease, 2.0),
        ] {
            edge_point(TriangleRule::Smooth, s, rule, &[3, 4], &mut m);
            let total = 2.0 * m.vertex + m.faces.iter().sum::<f64>();
            assert!((total - 1.0).abs() < 1e-15, "{rule:?} {s}");
        }
        // The blend weight is the single-precision sharpness, as in OpenSubdiv.
        edge_point(TriangleRule::Catmark, 0.3, Rule::Smooth, &[4, 4], &mut m);
        let p = f64::from(0.3f32);
        assert_eq!(m.vertex, p * 0.5 + (1.0 - p) * 0.25);
    }

    #[test]
    fn limit_masks_sum_to_one_and_tangents_to_zero() {
        let (mut p, mut t1, mut t2) = (Mask::default(), Mask::default(), Mask::default());
        for n in [3usize, 4, 5, 7] {
            let edges = vec![0.0f32; n];
            limit_position(Rule::Smooth, n, &edges, &mut p);
            assert!((sum(&p) - 1.0).abs() < 1e-14);
            limit_tangents(Rule::Smooth, n, &edges, &mut t1, &mut t2);
            assert!(
                sum(&t1).abs() < 1e-12 && sum(&t2).abs() < 1e-12,
                "valence {n}"
            );
        }
        let edges = [10.0f32, 0.0, 0.0, 10.0];
        limit_position(Rule::Crease, 3, &edges, &mut p);
        assert!((sum(&p) - 1.0).abs() < 1e-15);
        limit_tangents(Rule::Crease, 3, &edges, &mut t1, &mut t2);
        assert!(sum(&t1).abs() < 1e-14 && sum(&t2).abs() < 1e-12);
    }
}
