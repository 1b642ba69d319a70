//! Time stepping: implicit BDF2 or Baraff & Witkin's backward Euler ([`Settings::integrator`]),
//! with Newton iterations and a line search when asked, substeps in seconds, retries on
//! failure, and a symplectic Euler step.
//!
//! Backward Euler solves M (v₁ − v₀) = h f(x₀ + h v₁, v₁). Baraff & Witkin ("Large Steps in
//! Cloth Simulation", 1998, §4, eq. 16) linearize f once and solve
//!
//!   (M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f₀ + h ∂f/∂x v₀),   v₁ = v₀ + Δv.
//!
//! Its error is first order: it damps motion in proportion to the step, so the same shot at
//! 24 and 48 fps differed by 1.5 mm before the cloth touched anything, and cloth looked heavy.
//! BDF2 (Choi & Ko, "Stable but Responsive Cloth", SIGGRAPH 2002) is second order and keeps
//! backward Euler's stability:
//!
//!   x₁ = x̂ + ĥ v₁,   M (v₁ − v̂) = ĥ f(x₁, v₁),   x̂ = (4 x₀ − x₋₁)/3, v̂ = (4 v₀ − v₋₁)/3,
//!   ĥ = 2h/3,
//!
//! which is backward Euler's equation with (x̂, v̂, ĥ) for (x₀, v₀, h): everything below solves
//! that one form. With substeps of unequal length (a halved retry) the coefficients are those
//! of variable-step BDF2, ω = h / h₋₁: x̂ = a x₀ − b x₋₁, a = (1 + ω)²/(1 + 2ω),
//! b = ω²/(1 + 2ω), ĥ = h (1 + ω)/(1 + 2ω). Without a previous state (the first substep) the
//! step is the trapezoidal rule, also second order: x̂ = x₀ + h/2 v₀, v̂ = v₀ + h/2 M⁻¹ f₀,
//! ĥ = h/2; started with one backward Euler step instead, the drop of a falling sheet was off
//! by 3 h² g/4 for good. Constraints keep backward Euler's meaning: a pinned, attached or
//! contact direction moves from x₀ by h times its prescribed velocity (x̂ is set so).
//!
//! The linearized step is exactly one Newton iteration on the residual
//! R(v) = M (v − v̂) − ĥ f(x̂ + ĥ v, v) started from v = 0, which is how it is computed here,
//! CG warm-started at v̂ and stopped relative to the residual there (see
//! [`Settings::cg_tolerance`]).
//! When the solution takes free vertices into the body, they become contacts and the same
//! system is solved again from it (up to `CONTACT_ROUNDS` times; see the `response` module).
//! With `newton_iterations > 1`, further iterations re-linearize at the new iterate; R is the
//! gradient of the *incremental potential*
//!
//!   Φ(v) = ½ (v − v̂)ᵀ M (v − v̂) + U(x̂ + ĥ v) + ĥ D(v),
//!
//! (U elastic + gravitational energy, with −F · x for the kinetic friction F of sliding body
//! contacts, constant over the substep; D the dissipation function of dampers and drag, damper
//! directions frozen over the substep: `Work::frozen`), so with `line_search` each step
//! length is halved until Φ decreases enough (Armijo); [`StepReport`] counts the halvings,
//! and the steps taken without that decrease. Stiffness Hessians are projected to PSD (the
//! private `energy` module), so the matrix is SPD, CG converges and every Newton direction
//! descends. Sticking body contacts are held whole by the filter (see the
//! `collision::friction` module).
//!
//! After the solve, the collision response (the `response` module) applies Coulomb's law to
//! the contacts, strain limiting and the collision passes to the end positions and
//! velocities.
//!
//! The last iteration ends without evaluating the forces again when there is no line search
//! to decide: friction reads the contact impulses of the solve itself, b − A Δv on the contact
//! vertices (the constraint forces of Baraff & Witkin §5.3, zero elsewhere to the solve's
//! tolerance), one product with A instead of a force evaluation at the new positions. The
//! energy of a state is [`Simulator::energy`], computed when asked.
//!
//! A call to [`Simulator::step`] covers `dt` seconds in equal substeps no longer than
//! [`Settings::max_substep`], so the physics do not depend on the frame rate. A substep that
//! produces a non-finite value or whose solve fails is retried as two halves, down to
//! [`Settings::max_halvings`] levels, before [`ClothError::StepFailed`] is returned; the state
//! is only written when a substep succeeds, so it never holds NaN.

use tailor_collide::{CollideError, Hierarchy};
use tailor_subdiv::{Point, StencilTable};

use crate::assemble::{Assembly, Coefficients};
use crate::collision::ContactState;
use crate::constraint::{Attachment, Constraints, Contact, Filter, Motion};
use crate::energy::{Mat3, Vec3};
use crate::pcg::{Pcg, Stop};
use crate::reduce::{partial_count, sum_by};
use crate::response::Response;
pub use crate::settings::{Integrator, Settings};
use crate::substep::{Impulses, Substep};
use crate::{ClothError, Model, StepFailure};

