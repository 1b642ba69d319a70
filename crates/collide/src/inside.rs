//! Inside or outside a closed body: signed distance by angle-weighted pseudo-normals
//! (Bærentzen & Aanæs, "Signed distance computation using the angle weighted pseudonormal",
//! IEEE TVCG 2005).
//!
//! For a closed, consistently oriented (outward) triangle mesh, the sign of `(q - c) · n` tells
//! whether `q` is outside, where `c` is the closest point to `q` and `n` the pseudo-normal of the
//! feature `c` lies on: the face normal inside a face, the sum of the two face normals on an
//! edge, and on a vertex the sum of the incident face normals weighted by their angles there.
//! The closest point comes from the hierarchy, so each query is O(log n). An open mesh has no
//! inside; asking is an error.

use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use crate::Point;
use crate::convert::to_glam;
use crate::error::CollideError;
use crate::hierarchy::Hierarchy;
use crate::triangle::is_degenerate;

impl Hierarchy {
    /// Whether every triangle edge is shared by exactly two triangles, so the mesh can enclose a
    /// volume.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        self.open_edges() == 0
    }

    fn open_edges(&self) -> usize {
        self.topology
            .edge_triangle_count
            .iter()
            .filter(|&&n| n != 2)
            .count()
    }

    /// Signed distance from each query point to the mesh at the positions of the last refit:
    /// negative inside, positive outside. The faces must wind counter-clockwise seen from
    /// outside.
    ///
    /// # Errors
    /// [`CollideError::NotClosed`] when the mesh has a boundary or a non-manifold edge,
    /// [`CollideError::NonFiniteQuery`] for a NaN or infinite query point.
    pub fn signed_distances(&self, queries: &[Point]) -> Result<Vec<f64>, CollideError> {
        let open_edges = self.open_edges();
        if open_edges > 0 {
            return Err(CollideError::NotClosed { open_edges });
        }
        let closest = self.closest_points(queries, f64::INFINITY)?;
        let normals = PseudoNormals::new(self);
        Ok(queries
            .par_iter()
            .zip(closest)
            .map(|(q, c)| {
                let Some(c) = c else { return f64::INFINITY };
                let n = normals.at(self, c.triangle as usize, c.barycentric);
                if (to_glam(q) - to_glam(&c.point)).dot(n) < 0.0 {
                    -c.distance
                } else {
                    c.distance
                }
            })
            .collect())
    }
}

/// Angle-weighted vertex normals, edge normals and unit face normals of the fan triangles.
struct PseudoNormals {
    face: Vec<DVec3>,
    vertex: Vec<DVec3>,
    edge: Vec<DVec3>,
}

impl PseudoNormals {
    fn new(h: &Hierarchy) -> Self {
        let topology = &h.topology;
        let face: Vec<DVec3> = (0..topology.triangles.len())
            .map(|t| {
                let corners = h.triangle_at(t, h.end());
                if is_degenerate(corners) {
                    return DVec3::ZERO;
                }
                let [a, b, c] = corners;
                (b - a).cross(c - a).normalize()
            })
            .collect();
        let mut vertex = vec![DVec3::ZERO; topology.vertex_count];
        let mut edge = vec![DVec3::ZERO; topology.edges.len()];
        for (t, corners) in topology.triangles.iter().enumerate() {
            let p = corners.map(|v| h.end()[v as usize]);
            for i in 0..3 {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                let angle = (p[j] - p[i]).angle_between(p[k] - p[i]);
                if angle.is_finite() {
                    vertex[corners[i] as usize] += face[t] * angle;
                }
                edge[edge_index(h, corners[i], corners[j])] += face[t];
            }
        }
        Self { face, vertex, edge }
    }

    /// The pseudo-normal at barycentric `w` on triangle `t`: of its vertex, edge or face.
    fn at(&self, h: &Hierarchy, t: usize, w: [f64; 3]) -> DVec3 {
        let corners = h.topology.triangles[t];
        match w.map(|x| x == 0.0) {
            [false, true, true] => self.vertex[corners[0] as usize],
            [true, false, true] => self.vertex[corners[1] as usize],
            [true, true, false] => self.vertex[corners[2] as usize],
            [true, false, false] => self.edge[edge_index(h, corners[1], corners[2])],
            [false, true, false] => self.edge[edge_index(h, corners[0], corners[2])],
            [false, false, true] => self.edge[edge_index(h, corners[0], corners[1])],
            _ => self.face[t],
        }
    }
}

fn edge_index(h: &Hierarchy, a: u32, b: u32) -> usize {
    let key = [a.min(b), a.max(b)];
    h.topology.edges.binary_search(&key).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit cube `[0, 1]³` as six outward quads.
    fn cube() -> Hierarchy {
        let positions: Vec<Point> = (0..8)
            .map(|i| Point::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let corners = [
            0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5,
        ];
        Hierarchy::build(&positions, &[0, 4, 8, 12, 16, 20, 24], &corners).unwrap()
    }

    #[test]
    fn cube_signed_distances() {
        let h = cube();
        assert!(h.is_closed());
        let queries = [
            Point::new(0.5, 0.5, 0.5),
            Point::new(0.5, 0.5, 0.9),
            Point::new(1.5, 0.5, 0.5),
            Point::new(2.0, 2.0, 0.5),
            Point::new(2.0, 2.0, 2.0),
            Point::new(0.9, 0.9, 0.8),
        ];
        let d = h.signed_distances(&queries).unwrap();
        let expected = [-0.5, -0.1, 0.5, 2f64.sqrt(), 3f64.sqrt(), -0.1];
        for (got, want) in d.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
    }

    #[test]
    fn open_mesh_has_no_inside() {
        let p = [
            Point::origin(),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
        ];
        let h = Hierarchy::build(&p, &[0, 3], &[0, 1, 2]).unwrap();
        assert!(!h.is_closed());
        assert_eq!(
            h.signed_distances(&[Point::origin()]).unwrap_err(),
            CollideError::NotClosed { open_edges: 3 }
        );
    }
}
