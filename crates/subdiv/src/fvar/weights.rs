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

    /// Copies the vertex refinement's row `row`, mapping parent vertex `v`'s columns to values.
    fn translate(&self, row: usize, value_of: &dyn Fn(u32) -> u32, out: &mut SparseRows) {
        let np = self.parent.vertex_count;
        let first_face = self.refinement.layout.faces;
        let (cols, ws) = self.refinement.weights(self.parent).row(row);
        for (&col, &w) in cols.iter().zip(ws) {
            let col = col as usize;
            let mapped = if col >= np {
                self.face_column(col - np - first_face)
            } else {
                value_of(to_u32(col))
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
                let a = p.edge_verts[e][0];
                let row = self.refinement.layout.edges + e;
                self.translate(row, &|u| if u == a { ends[0] } else { ends[1] }, out);
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
                let vi = to_u32(v);
                let edges = p.vert_edges.row(v);
                let value_of = |u: u32| {
                    if u == vi {
                        return value;
                    }
                    let i = edges
                        .iter()
                        .position(|&e| p.other_end(e, vi) == u)
                        .expect("mask column is a neighbour");
                    pf.vertex_edge_value(p, v, i)
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
