//! Coulomb friction between the garment and the body, inside the implicit solve.
//!
//! Bridson, Fedkiw & Anderson (2002, §7.2) apply friction after the solve: a contact vertex
//! loses up to μ jₙ / m of its tangential velocity, and its position follows. After an
//! implicit solve that one vertex's new position strains the stiff springs around it by about
//! h² k / m times the kinetic energy friction removed, and the next substep gives that energy
//! back: a drape on a pedestal kept trembling at centimetres a second. Here friction is part of
//! the solve, with Baraff & Witkin's constraint filter ("Large Steps in Cloth Simulation",
//! 1998, §5.3) holding what sticks:
//!
//! - A **sticking** contact has its whole velocity prescribed to the body's (its filter is
//!   zero), so cloth at rest on the body is held exactly, whatever its springs pull.
//! - A **sliding** contact has only its normal velocity prescribed; the kinetic friction
//!   force μ N against its tangential velocity at the substep's start enters the solve as an
//!   external force, never more than stops that velocity within the substep. N is the normal
//!   force of the contact in the last substep, or the force that stops the vertex's approach
//!   if that is more.
//!
//! A new contact sticks at once when its tangential speed is under what one substep of that
//! friction removes, μ N h / m (cloth laid on the body, or landing more steeply than its
//! friction angle). After the solve, Coulomb's law with the solve's own contact impulses j
//! (the negated residual of the filtered system, b − A Δv, which the filter kept the solve
//! from meeting) decides each contact's next substep:
//!
//! - a sticking contact whose grip |jₜ| exceeds μ jₙ slides, at once: the kinetic force
//!   μ jₙ / ĥ along its grip joins the right-hand side and the system is solved once more
//!   (held for a substep, a sheet laid on a 30° incline with μ = 0.3 lagged 2% behind
//!   Coulomb's slide; handing the vertex the grip friction cannot give as a velocity instead
//!   would load one vertex with what the stiff springs around it pull);
//! - a sliding contact that slowed over the substep sticks from the next when the friction
//!   the solve did not use, μ jₙ less the kinetic force's impulse, would have stopped its
//!   tangential velocity, which it then loses (one that sped up is being pulled past its
//!   grip: stuck, it slipped again at once; the 64² drape over a sphere slipped 137 contacts
//!   a substep, each a solve's worth of work, and 81 with this rule);
//! - a contact that pulled its vertex towards the body (jₙ < 0, Baraff & Witkin's release
//!   rule) lets it go, and the vertex stays free until it comes within the thickness again.
//!   Released for one substep only, a vertex the cloth's bending lifts a few hundredths of a
//!   millimetre off the body was taken and let go on alternate substeps for ever.
//!
//! The change after the solve is to velocities only: positions stay where the solve put them,
//! so no spring is strained behind the solve's back. What carries from one substep to the
//! next is [`ContactState`]; a checkpoint keeps it.

use crate::constraint::{Contact, Filter};
use crate::energy::{Mat3, Vec3};
use crate::substep::{Impulses, Substep};

/// What friction carries from one substep to the next, per cloth vertex: a checkpoint must
/// keep it for a resumed run to compute the same bits.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactState {
    /// Vertices whose body contact pulled them towards the body: free until they come
    /// within the thickness of it again.
    pub lifted: Vec<bool>,
    /// Vertices whose contact sticks in the next substep.
    pub stuck: Vec<bool>,
    /// The normal force of each vertex's contact in the last substep, N (zero without one).
    pub normal_force: Vec<f64>,
}

impl ContactState {
    /// No contact carried, for `n` vertices.
    #[must_use]
    pub fn new(n: usize) -> Self {
        Self {
            lifted: vec![false; n],
            stuck: vec![false; n],
            normal_force: vec![0.0; n],
        }
    }

    /// The number of vertices it is for.
    #[must_use]
    pub fn len(&self) -> usize {
        self.lifted.len()
    }

