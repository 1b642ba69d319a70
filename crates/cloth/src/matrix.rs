//! Block-sparse matrices of 3×3 blocks, as Baraff & Witkin 1998 (§5) use for cloth.
//!
//! Rows are particles; the sparsity pattern (which particles share an element) is fixed by the
//! topology and built once; only the values change each step. The pattern is CSR over *slots*,
//! every (i, j) position of the matrix, columns sorted in each row. A general matrix
//! ([`BlockMatrix::from_pairs`]: the multigrid's coarse levels) stores a block per slot. A
//! symmetric one ([`BlockMatrix::symmetric`]: the implicit system) stores the diagonal and the
//! blocks above it, and each slot below the diagonal reads the block of its mirror, transposed:
//! half the bytes, which is what a product with the 128² system is bound by (the blocks of
//! the rows just above, whose mirrors a row reads, are still in cache), and the same numbers
//! as storing both triangles, since the assembled matrix is symmetric to the last bit (a
//! block and its transpose sum the same element terms in the same order).
//!
//! The implicit system stores its blocks in single precision ([`Precision`]), the coarse
//! levels of its multigrid in double; products, sums and everything read out are double. A
//! block rounded to f32 is off by 6e-8 of itself, far inside the solve's tolerance (1e-2 of
//! the residual), and a product then reads half the bytes again: the 64² drape about 5%
//! faster, the 128² 7–10% (alternated runs), the same CG iterations and worst strain. The
//! rounded matrix is still exactly symmetric, and the finite-difference checks of the
//! assembled Jacobians still hold to 1e-6.
//!
//! The product is a parallel loop over rows with a fixed order inside each row (the slots in
//! column order): the same bytes on any thread count.
//!
//! **Where the machine has AVX2 the product runs in vector registers, to the same bits.** A
//! block's three rows go in three lanes of one register: for a stored block the columns
//! times x₀, x₁, x₂ added in turn, for a mirrored one the columns times x transposed across
//! the three registers and added in turn, so each lane makes the scalar product's
//! multiplications and additions in the scalar product's order, and IEEE arithmetic rounds
//! them alike (no fused multiply-adds are formed). The compiler did not find this on its own:
//! built for the machine (`-C target-cpu=native`) the run was no faster. The `pulp` crate
//! detects the vector units at run time and wraps their intrinsics safely, so the binary
//! still runs on any x86-64, with the scalar product where there is no AVX2, and the
//! workspace has no `unsafe`. On the 64² drape at one substep the products took 31% fewer
//! instructions and the whole run 5% less wall time (`docs/BENCHMARKS.md`).

use nalgebra::Matrix3;
use rayon::prelude::*;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{__m128, __m256d};
use tailor_subdiv::csr::{Csr, group_into};

use crate::energy::{Mat3, Vec3};
use crate::reduce::CHUNK;

/// The scalar a [`BlockMatrix`] stores its blocks in (`f32` or `f64`); it computes in `f64`.
pub trait Precision: nalgebra::Scalar + Copy + Into<f64> + Send + Sync {
    /// `x` rounded to this precision.
    fn round(x: f64) -> Self;

    /// Entries `k..k + 4` of a block (stored column-major) in double precision, in the four
    /// lanes of an AVX register, for the vector product (the `simd` module).
    #[cfg(target_arch = "x86_64")]
    fn four(simd: pulp::x86::V3, block: &Matrix3<Self>, k: usize) -> __m256d;
}

impl Precision for f32 {
    fn round(x: f64) -> Self {
        x as f32
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn four(simd: pulp::x86::V3, block: &Matrix3<Self>, k: usize) -> __m256d {
        let m = &block.as_slice()[k..k + 4];
        let m: __m128 = pulp::cast(<[f32; 4]>::try_from(m).expect("four entries"));
        simd.avx._mm256_cvtps_pd(m)
    }
}

impl Precision for f64 {
    fn round(x: f64) -> Self {
        x
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn four(_: pulp::x86::V3, block: &Matrix3<Self>, k: usize) -> __m256d {
        let m = &block.as_slice()[k..k + 4];
        pulp::cast(<[f64; 4]>::try_from(m).expect("four entries"))
    }
}

/// A square matrix of 3×3 blocks in CSR form, general or symmetric, its blocks stored as `T`;
/// see the module docs.
#[derive(Clone, Debug)]
pub struct BlockMatrix<T: Precision> {
    pattern: Csr,
    /// Row of each slot.
    rows: Vec<u32>,
    /// Per slot, the index of its block in `values` (below the diagonal of a symmetric matrix:
    /// of its mirror's, read transposed).
    value: Vec<u32>,
    /// Per row, the first slot whose block is its own (the diagonal's, when symmetric): the
    /// row's own blocks are stored in a run of `values` from `value` of that slot.
    own: Vec<u32>,
    /// Per row, the slot of its diagonal block.
    diagonal: Vec<u32>,
    /// Per stored block, its slot.
    slot_of: Vec<u32>,
    values: Vec<Matrix3<T>>,
}

impl<T: Precision> BlockMatrix<T> {
    /// The general matrix whose pattern holds every diagonal block of `n` rows and both (i, j)
    /// and (j, i) for every pair given; values zero.
    #[must_use]
    pub fn from_pairs(n: usize, pairs: impl IntoIterator<Item = (u32, u32)>) -> Self {
        Self::new(n, pairs, false)
    }

