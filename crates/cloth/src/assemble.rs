//! Forces and their Jacobians, assembled into the implicit system every Newton iteration.
//!
//! For positions x, velocities v and the damping directions of the step's start, this computes
//! the total force f (springs, dampers, shear, bend, gravity, drag) and the matrix
//!
//!   A = c_m M + c_v (−∂f/∂v) + c_x (−∂f/∂x),
//!
//! which for Baraff & Witkin's backward Euler step (§4, eq. 16) is M − h ∂f/∂v − h² ∂f/∂x, and
//! for a finite-difference check is ∂f/∂x or ∂f/∂v alone ([`Coefficients`]).
//!
//! The pattern is built once from the model's elements; each evaluation works in two parallel
//! passes with no allocation: every element writes its local forces and 3×3 blocks into its
//! own slots of flat buffers, then every particle (for f) and every matrix block (for A) sums
//! the slots that feed it, in a fixed order recorded at construction. The result is the same on
//! any thread count. An evaluation without [`Coefficients`] (the end of a substep's last Newton
//! iteration, the symplectic step, the energy) computes forces and energies only: no element
//! Hessians, no projection, no matrix.
//!
//! Dampers follow the lesson's eq. 3, F_i = k_d ((v_j − v_i)·u) u, with the direction u taken
//! at the step's start (`damping_positions`) — the approximation Baraff & Witkin make in §5.2 —
//! so the damper is linear in v and derives from the dissipation ½ k_d ((v_j − v_i)·u)², which
//! lets a line search use a true potential. Air drag is −drag · area · (v − wind).

use rayon::prelude::*;
use tailor_subdiv::Point;
use tailor_subdiv::topology::Csr;

use crate::energy::{self, Local, Mat3, Vec3, expand_gradient, expand_hessian};
use crate::matrix::{BlockMatrix, csr_from_sorted};
use crate::model::Model;
use crate::reduce::{partial_count, sum_by};

/// Weights of the three parts of the assembled matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coefficients {
    /// Of the mass matrix.
    pub mass: f64,
    /// Of −∂f/∂v.
    pub damping: f64,
    /// Of −∂f/∂x.
    pub stiffness: f64,
}

/// The world around the cloth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Environment {
    /// m/s².
    pub gravity: Vec3,
    /// m/s.
    pub wind: Vec3,
}

/// Scalars of one evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Totals {
    /// Elastic plus gravitational potential energy, J.
    pub potential: f64,
    /// Dissipation function of dampers and drag, W.
    pub dissipation: f64,
}

/// One element's forces and scalars (its blocks go straight to their slots).
struct Out<const N: usize, E> {
    force: [Vec3; N],
    energy: f64,
    extra: E,
}

/// Buffers and gather tables for a model; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct Assembly {
    pub matrix: BlockMatrix,
    pub force: Vec<Vec3>,
    block_sources: Csr,
    force_sources: Csr,
    local_force: Vec<Vec3>,
    local_block: Vec<Mat3>,
    energy: Vec<f64>,
    /// Per spring: the damper's dissipation.
    spring_extra: Vec<f64>,
    partials: Vec<f64>,
}

/// The (vertex, local slot) and (vertex pair, local block) pairs of `N`-point elements whose
/// local forces start at `force_base` and local blocks at `block_base`.
fn sources<const N: usize>(
    verts: &[[u32; N]],
    force_base: usize,
    block_base: usize,
    force_pairs: &mut Vec<(u32, u32)>,
    block_pairs: &mut Vec<(u32, u32, u32)>,
) {
    for (e, vs) in verts.iter().enumerate() {
        for (a, &va) in vs.iter().enumerate() {
            force_pairs.push((va, (force_base + e * N + a) as u32));
            for (b, &vb) in vs.iter().enumerate() {
                block_pairs.push((va, vb, (block_base + (e * N + a) * N + b) as u32));
            }
        }
    }
}