/// Why a substep did not complete.
#[derive(Debug)]
enum SubstepError {
    /// A numeric failure, which a shorter substep may avoid.
    Retry(StepFailure),
    /// An error no retry can mend (a collision query that failed).
    Fatal(ClothError),
}

impl From<StepFailure> for SubstepError {
    fn from(failure: StepFailure) -> Self {
        Self::Retry(failure)
    }
}

impl From<CollideError> for SubstepError {
    /// A non-finite position or query point is numeric (a shorter substep may not make it);
    /// any other collision error is not.
    fn from(error: CollideError) -> Self {
        match error {
            CollideError::NonFinitePosition { .. } | CollideError::NonFiniteQuery { .. } => {
                Self::Retry(StepFailure::NonFinite)
            }
            error => Self::Fatal(ClothError::Collide(error)),
        }
    }
}

/// The velocity error, m/s, below which a solve has converged whatever its relative
/// tolerance asks: the filtered residual |S (b − A Δv)| at most this times |M 1|, what this
/// error in every vertex's velocity leaves. Cloth at rest starts each solve a round-off away
/// from its answer, and a tolerance relative to that asked CG for hundreds of iterations a
/// substep that changed nothing a viewer sees. A micrometre a second is a ten-thousandth of
/// what gravity adds in a substep of 1/1200 s, so free fall keeps its accuracy at fine steps.
const VELOCITY_FLOOR: f64 = 1e-6;

/// Most times a substep's linear system is solved again with the body contacts its last
/// solution revealed.
const CONTACT_ROUNDS: usize = 2;

/// The line search's sufficient decrease (Armijo's condition): a step α along the Newton
/// direction d is taken when Φ falls by at least this fraction of the fall its slope foretells,
/// α (−∇Φ · d), −∇Φ being the solve's right-hand side. Small, as usual, so that the search
/// shortens only steps that overshoot.
const ARMIJO: f64 = 1e-4;

/// The line search halves the step until it is shorter than this, then takes it whatever Φ
/// does: at most ten halvings, so a substep's cost stays bounded where the direction barely
/// descends.
const MIN_STEP: f64 = 1e-3;

/// Positions and velocities of the particles at a time, and the substep before it.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Positions, m.
    pub positions: Vec<Point>,
    /// Velocities, m/s.
    pub velocities: Vec<Vec3>,
    /// Time, s.
    pub time: f64,
    /// The state at the start of the last substep, which BDF2 steps from with this one;
    /// `None` at the start of a simulation (the first substep is then trapezoidal).
    pub previous: Option<Previous>,
}

/// The state one substep back.
#[derive(Clone, Debug, PartialEq)]
pub struct Previous {
    /// Positions, m.
    pub positions: Vec<Point>,
    /// Velocities, m/s.
    pub velocities: Vec<Vec3>,
    /// The length of the substep from them to the state that holds them, s.
    pub step: f64,
}

impl State {
    /// The model at rest at time 0.
    #[must_use]
    pub fn at_rest(model: &Model) -> Self {
        Self {
            positions: model.rest_positions().to_vec(),
            velocities: vec![Vec3::zeros(); model.vertex_count()],
            time: 0.0,
            previous: None,
        }
    }

    /// Makes the current positions and velocities the previous ones, `step` seconds before
    /// the next.
    fn remember(&mut self, step: f64) {
        match &mut self.previous {
            Some(p) => {
                p.positions.copy_from_slice(&self.positions);
                p.velocities.copy_from_slice(&self.velocities);
                p.step = step;
            }
            None => {
                self.previous = Some(Previous {
                    positions: self.positions.clone(),
                    velocities: self.velocities.clone(),
                    step,
                });
            }
        }
    }
}

/// What a step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Substeps taken, counting those of halved retries.
    pub substeps: u32,
    /// Substeps that failed and were retried as two halves.
    pub halvings: u32,
    /// Newton iterations over all substeps.
    pub newton_iterations: u32,
    /// Conjugate-gradient iterations over all substeps.
    pub cg_iterations: u32,
    /// Largest |l/L − 1| over the edges at the end of the step.
    pub max_strain: f64,
    /// Obstacle contact constraints in the last substep.
    pub contacts: u32,
    /// Impacts and projections the collision fail-safes made over all substeps.
    pub impacts: u32,
    /// Edge corrections strain limiting made over all substeps.
    pub strain_corrections: u32,
    /// Times the line search ([`Settings::line_search`]) halved a Newton step, over all
    /// substeps: each time, the longer step would not have decreased the incremental
    /// potential Φ as much as Armijo's condition asks (see the module docs).
    pub line_search_halvings: u32,
    /// Newton steps taken, over all substeps, that did not decrease Φ as much as Armijo's
    /// condition asks. With the line search these are the steps it gave up on (at its
    /// shortest step, or where Φ is not finite), so 0 means that every step taken decreased
    /// Φ; without it, every step whose Φ is evaluated counts: all but the last of each
    /// substep.
    pub insufficient_decreases: u32,
}

