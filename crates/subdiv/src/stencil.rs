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

use crate::csr::Csr;
use crate::mesh::to_u32;
use crate::refine::Refinement;
use crate::sparse::{CHUNK, Primvar, SharedRows, SharedRowsBuilder, SparseRows, weighted_sum};
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

/// A stencil table's output for control points that move a few at a time (the collision
/// passes of a substep move the control points they push, lift or relax, and ask for the
/// refined surface again): after the first evaluation, only the rows that read a control
/// point whose bits changed since the last are computed again, by the arithmetic of
/// [`StencilTable::apply`], so the points are the same bits as applying the whole table.
#[derive(Clone, Debug, Default)]
pub struct Refreshed<T> {
    /// Per control point, the rows that read it (the table's columns transposed).
    readers: Csr,
    /// The control points of the last evaluation; empty before the first.
    control: Vec<T>,
    points: Vec<T>,
    /// The rows to compute again, each once.
    rows: Vec<u32>,
    listed: Vec<bool>,
}

impl<T: Primvar> Refreshed<T> {
    /// Nothing evaluated yet, for `table`'s rows.
    #[must_use]
    pub fn new(table: &StencilTable) -> Self {
        let readers = Csr::group_by(
            table.control_points,
            (0..table.len()).flat_map(|r| table.rows.row(r).0.iter().map(move |&c| (c, to_u32(r)))),
        );
        Self {
            readers,
            control: Vec::new(),
            points: Vec::new(),
            rows: Vec::new(),
            listed: vec![false; table.len()],
        }
    }

    /// The points of the last [`Self::update`].
    #[must_use]
    pub fn points(&self) -> &[T] {
        &self.points
    }

    /// `table` (the one this was made for) applied to `control`: all of it the first time,
    /// after that the rows reading a control point that changed, or all of it in parallel
    /// when a quarter of the rows do.
    ///
    /// # Panics
    /// If `control` does not have the table's control point count.
    pub fn update(&mut self, table: &StencilTable, control: &[T]) -> &[T] {
        assert_eq!(control.len(), table.control_points, "control point count");
        let n = table.len();
        if self.control.len() == control.len() {
            let same = |a: &T, b: &T| {
                a.components()
                    .iter()
                    .zip(b.components())
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            };
            self.rows.clear();
            for (j, (was, is)) in self.control.iter().zip(control).enumerate() {
                if same(was, is) {
                    continue;
                }
                for &r in self.readers.row(j) {
                    if !std::mem::replace(&mut self.listed[r as usize], true) {
                        self.rows.push(r);
                    }
                }
                if self.rows.len() > n / 4 {
                    break;
                }
            }
            for &r in &self.rows {
                self.listed[r as usize] = false;
            }
            if self.rows.len() <= n / 4 {
                for &r in &self.rows {
                    self.points[r as usize] = weighted_sum(table.rows.row(r as usize), control);
                }
                self.control.copy_from_slice(control);
                return &self.points;
            }
        }
        self.points.resize(n, T::zero());
        table.apply(control, &mut self.points);
        self.control.clear();
        self.control.extend_from_slice(control);
        &self.points
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
