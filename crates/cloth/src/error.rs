//! The crate's error type.

/// Why a model could not be built or a step could not be taken.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClothError {
    /// A material parameter is negative, zero where it must be positive, or not finite.
    #[error("material {name} is {value}; it must be a finite number{}", if *.positive { " > 0" } else { " >= 0" })]
    BadMaterial {
        /// The parameter (`density`, `stretch`, …).
        name: &'static str,
        /// The value given.
        value: f64,
        /// Whether it must be strictly positive.
        positive: bool,
    },
    /// A vertex belongs to no face, so it has no mass.
    #[error(
        "vertex {vertex} belongs to no face (or only to faces of zero area), so it has no mass"
    )]
    NoMass {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// Two points an edge or a quad diagonal joins coincide at rest.
    #[error("vertices {a} and {b} coincide at rest; an edge or diagonal needs a length")]
    ZeroRestLength {
        /// One end.
        a: u32,
        /// The other end.
        b: u32,
    },
    /// A per-vertex table has the wrong length.
    #[error("{what} has {given} entries for {expected} vertices")]
    WrongLength {
        /// What was given.
        what: &'static str,
        /// How many entries it has.
        given: usize,
        /// How many vertices the model has.
        expected: usize,
    },
    /// A stiffness multiplier is negative or not finite.
    #[error("stiffness multiplier of vertex {vertex} is {value}; it must be finite and >= 0")]
    BadMultiplier {
        /// 0-based vertex index.
        vertex: usize,
        /// The value given.
        value: f64,
    },
    /// A constraint names a vertex that does not exist.
    #[error("{what} names vertex {vertex}, but the model has {count} vertices")]
    VertexOutOfRange {
        /// `pin`, `attachment` or `contact`.
        what: &'static str,
        /// The vertex named.
        vertex: u32,
        /// How many vertices exist.
        count: usize,
    },
    /// A time step, setting or input value is not a finite number in range.
    #[error("{what} is {value}, which is out of range")]
    BadValue {
        /// What was given.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// The obstacle was given a motion, but none was set.
    #[error("the obstacle was given a motion, but no obstacle was set (Simulator::set_obstacle)")]
    NoObstacle,
    /// The obstacle or the garment could not be turned into a collision hierarchy, the
    /// obstacle's positions do not fit its faces, or a collision query failed.
    #[error("collision: {0}")]
    Collide(#[from] tailor_collide::CollideError),
    /// A step failed even at the smallest allowed substep.
    #[error("the step at t = {time} s failed with a substep of {step} s: {reason}")]
    StepFailed {
        /// Simulation time (seconds) at the start of the failed substep.
        time: f64,
        /// The last substep tried (seconds).
        step: f64,
        /// What went wrong.
        reason: StepFailure,
    },
}

/// What made a substep fail.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StepFailure {
    /// A position, velocity or energy became NaN or infinite.
    #[error("a value became non-finite")]
    NonFinite,
    /// Conjugate gradients did not reach the tolerance within the iteration limit.
    #[error("conjugate gradients did not converge")]
    SolverDiverged,
}
