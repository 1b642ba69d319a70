//! Aggregation multigrid: the preconditioner of the implicit solve's conjugate gradients.
//!
//! With block-Jacobi alone CG needs a number of iterations that grows with the garment's
//! resolution, since the error that is smooth across the cloth, which block-Jacobi passes
//! along one particle per iteration, is what it reduces slowest; a coarser mesh represents
//! that error well, so with this preconditioner the count barely grows with resolution. Plain
//! (unsmoothed) aggregation (Braess, "Towards algebraic multigrid for elliptic problems of
//! second order", Computing 1995) builds that coarser mesh from the matrix's pattern alone, so
//! it is topology, built once:
//!
//! - **Aggregates** (the greedy rule of Vaněk, Mandel & Brezina 1996, phases 1 and 2): in index
//!   order, a particle whose strongly coupled neighbours are all unassigned forms an aggregate
//!   with them; each particle left over joins the aggregate of its first assigned strong
//!   neighbour. Strength is read off the matrix the hierarchy is made with (the simulator's,
//!   at the rest shape and the longest substep), so the bending springs' weak couplings
//!   across two edges do not make aggregates too large for the piecewise-constant
//!   prolongation. It is a function of the model and the settings alone, never of the state
//!   when a run started, so a run resumed from a checkpoint preconditions, and so iterates,
//!   exactly as the run it continues. Each aggregate is a node of the next level,
//!   which is coarsened the same way until a level has at most [`COARSEST`] nodes.
//! - **Coarse matrices**, per solve: with the piecewise-constant prolongation P (a coarse node's
//!   3-vector copied to every particle of its aggregate), the Galerkin product Pᵀ A P is the sum
//!   of the fine blocks between two aggregates: each coarse row sums the rows of its
//!   aggregate's members in order (sequential reads, a fixed order), through a table made once
//!   of where each fine slot lands.
//! - **The preconditioner** per CG iteration is additive at the fine level: the damped
//!   block-Jacobi step ω D⁻¹ r (weight [`FINE_OMEGA`]) plus the prolonged V-cycle of the coarse
//!   levels on the restricted r. It never multiplies by the fine matrix, whose blocks are
//!   most of the memory a CG iteration reads: the multiplicative cycle (sweep, residual,
//!   coarse correction, second sweep) read them twice more per iteration, and at 128² the
//!   products are bound by memory bandwidth. CG takes about twice the iterations (the 64²
//!   drape: 41 a frame where the multiplicative cycle took 18; 36 since the weights were
//!   tuned, [`FINE_OMEGA`] and [`OMEGA`]) and the drape is 15–20% faster. Below the fine
//!   level each V-cycle is multiplicative: a damped
//!   block-Jacobi sweep, the residual restricted to the next level, the cycle there, its
//!   correction prolonged, a second sweep; the coarsest level is solved by dense Cholesky.
//!   Both parts are symmetric and positive, so CG stays CG. The cycle runs on one thread: a
//!   pass over the 64² drape's first coarse level (704 nodes) takes tens of microseconds,
//!   less than waking the other worker for half of it costs. Split into tasks of 128 rows,
//!   the cycles of that drape took 73 ms of its run, on one thread 52–56 ms (the 128² drape:
//!   271–286 ms and 220–250 ms), the same iterates either way.
//!
//! The constraint filter S of [`crate::pcg`] enters at the fine level: the hierarchy is built
//! on S A S + (I − S), which decouples the constrained components, and every fine residual and
//! correction passes through S (without that, the coarse levels see the contacts as free and
//! CG needs nearly three times the iterations). Every pass runs over fixed chunks or rows
//! with a fixed order of sums, so the result does not depend on the number of threads.

use nalgebra::{DMatrix, DVector, Dyn, linalg::Cholesky};
use rayon::prelude::*;
use tailor_subdiv::csr::Csr;

use crate::energy::{Mat3, Vec3};
use crate::matrix::{BlockMatrix, Precision};
use crate::reduce::CHUNK;

/// Relative size of a coupling that [`aggregate`] follows (the 64² drape in contact: 0 takes
/// every stored pair, aggregates of 14 particles and 48 CG iterations per substep; 0.1 leaves
/// out the bending springs' weak reach across two edges, aggregates of 6 and 44 iterations).
const STRENGTH: f64 = 0.1;

