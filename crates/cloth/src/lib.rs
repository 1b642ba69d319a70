//! Cloth simulated on the control points of a subdivision surface, as in Pixar's *Geri's Game*
//! (DeRose, Kass & Truong, "Subdivision Surfaces in Character Animation", SIGGRAPH 1998, §5).
//!
//! The garment's control mesh is a mass-spring system ([`Model`]): particles at the control
//! vertices with lumped masses, and the paper's energies — stretch on edges (eq. 4), shear on
//! quad diagonals (eq. 5), bend along threads (eq. 6–7) — plus the lesson's spring dampers
//! (`../shared/background/mass-spring-lesson.txt`, eq. 1–7), gravity and air drag.
//! The [`Simulator`] advances it with implicit steps, BDF2 (Choi & Ko, "Stable but Responsive
//! Cloth", SIGGRAPH 2002) or Baraff & Witkin's backward Euler ("Large Steps in Cloth
//! Simulation", SIGGRAPH 1998): one linear solve per step — or several Newton iterations with
//! a line search — by conjugate gradients on a block-sparse matrix, with pins, attachments and
//! contact planes enforced exactly by the constraint filter.
//!
//! Layers, as in the rest of tailor: the private `energy` module holds the pure element rules
//! (energies, gradients, PSD-projected Hessians); [`model`] and the private `threads` module
//! the tables built once from the topology, as are the solver's multigrid aggregates; the
//! assembly, the block matrix, the preconditioned conjugate gradients and [`simulator`] the
//! per-step evaluation.
//!
//! A cotton sheet pinned at two corners, one second at 24 frames a second:
//!
//! ```
//! use tailor_cloth::shapes::sheet;
//! use tailor_cloth::{Material, Model, Motion, Settings, Simulator, State};
//!
//! let model = Model::new(&sheet(8, 8, 1.0, 1.0), &Material::COTTON)?;
//! let mut sim = Simulator::new(model, Settings::default())?;
//! sim.pin(&[0, 7], Motion::Fixed)?;
//! let mut state = State::at_rest(sim.model());
//! for _ in 0..24 {
//!     let report = sim.step(&mut state, 1.0 / 24.0)?;
//!     assert!(report.max_strain <= 0.1 + 1e-9);
//! }
//! // It fell, and hangs from its pins.
//! assert!(state.positions.iter().any(|p| p.y < -0.3));
//! assert_eq!(state.positions[0], sim.model().rest_positions()[0]);
//! # Ok::<(), tailor_cloth::ClothError>(())
//! ```
//!
//! Collisions go through `tailor-collide` (Bridson, Fedkiw & Anderson 2002; the private
//! `collision` module documents each pass, the private `response` module the order a substep
//! runs them in, with strain limiting between them). The obstacle is a polygon mesh of fixed topology:
//! [`Simulator::set_obstacle`] once with its rest positions and CSR faces (the positions guide
//! the hierarchy, which is built once; this is the one difference from the pipeline's sketch,
//! which had no positions), then [`Simulator::set_obstacle_motion`] per frame with its
//! positions at the frame's start and end; substeps interpolate linearly. [`Settings`] holds
//! the `thickness` (m), Coulomb `friction` and `self_collision`. Contacts become filter
//! constraints of the implicit solve; continuous collision and a final projection are the
//! fail-safes, so no vertex tunnels through the body or ends closer than half the thickness.
//! Given the stencils of the subdivided surface ([`Simulator::set_collision_surface`]), the
//! simulator also keeps every point of that surface, the one that renders, a full thickness
//! from the body, and given its faces too (as their collision hierarchy), with
//! self-collision on, keeps it from passing through itself. After each solve, strain
//! limiting (Provot 1995) keeps every edge within [`Settings::strain_limit`] of its rest
//! length.
#![warn(missing_docs)]

mod assemble;
mod collision;
pub mod constraint;
mod energy;
mod error;
pub mod material;
mod matrix;
pub mod model;
mod multigrid;
mod pcg;
mod reduce;
mod response;
mod settings;
pub mod shapes;
pub mod simulator;
mod strain_limit;
mod substep;
mod threads;

pub use collision::ContactState;
pub use constraint::{Attachment, Contact, Motion};
pub use energy::Vec3;
pub use error::{ClothError, StepFailure};
pub use material::Material;
pub use model::{Model, Stiffness};
pub use simulator::{Integrator, Previous, Settings, Simulator, State, StepReport};

#[cfg(test)]
pub(crate) mod testing {
    //! Deterministic random numbers and an irregular garment for tests.
    use crate::energy::Vec3;
    use tailor_subdiv::{Mesh, Point};

    /// xorshift64*: small, deterministic, good enough for test perturbations.
    pub struct Rng(u64);

    impl Rng {
        pub fn new(seed: u64) -> Self {
            Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }

        /// Uniform in [0, 1).
        pub fn unit(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }

        pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }

        /// Each coordinate uniform in [−1, 1).
        pub fn vec3(&mut self) -> Vec3 {
            Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            )
        }
    }

    /// A bumpy 5 × 4 grid of quads with one quad split into triangles and two merged into a
    /// hexagon: valences 3, 4 and 5, every face size the model treats differently.
    pub fn irregular_mesh(rng: &mut Rng) -> Mesh {
        let positions = (0..4)
            .flat_map(|j| (0..5).map(move |i| (i, j)))
            .map(|(i, j)| {
                let base = Point::new(f64::from(i), 0.0, f64::from(j));
                base + Vec3::new(0.1, 0.3, 0.1).component_mul(&rng.vec3())
            })
            .collect();
        let mut faces: Vec<Vec<u32>> =
            vec![vec![0, 5, 6], vec![0, 6, 1], vec![7, 12, 13, 14, 9, 8]];
        for j in 0..3 {
            for i in 0..4 {
                let a = i + 5 * j;
                if a != 0 && a != 7 && a != 8 {
                    faces.push(vec![a, a + 5, a + 6, a + 1]);
                }
            }
        }
        Mesh::from_polygons(positions, &faces).unwrap()
    }
}