/// Buffers of one substep.
#[derive(Clone, Debug)]
struct Work {
    /// The state at the substep's start.
    x0: Vec<Point>,
    v0: Vec<Vec3>,
    /// What the integrator steps from (x̂, v̂ of the module docs) and its step ĥ: the end
    /// positions are x = x̂ + ĥ v and the solve's residual M (v̂ − v) + ĥ f.
    base: Vec<Point>,
    base_velocity: Vec<Vec3>,
    base_step: f64,
    /// Where the dampers' directions are taken (Baraff & Witkin §5.2 freeze them over the
    /// substep): x₀ for backward Euler, first order like it; the predicted end x̂ + ĥ v̂ for
    /// BDF2, whose order they would otherwise cap at one.
    frozen: Vec<Point>,
    x: Vec<Point>,
    v: Vec<Vec3>,
    trial: Vec<Vec3>,
    delta: Vec<Vec3>,
    rhs: Vec<Vec3>,
    /// The contact impulses of the last solve, b − A Δv (zero on free vertices, up to the
    /// solve's tolerance), which friction reads.
    impulse: Vec<Vec3>,
    filter: Filter,
    /// 1 / mass, zero for a vertex whose position the constraints prescribe.
    inverse_mass: Vec<f64>,
    partials: Vec<f64>,
}

/// Advances a [`Model`] in time. See the module docs.
#[derive(Debug)]
pub struct Simulator {
    model: Model,
    settings: Settings,
    constraints: Constraints,
    assembly: Assembly,
    pcg: Pcg,
    response: Response,
    work: Work,
    /// [`VELOCITY_FLOOR`] as a residual: times |M 1|, the masses' Euclidean norm.
    residual_floor: f64,
}

impl Work {
    /// Positions at the substep's end for velocities `trial`: x = x̂ + ĥ v.
    fn place_at_trial(&mut self) {
        let h = self.base_step;
        for ((x, base), v) in self.x.iter_mut().zip(&self.base).zip(&self.trial) {
            *x = base + v * h;
        }
    }
}

impl Simulator {
    /// A simulator with no constraints and no obstacle.
    ///
    /// # Errors
    /// [`ClothError::BadValue`] for a non-positive substep, tolerance or thickness, negative
    /// friction, or non-finite gravity or wind; [`ClothError::Collide`] if the garment's faces
    /// cannot make a collision hierarchy.
    pub fn new(model: Model, settings: Settings) -> Result<Self, ClothError> {
        let checks = [
            (
                "max_substep",
                settings.max_substep,
                settings.max_substep > 0.0,
            ),
            (
                "cg_tolerance",
                settings.cg_tolerance,
                settings.cg_tolerance > 0.0,
            ),
            ("thickness", settings.thickness, settings.thickness > 0.0),
            ("friction", settings.friction, settings.friction >= 0.0),
            (
                "strain_limit",
                settings.strain_limit,
                (0.0..1.0).contains(&settings.strain_limit),
            ),
            ("gravity", settings.gravity.norm(), true),
            ("wind", settings.wind.norm(), true),
        ];
        for (what, value, ok) in checks {
            if !(ok && value.is_finite()) {
                return Err(ClothError::BadValue { what, value });
            }
        }
        let n = model.vertex_count();
        let mut assembly = Assembly::new(&model);
        // The preconditioner's aggregates follow the matrix of the rest shape at the longest
        // substep: a function of the model and the settings, so a resumed run makes the same.
        let rest = model.rest_positions();
        assembly.evaluate(
            &model,
            rest,
            rest,
            &vec![Vec3::zeros(); n],
            &settings.environment(),
            Some(Coefficients::implicit(settings.max_substep)),
            settings.project_hessians,
        );
        Ok(Self {
            residual_floor: VELOCITY_FLOOR * model.mass.iter().map(|m| m * m).sum::<f64>().sqrt(),
            response: Response::new(&model, &settings)?,
            constraints: Constraints::new(n),
            pcg: Pcg::new(&assembly.matrix),
            assembly,
            work: Work {
                x0: vec![Point::origin(); n],
                v0: vec![Vec3::zeros(); n],
                base: vec![Point::origin(); n],
                base_velocity: vec![Vec3::zeros(); n],
                base_step: 0.0,
                frozen: vec![Point::origin(); n],
                x: vec![Point::origin(); n],
                v: vec![Vec3::zeros(); n],
                trial: vec![Vec3::zeros(); n],
                delta: vec![Vec3::zeros(); n],
                impulse: vec![Vec3::zeros(); n],
                rhs: vec![Vec3::zeros(); n],
                filter: Filter::new(n),
                inverse_mass: vec![0.0; n],
                partials: vec![0.0; partial_count(n)],
            },
            model,
            settings,
        })
    }

    /// The model.
    #[must_use]
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The constraints.
    #[must_use]
    pub fn constraints(&self) -> &Constraints {
        &self.constraints
    }