/// Weight of each damped block-Jacobi sweep of the coarse levels' V-cycle. The cycle stays
/// positive definite only while the sweep converges, ω < 2 / λ_max(D⁻¹ A): 1.3 already breaks
/// the 64² drape's solve (hundreds of CG iterations); 0.85 keeps a margin for stiffer
/// garments and takes 5% fewer iterations than 0.7.
const OMEGA: f64 = 0.85;

/// Weight of the fine level's additive part ω D⁻¹ r: positive definite for any weight, it
/// only balances the fine part against the coarse one. With the coarse sweeps at [`OMEGA`],
/// CG iterations a frame over the whole drape: 64² 39.0 at 0.7, 36.3 at 1.2 (37.5 at 1.5);
/// 128² 36.9 and 35.4.
const FINE_OMEGA: f64 = 1.2;

/// A level with at most this many nodes is the coarsest.
const COARSEST: usize = 64;

/// Coarsening stops when a level would keep more than this fraction of the nodes above it.
const MIN_REDUCTION: f64 = 0.75;

/// Largest coarsest level, in nodes, solved by dense Cholesky (else by one Jacobi sweep): more
/// than [`COARSEST`] only when coarsening stalls, as on many disconnected pieces.
const DENSE: usize = 128;

/// A coarse level: the aggregates of the level above, the matrix between them, and the
/// vectors of the cycle.
#[derive(Clone, Debug)]
struct Level {
    /// The node here (aggregate) of each node of the level above.
    parent: Vec<u32>,
    /// The nodes of the level above in each aggregate.
    members: Csr,
    matrix: BlockMatrix<f64>,
    /// Per slot of the level above's matrix, the block of its aggregates' row here it sums to
    /// (its index among that row's blocks).
    target: Vec<u32>,
    inverse_diagonal: Vec<Mat3>,
    /// Right-hand side, iterate and scratch.
    r: Vec<Vec3>,
    x: Vec<Vec3>,
    t: Vec<Vec3>,
}

/// The hierarchy of one matrix pattern and the buffers of its cycle; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct Multigrid {
    levels: Vec<Level>,
    /// Fine level: whether each particle's filter is the identity and the inverses of the
    /// filtered diagonal blocks.
    free: Vec<bool>,
    inverse_diagonal: Vec<Mat3>,
    /// The filter of the last update: a re-solve inverts again only the blocks whose filter
    /// changed.
    last_filter: Vec<Mat3>,
    /// Dense Cholesky factor of the coarsest level, when it is small and positive definite.
    coarsest: Option<Cholesky<f64, Dyn>>,
}

/// The aggregate of each node of `a`, and the number of aggregates, through the strong
/// couplings only: (i, j) is strong when ‖A_ij‖ ≥ [`STRENGTH`] · √(‖A_ii‖ ‖A_jj‖) (Frobenius
/// norms; Vaněk, Mandel & Brezina's strength of connection), every stored pair when the
/// diagonal is zero (a coarse pattern not yet filled).
fn aggregate<T: Precision>(a: &BlockMatrix<T>) -> (Vec<u32>, usize) {
    const NONE: u32 = u32::MAX;
    let n = a.size();
    let diagonal: Vec<f64> = (0..n).map(|i| a.block(i as u32, i as u32).norm()).collect();
    let diagonal = &diagonal;
    let strong = |v: usize| {
        let slots = a.row_range(v);
        a.columns(v)
            .iter()
            .zip(slots)
            .filter_map(move |(&u, slot)| {
                let scale = (diagonal[v] * diagonal[u as usize]).sqrt();
                (a.block_at(slot).norm() >= STRENGTH * scale).then_some(u)
            })
    };
    let mut parent = vec![NONE; n];
    let mut count = 0;
    for v in 0..n {
        if parent[v] == NONE && strong(v).all(|u| parent[u as usize] == NONE) {
            for u in strong(v) {
                parent[u as usize] = count;
            }
            parent[v] = count;
            count += 1;
        }
    }
    for v in 0..n {
        if parent[v] == NONE {
            parent[v] = strong(v)
                .map(|u| parent[u as usize])
                .find(|&p| p != NONE)
                .unwrap_or_else(|| {
                    count += 1;
                    count - 1
                });
        }
    }
    (parent, count as usize)
}