    /// The symmetric matrix of the same pattern as [`Self::from_pairs`], storing the blocks on
    /// and above the diagonal; values zero.
    #[must_use]
    pub fn symmetric(n: usize, pairs: impl IntoIterator<Item = (u32, u32)>) -> Self {
        Self::new(n, pairs, true)
    }

    fn new(n: usize, pairs: impl IntoIterator<Item = (u32, u32)>, symmetric: bool) -> Self {
        let mut both: Vec<(u32, u32)> = (0..n as u32).map(|i| (i, i)).collect();
        for (i, j) in pairs {
            both.push((i, j));
            both.push((j, i));
        }
        // Each row's sorted columns, a repeated one once: the pattern, already grouped by row.
        let (offsets, columns) = sorted_rows(n, both.iter().copied(), |&j| j);
        let mut pattern = Csr {
            offsets: Vec::with_capacity(n + 1),
            items: Vec::with_capacity(columns.len()),
        };
        pattern.offsets.push(0);
        for row in offsets.windows(2) {
            let start = pattern.items.len();
            for &j in &columns[row[0] as usize..row[1] as usize] {
                if pattern.items.len() == start || pattern.items.last() != Some(&j) {
                    pattern.items.push(j);
                }
            }
            pattern.offsets.push(pattern.items.len() as u32);
        }
        let all: Vec<(u32, u32)> = (0..n)
            .flat_map(|i| pattern.row(i).iter().map(move |&j| (i as u32, j)))
            .collect();
        let mirrored = |&(i, j): &(u32, u32)| symmetric && j < i;
        let slot_of: Vec<u32> = (0..all.len() as u32)
            .filter(|&s| !mirrored(&all[s as usize]))
            .collect();
        let mut value = vec![0; all.len()];
        for (k, &s) in slot_of.iter().enumerate() {
            value[s as usize] = k as u32;
        }
        let find = |i: u32, j: u32| {
            let range = pattern.range(i as usize);
            let k = pattern.items[range.clone()].binary_search(&j);
            (range.start + k.expect("mirror in pattern")) as u32
        };
        for (s, pair) in all.iter().enumerate() {
            if mirrored(pair) {
                value[s] = value[find(pair.1, pair.0) as usize];
            }
        }
        let own: Vec<u32> = (0..n)
            .map(|i| {
                let range = pattern.range(i);
                let below = pattern.items[range.clone()]
                    .iter()
                    .take_while(|&&j| symmetric && (j as usize) < i)
                    .count();
                (range.start + below) as u32
            })
            .collect();
        let diagonal = (0..n as u32).map(|i| find(i, i)).collect();
        Self {
            diagonal,
            values: vec![Matrix3::from_element(T::round(0.0)); slot_of.len()],
            rows: all.iter().map(|&(i, _)| i).collect(),
            pattern,
            value,
            own,
            slot_of,
        }
    }

    /// Number of block rows.
    #[must_use]
    pub fn size(&self) -> usize {
        self.pattern.rows()
    }

    /// Number of slots, stored or mirrored.
    #[must_use]
    pub fn slots(&self) -> usize {
        self.rows.len()
    }

    /// The slot of block (i, j), if it is in the pattern.
    #[must_use]
    pub fn slot(&self, i: u32, j: u32) -> Option<usize> {
        let range = self.pattern.range(i as usize);
        let cols = &self.pattern.items[range.clone()];
        cols.binary_search(&j).ok().map(|k| range.start + k)
    }

