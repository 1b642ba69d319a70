//! Preconditioned conjugate gradients with Baraff & Witkin's constraint filter.
//!
//! Baraff & Witkin 1998, §5.3 ("modified PCG"): each particle has a 3×3 filter S_i — zero for a
//! pinned particle, I − n nᵀ for one held against a plane with normal n, I for a free one. CG
//! runs on the filtered system, every residual and search direction passing through S, so the
//! constrained components of the unknown keep their initial values *exactly*: the constraints
//! are not soft penalties. The preconditioner is aggregation multigrid (additive at the fine level) on the
//! filtered matrix (the private `multigrid` module), symmetric so CG stays CG, and its
//! iteration count barely grows with the garment's resolution where block-Jacobi's does.
//! Each iteration makes three parallel passes over fixed chunks of particles (the new
//! direction, the product with the matrix and p · q, the update of x and r with the fine
//! part of the preconditioned r and the sums r · r and r · z) and the coarse levels' cycle in
//! between: fused so, the 128² drape is 12% faster than with a pass per vector operation.
//! Dot products are summed per chunk and the chunks combined in order, so iterates are
//! identical on any number of threads.
//!
//! **A solve starts from the coarse levels' answer.** A solve measured against its own start
//! (no reference given: a substep's first) first adds to its starting guess the coarse levels'
//! correction of the starting residual, S P e, keeps it when the residual falls, and then runs
//! CG from there, still stopping at the tolerance times the residual it started with: the same
//! accuracy, reached from nearer.
//! This is the nested iteration of multigrid (the coarse answer as the fine start). Before it,
//! the first iteration of a free fall's solve at one substep a frame raised the residual five
//! to eight times and a tail of thirty iterations brought it back: the additive fine level
//! overshoots on the smooth error a fall is made of, which the coarse levels answer alone. Over
//! three variants of the 64² drape at one substep (`docs/BENCHMARKS.md`), CG took 10–19% fewer
//! iterations and the whole run 4–6% fewer instructions. Where the residual is not smooth (a
//! cape pulled by its attachments) the coarse answer can start CG farther off: taken always,
//! the cape's solves took 9% more iterations, so it is kept only when it lowers the residual.
//! A solve again after more contacts starts from the last solution, whose smooth error is
//! gone, and does not.

use rayon::prelude::*;

use crate::energy::{Mat3, Vec3};
use crate::matrix::BlockMatrix;
use crate::multigrid::Multigrid;
use crate::reduce::{CHUNK, partial_count};

/// Buffers and the multigrid hierarchy for [`Pcg::solve`], made once for a matrix pattern.
#[derive(Clone, Debug)]
pub struct Pcg {
    r: Vec<Vec3>,
    p: Vec<Vec3>,
    q: Vec<Vec3>,
    /// The fine level's part of the preconditioned residual.
    z: Vec<Vec3>,
    multigrid: Multigrid,
    /// Per chunk of [`CHUNK`] particles: up to two partial sums of a pass.
    partials: Vec<[f64; 2]>,
}

/// When a solve stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stop {
    /// Converged when the filtered residual is at most this times `reference`.
    pub tolerance: f64,
    /// The norm the tolerance is relative to; `None` for the filtered residual of the
    /// starting guess.
    pub reference: Option<f64>,
    /// Converged, too, when the filtered residual is at most this, whatever `reference` is.
    pub floor: f64,
    /// Iterations before the solve counts as failed.
    pub max_iterations: u32,
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solve {
    /// Iterations taken.
    pub iterations: u32,
    /// Whether the filtered residual fell below the tolerance.
    pub converged: bool,
    /// The norm the tolerance was relative to: the filtered residual of the starting guess,
    /// unless the caller gave one.
    pub reference: f64,
}

/// Runs `pass(first particle, chunk)` over `chunks`, the fixed chunks of [`CHUNK`] particles
/// of some arrays, in parallel, each returning two partial sums, and adds those in chunk
/// order: the same bytes on any number of threads.
fn chunked<T: Send>(
    chunks: impl IndexedParallelIterator<Item = T>,
    partials: &mut [[f64; 2]],
    pass: impl Fn(usize, T) -> [f64; 2] + Sync,
) -> [f64; 2] {
    let partials = &mut partials[..chunks.len()];
    chunks
        .zip(partials.par_iter_mut())
        .enumerate()
        .for_each(|(c, (chunk, part))| *part = pass(c * CHUNK, chunk));
    [0, 1].map(|k| partials.iter().map(|p| p[k]).sum())
}

impl Pcg {
    /// Buffers and hierarchy for systems with the pattern of `a`, the multigrid's aggregates
    /// following `a`'s strong couplings.
    #[must_use]
    pub fn new(a: &BlockMatrix<f32>) -> Self {
        let n = a.size();
        Self {
            r: vec![Vec3::zeros(); n],
            p: vec![Vec3::zeros(); n],
            q: vec![Vec3::zeros(); n],
            z: vec![Vec3::zeros(); n],
            multigrid: Multigrid::new(a),
            partials: vec![[0.0; 2]; partial_count(n)],
        }
    }