impl Level {
    /// The aggregates of `above` and the pattern and gather tables between them.
    fn new<T: Precision>(above: &BlockMatrix<T>) -> Self {
        let (parent, count) = aggregate(above);
        let slots = above.slots();
        let coarse_pair = |s: usize| {
            let (i, j) = above.entry(s);
            (parent[i as usize], parent[j as usize])
        };
        let matrix = BlockMatrix::from_pairs(count, (0..slots).map(coarse_pair));
        let target = (0..slots)
            .map(|s| {
                let (i, j) = coarse_pair(s);
                let slot = matrix.slot(i, j).expect("aggregate pair in pattern");
                (slot - matrix.row_range(i as usize).start) as u32
            })
            .collect();
        let members = parent.iter().enumerate().map(|(i, &p)| (p, i as u32));
        Self {
            members: Csr::group_by(count, members),
            target,
            inverse_diagonal: vec![Mat3::identity(); count],
            r: vec![Vec3::zeros(); count],
            x: vec![Vec3::zeros(); count],
            t: vec![Vec3::zeros(); count],
            parent,
            matrix,
        }
    }

    /// Sums the blocks of the level above, each as `block(row, column, block)` makes it, into
    /// this level's matrix: each coarse row from the rows of its aggregate's members, in order,
    /// so every block here is the sum of its sources in the order of their slots above.
    fn gather<T: Precision>(
        &mut self,
        above: &BlockMatrix<T>,
        block: impl Fn(usize, usize, Mat3) -> Mat3 + Sync,
    ) {
        let (members, target) = (&self.members, &self.target);
        self.matrix.fill_rows(|row, blocks| {
            blocks.fill(Mat3::zeros());
            for &i in members.row(row) {
                for (s, j, b) in above.row_blocks(i as usize) {
                    blocks[target[s] as usize] += block(i as usize, j as usize, b);
                }
            }
        });
        invert_diagonal(
            &self.matrix,
            &mut self.inverse_diagonal,
            |_, d| d,
            |_| false,
        );
    }
}

/// The inverse of `filtered(i, block)` for each diagonal block of `a` but those `kept`, or the
/// identity where it is singular.
fn invert_diagonal<T: Precision>(
    a: &BlockMatrix<T>,
    out: &mut [Mat3],
    filtered: impl Fn(usize, Mat3) -> Mat3 + Sync,
    kept: impl Fn(usize) -> bool + Sync,
) {
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (i, d) in (c * CHUNK..).zip(out) {
            if kept(i) {
                continue;
            }
            let block = filtered(i, a.diagonal(i));
            *d = block.try_inverse().unwrap_or_else(Mat3::identity);
        }
    });
}

/// x = ω D⁻¹ r (the first sweep, from x = 0).
fn first_sweep(x: &mut [Vec3], r: &[Vec3], inverse_diagonal: &[Mat3]) {
    for ((x, r), d) in x.iter_mut().zip(r).zip(inverse_diagonal) {
        *x = d * r * OMEGA;
    }
}

/// t = r − A x.
fn residual(t: &mut [Vec3], r: &[Vec3], a: &BlockMatrix<f64>, x: &[Vec3]) {
    a.mul_rows(0, x, t);
    for (t, r) in t.iter_mut().zip(r) {
        *t = r - *t;
    }
}

/// t = x + ω D⁻¹ (r − A x) (the second sweep, written beside x).
fn last_sweep(
    t: &mut [Vec3],
    x: &[Vec3],
    r: &[Vec3],
    a: &BlockMatrix<f64>,
    inverse_diagonal: &[Mat3],
) {
    a.mul_rows(0, x, t);
    for (i, t) in t.iter_mut().enumerate() {
        *t = x[i] + inverse_diagonal[i] * (r[i] - *t) * OMEGA;
    }
}