/// Runs `kernel` over `n` elements in parallel, writing each one's outputs to its slots; the
/// kernel writes its N × N blocks itself, given their slots (only `with_blocks`).
fn run<const N: usize, E: Send>(
    forces: &mut [Vec3],
    blocks: &mut [Mat3],
    energy: &mut [f64],
    extra: &mut [E],
    with_blocks: bool,
    kernel: impl Fn(usize, Option<&mut [Mat3]>) -> Out<N, E> + Sync,
) {
    forces
        .par_chunks_mut(N)
        .zip(blocks.par_chunks_mut(N * N))
        .zip(energy.par_iter_mut())
        .zip(extra.par_iter_mut())
        .enumerate()
        .for_each(|(e, (((f, b), en), ex))| {
            let out = kernel(e, with_blocks.then_some(b));
            f.copy_from_slice(&out.force);
            *en = out.energy;
            *ex = out.extra;
        });
}

/// Forces −∂E/∂p of a d-space energy, and into `blocks`, when given, scale · ∂²E/∂p².
fn conservative<const K: usize, const N: usize>(
    local: &Local<K>,
    coef: &[[f64; N]; K],
    blocks: Option<(&mut [Mat3], f64)>,
) -> [Vec3; N] {
    if let Some((blocks, scale)) = blocks {
        expand_hessian(local, coef, blocks);
        for h in blocks {
            *h *= scale;
        }
    }
    expand_gradient(local, coef).map(|g| -g)
}

