//! Limit positions and normals of a refined level (`Far::PrimvarRefiner::Limit`).
//!
//! After at least one refinement every face is a quad, so each vertex's limit point and two
//! limit tangents are masks over its one-ring: itself, the far end of each incident edge and the
//! vertex diagonally opposite in each incident quad (see [`crate::rules::masks`]). The normal is
//! `normalize(tan1 × tan2)`. Semi-sharp features that have not decayed by the last level are
//! taken at their current rule, so refine at least as many levels as the largest sharpness for
//! exact limits (OpenSubdiv behaves the same way).

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::mesh::to_u32;
use crate::rules::masks::{self, Mask};
use crate::sparse::{CHUNK, SparseRows};
use crate::topology::Level;

/// Limit masks of every vertex of a level, as three tables over that level's vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LimitMasks {
    /// Limit positions.
    pub position: SparseRows,
    /// First tangent (towards the leading edge).
    pub tangent1: SparseRows,
    /// Second tangent.
    pub tangent2: SparseRows,
}

impl LimitMasks {
    /// The limit masks of every vertex of `level` (which should have been refined at least once).
    #[must_use]
    pub fn new(level: &Level) -> Self {
        let starts: Vec<usize> = (0..level.vertex_count).step_by(CHUNK).collect();
        let parts: Vec<[SparseRows; 3]> = starts
            .into_par_iter()
            .map(|start| {
                let mut out = [SparseRows::new(), SparseRows::new(), SparseRows::new()];
                let mut masks = [Mask::default(), Mask::default(), Mask::default()];
                let mut ring = Ring::default();
                for v in start..(start + CHUNK).min(level.vertex_count) {
                    vertex_masks(level, v, &mut ring, &mut masks);
                    for (table, mask) in out.iter_mut().zip(&masks) {
                        ring.push_row(v, mask, table);
                    }
                }
                out
            })
            .collect();
        let (mut position, mut tangent1, mut tangent2) = (Vec::new(), Vec::new(), Vec::new());
        for [p, t1, t2] in parts {
            position.push(p);
            tangent1.push(t1);
            tangent2.push(t2);
        }
        Self {
            position: SparseRows::concat(position),
            tangent1: SparseRows::concat(tangent1),
            tangent2: SparseRows::concat(tangent2),
        }
    }

    /// Limit positions and unit normals from the level's positions.
    #[must_use]
    pub fn evaluate(&self, points: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let n = self.position.rows();
        let mut pos = vec![Vector3::zeros(); n];
        let mut t1 = vec![Vector3::zeros(); n];
        let mut t2 = vec![Vector3::zeros(); n];
        self.position.apply(points, &mut pos);
        self.tangent1.apply(points, &mut t1);
        self.tangent2.apply(points, &mut t2);
        let normals = t1.iter().zip(&t2).map(|(a, b)| normal(a, b)).collect();
        (pos, normals)
    }
}

/// `normalize(a × b)`, or zero where the tangents are degenerate.
#[must_use]
pub fn normal(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let n = a.cross(b);
    let len = n.norm();
    if len > 0.0 { n / len } else { Vector3::zeros() }
}

/// The one-ring of a vertex: far ends of its edges, opposite corners of its faces.
#[derive(Default)]
struct Ring {
    edge_ends: Vec<u32>,
    opposite: Vec<u32>,
    sharpness: Vec<f32>,
}

impl Ring {
    fn push_row(&self, v: usize, mask: &Mask, out: &mut SparseRows) {
        for (&q, &w) in self.opposite.iter().zip(&mask.faces) {
            if w != 0.0 {
                out.push(q, w);
            }
        }
        for (&e, &w) in self.edge_ends.iter().zip(&mask.edges) {
            if w != 0.0 {
                out.push(e, w);
            }
        }
        if mask.vertex != 0.0 || (mask.faces.is_empty() && mask.edges.is_empty()) {
            out.push(to_u32(v), mask.vertex);
        }
        out.end_row();
    }
}

fn vertex_masks(level: &Level, v: usize, ring: &mut Ring, masks: &mut [Mask; 3]) {
    let edges = level.vert_edges.row(v);
    let vi = to_u32(v);
    ring.edge_ends.clear();
    ring.edge_ends
        .extend(edges.iter().map(|&e| level.other_end(e, vi)));
    ring.sharpness.clear();
    ring.sharpness
        .extend(edges.iter().map(|&e| level.edge_sharpness[e as usize]));
    ring.opposite.clear();
    for i in level.vert_faces.range(v) {
        let f = level.vert_faces.items[i] as usize;
        let fv = level.face_verts.row(f);
        let local = level.vert_face_local[i] as usize;
        ring.opposite.push(fv[(local + 2) % fv.len()]);
    }
    let [pos, t1, t2] = masks;
    if edges.is_empty() {
        // Isolated vertices stay where they are and have no tangent plane.
        *pos = Mask {
            vertex: 1.0,
            ..Mask::default()
        };
        *t1 = Mask::default();
        *t2 = Mask::default();
        return;
    }
    let rule = level.vertex_rule[v];
    let faces = ring.opposite.len();
    masks::limit_position(rule, faces, &ring.sharpness, pos);
    masks::limit_tangents(rule, faces, &ring.sharpness, t1, t2);
}
