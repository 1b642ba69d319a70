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
//! passes with no allocation. First every element writes what it computes *in d-space* into
//! its own slots of flat buffers: the gradient and Hessian of its energy with respect to its
//! one or two difference vectors d = Σ c_a p_a (see [`crate::energy`]), a 3-vector and a 3×3
//! block per d, not per point: one block for a spring or a bend triple instead of four or
//! nine, four for a quad's shear instead of sixteen. Then every particle (for f) and every
//! matrix block (for A) sums the d-space slots that feed it, each times its constant weight
//! from the chain rule (f_a = −Σ_k c_ka g_k, A_ab = Σ_kl c_ka c_lb H_kl), in a fixed order
//! recorded at construction. The result is the same on any thread count, and a 64² sheet's
//! evaluation moves a fifth of the bytes it moved when elements wrote their point blocks. An
//! evaluation without [`Coefficients`] (the end of a substep's last Newton iteration, the
//! symplectic step, the energy) computes forces and energies only: no element Hessians, no
//! projection, no matrix.
//!
//! Dampers follow the lesson's eq. 3, F_i = k_d ((v_j − v_i)·u) u, with the direction u taken
//! at the step's start (`damping_positions`) — the approximation Baraff & Witkin make in §5.2 —
//! so the damper is linear in v and derives from the dissipation ½ k_d ((v_j − v_i)·u)², which
//! lets a line search use a true potential. Air drag is −drag · area · (v − wind).

use rayon::prelude::*;
use tailor_subdiv::Point;
use tailor_subdiv::csr::Csr;

use crate::energy::{self, Local, Mat3, Vec3};
use crate::matrix::{BlockMatrix, sorted_rows};
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

impl Coefficients {
    /// The matrix of an implicit step whose positions move by `h` times the new velocity:
    /// M − h ∂f/∂v − h² ∂f/∂x.
    pub fn implicit(h: f64) -> Self {
        Self {
            mass: 1.0,
            damping: h,
            stiffness: h * h,
        }
    }
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

/// One element's d-space gradient and scalars (its blocks go straight to their slots).
struct Out<const K: usize, E> {
    grad: [Vec3; K],
    energy: f64,
    extra: E,
}

/// Sums of weighted d-space slots: row `r` of `sources` lists the slots feeding output `r`,
/// `weights` the chain-rule weight of each.
#[derive(Clone, Debug)]
struct Gather {
    sources: Csr,
    weights: Vec<f64>,
}

impl Gather {
    /// From (output, slot, weight) triples, each (output, slot) once, in output then slot
    /// order.
    fn new(outputs: usize, triples: &[(u32, u32, f64)]) -> Self {
        let sources = triples.iter().map(|&(out, slot, w)| (out, (slot, w)));
        let (offsets, sources) = sorted_rows(outputs, sources, |&(slot, _)| slot);
        Self {
            sources: Csr {
                offsets,
                items: sources.iter().map(|&(slot, _)| slot).collect(),
            },
            weights: sources.iter().map(|&(_, w)| w).collect(),
        }
    }