    /// The index in [`Self::values`] of the block stored for `slot`, none if it mirrors
    /// another.
    #[must_use]
    pub fn value_index(&self, slot: usize) -> Option<usize> {
        let index = self.value[slot] as usize;
        (self.slot_of[index] as usize == slot).then_some(index)
    }

    /// The block in `slot`.
    #[must_use]
    pub fn block_at(&self, slot: usize) -> Mat3 {
        let block = widen(&self.values[self.value[slot] as usize]);
        if self.value_index(slot).is_some() {
            block
        } else {
            block.transpose()
        }
    }

    /// The diagonal block of row `i`.
    #[must_use]
    pub fn diagonal(&self, i: usize) -> Mat3 {
        widen(&self.values[self.value[self.diagonal[i] as usize] as usize])
    }

    /// The slots of row `i` with their columns and blocks, in column order.
    pub fn row_blocks(&self, i: usize) -> impl Iterator<Item = (usize, u32, Mat3)> + '_ {
        let own = self.own[i] as usize;
        self.pattern.range(i).map(move |s| {
            let block = widen(&self.values[self.value[s] as usize]);
            let block = if s < own { block.transpose() } else { block };
            (s, self.pattern.items[s], block)
        })
    }

    /// Block (i, j), zero outside the pattern.
    #[must_use]
    pub fn block(&self, i: u32, j: u32) -> Mat3 {
        self.slot(i, j)
            .map_or_else(Mat3::zeros, |s| self.block_at(s))
    }

    /// Row and column of the block in `slot`.
    #[must_use]
    pub fn entry(&self, slot: usize) -> (u32, u32) {
        (self.rows[slot], self.pattern.items[slot])
    }

    /// Slots of row `i`.
    #[must_use]
    pub fn row_range(&self, i: usize) -> std::ops::Range<usize> {
        self.pattern.range(i)
    }

    /// Columns of the slots of row `i`, sorted.
    #[must_use]
    pub fn columns(&self, i: usize) -> &[u32] {
        self.pattern.row(i)
    }

    /// The stored blocks, row after row (of a symmetric matrix, those on and above the
    /// diagonal).
    #[must_use]
    pub fn values(&self) -> &[Matrix3<T>] {
        &self.values
    }

    /// Fills every stored block with `f(value index, row, column)` (rounded to `T`), in
    /// parallel.
    pub fn fill(&mut self, f: impl Fn(usize, u32, u32) -> Mat3 + Sync) {
        let (rows, cols, slot_of) = (&self.rows, &self.pattern.items, &self.slot_of);
        self.values.par_iter_mut().enumerate().for_each(|(k, b)| {
            let s = slot_of[k] as usize;
            *b = f(k, rows[s], cols[s]).map(T::round);
        });
    }

    /// Fills the stored blocks row by row, rows in parallel: `f(row, blocks)` gets the row's
    /// stored blocks (all of them in a general matrix), in column order.
    pub fn fill_rows(&mut self, f: impl Fn(usize, &mut [Matrix3<T>]) + Sync) {
        let (pattern, own) = (&self.pattern, &self.own);
        let mut rows = Vec::with_capacity(own.len());
        let mut rest = self.values.as_mut_slice();
        for (i, &first) in own.iter().enumerate() {
            let (row, tail) = rest.split_at_mut(pattern.range(i).end - first as usize);
            rows.push(row);
            rest = tail;
        }
        rows.into_par_iter()
            .enumerate()
            .with_min_len(CHUNK / 16)
            .for_each(|(i, row)| f(i, row));
    }