impl Assembly {
    /// The pattern and gather tables of `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.vertex_count();
        let (s, q, t) = (&model.springs, &model.quads, &model.triples);
        let (fs, fq) = (2 * s.verts.len(), 4 * q.verts.len());
        let (bs, bq) = (4 * s.verts.len(), 16 * q.verts.len());
        let mut force_pairs = Vec::new();
        let mut block_pairs = Vec::new();
        sources(&s.verts, 0, 0, &mut force_pairs, &mut block_pairs);
        sources(&q.verts, fs, bs, &mut force_pairs, &mut block_pairs);
        sources(
            &t.verts,
            fs + fq,
            bs + bq,
            &mut force_pairs,
            &mut block_pairs,
        );
        let matrix = BlockMatrix::from_pairs(n, block_pairs.iter().map(|&(a, b, _)| (a, b)));
        let mut slot_pairs: Vec<(u32, u32)> = block_pairs
            .iter()
            .map(|&(a, b, local)| {
                let slot = matrix.slot(a, b).expect("element pair in pattern");
                (slot as u32, local)
            })
            .collect();
        slot_pairs.sort_unstable();
        force_pairs.sort_unstable();
        let elements = s.verts.len() + q.verts.len() + t.verts.len();
        Self {
            block_sources: csr_from_sorted(matrix.blocks().len(), &slot_pairs),
            force_sources: csr_from_sorted(n, &force_pairs),
            local_force: vec![Vec3::zeros(); force_pairs.len()],
            local_block: vec![Mat3::zeros(); block_pairs.len()],
            energy: vec![0.0; elements],
            spring_extra: vec![0.0; s.verts.len()],
            partials: vec![0.0; partial_count(elements.max(n))],
            force: vec![Vec3::zeros(); n],
            matrix,
        }
    }

    /// Evaluates forces into [`Self::force`] at positions `x` and velocities `v`, dampers along
    /// the edges at `damping_positions`, and, given its coefficients `c`, the matrix into
    /// [`Self::matrix`] (without, the matrix keeps its old values and the element Hessians are
    /// not assembled); Hessians of non-convex energies are projected to PSD when `project` is
    /// set.
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate(
        &mut self,
        model: &Model,
        x: &[Point],
        damping_positions: &[Point],
        v: &[Vec3],
        env: &Environment,
        c: Option<Coefficients>,
        project: bool,
    ) -> Totals {
        let with_blocks = c.is_some();
        // Projection changes only Hessians: without a matrix the cheaper raw ones will do.
        let project = project && with_blocks;
        let stiffness = c.map(|c| c.stiffness);
        let (s, q, t) = (&model.springs, &model.quads, &model.triples);
        let p = |i: u32| x[i as usize].coords;
        let (fs, fq) = self.local_force.split_at_mut(2 * s.verts.len());
        let (fq, ft) = fq.split_at_mut(4 * q.verts.len());
        let (bs, bq) = self.local_block.split_at_mut(4 * s.verts.len());
        let (bq, bt) = bq.split_at_mut(16 * q.verts.len());
        let (es, eq) = self.energy.split_at_mut(s.verts.len());
        let (eq, et) = eq.split_at_mut(q.verts.len());
        run(
            fs,
            bs,
            es,
            &mut self.spring_extra,
            with_blocks,
            |e, mut blocks| {
                let [a, b] = s.verts[e];
                let [stretch, compression, kd] = s.stiffness[e];
                let d = p(a) - p(b);
                let local = energy::stretch(&d, s.rest[e], stretch, compression, project);
                let mut force =
                    conservative(&local, &[[1.0, -1.0]], blocks.as_deref_mut().zip(stiffness));
                let u = (damping_positions[a as usize] - damping_positions[b as usize])
                    .try_normalize(0.0)
                    .unwrap_or_else(Vec3::zeros);
                let closing = (v[a as usize] - v[b as usize]).dot(&u);
                let damper = u * (kd * closing);
                force[0] -= damper;
                force[1] += damper;
                if let (Some(block), Some(c)) = (blocks, c) {
                    let dv = u * u.transpose() * (kd * c.damping);
                    block[0] += dv;
                    block[3] += dv;
                    block[1] -= dv;
                    block[2] -= dv;
                }
                Out {
                    force,
                    energy: local.energy,
                    extra: 0.5 * kd * closing * closing,
                }
            },
        );
        run(
            fq,
            bq,
            eq,
            &mut vec![(); q.verts.len()],
            with_blocks,
            |e, blocks| {
                let [p0, p1, p2, p3] = q.verts[e];
                let local = energy::shear(
                    &(p(p0) - p(p2)),
                    &(p(p1) - p(p3)),
                    q.rest[e],
                    q.stiffness[e],
                    project,
                );
                let coef = [[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]];
                Out {
                    force: conservative(&local, &coef, blocks.zip(stiffness)),
                    energy: local.energy,
                    extra: (),
                }
            },
        );
        run(
            ft,
            bt,
            et,
            &mut vec![(); t.verts.len()],
            with_blocks,
            |e, blocks| {
                let [p1, p2, p3] = t.verts[e];
                let k = t.coef[e];
                let bend = p(p1) * k[0] + p(p2) * k[1] + p(p3) * k[2];
                let local = energy::bend(&bend, t.rest[e], t.stiffness[e], project);
                Out {
                    force: conservative(&local, &[k], blocks.zip(stiffness)),
                    energy: local.energy,
                    extra: (),
                }
            },
        );
        let drag = model.material.drag;
        let (local_force, local_block) = (&self.local_force, &self.local_block);
        let force_sources = &self.force_sources;
        self.force.par_iter_mut().enumerate().for_each(|(i, f)| {
            let gathered: Vec3 = force_sources
                .row(i)
                .iter()
                .map(|&k| local_force[k as usize])
                .sum();
            *f =
                gathered + env.gravity * model.mass[i] - (v[i] - env.wind) * (drag * model.area[i]);
        });
        if let Some(c) = c {
            let block_sources = &self.block_sources;
            self.matrix.fill(|slot, row, col| {
                let mut sum: Mat3 = block_sources
                    .row(slot)
                    .iter()
                    .map(|&k| local_block[k as usize])
                    .sum();
                if row == col {
                    let i = row as usize;
                    sum += Mat3::identity()
                        * (c.mass * model.mass[i] + c.damping * drag * model.area[i]);
                }
                sum
            });
        }
        let energy = &self.energy;
        let elastic = sum_by(energy.len(), &mut self.partials, |e| energy[e]);
        let gravity = sum_by(x.len(), &mut self.partials, |i| {
            -model.mass[i] * env.gravity.dot(&x[i].coords)
        });
        let extra = &self.spring_extra;
        let dampers = sum_by(extra.len(), &mut self.partials, |e| extra[e]);
        let air = sum_by(v.len(), &mut self.partials, |i| {
            0.5 * drag * model.area[i] * (v[i] - env.wind).norm_squared()
        });
        Totals {
            potential: elastic + gravity,
            dissipation: dampers + air,
        }
    }
}

