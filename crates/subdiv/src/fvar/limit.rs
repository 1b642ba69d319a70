//! Limit values of the last level's face-varying values
//! (`Far::PrimvarRefiner::LimitFaceVarying`, `opensubdiv/far/primvarRefiner.h`).
//!
//! A value matching its vertex takes the vertex's limit mask (see
//! [`crate::rules::masks::limit_position`]) over the values seen from it; a crease value takes
//! `⅔ V + ⅙ (E_a + E_b)` from its crease end values; corners, isolated vertices and everything
//! in mode `All` stay where they are.

use rayon::prelude::*;

use super::level::FVarLevel;
use crate::rules::masks::{self, Mask};
use crate::sparse::{CHUNK, SparseRows};
use crate::topology::Level;

impl FVarLevel {
    /// One row per value of `l` (the last, all-quad level) over the same values.
    pub(crate) fn limit_weights(&self, l: &Level, linear: bool) -> SparseRows {
        let chunks: Vec<SparseRows> = (0..l.vertex_count)
            .step_by(CHUNK)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|start| {
                let (mut out, mut mask, mut sharpness) =
                    (SparseRows::new(), Mask::default(), Vec::new());
                for v in start..(start + CHUNK).min(l.vertex_count) {
                    self.limit_rows(l, v, linear, &mut mask, &mut sharpness, &mut out);
                }
                out
            })
            .collect();
        SparseRows::concat(chunks)
    }

    fn limit_rows(
        &self,
        l: &Level,
        v: usize,
        linear: bool,
        mask: &mut Mask,
        sharpness: &mut Vec<f32>,
        out: &mut SparseRows,
    ) {
        let edges = l.vert_edges.row(v);
        let slots = self.slots(v);
        let keep = |out: &mut SparseRows, slot: usize| {
            out.push(self.slot_values[slot], 1.0);
            out.end_row();
        };
        if edges.is_empty() || linear {
            slots.for_each(|s| keep(out, s));
            return;
        }
        if !self.tags[slots.start].mismatch {
            sharpness.clear();
            sharpness.extend(edges.iter().map(|&e| l.edge_sharpness[e as usize]));
            let faces = l.vert_faces.range(v);
            masks::limit_position(l.vertex_rule[v], faces.len(), sharpness, mask);
            for (i, &w) in faces.zip(&mask.faces) {
                let r = l.face_verts.range(l.vert_faces.items[i] as usize);
                let opposite = (l.vert_face_local[i] as usize + 2) % r.len();
                out.push(self.face_values[r.start + opposite], w);
            }
            for (i, &w) in mask.edges.iter().enumerate() {
                out.push(self.vertex_edge_value(l, v, i), w);
            }
            out.push(self.slot_values[slots.start], mask.vertex);
            out.end_row();
            return;
        }
        for (s, slot) in slots.enumerate() {
            if self.tags[slot].is_corner() {
                keep(out, slot);
                continue;
            }
            let [a, b] = self.crease_end_values(l, v, s);
            out.push(a, 1.0 / 6.0);
            out.push(b, 1.0 / 6.0);
            out.push(self.slot_values[slot], 2.0 / 3.0);
            out.end_row();
        }
    }
}