/// The coarse right-hand side: each aggregate's sum of the fine residuals `t`.
fn restrict(coarse: &mut Level, t: &[Vec3]) {
    let members = &coarse.members;
    for (k, r) in coarse.r.iter_mut().enumerate() {
        *r = members.row(k).iter().map(|&i| t[i as usize]).sum();
    }
}

/// x += P e: each node takes its aggregate's correction.
fn prolong(x: &mut [Vec3], coarse: &Level) {
    for (x, &p) in x.iter_mut().zip(&coarse.parent) {
        *x += coarse.x[p as usize];
    }
}

impl Multigrid {
    /// The hierarchy for matrices of `a`'s pattern, its aggregates following `a`'s strong
    /// couplings, and the buffers of its cycle; [`Self::update`] gives it values.
    pub fn new<T: Precision>(a: &BlockMatrix<T>) -> Self {
        let n = a.size();
        let mut multigrid = Self {
            levels: Vec::new(),
            free: vec![true; n],
            inverse_diagonal: vec![Mat3::identity(); n],
            last_filter: vec![Mat3::identity(); n],
            coarsest: None,
        };
        multigrid.build(a);
        multigrid
    }

    /// The levels below `fine`, down to [`COARSEST`] nodes.
    fn build<T: Precision>(&mut self, fine: &BlockMatrix<T>) {
        let coarser = |above: usize, make: &dyn Fn() -> Level| {
            (above > COARSEST)
                .then(make)
                .filter(|level| level.x.len() as f64 <= MIN_REDUCTION * above as f64)
        };
        let mut next = coarser(fine.size(), &|| Level::new(fine));
        while let Some(level) = next {
            let above = &level.matrix;
            next = coarser(above.size(), &|| Level::new(above));
            self.levels.push(level);
        }
    }

    /// The coarse matrices, diagonal inverses and coarsest factor for the fine matrix `a`
    /// filtered by `filter`; with `coarse` false (the matrix of the last update, a filter
    /// with more contacts) only the fine level's diagonal inverses whose filter changed, the
    /// coarse levels keeping the matrices of the last full update. The preconditioner
    /// stays symmetric and positive on the filtered space either way (the fine level filters
    /// what it restricts and prolongs), so a re-solve of the same matrix with a few more
    /// contacts need not gather the coarse matrices again.
    pub fn update(&mut self, a: &BlockMatrix<f32>, filter: &[Mat3], coarse: bool) {
        let identity = Mat3::identity();
        for (free, s) in self.free.iter_mut().zip(filter) {
            *free = *s == identity;
        }
        let free = &self.free;
        // The fine matrix S A S + (I − S), block by block.
        let filtered = |i: usize, j: usize, block: Mat3| {
            if free[i] && free[j] {
                block
            } else if i == j {
                filter[i] * block * filter[j] + (identity - filter[i])
            } else {
                filter[i] * block * filter[j]
            }
        };
        let last = &self.last_filter;
        invert_diagonal(
            a,
            &mut self.inverse_diagonal,
            |i, d| filtered(i, i, d),
            |i| !coarse && filter[i] == last[i],
        );
        self.last_filter.copy_from_slice(filter);
        if !coarse {
            return;
        }
        if let Some((first, below)) = self.levels.split_first_mut() {
            first.gather(a, filtered);
            let mut above = &first.matrix;
            for level in below {
                level.gather(above, |_, _, block| block);
                above = &level.matrix;
            }
        }
        self.coarsest = self.levels.last().and_then(|l| {
            let m = l.matrix.size();
            if m > DENSE {
                return None;
            }
            let mut dense = DMatrix::zeros(3 * m, 3 * m);
            for slot in 0..l.matrix.slots() {
                let (i, j) = l.matrix.entry(slot);
                dense
                    .fixed_view_mut::<3, 3>(3 * i as usize, 3 * j as usize)
                    .copy_from(&l.matrix.block_at(slot));
            }
            Cholesky::new(dense)
        });
    }

    /// The fine level's part of the preconditioner at particle `i` of the residual `r`:
    /// ω S_i D_i⁻¹ r_i, for the `filter` S given to the last [`Self::update`].
    pub fn smooth(&self, filter: &[Mat3], i: usize, r: Vec3) -> Vec3 {
        self.filtered(filter, i, self.inverse_diagonal[i] * r) * FINE_OMEGA
    }