#[cfg(test)]
mod tests {
    //! Finite-difference checks of the assembled forces and Jacobians of a whole garment, and
    //! the invariants of internal forces (Newton's third law, lesson eq. 5).
    use super::*;
    use crate::Material;
    use crate::testing::{Rng, irregular_mesh};

    struct Setup {
        model: Model,
        assembly: Assembly,
        x: Vec<Point>,
        x_damp: Vec<Point>,
        v: Vec<Vec3>,
        env: Environment,
    }

    fn setup(seed: u64, material: Material, env: Environment) -> Setup {
        let mut rng = Rng::new(seed);
        let model = Model::new(&irregular_mesh(&mut rng), &material).unwrap();
        let jitter = |rng: &mut Rng, scale: f64| -> Vec<Point> {
            model.rest.iter().map(|p| p + rng.vec3() * scale).collect()
        };
        let x = jitter(&mut rng, 0.15);
        let x_damp = jitter(&mut rng, 0.1);
        let v = (0..model.vertex_count()).map(|_| rng.vec3()).collect();
        Setup {
            assembly: Assembly::new(&model),
            model,
            x,
            x_damp,
            v,
            env,
        }
    }

    const WORLD: Environment = Environment {
        gravity: Vec3::new(0.0, -9.81, 0.0),
        wind: Vec3::new(1.0, 0.0, 0.5),
    };

    fn force(s: &mut Setup, x: &[Point], v: &[Vec3]) -> Vec<Vec3> {
        s.assembly
            .evaluate(&s.model, x, &s.x_damp, v, &s.env, None, false);
        s.assembly.force.clone()
    }

    /// Relative error of J·δ against central differences of f, for `c` selecting J.
    fn jacobian_error(s: &mut Setup, c: Coefficients, along_x: bool, rng: &mut Rng) -> f64 {
        let delta: Vec<Vec3> = (0..s.x.len()).map(|_| rng.vec3()).collect();
        let (x, v) = (s.x.clone(), s.v.clone());
        s.assembly
            .evaluate(&s.model, &x, &s.x_damp, &v, &s.env, Some(c), false);
        let mut jd = vec![Vec3::zeros(); x.len()];
        s.assembly.matrix.mul_into(&delta, &mut jd);
        let eps = 1e-6;
        let shift = |sign: f64| -> (Vec<Point>, Vec<Vec3>) {
            if along_x {
                (
                    x.iter()
                        .zip(&delta)
                        .map(|(p, d)| p + d * (sign * eps))
                        .collect(),
                    v.clone(),
                )
            } else {
                (
                    x.clone(),
                    v.iter()
                        .zip(&delta)
                        .map(|(p, d)| p + d * (sign * eps))
                        .collect(),
                )
            }
        };
        let (xp, vp) = shift(1.0);
        let (xm, vm) = shift(-1.0);
        let (fp, fm) = (force(s, &xp, &vp), force(s, &xm, &vm));
        let mut err: f64 = 0.0;
        let mut norm: f64 = 0.0;
        for i in 0..x.len() {
            let fd = (fp[i] - fm[i]) / (2.0 * eps);
            err += (fd - jd[i]).norm_squared();
            norm += jd[i].norm_squared();
        }
        (err / norm).sqrt()
    }