    /// Sets up the preconditioner for `a` filtered by `filter`. With `same_matrix`, `a` is the
    /// matrix of the last call, only the filter changed (more contacts), and the coarse
    /// levels are kept.
    pub fn prepare(&mut self, a: &BlockMatrix<f32>, filter: &[Mat3], same_matrix: bool) {
        self.multigrid.update(a, filter, !same_matrix);
    }

    /// Solves S A S x = S b for the free components of `x`, starting from `x` (whose filtered
    /// part is a warm start and whose constrained part, (I − S) x, is left untouched), until
    /// |S (b − A x)| ≤ `stop.tolerance` · `stop.reference` (or ≤ `stop.floor`), preconditioned as the last
    /// [`Self::prepare`] set up. The reference defaults to the starting residual |S (b − A x₀)|:
    /// the tolerance then bounds the error in what the solve changes, not in the whole of b.
    /// (Relative to |S b|, a substep's velocity update from a warm start at the last velocity
    /// stops as soon as its forces are under the tolerance times the momentum, and a falling
    /// sheet at 20 substeps a frame lost a third of its gravity.) Without a reference, the start
    /// is first corrected by the coarse levels (see the module docs). `a` must have the pattern
    /// given to [`Self::new`].
    pub fn solve(
        &mut self,
        a: &BlockMatrix<f32>,
        filter: &[Mat3],
        b: &[Vec3],
        x: &mut [Vec3],
        stop: Stop,
    ) -> Solve {
        let Self {
            r,
            p,
            q,
            z,
            multigrid,
            partials,
        } = self;
        let [mut residual, mut rz_fine] = start(a, filter, b, x, r, z, q, multigrid, partials);
        let reference = stop.reference.unwrap_or(residual.sqrt());
        if stop.reference.is_none() && multigrid.has_coarse_levels() {
            // The start corrected by the coarse levels (see the module docs), kept when it
            // leaves a smaller residual; `p`, cleared below, holds the start meanwhile.
            multigrid.coarse_cycle(r);
            p.copy_from_slice(x);
            let mg = &*multigrid;
            x.par_chunks_mut(CHUNK).enumerate().for_each(|(c, x)| {
                for (i, x) in (c * CHUNK..).zip(x) {
                    *x += mg.filtered(filter, i, mg.correction(i));
                }
            });
            let corrected = start(a, filter, b, x, r, z, q, multigrid, partials);
            if corrected[0] < residual {
                [residual, rz_fine] = corrected;
            } else {
                x.copy_from_slice(p);
                [residual, rz_fine] = start(a, filter, b, x, r, z, q, multigrid, partials);
            }
        }
        let target = (stop.tolerance * reference).max(stop.floor).powi(2);
        let mut rz = 0.0;
        let mut beta = 0.0;
        // The first direction is z itself (β = 0); p is cleared so that nothing a failed
        // solve left in it can leak in.
        p.fill(Vec3::zeros());
        let mut iterations = 0;
        loop {
            if !residual.is_finite() || iterations >= stop.max_iterations || residual <= target {
                return Solve {
                    iterations,
                    converged: residual <= target,
                    reference,
                };
            }
            // The preconditioned residual z + S P e (the coarse correction e) and the next
            // direction p = z + S P e + β p, with β from r · z.
            let rz_next = rz_fine + multigrid.coarse_cycle(r);
            if iterations > 0 {
                beta = rz_next / rz;
            }
            rz = rz_next;
            let mg = &*multigrid;
            p.par_chunks_mut(CHUNK)
                .zip(z.par_chunks(CHUNK))
                .enumerate()
                .for_each(|(c, (p, z))| {
                    for (i, (p, z)) in (c * CHUNK..).zip(p.iter_mut().zip(z)) {
                        *p = z + mg.filtered(filter, i, mg.correction(i)) + *p * beta;
                    }
                });
            iterations += 1;
            // q = S A p, with the partial sums of p · q.
            let p_now = &*p;
            let [pq, _] = chunked(q.par_chunks_mut(CHUNK), partials, |base, q| {
                a.mul_rows(base, p_now, q);
                let mut pq = 0.0;
                for (i, q) in (base..).zip(q) {
                    *q = multigrid.filtered(filter, i, *q);
                    pq += p_now[i].dot(q);
                }
                [pq, 0.0]
            });
            let alpha = rz / pq;
            // x += α p, r −= α q and the fine part of the preconditioned r, with the partial
            // sums of r · r and r · z.
            let q_now = &*q;
            let chunks = x
                .par_chunks_mut(CHUNK)
                .zip(r.par_chunks_mut(CHUNK))
                .zip(z.par_chunks_mut(CHUNK));
            [residual, rz_fine] = chunked(chunks, partials, |base, ((x, r), z)| {
                let mut sums = [0.0; 2];
                for (i, ((x, r), z)) in (base..).zip(x.iter_mut().zip(r).zip(z)) {
                    *x += p_now[i] * alpha;
                    *r -= q_now[i] * alpha;
                    *z = mg.smooth(filter, i, *r);
                    sums[0] += r.dot(r);
                    sums[1] += r.dot(z);
                }
                sums
            });
        }
    }
}