    /// Σ weight · `slots[slot]` over the sources of output `r`.
    fn sum<T>(&self, r: usize, slots: &[T]) -> T
    where
        T: Copy + std::ops::Mul<f64, Output = T> + std::iter::Sum,
    {
        let range = self.sources.range(r);
        self.sources.items[range.clone()]
            .iter()
            .zip(&self.weights[range])
            .map(|(&k, &w)| slots[k as usize] * w)
            .sum()
    }
}

/// Buffers and gather tables for a model; see the module docs.
#[derive(Clone, Debug)]
pub(crate) struct Assembly {
    pub matrix: BlockMatrix<f32>,
    pub force: Vec<Vec3>,
    /// Per stored matrix block, and per particle: the d-space slots that sum to it.
    blocks: Gather,
    forces: Gather,
    /// d-space gradients and Hessians of every element, springs then quads then triples.
    local_grad: Vec<Vec3>,
    local_hess: Vec<Mat3>,
    energy: Vec<f64>,
    /// Per spring: the damper's dissipation.
    spring_extra: Vec<f64>,
    partials: Vec<f64>,
}

/// The gather triples of `N`-point elements of `K` difference vectors with coefficients
/// `coef(e)`, whose gradients start at slot `grad_base` and Hessians at `hess_base`: (particle,
/// gradient slot, −c_ka) for the forces, ((row, column), Hessian slot, c_ka c_lb) for the blocks.
fn sources<const N: usize, const K: usize>(
    verts: &[[u32; N]],
    coef: impl Fn(usize) -> [[f64; N]; K],
    (grad_base, hess_base): (usize, usize),
    force_triples: &mut Vec<(u32, u32, f64)>,
    block_triples: &mut Vec<((u32, u32), u32, f64)>,
) {
    for (e, vs) in verts.iter().enumerate() {
        let c = coef(e);
        for (k, c_k) in c.iter().enumerate() {
            for (&va, &ca) in vs.iter().zip(c_k) {
                if ca != 0.0 {
                    force_triples.push((va, (grad_base + e * K + k) as u32, -ca));
                }
                for (l, c_l) in c.iter().enumerate() {
                    for (&vb, &cb) in vs.iter().zip(c_l) {
                        if ca * cb != 0.0 {
                            let slot = (hess_base + (e * K + k) * K + l) as u32;
                            block_triples.push(((va, vb), slot, ca * cb));
                        }
                    }
                }
            }
        }
    }
}

/// Runs `kernel` over `n` elements in parallel, writing each one's d-space outputs to its
/// slots; the kernel writes its K × K Hessian blocks itself, given their slots (only
/// `with_blocks`).
fn run<const K: usize, E: Send>(
    grads: &mut [Vec3],
    hessians: &mut [Mat3],
    energy: &mut [f64],
    extra: &mut [E],
    with_blocks: bool,
    kernel: impl Fn(usize, Option<&mut [Mat3]>) -> Out<K, E> + Sync,
) {
    grads
        .par_chunks_mut(K)
        .zip(hessians.par_chunks_mut(K * K))
        .zip(energy.par_iter_mut())
        .zip(extra.par_iter_mut())
        .enumerate()
        .for_each(|(e, (((g, h), en), ex))| {
            let out = kernel(e, with_blocks.then_some(h));
            g.copy_from_slice(&out.grad);
            *en = out.energy;
            *ex = out.extra;
        });
}

/// The gradient of a d-space energy, and into `blocks`, when given, scale · its Hessian.
fn conservative<const K: usize>(local: &Local<K>, blocks: Option<(&mut [Mat3], f64)>) -> [Vec3; K] {
    if let Some((blocks, scale)) = blocks {
        for (b, h) in blocks.iter_mut().zip(local.hess.iter().flatten()) {
            *b = h * scale;
        }
    }
    local.grad
}

/// Coefficients of a spring's difference vector p1 − p2.
const SPRING: [[f64; 2]; 1] = [[1.0, -1.0]];

/// Coefficients of a quad's diagonals p0 − p2 and p1 − p3.
const DIAGONALS: [[f64; 4]; 2] = [[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]];

impl Assembly {
    /// The pattern and gather tables of `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.vertex_count();
        let (s, q, t) = (&model.springs, &model.quads, &model.triples);
        let (gs, gq) = (s.verts.len(), 2 * q.verts.len());
        let (hs, hq) = (s.verts.len(), 4 * q.verts.len());
        let mut force_triples = Vec::new();
        let mut block_triples = Vec::new();
        let (f, b) = (&mut force_triples, &mut block_triples);
        sources(&s.verts, |_| SPRING, (0, 0), f, b);
        sources(&q.verts, |_| DIAGONALS, (gs, hs), f, b);
        sources(&t.verts, |e| [t.coef[e]], (gs + gq, hs + hq), f, b);
        let matrix = BlockMatrix::symmetric(n, block_triples.iter().map(|&(pair, _, _)| pair));
        // Only the blocks on and above the diagonal are summed: each below is the transpose
        // of its mirror, the same terms transposed (every element's d-space Hessian is
        // symmetric).
        let slot_triples: Vec<_> = block_triples
            .iter()
            .filter_map(|&((a, b), local, w)| {
                let slot = matrix.slot(a, b).expect("element pair in pattern");
                let value = matrix.value_index(slot)?;
                Some((value as u32, local, w))
            })
            .collect();
        let elements = s.verts.len() + q.verts.len() + t.verts.len();
        Self {
            blocks: Gather::new(matrix.values().len(), &slot_triples),
            forces: Gather::new(n, &force_triples),
            local_grad: vec![Vec3::zeros(); gs + gq + t.verts.len()],
            local_hess: vec![Mat3::zeros(); hs + hq + t.verts.len()],
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
        let (gs, gq) = self.local_grad.split_at_mut(s.verts.len());
        let (gq, gt) = gq.split_at_mut(2 * q.verts.len());
        let (hs, hq) = self.local_hess.split_at_mut(s.verts.len());
        let (hq, ht) = hq.split_at_mut(4 * q.verts.len());
        let (es, eq) = self.energy.split_at_mut(s.verts.len());
        let (eq, et) = eq.split_at_mut(q.verts.len());
        run(
            gs,
            hs,
            es,
            &mut self.spring_extra,
            with_blocks,
            |e, mut blocks| {
                let [a, b] = s.verts[e];
                let [stretch, compression, kd] = s.stiffness[e];
                let d = p(a) - p(b);
                let local = energy::stretch(&d, s.rest[e], stretch, compression, project);
                let [grad] = conservative(&local, blocks.as_deref_mut().zip(stiffness));
                let u = (damping_positions[a as usize] - damping_positions[b as usize])
                    .try_normalize(0.0)
                    .unwrap_or_else(Vec3::zeros);
                let closing = (v[a as usize] - v[b as usize]).dot(&u);
                // The damper acts along the same d = p1 − p2: its force on p1 is −k_d (u·v̇) u.
                if let (Some([block]), Some(c)) = (blocks, c) {
                    *block += u * u.transpose() * (kd * c.damping);
                }
                Out {
                    grad: [grad + u * (kd * closing)],
                    energy: local.energy,
                    extra: 0.5 * kd * closing * closing,
                }
            },
        );
        run(
            gq,
            hq,
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
                Out {
                    grad: conservative(&local, blocks.zip(stiffness)),
                    energy: local.energy,
                    extra: (),
                }
            },
        );
        run(
            gt,
            ht,
            et,
            &mut vec![(); t.verts.len()],
            with_blocks,
            |e, blocks| {
                let [p1, p2, p3] = t.verts[e];
                let k = t.coef[e];
                let bend = p(p1) * k[0] + p(p2) * k[1] + p(p3) * k[2];
                let local = energy::bend(&bend, t.rest[e], t.stiffness[e], project);
                Out {
                    grad: conservative(&local, blocks.zip(stiffness)),
                    energy: local.energy,
                    extra: (),
                }
            },
        );
        let drag = model.material.drag;
        let (local_grad, local_hess) = (&self.local_grad, &self.local_hess);
        let forces = &self.forces;
        self.force.par_iter_mut().enumerate().for_each(|(i, f)| {
            *f = forces.sum(i, local_grad) + env.gravity * model.mass[i]
                - (v[i] - env.wind) * (drag * model.area[i]);
        });
        if let Some(c) = c {
            let blocks = &self.blocks;
            self.matrix.fill(|value, row, col| {
                let mut sum = blocks.sum(value, local_hess);
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
        // The matrix stores the blocks on and above the diagonal, standing for their mirrors
        // transposed: right when every element's d-space Hessian is symmetric, to the bit.
        let (springs, quads) = (s.model.springs.verts.len(), s.model.quads.verts.len());
        let hess = &s.assembly.local_hess;
        for (k, h) in hess.iter().enumerate() {
            let quad_slot = (k >= springs && k < springs + 4 * quads).then(|| (k - springs) % 4);
            let mirror = match quad_slot {
                Some(1) => hess[k + 1],
                Some(2) => hess[k - 1],
                _ => *h,
            };
            assert_eq!(*h, mirror.transpose(), "d-space Hessian slot {k}");
        }
        let a = &s.assembly.matrix;
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
