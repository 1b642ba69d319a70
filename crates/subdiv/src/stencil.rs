//! Stencil tables: refined or limit points as weights of the control points (`Far::StencilTable`).
//!
//! Topology is fixed for a whole shot while the control points move every frame, so the
//! refinement steps are composed once into one sparse table per output; a frame is then a single
//! parallel gather ([`StencilTable::apply`]). Composition walks the levels: a child vertex's
//! stencil is the weighted sum of its parents' stencils (and of the face points' just made),
//! accumulated in a dense scratch row and emitted with columns in increasing order, so the result
//! does not depend on the thread count.
//!
//! Rows keep their weight lists in a shared pool ([`SharedRows`]): stencils of regular regions
//! repeat the same weights with other columns, so each distinct list is stored once (in chunks
//! of rows built in parallel). A frame then reads columns and a small, cache-resident pool
//! instead of a weight per entry, about half the bytes (`Far::StencilTable` stores every weight).

use rayon::prelude::*;

use crate::mesh::to_u32;
use crate::refine::Refinement;
use crate::sparse::{CHUNK, Primvar, SharedRows, SharedRowsBuilder, SparseRows};
use crate::topology::Level;

/// Rows of weights over the control points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StencilTable {
    /// One row per output point.
    pub rows: SharedRows,
    /// Number of control points the rows refer to.
    pub control_points: usize,
}

impl StencilTable {
    /// The identity over `n` control points (level 0).
    #[must_use]
    pub fn identity(n: usize) -> Self {
        let mut rows = SharedRowsBuilder::default();
        for i in 0..n {
            rows.push_row(&[to_u32(i)], &[1.0]);
        }
        Self {
            rows: rows.finish(),
            control_points: n,
        }
    }

    /// Number of output points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.rows.rows()
    }

    /// True when the table has no rows.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Evaluates every output point from the control points, in parallel.
    ///
    /// # Panics
    /// If `control` or `out` do not have the table's sizes.
    pub fn apply<T: Primvar>(&self, control: &[T], out: &mut [T]) {
        assert_eq!(control.len(), self.control_points, "control point count");
        self.rows.apply(control, out);
    }

    /// The stencils of a refinement's child level, given this table for its parent level
    /// (`parent` is the level the step refined).
    #[must_use]
    pub fn refine(&self, parent: &Level, step: &Refinement) -> Self {
        let weights = step.weights(parent);
        let layout = step.layout;
        let np = self.len();
        let n = self.control_points;
        let face_rows = compose_rows(n, layout.faces..layout.edges, &|row, acc| {
            let (cols, ws) = weights.row(row);
            for (&c, &w) in cols.iter().zip(ws) {
                acc.add(self.rows.row(c as usize), w);
            }
        });
        let other = |range: std::ops::Range<usize>| {
            compose_rows(n, range, &|row, acc| {
                let (cols, ws) = weights.row(row);
                for (&c, &w) in cols.iter().zip(ws) {
                    let c = c as usize;
                    if c < np {
                        acc.add(self.rows.row(c), w);
                    } else {
                        acc.add(face_rows.row(c - np - layout.faces), w);
                    }
                }
            })
        };
        let vertex_rows = other(0..layout.faces);
        let edge_rows = other(layout.edges..step.child.vertex_count);
        Self {
            rows: SharedRows::concat(vec![vertex_rows, face_rows, edge_rows]),
            control_points: n,
        }
    }

    /// Composes a table over this table's outputs (limit masks, say) with this table.
    #[must_use]
    pub fn then(&self, outer: &SparseRows) -> Self {
        let rows = compose_rows(self.control_points, 0..outer.rows(), &|row, acc| {
            let (cols, ws) = outer.row(row);
            for (&c, &w) in cols.iter().zip(ws) {
                acc.add(self.rows.row(c as usize), w);
            }
        });
        Self {
            rows,
            control_points: self.control_points,
        }
    }

    /// Memory held, in bytes.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.rows.bytes()
    }
}

/// A dense accumulator for one output row.
struct Accumulator {
    weights: Vec<f64>,
    touched: Vec<u32>,
    row_weights: Vec<f64>,
}

impl Accumulator {
    /// Adds `w` times a row (columns, weights).
    fn add(&mut self, (cols, ws): (&[u32], &[f64]), w: f64) {
        for (&c, &x) in cols.iter().zip(ws) {
            let slot = &mut self.weights[c as usize];
            if *slot == 0.0 {
                self.touched.push(c);
            }
            *slot += w * x;
            // A weight that cancels to exactly zero is re-touched harmlessly: emit dedups.
        }
    }

    /// Writes the accumulated row, columns in increasing order and zero weights dropped, and
    /// clears the accumulator.
    fn emit(&mut self, out: &mut SharedRowsBuilder) {
        self.touched.sort_unstable();
        self.touched.dedup();
        self.row_weights.clear();
        let weights = &mut self.weights;
        let row_weights = &mut self.row_weights;
        self.touched.retain(|&c| {
            let w = std::mem::take(&mut weights[c as usize]);
            if w != 0.0 {
                row_weights.push(w);
            }
            w != 0.0
        });
        out.push_row(&self.touched, &self.row_weights);
        self.touched.clear();
    }
}

fn compose_rows(
    control_points: usize,
    range: std::ops::Range<usize>,
    row: &(dyn Fn(usize, &mut Accumulator) + Sync),
) -> SharedRows {
    let starts: Vec<usize> = range.clone().step_by(CHUNK).collect();
    let parts = starts
        .into_par_iter()
        .map_init(
            || Accumulator {
                weights: vec![0.0; control_points],
                touched: Vec::new(),
                row_weights: Vec::new(),
            },
            |acc, start| {
                let mut out = SharedRowsBuilder::default();
                for r in start..(start + CHUNK).min(range.end) {
                    row(r, acc);
                    acc.emit(&mut out);
                }
                out.finish()
            },
        )
        .collect();
    SharedRows::concat(parts)
}
