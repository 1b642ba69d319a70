//! Attachments: garment vertices that ride on the body.
//!
//! At the first frame each attached vertex is bound to the nearest triangle of the refined
//! body (`tailor_collide::Hierarchy::closest_points`): the barycentric coordinates of the
//! nearest point, and the vertex's offset from it in the triangle's own frame (first edge,
//! normal, and their cross product). The garment is modelled a centimetre or two off the body,
//! so keeping the offset leaves the vertex where it was modelled instead of snapping it onto the
//! skin; and since the frame turns with the triangle, the vertex follows the body's rotation
//! as well as its translation. Every frame the goal is rebuilt from the posed triangle.

use anyhow::{Context, Result, bail};
use tailor_cloth::Attachment;
use tailor_cloth::Vec3;
use tailor_collide::Hierarchy;
use tailor_subdiv::Point;

/// One garment vertex bound to a body triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Binding {
    vertex: u32,
    triangle: [u32; 3],
    barycentric: [f64; 3],
    /// Offset from the bound point along the triangle frame's axes.
    offset: [f64; 3],
}

/// The bindings of every attached vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bindings(Vec<Binding>);

/// The bound point on a posed triangle and the triangle's orthonormal frame, or `None` for a
/// triangle collapsed to a line or a point.
fn frame(body: &[Point], b: &Binding) -> Option<(Point, [Vec3; 3])> {
    let [a, p, q] = b.triangle.map(|v| body[v as usize]);
    let point = Point::from(
        a.coords * b.barycentric[0] + p.coords * b.barycentric[1] + q.coords * b.barycentric[2],
    );
    let e1 = (p - a).try_normalize(0.0)?;
    let n = (p - a).cross(&(q - a)).try_normalize(0.0)?;
    Some((point, [e1, n.cross(&e1), n]))
}

impl Bindings {
    /// Binds `vertices` at positions `cloth` to the body at `body` (the positions `hierarchy`
    /// was last refit at).
    ///
    /// # Errors
    /// When a query fails or a vertex's nearest triangle has no area.
    pub fn new(
        hierarchy: &Hierarchy,
        body: &[Point],
        cloth: &[Point],
        vertices: &[u32],
    ) -> Result<Self> {
        let queries: Vec<Point> = vertices.iter().map(|&v| cloth[v as usize]).collect();
        let closest = hierarchy
            .closest_points(&queries, f64::INFINITY)
            .context("binding attached vertices to the body")?;
        let mut out = Vec::with_capacity(vertices.len());
        for ((&vertex, query), hit) in vertices.iter().zip(&queries).zip(closest) {
            let Some(hit) = hit else {
                bail!("attached vertex {vertex} found no body triangle to bind to");
            };
            let mut binding = Binding {
                vertex,
                triangle: hit.vertices,
                barycentric: hit.barycentric,
                offset: [0.0; 3],
            };
            let Some((point, axes)) = frame(body, &binding) else {
                bail!("attached vertex {vertex} is nearest to a body triangle without area");
            };
            let d = query - point;
            binding.offset = axes.map(|axis| axis.dot(&d));
            out.push(binding);
        }
        Ok(Self(out))
    }

    /// Where each attached vertex should be when the body is at `body`. A triangle that
    /// collapses in the animation keeps its bound point and drops the offset.
    #[must_use]
    pub fn goals(&self, body: &[Point]) -> Vec<Point> {
        self.0
            .iter()
            .map(|b| match frame(body, b) {
                Some((point, axes)) => {
                    point + axes[0] * b.offset[0] + axes[1] * b.offset[1] + axes[2] * b.offset[2]
                }
                None => {
                    let [a, p, q] = b.triangle.map(|v| body[v as usize].coords);
                    Point::from(a * b.barycentric[0] + p * b.barycentric[1] + q * b.barycentric[2])
                }
            })
            .collect()
    }

    /// Attachment targets for the step from the body at `start` to the body at `end`, `dt`
    /// seconds later: each goal moves on the straight line between the two poses.
    #[must_use]
    pub fn targets(&self, start: &[Point], end: &[Point], dt: f64) -> Vec<Attachment> {
        let from = self.goals(start);
        let to = self.goals(end);
        self.0
            .iter()
            .zip(from.iter().zip(&to))
            .map(|(b, (from, to))| Attachment {
                vertex: b.vertex,
                position: *from,
                velocity: (to - from) / dt,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};

    #[test]
    fn bound_vertices_keep_their_offset_as_the_body_turns() {
        let body = vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
        ];
        let h = Hierarchy::build(&body, &[0, 3], &[0, 1, 2]).unwrap();
        let cloth = vec![Point::new(0.25, 0.25, 0.1), Point::new(2.0, 0.0, 0.0)];
        let bindings = Bindings::new(&h, &body, &cloth, &[0, 1]).unwrap();
        let goals = bindings.goals(&body);
        assert!((goals[0] - cloth[0]).norm() < 1e-12);
        assert!((goals[1] - cloth[1]).norm() < 1e-12);
        let turn = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.5);
        let moved: Vec<Point> = body.iter().map(|p| turn * p + Vector3::z()).collect();
        let goals = bindings.goals(&moved);
        let expected = turn * cloth[0] + Vector3::z();
        assert!((goals[0] - expected).norm() < 1e-12);
        let targets = bindings.targets(&body, &moved, 0.5);
        assert_eq!(targets[0].position, bindings.goals(&body)[0]);
        assert!((targets[0].position + targets[0].velocity * 0.5 - expected).norm() < 1e-12);
    }
}
