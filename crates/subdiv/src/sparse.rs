//! Sparse weight tables and the values they combine.
//!
//! Every linear map in the crate — one refinement step, a stencil table from control points to
//! refined or limit points, a face-varying step — is a [`SparseRows`] table: one row per output
//! value, each a list of (input index, weight). Applying a table is a gather, parallel over rows
//! and independent of the thread count (each row is summed in its own fixed order).

use std::collections::HashMap;

use nalgebra::{Point3, SVector};
use rayon::prelude::*;

use crate::csr::{Csr, offsets_from_lengths};

/// A value that can be interpolated: positions, UVs, scalar fields.
pub trait Primvar: Copy + Send + Sync {
    /// The additive identity.
    fn zero() -> Self;
    /// `self += w * other`.
    fn add_scaled(&mut self, other: &Self, w: f64);
    /// The value's components (one for a scalar, two for a UV, three for a point), so that
    /// kernels can work on plain arrays of them.
    fn components(&self) -> &[f64];
    /// The value's components, to write.
    fn components_mut(&mut self) -> &mut [f64];
}

impl Primvar for f64 {
    #[inline]
    fn zero() -> Self {
        0.0
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, w: f64) {
        *self += w * other;
    }
    #[inline]
    fn components(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
    #[inline]
    fn components_mut(&mut self) -> &mut [f64] {
        std::slice::from_mut(self)
    }
}

/// Vectors of any size (UVs, directions): component by component.
impl<const D: usize> Primvar for SVector<f64, D> {
    #[inline]
    fn zero() -> Self {
        Self::zeros()
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, w: f64) {
        for (a, b) in self.iter_mut().zip(other.iter()) {
            *a += w * b;
        }
    }
    #[inline]
    fn components(&self) -> &[f64] {
        self.as_slice()
    }
    #[inline]
    fn components_mut(&mut self) -> &mut [f64] {
        self.as_mut_slice()
    }
}

impl Primvar for Point3<f64> {
    #[inline]
    fn zero() -> Self {
        Self::origin()
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, w: f64) {
        self.coords.add_scaled(&other.coords, w);
    }
    #[inline]
    fn components(&self) -> &[f64] {
        self.coords.as_slice()
    }
    #[inline]
    fn components_mut(&mut self) -> &mut [f64] {
        self.coords.as_mut_slice()
    }
}

/// Rows of (column, weight) pairs in CSR form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SparseRows {
    /// Row starts; one more than the number of rows.
    pub offsets: Vec<u32>,
    /// Column of each entry.
    pub cols: Vec<u32>,
    /// Weight of each entry.
    pub weights: Vec<f64>,
}

/// Rows per parallel task: large enough to amortise scheduling, small enough to balance.
pub(crate) const CHUNK: usize = 4096;