    /// S_i v, for the `filter` S given to the last [`Self::update`]: v itself where S_i is
    /// the identity (most particles; the product would give the same numbers, but for the
    /// sign of a zero), without reading the filter.
    #[inline]
    pub fn filtered(&self, filter: &[Mat3], i: usize, v: Vec3) -> Vec3 {
        if self.free[i] { v } else { filter[i] * v }
    }

    /// The coarse levels' part of the preconditioner on the fine residual `r` (filtered):
    /// restricts it and runs the V-cycle there, leaving the correction e for
    /// [`Self::correction`]. Returns r · S P e, computed on the first coarse level as
    /// (Pᵀ r) · e (r is filtered and S symmetric): with the fine part's r · ω S D⁻¹ r it
    /// makes the r · z of conjugate gradients without another pass over the particles.
    pub fn coarse_cycle(&mut self, r: &[Vec3]) -> f64 {
        let Some(coarse) = self.levels.first_mut() else {
            return 0.0;
        };
        restrict(coarse, r);
        cycle(&mut self.levels, self.coarsest.as_ref());
        let level = &self.levels[0];
        level.r.iter().zip(&level.x).map(|(r, e)| r.dot(e)).sum()
    }

    /// Whether there are coarse levels (none for a garment too small to coarsen).
    pub fn has_coarse_levels(&self) -> bool {
        !self.levels.is_empty()
    }

    /// The coarse correction of the last [`Self::coarse_cycle`] at fine particle `i`,
    /// unfiltered: its aggregate's (zero without coarse levels).
    pub fn correction(&self, i: usize) -> Vec3 {
        self.levels
            .first()
            .map_or_else(Vec3::zeros, |l| l.x[l.parent[i] as usize])
    }
}

/// The V-cycle from the first of `levels` (its `r` set) down: leaves its iterate in `x`.
fn cycle(levels: &mut [Level], coarsest: Option<&Cholesky<f64, Dyn>>) {
    let (level, below) = levels.split_first_mut().expect("a level to cycle on");
    let Some(coarse) = below.first_mut() else {
        match coarsest {
            Some(factor) => {
                let rhs =
                    DVector::from_iterator(3 * level.r.len(), level.r.iter().flatten().copied());
                let solution = factor.solve(&rhs);
                for (k, x) in level.x.iter_mut().enumerate() {
                    *x = solution.fixed_rows::<3>(3 * k).into();
                }
            }
            None => first_sweep(&mut level.x, &level.r, &level.inverse_diagonal),
        }
        return;
    };
    first_sweep(&mut level.x, &level.r, &level.inverse_diagonal);
    residual(&mut level.t, &level.r, &level.matrix, &level.x);
    restrict(coarse, &level.t);
    cycle(below, coarsest);
    prolong(&mut level.x, &below[0]);
    last_sweep(
        &mut level.t,
        &level.x,
        &level.r,
        &level.matrix,
        &level.inverse_diagonal,
    );
    std::mem::swap(&mut level.x, &mut level.t);
}

#[cfg(test)]
mod tests {
    //! The hierarchy of a grid, and the cycle as a preconditioner: symmetric and positive on
    //! the filtered space, as CG needs.
    use super::*;
    use crate::testing::Rng;