    /// Pins `vertices` to follow `motion` applied to their rest positions.
    ///
    /// # Errors
    /// See [`Constraints::pin`].
    pub fn pin(&mut self, vertices: &[u32], motion: Motion) -> Result<(), ClothError> {
        self.constraints.pin(vertices, motion)
    }

    /// Replaces the attachments; their positions are those at `time` (seconds) and they move
    /// on with their velocities until replaced. Call before each step with the body's points.
    ///
    /// # Errors
    /// See [`Constraints::set_attachments`].
    pub fn set_attachment_targets(
        &mut self,
        time: f64,
        targets: &[Attachment],
    ) -> Result<(), ClothError> {
        self.constraints.set_attachments(time, targets)
    }

    /// Replaces the contact planes the next steps honour (the collision seam).
    ///
    /// # Errors
    /// See [`Constraints::set_contacts`].
    pub fn set_contacts(&mut self, contacts: &[Contact]) -> Result<(), ClothError> {
        self.constraints.set_contacts(contacts)
    }

    /// Makes the polygon mesh with CSR faces `face_offsets`/`face_vertices` the obstacle,
    /// resting at `positions` (which also guide its hierarchy, built once here) until
    /// [`Self::set_obstacle_motion`] moves it. Its faces must wind counter-clockwise seen from
    /// outside: the cloth is kept on that side. Replaces any earlier obstacle.
    ///
    /// # Errors
    /// [`ClothError::Collide`] for faces the hierarchy cannot take (see
    /// [`tailor_collide::Hierarchy::build`]).
    pub fn set_obstacle(
        &mut self,
        positions: &[Point],
        face_offsets: &[u32],
        face_vertices: &[u32],
    ) -> Result<(), ClothError> {
        self.response
            .collisions_mut()
            .set_obstacle(positions, face_offsets, face_vertices)
    }

    /// Makes the clearance from the obstacle hold for the refined surface `stencils` evaluates
    /// (rows of weights over this garment's control points; typically
    /// [`tailor_subdiv::Refiner::stencils`] of the level that is rendered), not only for the
    /// control points: after the other collision passes of each substep the control points
    /// are lifted until every refined point is at least the thickness from the obstacle.
    ///
    /// Given the refined surface's collision hierarchy `faces` (of its faces over the refined
    /// points in the stencils' order, built at any pose: it is refit at the rest shape's
    /// refined points), and with self-collision on, that surface is also kept from passing
    /// through itself: the continuous self tests run on the refined points, their impulses
    /// and impact zones acting on the control points through the stencils (step 8 of the
    /// response). A caller that writes the refined surface has built that hierarchy already,
    /// and the simulator refits a copy rather than building its own.
    ///
    /// # Errors
    /// [`ClothError::WrongLength`] when the table is not over this garment's control points,
    /// or the hierarchy is not over the table's refined points.
    pub fn set_collision_surface(
        &mut self,
        stencils: StencilTable,
        faces: Option<&Hierarchy>,
    ) -> Result<(), ClothError> {
        let expected = self.model.vertex_count();
        if stencils.control_points != expected {
            return Err(ClothError::WrongLength {
                what: "collision surface stencils' control points",
                given: stencils.control_points,
                expected,
            });
        }
        if let Some(faces) = faces
            && faces.vertex_count() != stencils.len()
        {
            return Err(ClothError::WrongLength {
                what: "collision surface hierarchy's vertices",
                given: faces.vertex_count(),
                expected: stencils.len(),
            });
        }
        let faces = faces.filter(|_| self.settings.self_collision);
        self.response
            .collisions_mut()
            .set_surface(stencils, faces, &self.model.rest)?;
        Ok(())
    }

    /// The only collision state carried from one step to the next: what friction keeps of
    /// each vertex's body contact (see [`ContactState`]). A checkpoint must keep it for a
    /// resumed run to compute the same bits.
    #[must_use]
    pub fn contact_state(&self) -> &ContactState {
        self.response.collisions().contact_state()
    }

    /// Restores [`Self::contact_state`] from a checkpoint.
    ///
    /// # Errors
    /// [`ClothError::WrongLength`] when `state` does not have one entry per vertex in each
    /// of its tables.
    pub fn restore_contact_state(&mut self, state: &ContactState) -> Result<(), ClothError> {
        let expected = self.model.vertex_count();
        if state.len() != expected || !state.is_consistent() {
            return Err(ClothError::WrongLength {
                what: "contact state",
                given: state.len(),
                expected,
            });
        }
        self.response.collisions_mut().set_contact_state(state);
        Ok(())
    }

