//! The moving garment of one substep, as the passes after the implicit solve see it: the
//! start positions x₀, free of intersections, and the end positions x and velocities v that
//! friction, strain limiting and the collision passes correct, each vertex moving by its
//! inverse mass (zero for a pinned or attached vertex, which does not move).
//!
//! The passes act on velocities and keep the positions those reach, x = x₀ + h v, so the
//! straight path from the start stays what the continuous tests examine (Bridson, Fedkiw &
//! Anderson, "Robust treatment of collisions, contact and friction for cloth animation",
//! SIGGRAPH 2002, §6–7). A pass that must leave some vertices where they are counts them
//! [`HELD_MASS`] times heavier ([`Substep::weighted`]), and strain limiting keeps a vertex
//! near the body above its [`Floor`].

use tailor_subdiv::Point;

use crate::energy::Vec3;

/// How much heavier a vertex counts where a pass should leave it in place: one resting on
/// the body in the self-collision passes, so the layers above give way instead; one a
/// collision pass moved, in the strain limiting after it, so the cloth around takes up the
/// strain rather than undoing the pass.
pub(crate) const HELD_MASS: f64 = 100.0;

/// The contact impulses of a substep's solve (its residual b − A Δv, zero off the
/// constrained vertices to the solve's tolerance) and the time they act over, s.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Impulses<'a> {
    pub impulse: &'a [Vec3],
    pub span: f64,
}

/// The moving garment of one substep: start positions, and end positions and velocities the
/// response changes.
pub(crate) struct Substep<'a> {
    /// The step the end positions are reached over, s: x = x₀ + h v.
    pub h: f64,
    /// Where the motion starts: the substep's start, free of intersections, for the collision
    /// passes; the integrator's x̂ for friction (see the `simulator` module).
    pub x0: &'a [Point],
    /// Positions at the end.
    pub x: &'a mut [Point],
    /// Velocities at the end.
    pub v: &'a mut [Vec3],
    /// 1 / mass, zero for a vertex whose motion is prescribed (it does not move).
    pub inverse_mass: &'a [f64],
}

impl Substep<'_> {
    /// The same motion with other inverse masses.
    pub fn weighted<'b>(&'b mut self, inverse_mass: &'b [f64]) -> Substep<'b> {
        Substep {
            h: self.h,
            x0: self.x0,
            x: &mut *self.x,
            v: &mut *self.v,
            inverse_mass,
        }
    }

    /// Positions again from velocities, x = x₀ + h v, for every movable vertex.
    pub fn sync_positions(&mut self) {
        for (i, x) in self.x.iter_mut().enumerate() {
            if self.inverse_mass[i] > 0.0 {
                *x = self.x0[i] + self.v[i] * self.h;
            }
        }
    }

    /// Removes vertex `i`'s velocity into the body along the unit `normal` away from it,
    /// relative to `body`, the body's velocity there, if it approaches: what is left slides
    /// along the body or leaves it (an inelastic contact).
    pub fn stop_approach(&mut self, i: usize, normal: Vec3, body: Vec3) {
        let closing = (self.v[i] - body).dot(&normal);
        if closing < 0.0 {
            self.v[i] -= normal * closing;
        }
    }

    /// Applies the impulse along unit `normal` that brings the relative normal velocity
    /// Σ αₖ vₖ · n of `vertices` up to `target`, if it is below; each vertex's share is
    /// αₖ / mₖ. Each vertex is listed once. Returns whether it changed anything.
    pub fn push_apart(
        &mut self,
        vertices: &[u32],
        alpha: &[f64],
        normal: Vec3,
        target: f64,
    ) -> bool {
        let mut relative = 0.0;
        let mut weight = 0.0;
        for (&k, &a) in vertices.iter().zip(alpha) {
            relative += a * self.v[k as usize].dot(&normal);
            weight += a * a * self.inverse_mass[k as usize];
        }
        if relative >= target || weight <= 0.0 {
            return false;
        }
        let impulse = (target - relative) / weight;
        for (&k, &a) in vertices.iter().zip(alpha) {
            let k = k as usize;
            self.v[k] += normal * (a * impulse * self.inverse_mass[k]);
        }
        true
    }
}

/// A half-space a vertex's corrections must not leave: n · x ≥ offset for a unit normal n
/// pointing away from the body (a floor a little above the body's surface at the end of the
/// substep), or none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Floor {
    pub normal: Vec3,
    pub offset: f64,
}

impl Floor {
    /// No floor.
    pub const NONE: Self = Self {
        normal: Vec3::new(0.0, 0.0, 0.0),
        offset: f64::NEG_INFINITY,
    };

    /// The correction `delta` of a vertex at `x`, shortened along the normal where it would
    /// take the vertex below the floor: a vertex near the body slides along it or stops at
    /// the floor, never pushed into the body for the projection after to push back.
    pub fn clamp(&self, x: Point, delta: Vec3) -> Vec3 {
        let inward = delta.dot(&self.normal);
        if inward >= 0.0 {
            return delta;
        }
        let room = (self.normal.dot(&x.coords) - self.offset).max(0.0);
        if inward < -room {
            delta - self.normal * (inward + room)
        } else {
            delta
        }
    }
}