    #[test]
    fn force_is_minus_the_energy_gradient() {
        let mut rng = Rng::new(10);
        for seed in 0..5 {
            let mut s = setup(seed, Material::DENIM, WORLD);
            // Moving with the wind, dampers and drag exert nothing: f = −∇U.
            let (x, v) = (s.x.clone(), vec![s.env.wind; s.x.len()]);
            let f = force(&mut s, &x, &v);
            let delta: Vec<Vec3> = (0..x.len()).map(|_| rng.vec3()).collect();
            let eps = 1e-6;
            let mut potential = |sign: f64| {
                let xs: Vec<Point> = x
                    .iter()
                    .zip(&delta)
                    .map(|(p, d)| p + d * (sign * eps))
                    .collect();
                s.assembly
                    .evaluate(&s.model, &xs, &s.x_damp, &v, &s.env, None, false)
                    .potential
            };
            let fd = (potential(1.0) - potential(-1.0)) / (2.0 * eps);
            let exact: f64 = -f.iter().zip(&delta).map(|(f, d)| f.dot(d)).sum::<f64>();
            assert!(
                (fd - exact).abs() < 1e-6 * exact.abs(),
                "seed {seed}: fd {fd} vs {exact}"
            );
        }
    }

    #[test]
    fn position_jacobian_matches_finite_differences() {
        let mut rng = Rng::new(11);
        let c = Coefficients {
            mass: 0.0,
            damping: 0.0,
            stiffness: -1.0,
        };
        for seed in 0..5 {
            let mut s = setup(seed, Material::DENIM, WORLD);
            let err = jacobian_error(&mut s, c, true, &mut rng);
            assert!(err < 1e-6, "seed {seed}: relative error {err}");
        }
    }

    #[test]
    fn velocity_jacobian_matches_finite_differences() {
        let mut rng = Rng::new(12);
        let c = Coefficients {
            mass: 0.0,
            damping: -1.0,
            stiffness: 0.0,
        };
        for seed in 0..5 {
            let mut s = setup(seed, Material::LEATHER, WORLD);
            let err = jacobian_error(&mut s, c, false, &mut rng);
            assert!(err < 1e-6, "seed {seed}: relative error {err}");
        }
    }

    #[test]
    fn internal_forces_sum_to_zero_and_conserve_angular_momentum() {
        let still = Environment {
            gravity: Vec3::zeros(),
            wind: Vec3::zeros(),
        };
        let material = Material {
            drag: 0.0,
            ..Material::COTTON
        };
        for seed in 0..5 {
            let mut s = setup(seed, material, still);
            s.x_damp.clone_from(&s.x);
            let (x, v) = (s.x.clone(), s.v.clone());
            let f = force(&mut s, &x, &v);
            let scale: f64 = f.iter().map(|f| f.norm()).sum();
            let total: Vec3 = f.iter().sum();
            let torque: Vec3 = x.iter().zip(&f).map(|(p, f)| p.coords.cross(f)).sum();
            assert!(total.norm() < 1e-12 * scale, "seed {seed}: Σf = {total}");
            assert!(
                torque.norm() < 1e-12 * scale,
                "seed {seed}: Σx×f = {torque}"
            );
        }
    }

    #[test]
    fn projected_system_is_symmetric_positive_definite() {
        let mut rng = Rng::new(13);
        let mut s = setup(3, Material::COTTON, WORLD);
        let h = 1.0 / 120.0;
        let c = Coefficients {
            mass: 1.0,
            damping: h,
            stiffness: h * h,
        };
        let (x, v) = (s.x.clone(), s.v.clone());
        s.assembly
            .evaluate(&s.model, &x, &s.x_damp, &v, &s.env, Some(c), true);
        let a = &s.assembly.matrix;
        for (slot, (i, j)) in a.entries().enumerate() {
            assert_eq!(a.blocks()[slot], a.block(j, i).transpose());
        }
        for _ in 0..20 {
            let y: Vec<Vec3> = (0..x.len()).map(|_| rng.vec3()).collect();
            let mut ay = vec![Vec3::zeros(); x.len()];
            a.mul_into(&y, &mut ay);
            let quad: f64 = y.iter().zip(&ay).map(|(a, b)| a.dot(b)).sum();
            let mass: f64 = y
                .iter()
                .zip(&s.model.mass)
                .map(|(y, m)| m * y.norm_squared())
                .sum();
            assert!(quad >= mass * (1.0 - 1e-9), "yᵀAy = {quad} < yᵀMy = {mass}");
        }
    }
}
