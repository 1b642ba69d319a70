//! The weights of every child value over the parent values of one refinement step
//! (OpenSubdiv's `Far::PrimvarRefiner::InterpolateFaceVarying`, `opensubdiv/far/primvarRefiner.h`).
//!
//! - Face points: the centroid of the face's values.
//! - A value whose topology matches its vertex's uses the vertex mask exactly (the row the
//!   vertex refinement built, its columns moved from vertices to the values seen from this
//!   vertex); under `All` it is linear instead: the edge midpoint, or the vertex value itself.
//! - A mismatched edge-point value is the midpoint of the two values of its face.
//! - A mismatched vertex-point value is kept (corner), or gets the crease rule
//!   `¾ V + ⅛ (E_a + E_b)` from its span's end values, blended with the corner by the span's
//!   fractional sharpness while a semi-sharp value decays.
//!
//! Rows are in child value order; a column at or above the parent value count names a child
//! face-point value (as [`crate::refine::Refinement::weights`] does for vertices), so the table
//! is applied with [`crate::refine::apply_two_phase`].

use rayon::prelude::*;

use super::level::{FVarLevel, Mode};
use crate::mesh::to_u32;
use crate::options::CreaseMethod;
use crate::refine::{ChildLayout, Refinement};
use crate::sparse::{CHUNK, SparseRows};
use crate::topology::Level;

/// Everything one step's rows read.
pub(crate) struct Step<'a> {
    pub parent: &'a Level,
    pub refinement: &'a Refinement,
    pub parent_fvar: &'a FVarLevel,
    pub child_fvar: &'a FVarLevel,
    pub mode: Mode,
    pub method: CreaseMethod,
}

impl Step<'_> {
    /// Where the child's vertex-point, face-point and edge-point values start.
    pub(crate) fn layout(&self) -> ChildLayout {
        let faces = self.child_fvar.offsets[self.parent.vertex_count] as usize;
        ChildLayout {
            faces,
            edges: faces + self.parent.face_count(),
        }
    }

    /// All rows, built in parallel chunks of parent components.
    pub(crate) fn weights(&self) -> SparseRows {
        let p = self.parent;
        let rows = |count: usize, row: &(dyn Fn(usize, &mut SparseRows) + Sync)| {
            let chunks: Vec<SparseRows> = (0..count)
                .step_by(CHUNK)
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(|start| {
                    let mut out = SparseRows::new();
                    for i in start..(start + CHUNK).min(count) {
                        row(i, &mut out);
                    }
                    out
                })
                .collect();
            SparseRows::concat(chunks)
        };
        let mut all = rows(p.vertex_count, &|v, out| self.vertex_rows(v, out));
        all.append(&rows(p.face_count(), &|f, out| {
            let values = &self.parent_fvar.face_values[p.face_verts.range(f)];
            let w = 1.0 / values.len() as f64;
            for &x in values {
                out.push(x, w);
            }
            out.end_row();
        }));
        all.append(&rows(p.edge_count(), &|e, out| self.edge_rows(e, out)));
        all
    }

    /// The column of the child face-point value of parent face `f`.
    fn face_column(&self, f: usize) -> u32 {
        to_u32(self.parent_fvar.value_count + self.layout().faces + f)
    }

    /// Copies the vertex refinement's row `row`, mapping the parent vertex at position `k` of
    /// the row to `value_of(k)`. Positions, not vertex indices, identify the mask's points (as
    /// `PrimvarRefiner` does), since a degenerate edge has the same vertex at both ends.
    fn translate(&self, row: usize, value_of: &dyn Fn(usize) -> u32, out: &mut SparseRows) {
        let np = self.parent.vertex_count;
        let first_face = self.refinement.layout.faces;
        let (cols, ws) = self.refinement.weights(self.parent).row(row);
        for (k, (&col, &w)) in cols.iter().zip(ws).enumerate() {
            let col = col as usize;
            let mapped = if col >= np {
                self.face_column(col - np - first_face)
            } else {
                value_of(k)
            };
            out.push(mapped, w);
        }
        out.end_row();
    }

    fn edge_rows(&self, e: usize, out: &mut SparseRows) {
        let (p, pf) = (self.parent, self.parent_fvar);
        let cv = self.refinement.layout.edges + e;
        let count = self.child_fvar.count(cv);
        if !self.child_fvar.tags[self.child_fvar.offsets[cv] as usize].mismatch {
            let ends = pf.edge_face_values(p, e, 0);
            if self.mode.linear {
                midpoint(ends, out);
            } else {
                // The row starts with the two ends, in edge order.
                let row = self.refinement.layout.edges + e;
                self.translate(row, &|k| ends[k], out);
            }
            return;
        }
        for i in 0..count {
            midpoint(pf.edge_face_values(p, e, i), out);
        }
    }

    fn vertex_rows(&self, v: usize, out: &mut SparseRows) {
        let (p, pf, cf) = (self.parent, self.parent_fvar, self.child_fvar);
        let c = &self.refinement.child;
        let cslots = cf.slots(v);
        let pslot0 = pf.offsets[v] as usize;
        if !cf.tags[cslots.start].mismatch {
            let value = pf.first_value(v);
            if self.mode.linear {
                out.push(value, 1.0);
                out.end_row();
            } else {
                // The row holds the face points, the far end of each edge, then the vertex.
                let faces = p.vert_faces.range(v).len();
                let edges = p.vert_edges.range(v).len();
                let value_of = |k: usize| {
                    if k == faces + edges {
                        value
                    } else {
                        pf.vertex_edge_value(p, v, k - faces)
                    }
                };
                self.translate(v, &value_of, out);
            }
            return;
        }
        for (s, cslot) in cslots.enumerate() {
            let value = pf.slot_values[pslot0 + s];
            let ptag = pf.tags[pslot0 + s];
            if self.mode.linear || cf.tags[cslot].is_corner() {
                out.push(value, 1.0);
                out.end_row();
                continue;
            }
            let ends = pf.crease_end_values(p, v, s);
            let (mut wv, mut we) = (0.75, 0.125);
            if ptag.semi_sharp {
                let source = if ptag.dep_sharp {
                    usize::from(s == 0)
                } else {
                    s
                };
                let corner = f64::from(pf.fractional_weight(p, c, self.method, v, source));
                let smooth = 1.0 - corner;
                wv = smooth * 0.75 + corner;
                we = smooth * 0.125;
            }
            out.push(ends[0], we);
            out.push(ends[1], we);
            out.push(value, wv);
            out.end_row();
        }
    }
}

fn midpoint([a, b]: [u32; 2], out: &mut SparseRows) {
    out.push(a, 0.5);
    out.push(b, 0.5);
    out.end_row();
}
