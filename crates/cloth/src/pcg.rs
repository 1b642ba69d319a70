//! Preconditioned conjugate gradients with Baraff & Witkin's constraint filter.
//!
//! Baraff & Witkin 1998, §5.3 ("modified PCG"): each particle has a 3×3 filter S_i — zero for a
//! pinned particle, I − n nᵀ for one held against a plane with normal n, I for a free one. CG
//! runs on the filtered system, every residual and search direction passing through S, so the
//! constrained components of the unknown keep their initial values *exactly*: the constraints
//! are not soft penalties. The preconditioner is block-Jacobi: the inverse of each particle's
//! 3×3 diagonal block (SPD because the mass is). Dot products are summed in fixed-size
//! chunks combined in order, so iterates are identical on any number of threads.

use rayon::prelude::*;

use crate::energy::{Mat3, Vec3};
use crate::matrix::BlockMatrix;
use crate::reduce::{dot, partial_count};

/// Buffers for [`Pcg::solve`], allocated once for a problem size.
#[derive(Clone, Debug)]
pub struct Pcg {
    r: Vec<Vec3>,
    z: Vec<Vec3>,
    p: Vec<Vec3>,
    q: Vec<Vec3>,
    inverse_diagonal: Vec<Mat3>,
    partials: Vec<f64>,
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solve {
    /// Iterations taken.
    pub iterations: u32,
    /// Whether the filtered residual fell below the tolerance.
    pub converged: bool,
}

impl Pcg {
    /// Buffers for `n` particles.
    #[must_use]
    pub fn new(n: usize) -> Self {
        Self {
            r: vec![Vec3::zeros(); n],
            z: vec![Vec3::zeros(); n],
            p: vec![Vec3::zeros(); n],
            q: vec![Vec3::zeros(); n],
            inverse_diagonal: vec![Mat3::identity(); n],
            partials: vec![0.0; partial_count(n)],
        }
    }

    /// Solves S A S x = S b for the free components of `x`, starting from `x` (whose filtered
    /// part is a warm start and whose constrained part, (I − S) x, is left untouched), until
    /// |S (b − A x)| ≤ `tolerance` · |S b|.
    pub fn solve(
        &mut self,
        a: &BlockMatrix,
        filter: &[Mat3],
        b: &[Vec3],
        x: &mut [Vec3],
        tolerance: f64,
        max_iterations: u32,
    ) -> Solve {
        let Self {
            r,
            z,
            p,
            q,
            inverse_diagonal,
            partials,
        } = self;
        inverse_diagonal
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, d)| {
                let block = a.block(i as u32, i as u32);
                *d = block.try_inverse().unwrap_or_else(Mat3::identity);
            });
        a.mul_into(x, q);
        r.par_iter_mut()
            .enumerate()
            .for_each(|(i, ri)| *ri = filter[i] * (b[i] - q[i]));
        z.par_iter_mut()
            .enumerate()
            .for_each(|(i, zi)| *zi = filter[i] * b[i]);
        let target = tolerance * tolerance * dot(z, z, partials);
        let precondition = |r: &[Vec3], z: &mut [Vec3]| {
            z.par_iter_mut()
                .enumerate()
                .for_each(|(i, zi)| *zi = filter[i] * (inverse_diagonal[i] * r[i]));
        };
        precondition(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(r, z, partials);
        let mut iterations = 0;
        loop {
            let residual = dot(r, r, partials);
            if !residual.is_finite() {
                return Solve {
                    iterations,
                    converged: false,
                };
            }
            if residual <= target {
                return Solve {
                    iterations,
                    converged: true,
                };
            }
            if iterations >= max_iterations {
                return Solve {
                    iterations,
                    converged: false,
                };
            }
            iterations += 1;
            a.mul_into(p, q);
            q.par_iter_mut()
                .enumerate()
                .for_each(|(i, qi)| *qi = filter[i] * *qi);
            let alpha = rz / dot(p, q, partials);
            x.par_iter_mut()
                .zip(r.par_iter_mut())
                .enumerate()
                .for_each(|(i, (xi, ri))| {
                    *xi += p[i] * alpha;
                    *ri -= q[i] * alpha;
                });
            precondition(r, z);
            let rz_next = dot(r, z, partials);
            let beta = rz_next / rz;
            rz = rz_next;
            p.par_iter_mut()
                .zip(z.par_iter())
                .for_each(|(pi, zi)| *pi = zi + *pi * beta);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tridiagonal SPD block matrix: 4 I on the diagonal, −I between neighbours.
    fn chain(n: usize) -> BlockMatrix {
        let mut a = BlockMatrix::from_pairs(n, (1..n as u32).map(|i| (i - 1, i)));
        a.fill(|_, i, j| {
            if i == j {
                Mat3::identity() * 4.0 + Mat3::from_fn(|r, c| 0.1 * (r + c) as f64)
            } else {
                -Mat3::identity()
            }
        });
        a
    }

    #[test]
    fn solves_spd_systems_and_keeps_constrained_components() {
        let n = 50;
        let a = chain(n);
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
        let mut pcg = Pcg::new(n);
        let solve = pcg.solve(&a, &filter, &b, &mut x, 1e-12, 500);
        assert!(solve.converged);
        assert_eq!(x[3], Vec3::new(0.5, -0.25, 2.0));
        assert_eq!(x[7].y, 0.75);
        let mut ax = vec![Vec3::zeros(); n];
        a.mul_into(&x, &mut ax);
        for i in 0..n {
            let residual = filter[i] * (b[i] - ax[i]);
            assert!(residual.norm() < 1e-9, "row {i}: {residual}");
        }
    }
}
