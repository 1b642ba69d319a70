//! How the simulator steps: the implicit integrator — Baraff & Witkin's backward Euler
//! ("Large Steps in Cloth Simulation", SIGGRAPH 1998) or BDF2 (Choi & Ko, "Stable but
//! Responsive Cloth", SIGGRAPH 2002) — and its solver's tolerances, the world the cloth moves
//! in, the collision thickness and friction (Bridson, Fedkiw & Anderson 2002) and the strain
//! limit (Provot 1995), with the library's defaults. The [`simulator`](crate::simulator)
//! module documents how each is used.

use crate::assemble::Environment;
use crate::energy::Vec3;

/// The implicit integrator of a substep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Second-order backward differentiation (Choi & Ko 2002), started by one trapezoidal
    /// substep: results change little with the step ([`Settings::default`]'s, and
    /// `tailor simulate`'s).
    Bdf2,
    /// Baraff & Witkin's first-order backward Euler, which damps motion in proportion to the
    /// step.
    BackwardEuler,
}

/// How the simulator steps. The defaults are the library's (BDF2 at two substeps a frame at
/// 24 fps, no self-collision); a `tailor` scene has its own (five substeps, self-collision
/// on), for the reasons `docs/DESIGN.md` gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Longest substep, seconds (default 1/48: 2 substeps per frame at 24 fps).
    pub max_substep: f64,
    /// The implicit integrator (see the [`simulator`](crate::simulator) module).
    pub integrator: Integrator,
    /// Newton iterations per substep; 1 is Baraff & Witkin's linearly implicit step.
    pub newton_iterations: u32,
    /// Backtracking line search on the incremental potential in each Newton iteration.
    pub line_search: bool,
    /// Conjugate gradients stop when the filtered residual is this fraction of the residual
    /// of their warm start at the last velocity, that is of the substep's impulses h (f₀ +
    /// h ∂f/∂x v₀ + ∂f/∂v v₀), not of the whole right-hand side with its momentum M v₀: so
    /// every substep applies its forces to the same relative accuracy however many substeps
    /// a frame there are. Default 1e-2: strain limiting and the collision passes after the
    /// solve see to the figures that matter.
    pub cg_tolerance: f64,
    /// Conjugate-gradient iterations before a solve counts as failed.
    pub cg_max_iterations: u32,
    /// How many times a failing substep may be halved.
    pub max_halvings: u32,
    /// Gravity, m/s².
    pub gravity: Vec3,
    /// Wind velocity that air drag pulls towards, m/s.
    pub wind: Vec3,
    /// Project element Hessians to PSD (turn off only to study the raw Jacobians).
    pub project_hessians: bool,
    /// Collision thickness, m: contacts hold the cloth this far from the obstacle, no vertex
    /// ends closer than half of it (no point of the refined surface closer than all of it,
    /// with [`Simulator::set_collision_surface`](crate::Simulator::set_collision_surface)), and cloth layers repel within it.
    pub thickness: f64,
    /// Coulomb friction coefficient μ between cloth and obstacle.
    pub friction: f64,
    /// Whether the cloth collides with itself.
    pub self_collision: bool,
    /// Strain limit: after each solve no edge stays stretched or squashed by more than this
    /// fraction of its rest length (the `strain_limit` module, after Provot 1995); 0 turns it
    /// off.
    pub strain_limit: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            max_substep: 1.0 / 48.0,
            integrator: Integrator::Bdf2,
            newton_iterations: 1,
            line_search: false,
            cg_tolerance: 1e-2,
            cg_max_iterations: 2000,
            max_halvings: 4,
            gravity: Vec3::new(0.0, -9.81, 0.0),
            wind: Vec3::zeros(),
            project_hessians: true,
            thickness: 0.005,
            friction: 0.3,
            self_collision: false,
            strain_limit: 0.1,
        }
    }
}

impl Settings {
    /// The world the cloth moves in.
    pub(crate) fn environment(&self) -> Environment {
        Environment {
            gravity: self.gravity,
            wind: self.wind,
        }
    }
}