    /// Whether it is for no vertex.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lifted.is_empty()
    }

    /// Whether all three tables have one entry per vertex.
    pub(crate) fn is_consistent(&self) -> bool {
        self.stuck.len() == self.len() && self.normal_force.len() == self.len()
    }
}

/// Friction's state and the forces it puts into the current substep's solve.
#[derive(Clone, Debug)]
pub(crate) struct Friction {
    pub state: ContactState,
    /// The kinetic friction force on each sliding contact vertex in the current substep.
    force: Vec<Vec3>,
    /// Which vertices have a contact in the current substep.
    touching: Vec<bool>,
    /// Each contact vertex's tangential speed relative to the body at the substep's start
    /// (zero for the contacts the solve's second look adds).
    start_speed: Vec<f64>,
}

impl Friction {
    pub fn new(n: usize) -> Self {
        Self {
            state: ContactState::new(n),
            force: vec![Vec3::zeros(); n],
            touching: vec![false; n],
            start_speed: vec![0.0; n],
        }
    }

    /// The kinetic friction forces of the current substep.
    pub fn force(&self) -> &[Vec3] {
        &self.force
    }

    /// Before the solve of the substep of length `h` from velocities `v0` under `gravity`:
    /// decides which new `contacts` stick and sets the sliding ones' friction forces, with
    /// coefficient `mu`; forgets what it carried for vertices without a contact.
    pub fn prepare(
        &mut self,
        contacts: &[Contact],
        v0: &[Vec3],
        mass: &[f64],
        gravity: Vec3,
        mu: f64,
        h: f64,
    ) {
        self.force.fill(Vec3::zeros());
        self.touching.fill(false);
        // A contact the second look after the solve adds (`Collisions::missed_contacts`) has
        // no speed at the start recorded here, and so cannot start to stick before its next
        // substep: its zero here, not whatever speed an earlier substep left, which a run
        // resumed from a checkpoint would not have (a crumpled pile resumed at frame 12
        // stuck two contacts fewer in frame 13's second substep, and went its own way).
        self.start_speed.fill(0.0);
        let ContactState {
            stuck,
            normal_force,
            ..
        } = &mut self.state;
        for c in contacts {
            let i = c.vertex as usize;
            self.touching[i] = true;
            let relative = v0[i] - c.velocity;
            let tangential = relative - c.normal * relative.dot(&c.normal);
            let speed = tangential.norm();
            self.start_speed[i] = speed;
            // The force that stops the vertex's approach within the substep, gravity's
            // included.
            let stopping = mass[i] * (c.velocity - v0[i] - gravity * h).dot(&c.normal) / h;
            let new = normal_force[i] == 0.0;
            let most = mu * normal_force[i].max(stopping).max(0.0);
            if new && mu > 0.0 && speed <= most * h / mass[i] {
                stuck[i] = true;
            }
            if !stuck[i] && speed > 0.0 {
                self.force[i] = -tangential * (most.min(mass[i] * speed / h) / speed);
            }
        }
        for (i, &touching) in self.touching.iter().enumerate() {
            if !touching {
                stuck[i] = false;
                normal_force[i] = 0.0;
            }
        }
    }

    /// Within the substep, after a solve: each sticking contact whose grip in the solve's
    /// `residual` (its negated contact impulse, over the integrator's step `h`) exceeds
    /// μ jₙ slides, under the kinetic friction force μ jₙ / h along its grip, which `rhs`
    /// gains for the solve to be made again. Returns whether any did.
    pub fn slip(
        &mut self,
        contacts: &[Contact],
        residual: &[Vec3],
        mu: f64,
        h: f64,
        rhs: &mut [Vec3],
    ) -> bool {
        let mut any = false;
        for c in contacts {
            let i = c.vertex as usize;
            if !self.state.stuck[i] {
                continue;
            }
            let impulse = -residual[i];
            let push = impulse.dot(&c.normal);
            let grip = impulse - c.normal * push;
            let needed = grip.norm();
            if push > 0.0 && needed > mu * push {
                self.state.stuck[i] = false;
                self.force[i] = grip * (mu * push / (h * needed));
                rhs[i] += self.force[i] * h;
                any = true;
            }
        }
        any
    }

