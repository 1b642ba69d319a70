//! Sums whose result does not depend on the number of threads.
//!
//! Items are summed in fixed-size chunks (in parallel), then the chunk sums in order, so the
//! rounding is the same with 1 thread or 16 (STYLE.md, "Parallelism and determinism"). The
//! caller owns the buffer of partial sums, so nothing allocates per call.

use rayon::prelude::*;

/// Items per chunk.
pub(crate) const CHUNK: usize = 1024;

/// Number of partial sums `n` items need.
pub(crate) fn partial_count(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// Σ `f(i)` over `0..n`, in a fixed order of chunks.
pub(crate) fn sum_by(n: usize, partials: &mut [f64], f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let partials = &mut partials[..partial_count(n)];
    partials.par_iter_mut().enumerate().for_each(|(c, p)| {
        let end = ((c + 1) * CHUNK).min(n);
        *p = (c * CHUNK..end).map(&f).sum();
    });
    partials.iter().sum()
}