/// r = S (b − A x) and z, the fine part of the preconditioned r (q the product A x); returns
/// |r|² and r · z.
#[allow(clippy::too_many_arguments)]
fn start(
    a: &BlockMatrix<f32>,
    filter: &[Mat3],
    b: &[Vec3],
    x: &[Vec3],
    r: &mut [Vec3],
    z: &mut [Vec3],
    q: &mut [Vec3],
    multigrid: &Multigrid,
    partials: &mut [[f64; 2]],
) -> [f64; 2] {
    a.mul_into(x, q);
    let q = &*q;
    let chunks = r.par_chunks_mut(CHUNK).zip(z.par_chunks_mut(CHUNK));
    chunked(chunks, partials, |base, (r, z)| {
        let mut sums = [0.0; 2];
        for (i, (r, z)) in (base..).zip(r.iter_mut().zip(z)) {
            *r = multigrid.filtered(filter, i, b[i] - q[i]);
            *z = multigrid.smooth(filter, i, *r);
            sums[0] += r.dot(r);
            sums[1] += r.dot(z);
        }
        sums
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tridiagonal SPD block matrix: `diagonal` on the diagonal, −I between neighbours.
    fn chain(n: usize, diagonal: Mat3) -> BlockMatrix<f32> {
        let mut a = BlockMatrix::symmetric(n, (1..n as u32).map(|i| (i - 1, i)));
        a.fill(|_, i, j| if i == j { diagonal } else { -Mat3::identity() });
        a
    }

    /// A uniform right-hand side, the smooth error a fall is made of: a solve measured against
    /// its own start begins from the coarse levels' answer and reaches the same residual in
    /// fewer iterations than the same solve told that reference.
    #[test]
    fn a_solve_from_its_own_start_begins_from_the_coarse_answer() {
        // Couplings outweighing the diagonal, as a falling sheet's springs outweigh its masses.
        let n = 2000;
        let a = chain(n, Mat3::identity() * 2.05);
        let b = vec![Vec3::new(0.0, -1.0, 0.5); n];
        let filter = vec![Mat3::identity(); n];
        let mut pcg = Pcg::new(&a);
        pcg.prepare(&a, &filter, false);
        let stop = Stop {
            tolerance: 1e-2,
            reference: None,
            floor: 0.0,
            max_iterations: 500,
        };
        let mut fresh_x = vec![Vec3::zeros(); n];
        let fresh = pcg.solve(&a, &filter, &b, &mut fresh_x, stop);
        let told = Stop {
            reference: Some(fresh.reference),
            ..stop
        };
        let mut told_x = vec![Vec3::zeros(); n];
        let again = pcg.solve(&a, &filter, &b, &mut told_x, told);
        assert!(fresh.converged && again.converged);
        assert!(
            fresh.iterations < again.iterations,
            "{} iterations from the coarse answer, {} without",
            fresh.iterations,
            again.iterations
        );
    }

    #[test]
    fn solves_spd_systems_and_keeps_constrained_components() {
        // 50 particles are preconditioned by block-Jacobi alone, 2000 through the hierarchy.
        for n in [50, 2000] {
            solves_and_keeps_constraints(n);
        }
    }

    fn solves_and_keeps_constraints(n: usize) {
        let a = chain(
            n,
            Mat3::identity() * 4.0 + Mat3::from_fn(|r, c| 0.1 * (r + c) as f64),
        );
        let b: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(i as f64, 1.0, -(i as f64).sin()))
            .collect();
        let normal = Vec3::new(0.0, 1.0, 0.0);
        let mut filter = vec![Mat3::identity(); n];
        filter[3] = Mat3::zeros();
        filter[7] = Mat3::identity() - normal * normal.transpose();
        let mut x = vec![Vec3::zeros(); n];
        x[3] = Vec3::new(0.5, -0.25, 2.0);
        x[7] = Vec3::new(0.0, 0.75, 0.0);
        let mut pcg = Pcg::new(&a);
        pcg.prepare(&a, &filter, false);
        let stop = Stop {
            tolerance: 1e-12,
            reference: None,
            floor: 0.0,
            max_iterations: 500,
        };
        let solve = pcg.solve(&a, &filter, &b, &mut x, stop);
        assert!(solve.converged);
        assert_eq!(x[3], Vec3::new(0.5, -0.25, 2.0));
        assert_eq!(x[7].y, 0.75);
        let mut ax = vec![Vec3::zeros(); n];
        a.mul_into(&x, &mut ax);
        let scale: f64 = (0..n).map(|i| (filter[i] * b[i]).norm_squared()).sum();
        for i in 0..n {
            let residual = filter[i] * (b[i] - ax[i]);
            assert!(
                residual.norm() < 1e-11 * scale.sqrt(),
                "row {i}: {residual}"
            );
        }
    }
}