    /// Holds the sticking contacts' whole velocity in `filter` (pins and attachments, which
    /// place their vertices, keep theirs).
    pub fn stick(&self, contacts: &[Contact], filter: &mut Filter) {
        for c in contacts {
            let i = c.vertex as usize;
            if self.state.stuck[i] && !filter.placed[i] {
                filter.s[i] = Mat3::zeros();
                filter.z[i] = c.velocity;
            }
        }
    }

    /// After the solve: Coulomb's law on the contact impulses, the negated residual
    /// b − A Δv of the solve (over `contact.span`; the integrator's step is `m.h`), decides
    /// each contact's next substep, with coefficient `mu`; a contact that sticks from now on
    /// loses its tangential velocity in `m.v` (see the module docs).
    pub fn after_solve(
        &mut self,
        contacts: &[Contact],
        contact: Impulses,
        mu: f64,
        m: &mut Substep,
    ) {
        let ContactState {
            lifted,
            stuck,
            normal_force,
        } = &mut self.state;
        for c in contacts {
            let i = c.vertex as usize;
            let inverse = m.inverse_mass[i];
            if inverse == 0.0 {
                continue;
            }
            let impulse = -contact.impulse[i];
            let push = impulse.dot(&c.normal);
            if push < 0.0 {
                lifted[i] = true;
                stuck[i] = false;
                normal_force[i] = 0.0;
                continue;
            }
            normal_force[i] = push / contact.span;
            if stuck[i] {
                let grip = impulse - c.normal * push;
                stuck[i] = grip.norm() <= mu * push;
            } else {
                let spare = mu * push - self.force[i].norm() * m.h;
                let relative = m.v[i] - c.velocity;
                let tangential = relative - c.normal * relative.dot(&c.normal);
                let speed = tangential.norm();
                let slowing = speed <= self.start_speed[i];
                if mu > 0.0 && slowing && speed <= spare * inverse {
                    stuck[i] = true;
                    m.v[i] -= tangential;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tailor_subdiv::Point;

    /// Four vertices of mass 2 on a floor (normal +y) at rest, μ = 0.5, substeps of 0.01 s.
    fn on_the_floor() -> (Vec<Contact>, Friction) {
        let contacts = (0..4)
            .map(|vertex| Contact {
                vertex,
                normal: Vec3::y(),
                velocity: Vec3::zeros(),
            })
            .collect();
        (contacts, Friction::new(4))
    }

    /// [`Friction::after_solve`] for a solve of step `h` that ended the vertices of mass
    /// `mass` at velocities `v` with contact impulses −`residual`; `x` are their positions.
    fn after_solve(
        friction: &mut Friction,
        contacts: &[Contact],
        residual: &[Vec3],
        (mu, h, mass): (f64, f64, f64),
        v: &mut [Vec3],
        x: &mut [Point],
    ) {
        let x0 = x.to_vec();
        let mut m = Substep {
            h,
            x0: &x0,
            x,
            v,
            inverse_mass: &[1.0 / mass; 4],
        };
        let contact = Impulses {
            impulse: residual,
            span: h,
        };
        friction.after_solve(contacts, contact, mu, &mut m);
    }

    #[test]
    fn coulombs_law_on_the_solve_impulses_decides_the_next_substep() {
        let (contacts, mut friction) = on_the_floor();
        let (mu, h, mass, gravity) = (0.5, 0.01, 2.0, Vec3::new(0.0, -10.0, 0.0));
        // Before the first solve: new contacts whose tangential speed one substep of
        // friction (μ m g h / m = 0.05 m/s) removes stick; the others slide under μ m g.
        let v0 = [0.04, 0.06, 0.0, 1.0].map(|x| Vec3::new(x, 0.0, 0.0));
        friction.prepare(&contacts, &v0, &[mass; 4], gravity, mu, h);
        assert_eq!(friction.state.stuck, [true, false, true, false]);
        assert_eq!(friction.force()[0], Vec3::zeros());
        // The sliding ones feel μ N = 10 N against their motion, but no more than stops
        // them within the substep (m · 0.06 / h = 12 N for vertex 1).
        assert!((friction.force()[1] - Vec3::new(-10.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((friction.force()[3] - Vec3::new(-10.0, 0.0, 0.0)).norm() < 1e-12);
        // The solve's contact impulses j = −residual (N s): vertex 0 is gripped by 0.06
        // against a push of 0.1, more than μ jₙ = 0.05: it slides next. Vertex 2 is gripped
        // by 0.04: it keeps sticking. Vertex 1 ends with 0.01 m/s, which the friction the
        // solve left unused (μ jₙ − 10 N · h = 0.05 − 0.1 < 0) cannot remove: it slides on.
        // Vertex 3 pulled the floor (jₙ < 0): it is let go, lifted.
        let residual = [
            Vec3::new(0.06, -0.1, 0.0),
            Vec3::new(0.0, -0.1, 0.0),
            Vec3::new(-0.04, -0.1, 0.0),
            Vec3::new(0.0, 0.01, 0.0),
        ];
        let x0 = [Point::origin(); 4];
        let mut x = x0;
        let mut v = [0.0, 0.01, 0.0, 0.9].map(|x| Vec3::new(x, 0.0, 0.0));
        let step = (mu, h, mass);
        after_solve(&mut friction, &contacts, &residual, step, &mut v, &mut x);
        assert_eq!(friction.state.stuck, [false, false, true, false]);
        assert_eq!(friction.state.lifted, [false, false, false, true]);
        assert_eq!(friction.state.normal_force, [10.0, 10.0, 10.0, 0.0]);
        // Velocities change only where a contact starts to stick; positions never.
        assert_eq!(v[1], Vec3::new(0.01, 0.0, 0.0));
        assert_eq!(x, x0);
        // A sliding contact slowed to what unused friction removes sticks, losing it.
        let pressed = [Vec3::new(0.0, -0.1, 0.0); 4];
        let (contacts, mut friction) = on_the_floor();
        friction.state.normal_force = vec![10.0; 4];
        let v0 = [Vec3::new(0.004, 0.0, 0.0); 4];
        friction.prepare(&contacts, &v0, &[mass; 4], gravity, mu, h);
        // Carried contacts do not stick before a solve; friction is what stops 0.004 m/s.
        assert_eq!(friction.state.stuck, [false; 4]);
        assert!((friction.force()[0] - Vec3::new(-0.8, 0.0, 0.0)).norm() < 1e-12);
        let mut v = [Vec3::new(0.003, 0.0, 0.0); 4];
        after_solve(&mut friction, &contacts, &pressed, step, &mut v, &mut x);
        // Unused: 0.05 − 0.8 · 0.01 = 0.042 N s, which stops 0.021 m/s; they slowed.
        assert_eq!(friction.state.stuck, [true; 4]);
        assert_eq!(v[0], Vec3::zeros());
        // One that sped up, however slowly, is pulled past its grip: it slides on.
        let (contacts, mut friction) = on_the_floor();
        friction.state.normal_force = vec![10.0; 4];
        friction.prepare(&contacts, &v0, &[mass; 4], gravity, mu, h);
        let mut v = [Vec3::new(0.005, 0.0, 0.0); 4];
        after_solve(&mut friction, &contacts, &pressed, step, &mut v, &mut x);
        assert_eq!(friction.state.stuck, [false; 4]);
    }
}