impl SparseRows {
    /// An empty table ready for [`Self::push`].
    #[must_use]
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            cols: Vec::new(),
            weights: Vec::new(),
        }
    }

    /// Number of rows.
    #[must_use]
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of stored weights.
    #[must_use]
    pub fn entries(&self) -> usize {
        self.cols.len()
    }

    /// Row `i` as (columns, weights).
    #[must_use]
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        (&self.cols[r.clone()], &self.weights[r])
    }

    /// Builds a table whose row lengths are known in advance, filling rows in parallel
    /// straight into their final place (no per-chunk buffers, no copies).
    ///
    /// `fill(row, cols, weights)` must write every slot of its row.
    pub fn from_lengths(
        rows: usize,
        length: impl Fn(usize) -> usize + Sync,
        fill: impl Fn(usize, &mut [u32], &mut [f64]) + Sync,
    ) -> Self {
        let offsets = offsets_from_lengths(rows, length);
        let total = *offsets.last().expect("offsets start at 0") as usize;
        let mut cols = vec![0u32; total];
        let mut weights = vec![0.0f64; total];
        fill_rows(&offsets, &mut cols, &mut weights, fill);
        Self {
            offsets,
            cols,
            weights,
        }
    }

    /// Adds one entry to the row being built.
    pub fn push(&mut self, col: u32, weight: f64) {
        self.cols.push(col);
        self.weights.push(weight);
    }

    /// Closes the row being built.
    pub fn end_row(&mut self) {
        self.offsets.push(crate::mesh::to_u32(self.cols.len()));
    }

    /// Appends all rows of `other`.
    pub fn append(&mut self, other: &Self) {
        let base = *self.offsets.last().expect("offsets start at 0");
        self.offsets
            .extend(other.offsets[1..].iter().map(|o| o + base));
        self.cols.extend_from_slice(&other.cols);
        self.weights.extend_from_slice(&other.weights);
    }

    /// Concatenates tables built in parallel chunks, in order, with one allocation per array.
    #[must_use]
    pub fn concat(parts: Vec<Self>) -> Self {
        let rows: usize = parts.iter().map(Self::rows).sum();
        let entries: usize = parts.iter().map(Self::entries).sum();
        let mut all = Self {
            offsets: Vec::with_capacity(rows + 1),
            cols: Vec::with_capacity(entries),
            weights: Vec::with_capacity(entries),
        };
        all.offsets.push(0);
        for p in &parts {
            all.append(p);
        }
        all
    }

    /// The weighted sum of row `i` over `src`.
    #[must_use]
    #[inline]
    pub fn gather<T: Primvar>(&self, i: usize, src: &[T]) -> T {
        weighted_sum(self.row(i), src)
    }

    /// `dst[i] = Σ w · src[col]` for every row, in parallel.
    pub fn apply<T: Primvar>(&self, src: &[T], dst: &mut [T]) {
        apply_rows(self.rows(), |i| self.row(i), src, dst);
    }

    /// Memory held, in bytes.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.offsets.len() * 4 + self.cols.len() * 4 + self.weights.len() * 8
    }
}

/// `Σ w · src[col]` over one row.
#[inline]
pub(crate) fn weighted_sum<T: Primvar>((cols, weights): (&[u32], &[f64]), src: &[T]) -> T {
    let mut acc = T::zero();
    for (&c, &w) in cols.iter().zip(weights) {
        acc.add_scaled(&src[c as usize], w);
    }
    acc
}

/// `dst[i] = Σ w · src[col]` over every row `i` (given by `row`) of a table, in parallel
/// fixed-size chunks.
pub(crate) fn apply_rows<'a, T: Primvar>(
    rows: usize,
    row: impl Fn(usize) -> (&'a [u32], &'a [f64]) + Sync,
    src: &[T],
    dst: &mut [T],
) {
    assert_eq!(dst.len(), rows, "destination length");
    dst.par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(chunk, out)| {
            let base = chunk * CHUNK;
            for (k, d) in out.iter_mut().enumerate() {
                *d = weighted_sum(row(base + k), src);
            }
        });
}

/// Sparse rows whose weight lists are stored once per distinct list: row `i` has the columns
/// `cols.row(i)` and as many weights from `weights[weight_starts[i]..]`.
///
/// Stencils of a mesh come in few shapes (every regular interior vertex of a level has the
/// same weights, only its columns differ), so sharing the weights cuts a stencil table's
/// memory, and the bytes read per evaluation, by more than half.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SharedRows {
    /// The columns of each row.
    pub cols: Csr,
    /// Where each row's weights start in `weights`.
    pub weight_starts: Vec<u32>,
    /// The distinct weight lists, one after another.
    pub weights: Vec<f64>,
}

impl SharedRows {
    /// Number of rows.
    #[must_use]
    pub fn rows(&self) -> usize {
        self.weight_starts.len()
    }