    /// Moves the obstacle for the next frame: at `start` at time `t0`, at `end` at time `t1`
    /// (seconds), linearly in between, so each body vertex has the velocity
    /// (end − start)/(t1 − t0); before `t0` and after `t1` it holds still.
    ///
    /// # Errors
    /// [`ClothError::NoObstacle`] without an obstacle; [`ClothError::BadValue`] for
    /// `t1 <= t0` or a non-finite position; [`ClothError::WrongLength`] for a position count
    /// that does not match the obstacle.
    pub fn set_obstacle_motion(
        &mut self,
        t0: f64,
        start: &[Point],
        t1: f64,
        end: &[Point],
    ) -> Result<(), ClothError> {
        self.response
            .collisions_mut()
            .set_obstacle_motion(t0, start, t1, end)
    }

    fn check_state(&self, state: &State, dt: f64) -> Result<u32, ClothError> {
        let n = self.model.vertex_count();
        let previous = state.previous.as_ref();
        for (what, given) in [
            ("positions", state.positions.len()),
            ("velocities", state.velocities.len()),
            (
                "previous positions",
                previous.map_or(n, |p| p.positions.len()),
            ),
            (
                "previous velocities",
                previous.map_or(n, |p| p.velocities.len()),
            ),
        ] {
            if given != n {
                return Err(ClothError::WrongLength {
                    what,
                    given,
                    expected: n,
                });
            }
        }
        for (what, value) in [
            ("time step", dt),
            ("previous step", previous.map_or(1.0, |p| p.step)),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(ClothError::BadValue { what, value });
            }
        }
        // A hair below the exact ratio, so 1/24 s in 1/120 s substeps is 5, not 6.
        let count = (dt / self.settings.max_substep * (1.0 - 1e-12))
            .ceil()
            .max(1.0);
        Ok(count as u32)
    }

    /// Advances `state` by `dt` seconds with implicit backward Euler.
    ///
    /// # Errors
    /// [`ClothError::WrongLength`] or [`ClothError::BadValue`] for a bad state or `dt`;
    /// [`ClothError::StepFailed`] if a substep fails even after [`Settings::max_halvings`]
    /// halvings (the state then holds the last good substep).
    pub fn step(&mut self, state: &mut State, dt: f64) -> Result<StepReport, ClothError> {
        let count = self.check_state(state, dt)?;
        // The whole step runs on a worker of the thread pool: each of its many short
        // parallel passes then forks from there rather than waking the pool from outside and
        // waiting for it.
        rayon::scope(|_| {
            let mut report = StepReport::default();
            for _ in 0..count {
                self.advance(state, dt / f64::from(count), 0, &mut report)?;
            }
            report.max_strain = self.model.max_strain(&state.positions);
            Ok(report)
        })
    }

    fn advance(
        &mut self,
        state: &mut State,
        h: f64,
        depth: u32,
        report: &mut StepReport,
    ) -> Result<(), ClothError> {
        match self.implicit_substep(state, h, report) {
            Ok(()) => Ok(()),
            Err(SubstepError::Fatal(error)) => Err(error),
            Err(SubstepError::Retry(reason)) if depth >= self.settings.max_halvings => {
                Err(ClothError::StepFailed {
                    time: state.time,
                    step: h,
                    reason,
                })
            }
            Err(SubstepError::Retry(_)) => {
                report.halvings += 1;
                self.advance(state, 0.5 * h, depth + 1, report)?;
                self.advance(state, 0.5 * h, depth + 1, report)
            }
        }
    }

    /// Evaluates at velocities `work.trial`: positions, forces, the right-hand side −R, the
    /// matrix of the next linear solve when `with_matrix`; returns the incremental potential Φ.
    fn evaluate(&mut self, with_matrix: bool) -> f64 {
        let env = self.settings.environment();
        self.work.place_at_trial();
        let Work {
            frozen,
            base_velocity,
            base_step,
            x,
            trial,
            rhs,
            partials,
            ..
        } = &mut self.work;
        let h = *base_step;
        let c = with_matrix.then_some(Coefficients::implicit(h));
        let totals = self.assembly.evaluate(
            &self.model,
            x,
            frozen,
            trial,
            &env,
            c,
            self.settings.project_hessians,
        );
        let mass = &self.model.mass;
        let force = &self.assembly.force;
        // Kinetic friction is a constant force over the substep: its potential is −F · x,
        // and x = x̂ + ĥ v.
        let friction = self.response.collisions().friction_force();
        for (i, r) in rhs.iter_mut().enumerate() {
            *r = (base_velocity[i] - trial[i]) * mass[i] + (force[i] + friction[i]) * h;
        }
        let inertia = sum_by(mass.len(), partials, |i| {
            0.5 * mass[i] * (trial[i] - base_velocity[i]).norm_squared()
                - h * friction[i].dot(&trial[i])
        });
        inertia + totals.potential + h * totals.dissipation
    }

    /// What the substep of length `h` from the state in `work.x0`, `work.v0` (one `previous`
    /// step on) steps from: x̂, v̂ and ĥ of the module docs, with the constrained components
    /// of x̂ set so that the filter's velocities z move them as backward Euler would, from x₀
    /// by h z (the filter of this substep must be prepared).
    fn prepare_base(&mut self, h: f64, previous: Option<&Previous>) {
        let w = &mut self.work;
        match (self.settings.integrator, previous) {
            (Integrator::BackwardEuler, _) => {
                w.base.copy_from_slice(&w.x0);
                w.base_velocity.copy_from_slice(&w.v0);
                w.base_step = h;
            }
            (Integrator::Bdf2, Some(p)) => {
                // Variable-step BDF2: with ω = h / h₋₁, x̂ = a x₀ − b x₋₁, v̂ = a v₀ − b v₋₁
                // and ĥ = β h (4/3, 1/3 and 2/3 for equal steps).
                let omega = h / p.step;
                let a = (1.0 + omega).powi(2) / (1.0 + 2.0 * omega);
                let b = omega * omega / (1.0 + 2.0 * omega);
                for i in 0..w.x0.len() {
                    w.base[i] = Point::from(w.x0[i].coords * a - p.positions[i].coords * b);
                    w.base_velocity[i] = w.v0[i] * a - p.velocities[i] * b;
                }
                w.base_step = h * (1.0 + omega) / (1.0 + 2.0 * omega);
            }
            (Integrator::Bdf2, None) => {
                // The trapezoidal rule: x̂ = x₀ + h/2 v₀, v̂ = v₀ + h/2 M⁻¹ f(x₀, v₀), ĥ = h/2.
                let env = self.settings.environment();
                self.assembly
                    .evaluate(&self.model, &w.x0, &w.x0, &w.v0, &env, None, false);
                let (force, mass) = (&self.assembly.force, &self.model.mass);
                for i in 0..w.x0.len() {
                    w.base[i] = w.x0[i] + w.v0[i] * (0.5 * h);
                    w.base_velocity[i] = w.v0[i] + force[i] * (0.5 * h / mass[i]);
                }
                w.base_step = 0.5 * h;
            }
        }
        let (f, lag) = (&w.filter, h - w.base_step);
        for i in 0..w.x0.len() {
            if !f.is_free(i) {
                let held = w.x0[i] + f.z[i] * lag;
                let toward = (Mat3::identity() - f.s[i]) * (held - w.base[i]);
                w.base[i] += toward;
            }
        }
        match self.settings.integrator {
            Integrator::BackwardEuler => w.frozen.copy_from_slice(&w.x0),
            Integrator::Bdf2 => {
                for ((p, base), v) in w.frozen.iter_mut().zip(&w.base).zip(&w.base_velocity) {
                    *p = base + v * w.base_step;
                }
            }
        }
    }

    /// The second look at the body (step 1 of [`crate::response`]): vertices the solve's
    /// result `v + delta` takes into the body become contacts and the same linear system is
    /// solved again with them constrained, from the last solution, up to
    /// [`CONTACT_ROUNDS`] times. Without it a vertex the first look missed (released, or
    /// pulled in faster than its velocity foretold) would end inside the body and only the
    /// projection after the solve would put it back, straining the edges around it.
    fn add_missed_contacts(
        &mut self,
        t1: f64,
        h: f64,
        reference: f64,
        report: &mut StepReport,
    ) -> Result<(), StepFailure> {
        for _ in 0..CONTACT_ROUNDS {
            let w = &mut self.work;
            for (i, x) in w.x.iter_mut().enumerate() {
                *x = w.base[i] + (w.v[i] + w.delta[i]) * w.base_step;
            }
            if self.response.collisions_mut().missed_contacts(
                &self.settings,
                h,
                &w.x0,
                &w.x,
                &w.filter,
            ) == 0
            {
                break;
            }
            self.solve_again(t1, h, reference, report)?;
        }
        Ok(())
    }

    /// The contact impulses of the last solve, b − A Δv, for friction; if they show sticking
    /// contacts that cannot hold (see the `collision::friction` module), those slide and the
    /// same system is solved again from the last solution, once.
    fn slip(
        &mut self,
        t1: f64,
        h: f64,
        reference: f64,
        report: &mut StepReport,
    ) -> Result<(), StepFailure> {
        self.contact_impulses();
        let w = &mut self.work;
        let slipped = self.response.collisions_mut().slip(
            &self.settings,
            &w.impulse,
            w.base_step,
            &mut w.rhs,
        );
        if slipped {
            self.solve_again(t1, h, reference, report)?;
            self.contact_impulses();
        }
        Ok(())
    }

    /// Solves the same system again with the filter the changed contacts make, from the last
    /// solution: its free part kept, its constrained part put on target.
    fn solve_again(
        &mut self,
        t1: f64,
        h: f64,
        reference: f64,
        report: &mut StepReport,
    ) -> Result<(), StepFailure> {
        self.prepare_filter(t1, h);
        let w = &mut self.work;
        let f = &w.filter;
        for (i, d) in w.delta.iter_mut().enumerate() {
            *d = f.s[i] * *d + (Mat3::identity() - f.s[i]) * (f.z[i] - w.v[i]);
        }
        self.solve(report, Some(reference))?;
        Ok(())
    }

    /// The contact impulses of the last solve: `work.impulse` = b − A Δv.
    fn contact_impulses(&mut self) {
        let w = &mut self.work;
        self.assembly.matrix.mul_into(&w.delta, &mut w.impulse);
        for (j, b) in w.impulse.iter_mut().zip(&w.rhs) {
            *j = b - *j;
        }
    }

    /// The filter of the substep ending at `t1`: the constraints and the body contacts.
    fn prepare_filter(&mut self, t1: f64, h: f64) {
        let w = &mut self.work;
        self.constraints.prepare(
            &self.model.rest,
            &w.x0,
            t1,
            h,
            self.response.collisions().contacts(),
            &mut w.filter,
        );
        self.response.collisions().stick(&mut w.filter);
    }

    /// Solves the filtered system for `work.delta`, from its value, and returns the norm its
    /// tolerance was relative to. A re-solve with more contacts (the matrix is the last
    /// solve's) passes that solve's `reference`, so it stops at the same accuracy rather than
    /// a fraction of what the new contacts disturbed.
    fn solve(
        &mut self,
        report: &mut StepReport,
        reference: Option<f64>,
    ) -> Result<f64, StepFailure> {
        let w = &mut self.work;
        self.pcg
            .prepare(&self.assembly.matrix, &w.filter.s, reference.is_some());
        let solve = self.pcg.solve(
            &self.assembly.matrix,
            &w.filter.s,
            &w.rhs,
            &mut w.delta,
            Stop {
                tolerance: self.settings.cg_tolerance,
                reference,
                floor: self.residual_floor,
                max_iterations: self.settings.cg_max_iterations,
            },
        );
        report.cg_iterations += solve.iterations;
        if solve.converged {
            Ok(solve.reference)
        } else {
            Err(StepFailure::SolverDiverged)
        }
    }

    fn implicit_substep(
        &mut self,
        state: &mut State,
        h: f64,
        report: &mut StepReport,
    ) -> Result<(), SubstepError> {
        let t1 = state.time + h;
        // Repulsion's pairs depend on the substep's start alone: with self-collision they are
        // found beside the body contacts and the solve, which leave a core idle much of the
        // time (their passes are short and partly serial), and wait after it (step 3 of
        // [`crate::response`]).
        let at = if self.settings.self_collision {
            let mut garment = self.response.collisions_mut().take_garment();
            let thickness = self.settings.thickness;
            let x0 = &state.positions;
            let (solved, found) = rayon::join(
                || self.solve_from(state, h, report),
                || garment.find_near(thickness, x0),
            );
            self.response.collisions_mut().give_back(garment);
            let at = solved?;
            found?;
            at
        } else {
            self.solve_from(state, h, report)?
        };
        let w = &mut self.work;
        for i in 0..w.x.len() {
            if w.filter.placed[i] {
                w.x[i] = w.filter.goal[i];
            }
            w.inverse_mass[i] = if w.filter.placed[i] {
                0.0
            } else {
                1.0 / self.model.mass[i]
            };
        }
        let finite = at.is_finite()
            && w.x.iter().all(|p| p.iter().all(|c| c.is_finite()))
            && w.trial.iter().all(|v| v.iter().all(|c| c.is_finite()));
        if !finite {
            return Err(StepFailure::NonFinite.into());
        }
        let integrator = Substep {
            h: w.base_step,
            x0: &w.base,
            x: &mut w.x,
            v: &mut w.trial,
            inverse_mass: &w.inverse_mass,
        };
        // The time the solve's contact impulses act over: its step ĥ, or for BDF2's
        // trapezoidal start the whole substep, whose explicit half's forces they also cancel.
        let trapezoidal = self.settings.integrator == Integrator::Bdf2 && state.previous.is_none();
        let contact = Impulses {
            impulse: &w.impulse,
            span: if trapezoidal { h } else { w.base_step },
        };
        let springs = &self.model.springs;
        let impacts =
            self.response
                .after_solve(&self.settings, springs, integrator, &w.x0, h, contact);
        report.strain_corrections += self.response.take_strain_corrections();
        let impacts = impacts?;
        state.remember(h);
        state.positions.copy_from_slice(&w.x);
        state.velocities.copy_from_slice(&w.trial);
        state.time = t1;
        report.substeps += 1;
        report.contacts = self.response.collisions().contacts().len() as u32;
        report.impacts += impacts;
        Ok(())
    }

    /// The body contacts and the Newton iterations of the substep of length `h` from `state`:
    /// the end positions and velocities in `work.x` and `work.trial`; returns Φ there.
    fn solve_from(
        &mut self,
        state: &State,
        h: f64,
        report: &mut StepReport,
    ) -> Result<f64, SubstepError> {
        let t1 = state.time + h;
        let w = &mut self.work;
        w.x0.copy_from_slice(&state.positions);
        w.v0.copy_from_slice(&state.velocities);
        self.response.collisions_mut().before_solve(
            &self.settings,
            state.time,
            h,
            &w.x0,
            &w.v0,
            &self.model.mass,
        )?;
        self.prepare_filter(t1, h);
        self.prepare_base(h, state.previous.as_ref());
        let w = &mut self.work;
        for (i, v) in w.trial.iter_mut().enumerate() {
            *v = w.filter.z[i] - w.filter.s[i] * w.filter.z[i];
        }
        let mut at = self.evaluate(true);
        for iteration in 0..self.settings.newton_iterations {
            let w = &mut self.work;
            w.v.copy_from_slice(&w.trial);
            for (i, d) in w.delta.iter_mut().enumerate() {
                *d = if iteration == 0 {
                    w.filter.s[i] * (w.base_velocity[i] - w.v[i])
                } else {
                    Vec3::zeros()
                };
            }
            report.newton_iterations += 1;
            let reference = self.solve(report, None)?;
            self.add_missed_contacts(t1, h, reference, report)?;
            let last = iteration + 1 == self.settings.newton_iterations;
            if last {
                self.slip(t1, h, reference, report)?;
            }
            let w = &self.work;
            let slope: f64 = w.rhs.iter().zip(&w.delta).map(|(r, d)| r.dot(d)).sum();
            let mut alpha = 1.0;
            loop {
                let w = &mut self.work;
                for ((t, v), d) in w.trial.iter_mut().zip(&w.v).zip(&w.delta) {
                    *t = v + d * alpha;
                }
                if last && !self.settings.line_search {
                    // Nothing is left to decide at the last iteration's end: no forces, no Φ.
                    w.place_at_trial();
                    break;
                }
                // The last iteration's end needs only Φ, not another matrix.
                let next = self.evaluate(!last);
                let enough = next <= at - ARMIJO * alpha * slope;
                if !self.settings.line_search || enough || alpha < MIN_STEP || !next.is_finite() {
                    report.insufficient_decreases += u32::from(!enough);
                    at = next;
                    break;
                }
                report.line_search_halvings += 1;
                alpha *= 0.5;
            }
        }
        Ok(at)
    }

    /// Advances `state` by `dt` seconds with symplectic (semi-implicit) Euler,
    /// v₁ = v₀ + h M⁻¹ f(x₀, v₀), x₁ = x₀ + h v₁: explicit, so only stable for small substeps;
    /// kept to test energy behaviour. Constraints apply as in [`Self::step`]; collisions do not.
    ///
    /// # Errors
    /// As [`Self::step`], without retries.
    pub fn step_symplectic(
        &mut self,
        state: &mut State,
        dt: f64,
    ) -> Result<StepReport, ClothError> {
        let count = self.check_state(state, dt)?;
        let h = dt / f64::from(count);
        let env = self.settings.environment();
        let mut report = StepReport::default();
        for _ in 0..count {
            let t1 = state.time + h;
            let w = &mut self.work;
            self.constraints.prepare(
                &self.model.rest,
                &state.positions,
                t1,
                h,
                &[],
                &mut w.filter,
            );
            let x = &state.positions;
            self.assembly
                .evaluate(&self.model, x, x, &state.velocities, &env, None, false);
            let f = &self.assembly.force;
            let s = &w.filter;
            for i in 0..x.len() {
                let free = state.velocities[i] + f[i] * (h / self.model.mass[i]);
                w.v[i] = s.s[i] * free + (s.z[i] - s.s[i] * s.z[i]);
                w.x[i] = if s.placed[i] {
                    s.goal[i]
                } else {
                    x[i] + w.v[i] * h
                };
            }
            let finite = w.x.iter().all(|p| p.iter().all(|c| c.is_finite()));
            if !finite {
                return Err(ClothError::StepFailed {
                    time: state.time,
                    step: h,
                    reason: StepFailure::NonFinite,
                });
            }
            state.remember(h);
            state.positions.copy_from_slice(&w.x);
            state.velocities.copy_from_slice(&w.v);
            state.time = t1;
            report.substeps += 1;
        }
        report.max_strain = self.model.max_strain(&state.positions);
        Ok(report)
    }

    /// Kinetic + elastic + gravitational energy of `state`, J.
    pub fn energy(&mut self, state: &State) -> f64 {
        let env = self.settings.environment();
        let x = &state.positions;
        let totals =
            self.assembly
                .evaluate(&self.model, x, x, &state.velocities, &env, None, false);
        let mass = &self.model.mass;
        let v = &state.velocities;
        totals.potential
            + sum_by(mass.len(), &mut self.work.partials, |i| {
                0.5 * mass[i] * v[i].norm_squared()
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_numeric_collision_errors_are_retried() {
        let retried = |e| matches!(SubstepError::from(e), SubstepError::Retry(_));
        assert!(retried(CollideError::NonFinitePosition { vertex: 3 }));
        assert!(retried(CollideError::NonFiniteQuery { point: 1 }));
        assert!(!retried(CollideError::Empty));
        assert!(!retried(CollideError::PositionCount {
            given: 3,
            expected: 4
        }));
    }
}