    /// y = A x.
    pub fn mul_into(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, y)| self.mul_rows(c * CHUNK, x, y));
    }

    /// Rows `first..first + y.len()` of A x into `y`: each row's slots in column order, the
    /// mirrored ones (left of the diagonal) first.
    pub fn mul_rows(&self, first: usize, x: &[Vec3], y: &mut [Vec3]) {
        if !simd::mul_rows(self, first, x, y) {
            self.mul_rows_scalar(first, x, y);
        }
    }

    /// [`Self::mul_rows`] one component at a time.
    fn mul_rows_scalar(&self, first: usize, x: &[Vec3], y: &mut [Vec3]) {
        for (i, yi) in (first..).zip(y) {
            let mut sum = Vec3::zeros();
            for (block, col) in self.mirrored_blocks(i) {
                sum += tr_mul(block, &x[col]);
            }
            for (block, col) in self.own_blocks(i) {
                sum += mul(block, &x[col]);
            }
            *yi = sum;
        }
    }

    /// Row `i`'s slots left of its own blocks (below the diagonal of a symmetric matrix), with
    /// their columns: each block is its mirror's, for a product to read transposed. A
    /// product adds these first, then [`Self::own_blocks`].
    #[inline(always)]
    fn mirrored_blocks(&self, i: usize) -> impl Iterator<Item = (&Matrix3<T>, usize)> {
        let (start, own) = (self.pattern.range(i).start, self.own[i] as usize);
        self.value[start..own]
            .iter()
            .zip(&self.pattern.items[start..own])
            .map(|(&v, &col)| (&self.values[v as usize], col as usize))
    }

    /// Row `i`'s own blocks, stored in a run, with their columns.
    #[inline(always)]
    fn own_blocks(&self, i: usize) -> impl Iterator<Item = (&Matrix3<T>, usize)> {
        let (end, own) = (self.pattern.range(i).end, self.own[i] as usize);
        let start = self.value[own] as usize;
        self.values[start..start + (end - own)]
            .iter()
            .zip(&self.pattern.items[own..end])
            .map(|(block, &col)| (block, col as usize))
    }
}

/// The items of `pairs` grouped by their rows (`rows` of them), each row sorted by `key`: for
/// items whose keys differ within a row, the order one sort by (row, key) gives, found by
/// bucketing the items into rows first and sorting the rows in parallel, each a few items
/// (a matrix row's columns, a block's sources). Returns the rows' offsets and the items.
pub(crate) fn sorted_rows<T, I>(
    rows: usize,
    pairs: I,
    key: impl Fn(&T) -> u32 + Sync,
) -> (Vec<u32>, Vec<T>)
where
    T: Copy + Default + Send,
    I: IntoIterator<Item = (u32, T)>,
    I::IntoIter: Clone,
{
    let (mut offsets, mut items) = (Vec::new(), Vec::new());
    group_into(rows, pairs, &mut offsets, &mut items);
    let mut slices = Vec::with_capacity(rows);
    let mut rest = items.as_mut_slice();
    for row in offsets.windows(2) {
        let (slice, tail) = rest.split_at_mut((row[1] - row[0]) as usize);
        slices.push(slice);
        rest = tail;
    }
    slices
        .into_par_iter()
        .with_min_len(CHUNK / 16)
        .for_each(|slice| slice.sort_unstable_by_key(&key));
    (offsets, items)
}

/// A stored block in double precision.
fn widen<T: Precision>(b: &Matrix3<T>) -> Mat3 {
    b.map(Into::into)
}

/// b x in double precision, each component summed left to right (as nalgebra's product).
#[inline]
fn mul<T: Precision>(b: &Matrix3<T>, x: &Vec3) -> Vec3 {
    let m = b.as_slice();
    let c = |k: usize| -> f64 { m[k].into() };
    Vec3::new(
        c(0) * x[0] + c(3) * x[1] + c(6) * x[2],
        c(1) * x[0] + c(4) * x[1] + c(7) * x[2],
        c(2) * x[0] + c(5) * x[1] + c(8) * x[2],
    )
}

/// bᵀ x in double precision, each component summed left to right.
#[inline]
fn tr_mul<T: Precision>(b: &Matrix3<T>, x: &Vec3) -> Vec3 {
    let m = b.as_slice();
    let c = |k: usize| -> f64 { m[k].into() };
    Vec3::new(
        c(0) * x[0] + c(1) * x[1] + c(2) * x[2],
        c(3) * x[0] + c(4) * x[1] + c(5) * x[2],
        c(6) * x[0] + c(7) * x[1] + c(8) * x[2],
    )
}

/// The product in AVX registers: a block's three rows in three lanes of one register, the
/// same multiplications and additions in the same order as [`mul`] and [`tr_mul`] lane by
/// lane (no fused multiply-adds), so the same bits as the scalar product. Through `pulp`,
/// which finds the machine's vector units at run time and wraps the intrinsics safely.
mod simd {
    use super::{BlockMatrix, Precision, Vec3};

    /// Rows `first..` of A x into `y`, as [`BlockMatrix::mul_rows`], when the machine has
    /// AVX2; false, with nothing written, when it has not.
    #[cfg(target_arch = "x86_64")]
    pub(super) fn mul_rows<T: Precision>(
        a: &BlockMatrix<T>,
        first: usize,
        x: &[Vec3],
        y: &mut [Vec3],
    ) -> bool {
        let Some(simd) = pulp::x86::V3::try_new() else {
            return false;
        };
        simd.vectorize(Rows {
            simd,
            a,
            first,
            x,
            y,
        });
        true
    }