    /// Row `i` as (columns, weights).
    #[must_use]
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let cols = self.cols.row(i);
        let w = self.weight_starts[i] as usize;
        (cols, &self.weights[w..w + cols.len()])
    }

    /// `dst[i] = Σ w · src[col]` for every row, in parallel.
    pub fn apply<T: Primvar>(&self, src: &[T], dst: &mut [T]) {
        apply_rows(self.rows(), |i| self.row(i), src, dst);
    }

    /// Concatenates tables built in parallel chunks, in order.
    #[must_use]
    pub fn concat(parts: Vec<Self>) -> Self {
        let sum = |f: fn(&Self) -> usize| parts.iter().map(f).sum::<usize>();
        let mut all = Self {
            cols: Csr {
                offsets: Vec::with_capacity(sum(Self::rows) + 1),
                items: Vec::with_capacity(sum(|p| p.cols.items.len())),
            },
            weight_starts: Vec::with_capacity(sum(Self::rows)),
            weights: Vec::with_capacity(sum(|p| p.weights.len())),
        };
        all.cols.offsets.push(0);
        for p in &parts {
            let col_base = crate::mesh::to_u32(all.cols.items.len());
            let weight_base = crate::mesh::to_u32(all.weights.len());
            all.cols
                .offsets
                .extend(p.cols.offsets[1..].iter().map(|o| o + col_base));
            all.cols.items.extend_from_slice(&p.cols.items);
            all.weight_starts
                .extend(p.weight_starts.iter().map(|w| w + weight_base));
            all.weights.extend_from_slice(&p.weights);
        }
        all
    }

    /// Memory held, in bytes.
    #[must_use]
    pub fn bytes(&self) -> usize {
        (self.cols.offsets.len() + self.cols.items.len() + self.weight_starts.len()) * 4
            + self.weights.len() * 8
    }
}

/// Builds [`SharedRows`] row by row, storing each distinct weight list (bit for bit) once.
#[derive(Default)]
pub(crate) struct SharedRowsBuilder {
    rows: SharedRows,
    seen: HashMap<Vec<u64>, u32>,
    key: Vec<u64>,
}

impl SharedRowsBuilder {
    /// Appends a row.
    pub(crate) fn push_row(&mut self, cols: &[u32], weights: &[f64]) {
        debug_assert_eq!(cols.len(), weights.len());
        let rows = &mut self.rows;
        if rows.cols.offsets.is_empty() {
            rows.cols.offsets.push(0);
        }
        self.key.clear();
        self.key.extend(weights.iter().map(|w| w.to_bits()));
        let start = match self.seen.get(self.key.as_slice()) {
            Some(&start) => start,
            None => {
                let start = crate::mesh::to_u32(rows.weights.len());
                rows.weights.extend_from_slice(weights);
                self.seen.insert(self.key.clone(), start);
                start
            }
        };
        rows.cols.items.extend_from_slice(cols);
        rows.cols
            .offsets
            .push(crate::mesh::to_u32(rows.cols.items.len()));
        rows.weight_starts.push(start);
    }

    /// The rows built.
    pub(crate) fn finish(mut self) -> SharedRows {
        if self.rows.cols.offsets.is_empty() {
            self.rows.cols.offsets.push(0);
        }
        self.rows
    }
}

/// Fills two arrays laid out by CSR `offsets` row by row, in parallel: `fill(row, a, b)` gets
/// that row's slices of both. Rows are cut into fixed chunks, so the work split, and therefore
/// the result, does not depend on the thread count.
pub(crate) fn fill_rows<A: Send, B: Send>(
    offsets: &[u32],
    a: &mut [A],
    b: &mut [B],
    fill: impl Fn(usize, &mut [A], &mut [B]) + Sync,
) {
    let rows = offsets.len() - 1;
    let mut tasks = Vec::with_capacity(rows.div_ceil(CHUNK));
    let (mut a_rest, mut b_rest) = (a, b);
    for start in (0..rows).step_by(CHUNK) {
        let end = (start + CHUNK).min(rows);
        let len = (offsets[end] - offsets[start]) as usize;
        let (x, xr) = a_rest.split_at_mut(len);
        let (y, yr) = b_rest.split_at_mut(len);
        (a_rest, b_rest) = (xr, yr);
        tasks.push((start, end, x, y));
    }
    tasks.into_par_iter().for_each(|(start, end, x, y)| {
        let base = offsets[start] as usize;
        for r in start..end {
            let range = offsets[r] as usize - base..offsets[r + 1] as usize - base;
            fill(r, &mut x[range.clone()], &mut y[range]);
        }
    });
}
