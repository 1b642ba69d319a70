//! A symmetric block-sparse matrix of 3×3 blocks, as Baraff & Witkin 1998 (§5) use for cloth.
//!
//! Rows are particles; the sparsity pattern (which particles share an element) is fixed by the
//! topology and built once ([`BlockMatrix::from_pairs`]); only the values change each step.
//! Both triangles are stored (CSR of blocks, columns sorted), so the product is a parallel
//! loop over rows with a fixed order inside each row: the same bytes on any thread count.

use rayon::prelude::*;
use tailor_subdiv::topology::Csr;

use crate::energy::{Mat3, Vec3};
use crate::reduce::CHUNK;

/// A square matrix of 3×3 blocks in CSR form.
#[derive(Clone, Debug)]
pub struct BlockMatrix {
    pattern: Csr,
    /// Row of each stored block.
    rows: Vec<u32>,
    blocks: Vec<Mat3>,
}

impl BlockMatrix {
    /// The pattern holding every diagonal block of `n` rows and both (i, j) and (j, i) for every
    /// pair given; values zero.
    #[must_use]
    pub fn from_pairs(n: usize, pairs: impl IntoIterator<Item = (u32, u32)>) -> Self {
        let mut all: Vec<(u32, u32)> = (0..n as u32).map(|i| (i, i)).collect();
        for (i, j) in pairs {
            all.push((i, j));
            all.push((j, i));
        }
        all.sort_unstable();
        all.dedup();
        let pattern = csr_from_sorted(n, &all);
        let rows = all.iter().map(|&(i, _)| i).collect();
        Self {
            blocks: vec![Mat3::zeros(); all.len()],
            pattern,
            rows,
        }
    }

    /// Number of block rows.
    #[must_use]
    pub fn size(&self) -> usize {
        self.pattern.rows()
    }

    /// The slot of block (i, j) in [`Self::blocks`], if it is in the pattern.
    #[must_use]
    pub fn slot(&self, i: u32, j: u32) -> Option<usize> {
        let range = self.pattern.range(i as usize);
        let cols = &self.pattern.items[range.clone()];
        cols.binary_search(&j).ok().map(|k| range.start + k)
    }

    /// Block (i, j), zero outside the pattern.
    #[must_use]
    pub fn block(&self, i: u32, j: u32) -> Mat3 {
        self.slot(i, j).map_or_else(Mat3::zeros, |s| self.blocks[s])
    }

    /// Row and column of the block in `slot`.
    #[must_use]
    pub fn entry(&self, slot: usize) -> (u32, u32) {
        (self.rows[slot], self.pattern.items[slot])
    }

    /// Slots of the blocks stored in row `i`.
    #[must_use]
    pub fn row_range(&self, i: usize) -> std::ops::Range<usize> {
        self.pattern.range(i)
    }

    /// Columns of the blocks stored in row `i`, sorted.
    #[must_use]
    pub fn columns(&self, i: usize) -> &[u32] {
        self.pattern.row(i)
    }

    /// All stored blocks, row after row.
    #[must_use]
    pub fn blocks(&self) -> &[Mat3] {
        &self.blocks
    }

    /// Row and column of each stored block, parallel to [`Self::blocks`].
    pub fn entries(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.rows
            .iter()
            .copied()
            .zip(self.pattern.items.iter().copied())
    }

    /// Fills every block with `f(slot, row, column)`, in parallel.
    pub fn fill(&mut self, f: impl Fn(usize, u32, u32) -> Mat3 + Sync) {
        let (rows, cols) = (&self.rows, &self.pattern.items);
        self.blocks
            .par_iter_mut()
            .enumerate()
            .for_each(|(s, b)| *b = f(s, rows[s], cols[s]));
    }

    /// y = A x.
    pub fn mul_into(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| self.mul_rows(c * CHUNK, x, y));
    }

    /// Rows `first..first + y.len()` of A x into `y`.
    pub fn mul_rows(&self, first: usize, x: &[Vec3], y: &mut [Vec3]) {
        for (i, yi) in (first..).zip(y) {
            let range = self.pattern.range(i);
            let mut sum = Vec3::zeros();
            for (block, &col) in self.blocks[range.clone()]
                .iter()
                .zip(&self.pattern.items[range])
            {
                sum += block * x[col as usize];
            }
            *yi = sum;
        }
    }
}

/// A CSR table of `rows` rows from (row, item) pairs sorted by row.
pub(crate) fn csr_from_sorted(rows: usize, pairs: &[(u32, u32)]) -> Csr {
    let mut offsets = vec![0u32; rows + 1];
    for &(r, _) in pairs {
        offsets[r as usize + 1] += 1;
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    Csr {
        offsets,
        items: pairs.iter().map(|&(_, item)| item).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_matches_dense() {
        let mut a = BlockMatrix::from_pairs(3, [(0, 2), (2, 1)]);
        assert_eq!(a.blocks().len(), 3 + 4);
        assert!(a.slot(0, 1).is_none());
        a.fill(|s, i, j| Mat3::from_fn(|r, c| (s + 3 * r + c) as f64 + f64::from(i + 10 * j)));
        let x = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, 0.5, 0.0),
            Vec3::new(0.0, 1.0, -2.0),
        ];
        let mut y = [Vec3::zeros(); 3];
        a.mul_into(&x, &mut y);
        for i in 0..3u32 {
            let mut expect = Vec3::zeros();
            for j in 0..3u32 {
                expect += a.block(i, j) * x[j as usize];
            }
            assert_eq!(y[i as usize], expect);
        }
    }
}