    #[cfg(not(target_arch = "x86_64"))]
    pub(super) fn mul_rows<T: Precision>(
        _: &BlockMatrix<T>,
        _: usize,
        _: &[Vec3],
        _: &mut [Vec3],
    ) -> bool {
        false
    }

    /// The columns of `block` in lanes 0–2 of three registers (lane 3 unspecified): entries
    /// 0–3, 3–6 and 5–8, the last moved down a lane; three loads where the entries one by one
    /// took ten instructions.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn columns<T: Precision>(
        simd: pulp::x86::V3,
        block: &nalgebra::Matrix3<T>,
    ) -> [std::arch::x86_64::__m256d; 3] {
        let last = T::four(simd, block, 5);
        [
            T::four(simd, block, 0),
            T::four(simd, block, 3),
            simd.avx2._mm256_permute4x64_pd::<0b11_11_10_01>(last),
        ]
    }

    /// The rows to compute, for [`pulp::x86::V3::vectorize`] (which compiles what it is given
    /// for AVX2 when it is inlined into it).
    #[cfg(target_arch = "x86_64")]
    struct Rows<'a, T: Precision> {
        simd: pulp::x86::V3,
        a: &'a BlockMatrix<T>,
        first: usize,
        x: &'a [Vec3],
        y: &'a mut [Vec3],
    }

    #[cfg(target_arch = "x86_64")]
    impl<T: Precision> pulp::NullaryFnOnce for Rows<'_, T> {
        type Output = ();

        #[inline(always)]
        fn call(self) {
            let Self {
                simd,
                a,
                first,
                x,
                y,
            } = self;
            let avx = simd.avx;
            for (i, yi) in (first..).zip(y) {
                let mut sum = avx._mm256_setzero_pd();
                for (block, col) in a.mirrored_blocks(i) {
                    // Bᵀ x: lane k of pⱼ = c_j x is b[3j + k] xₖ; transposed into t₀, t₁, t₂,
                    // lane j of (t₀ + t₁) + t₂ is row j of Bᵀ x summed left to right.
                    let [c0, c1, c2] = columns(simd, block);
                    let xj = &x[col];
                    let xv = avx._mm256_set_pd(0.0, xj[2], xj[1], xj[0]);
                    let p0 = avx._mm256_mul_pd(c0, xv);
                    let p1 = avx._mm256_mul_pd(c1, xv);
                    let p2 = avx._mm256_mul_pd(c2, xv);
                    let (u0, u1) = (
                        avx._mm256_unpacklo_pd(p0, p1),
                        avx._mm256_unpackhi_pd(p0, p1),
                    );
                    let (u2, u3) = (
                        avx._mm256_unpacklo_pd(p2, p2),
                        avx._mm256_unpackhi_pd(p2, p2),
                    );
                    let t0 = avx._mm256_permute2f128_pd::<0x20>(u0, u2);
                    let t1 = avx._mm256_permute2f128_pd::<0x20>(u1, u3);
                    let t2 = avx._mm256_permute2f128_pd::<0x31>(u0, u2);
                    let t = avx._mm256_add_pd(avx._mm256_add_pd(t0, t1), t2);
                    sum = avx._mm256_add_pd(sum, t);
                }
                for (block, col) in a.own_blocks(i) {
                    // B x: column j times xⱼ, added left to right.
                    let [c0, c1, c2] = columns(simd, block);
                    let xj = &x[col];
                    let t = avx._mm256_mul_pd(c0, avx._mm256_broadcast_sd(&xj[0]));
                    let t = avx
                        ._mm256_add_pd(t, avx._mm256_mul_pd(c1, avx._mm256_broadcast_sd(&xj[1])));
                    let t = avx
                        ._mm256_add_pd(t, avx._mm256_mul_pd(c2, avx._mm256_broadcast_sd(&xj[2])));
                    sum = avx._mm256_add_pd(sum, t);
                }
                let lanes: [f64; 4] = pulp::cast(sum);
                *yi = Vec3::new(lanes[0], lanes[1], lanes[2]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values of every sign over ten orders of magnitude, a few zeros of either sign.
    fn spread(k: usize) -> f64 {
        match k % 11 {
            3 => 0.0,
            7 => -0.0,
            _ => (k as f64 * 0.7).sin() * 10f64.powi((k % 10) as i32 - 5),
        }
    }

    /// The product in vector registers (where the machine has them) is the scalar product to
    /// the bit, zeros' signs included: a symmetric single-precision system (blocks read
    /// transposed left of the diagonal) and a general double-precision one, rows from the
    /// middle of the matrix as a chunk of a parallel product has them.
    #[test]
    fn vector_product_is_the_scalar_product_to_the_bit() {
        let (n, side) = (60, 10u32);
        // A grid's neighbours up to two apart, as a cloth's springs couple its particles.
        let pairs: Vec<(u32, u32)> = (0..n as u32)
            .flat_map(|i| [1, side - 1, side, side + 1, 2, 2 * side].map(|d| (i, i + d)))
            .filter(|&(_, j)| j < n as u32)
            .collect();
        let x: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(spread(3 * i + 1), spread(3 * i + 2), spread(3 * i + 5)))
            .collect();
        let block = |s: usize| Mat3::from_fn(|r, c| spread(9 * s + 3 * r + c + 13));
        let mut single = BlockMatrix::<f32>::symmetric(n, pairs.iter().copied());
        single.fill(|s, _, _| block(s));
        let mut double = BlockMatrix::<f64>::from_pairs(n, pairs.iter().copied());
        double.fill(|s, _, _| block(s));
        // The first row and component whose bits differ, if any.
        let differ = |a: &[Vec3], b: &[Vec3]| {
            a.iter().zip(b).enumerate().find_map(|(i, (a, b))| {
                (0..3)
                    .find(|&k| a[k].to_bits() != b[k].to_bits())
                    .map(|k| (i, k, a[k], b[k]))
            })
        };
        let rows = 7..n - 5;
        let (mut scalar, mut vector) = (
            vec![Vec3::zeros(); rows.len()],
            vec![Vec3::zeros(); rows.len()],
        );
        single.mul_rows_scalar(rows.start, &x, &mut scalar);
        if !simd::mul_rows(&single, rows.start, &x, &mut vector) {
            eprintln!("no AVX2 on this machine: the scalar product alone is in use");
            return;
        }
        assert_eq!(
            differ(&vector, &scalar),
            None,
            "single precision, symmetric"
        );
        double.mul_rows_scalar(rows.start, &x, &mut scalar);
        assert!(simd::mul_rows(&double, rows.start, &x, &mut vector));
        assert_eq!(differ(&vector, &scalar), None, "double precision, general");
    }

    #[test]
    fn product_matches_dense() {
        let mut a = BlockMatrix::<f64>::from_pairs(3, [(0, 2), (2, 1)]);
        assert_eq!(a.values().len(), 3 + 4);
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

    #[test]
    fn symmetric_storage_makes_the_product_of_both_triangles_to_the_bit() {
        let pairs = [(0, 3), (3, 1), (1, 2), (4, 0), (2, 4)];
        let mut sym = BlockMatrix::<f64>::symmetric(5, pairs);
        let mut full = BlockMatrix::<f64>::from_pairs(5, pairs);
        assert_eq!((sym.values().len(), full.values().len()), (5 + 5, 5 + 10));
        assert_eq!(sym.slots(), full.slots());
        let upper = |i: u32, j: u32| {
            let (a, b) = (i.min(j), i.max(j));
            let m = Mat3::from_fn(|r, c| ((a * 7 + b * 3) as f64 + (r * 3 + c) as f64).sin());
            let m = if a == b { m + m.transpose() } else { m };
            if i <= j { m } else { m.transpose() }
        };
        sym.fill(|_, i, j| {
            assert!(i <= j, "({i}, {j}) stored");
            upper(i, j)
        });
        full.fill(|_, i, j| upper(i, j));
        for s in 0..full.slots() {
            assert_eq!(sym.entry(s), full.entry(s));
            assert_eq!(sym.block_at(s), full.block_at(s));
        }
        let x: Vec<Vec3> = (0..5)
            .map(|i| Vec3::new(1.0 + f64::from(i), -0.3 * f64::from(i), 0.7).map(f64::cos))
            .collect();
        let (mut ys, mut yf) = (vec![Vec3::zeros(); 5], vec![Vec3::zeros(); 5]);
        sym.mul_into(&x, &mut ys);
        full.mul_into(&x, &mut yf);
        assert_eq!(ys, yf);
    }
}