    /// An n × n grid of particles coupled to their 8 neighbours: a random SPD block on each
    /// diagonal (mass plus stiffness), −k I between neighbours, diagonally dominant.
    fn grid(n: u32, rng: &mut Rng) -> BlockMatrix<f32> {
        let id = |i: u32, j: u32| i * n + j;
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for (di, dj) in [(0, 1), (1, 0), (1, 1), (1, -1)] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a < i64::from(n) && (0..i64::from(n)).contains(&b) {
                        pairs.push((id(i, j), id(a as u32, b as u32)));
                    }
                }
            }
        }
        let mut a = BlockMatrix::symmetric((n * n) as usize, pairs);
        let diagonal: Vec<Mat3> = (0..n * n)
            .map(|_| {
                let m = Mat3::from_fn(|_, _| rng.range(-1.0, 1.0));
                Mat3::identity() * 9.0 + m * m.transpose()
            })
            .collect();
        a.fill(|_, i, j| {
            if i == j {
                diagonal[i as usize]
            } else {
                -Mat3::identity()
            }
        });
        a
    }

    #[test]
    fn aggregates_cover_every_node_and_coarsen_to_the_coarsest_size() {
        let mut rng = Rng::new(20);
        let a = grid(40, &mut rng);
        let (parent, count) = aggregate(&a);
        assert!(parent.iter().all(|&p| (p as usize) < count));
        assert!(
            count * 3 < parent.len(),
            "{count} aggregates of {}",
            parent.len()
        );
        let mut mg = Multigrid::new(&a);
        mg.update(&a, &vec![Mat3::identity(); a.size()], true);
        let sizes: Vec<usize> = mg.levels.iter().map(|l| l.x.len()).collect();
        assert!(sizes.windows(2).all(|w| w[1] < w[0]), "sizes {sizes:?}");
        assert!(*sizes.last().unwrap() <= COARSEST, "sizes {sizes:?}");
    }

    #[test]
    fn aggregates_do_not_follow_weak_couplings() {
        // A chain of six, every link strong but the one between 2 and 3.
        let mut a = BlockMatrix::<f64>::from_pairs(6, (1..6).map(|i| (i - 1, i)));
        a.fill(|_, i, j| match (i.min(j), i.max(j)) {
            (d, e) if d == e => Mat3::identity() * 4.0,
            (2, 3) => Mat3::identity() * -1e-3,
            _ => -Mat3::identity(),
        });
        let (parent, count) = aggregate(&a);
        assert_eq!((parent, count), (vec![0, 0, 0, 1, 1, 1], 2));
        // Without values (a pattern) every pair counts, and 2 joins 3.
        let pattern = BlockMatrix::<f64>::from_pairs(6, (1..6).map(|i| (i - 1, i)));
        let (parent, _) = aggregate(&pattern);
        assert_eq!(parent[2], parent[3]);
    }

    #[test]
    fn the_cycle_is_symmetric_and_positive_on_the_filtered_space() {
        let mut rng = Rng::new(21);
        let a = grid(30, &mut rng);
        let n = a.size();
        let mut filter = vec![Mat3::identity(); n];
        for (k, s) in filter.iter_mut().enumerate().step_by(7) {
            let normal = rng.vec3().normalize();
            *s = if k % 2 == 0 {
                Mat3::zeros()
            } else {
                Mat3::identity() - normal * normal.transpose()
            };
        }
        let mut mg = Multigrid::new(&a);
        mg.update(&a, &filter, true);
        // z = M r as conjugate gradients makes it, and its r · z.
        let mut apply = |r: &[Vec3]| -> (Vec<Vec3>, f64) {
            let coarse = mg.coarse_cycle(r);
            let z: Vec<Vec3> = (0..n)
                .map(|i| mg.smooth(&filter, i, r[i]) + filter[i] * mg.correction(i))
                .collect();
            let fine: f64 = (0..n).map(|i| r[i].dot(&mg.smooth(&filter, i, r[i]))).sum();
            (z, fine + coarse)
        };
        let filtered =
            |rng: &mut Rng| -> Vec<Vec3> { (0..n).map(|i| filter[i] * rng.vec3()).collect() };
        let dot = |u: &[Vec3], v: &[Vec3]| -> f64 { u.iter().zip(v).map(|(a, b)| a.dot(b)).sum() };
        for _ in 0..5 {
            let (y, z) = (filtered(&mut rng), filtered(&mut rng));
            let (my, ymy) = apply(&y);
            let (mz, _) = apply(&z);
            let (zmy, ymz) = (dot(&z, &my), dot(&y, &mz));
            assert!(
                (ymy - dot(&y, &my)).abs() < 1e-10 * ymy.abs(),
                "{ymy} vs y · My"
            );
            assert!(
                (zmy - ymz).abs() < 1e-10 * zmy.abs().max(1.0),
                "{zmy} vs {ymz}"
            );
            assert!(dot(&y, &my) > 0.0);
            for (s, v) in filter.iter().zip(&my) {
                assert!(((Mat3::identity() - s) * v).norm() < 1e-12 * (1.0 + v.norm()));
            }
        }
    }
}
