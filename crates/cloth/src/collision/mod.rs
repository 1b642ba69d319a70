//! Collision response: the garment against an animated obstacle (the body) and against itself,
//! after Bridson, Fedkiw & Anderson, "Robust treatment of collisions, contact and friction for
//! cloth animation" (SIGGRAPH 2002), with contact handled inside the implicit solve as Baraff &
//! Witkin do ("Large Steps in Cloth Simulation", 1998, §5.3).
//!
//! Every substep of length h, around the implicit solve:
//!
//! 1. **Body contacts, before the solve** ([`Obstacle::find_contacts`]). Each cloth vertex whose
//!    closest body point is near enough that, moving on, it would end the substep closer than
//!    the thickness becomes a contact constraint of the filter ([`crate::constraint`]): the
//!    plane through the closest point, its normal velocity prescribed to the body's (or to an
//!    approach that ends exactly at the thickness), the tangential velocity free. A vertex whose
//!    contact pulled it towards the body in the last substep is released (Baraff & Witkin's
//!    release rule).
//! 2. **Friction, after the solve** ([`Collisions::friction`]). The constraint impulse j is
//!    what the solve's residual leaves on a contact vertex (M Δv − h f); Coulomb friction
//!    removes up to μ jₙ / m of the tangential velocity relative to the body (Bridson et al.
//!    §7.2). The simulator then limits strain (`crate::strain_limit`), before the passes
//!    below, so friction cannot hold an edge stretched and collisions have the last word.
//! 3. **Self repulsion** ([`self_collision::repel`]): for every vertex within the thickness of
//!    a face of the garment, an impulse that stops the pair approaching and starts separating
//!    it by a tenth of the overlap per step (Bridson et al. §7.1).
//! 4. **Self impacts, the fail-safe** ([`self_collision::resolve_impacts`]): continuous
//!    vertex–triangle and edge–edge tests over the straight-line motion; each impact gets an
//!    inelastic impulse at the time of contact; a few rounds, then the remaining colliding
//!    vertices are merged into impact zones that move together (Bridson et al. §7.4, with
//!    zones that translate rather than rotate), which the collision-free start guarantees
//!    collision-free.
//! 5. **Body impacts and the final projection** ([`Obstacle::resolve_impacts`],
//!    [`Obstacle::project`]): any vertex whose path enters a body triangle from the front is put
//!    back on that triangle's front at the end of the substep, however fast the body moved,
//!    and any vertex closer than half the thickness is pushed out to it.
//! 6. **The refined surface** ([`surface`]), when the caller gave its stencils: the control
//!    points are lifted until every point of the subdivided surface, the one that renders,
//!    is at least the thickness from the body.
//!
//! The body is one-sided: its faces' counter-clockwise normals point outwards (a closed
//! character), so a vertex behind a face is inside and is pushed to the front. Impulses are
//! applied one after another in the sorted order the hierarchy reports, so results do not
//! depend on the thread count. Pinned and attached vertices have infinite mass here.

mod obstacle;
mod self_collision;
mod surface;

pub(crate) use obstacle::Obstacle;
pub(crate) use surface::Surface;

use tailor_collide::{CollideError, Hierarchy};
use tailor_subdiv::Point;

use crate::constraint::Contact;
use crate::energy::Vec3;
use crate::{ClothError, Model, Settings};

/// How much heavier a vertex resting on the body is in the self-collision passes.
const HELD_MASS: f64 = 100.0;

/// The collision state of one simulator: the garment's hierarchy, the obstacle, and the
/// buffers of the current substep.
#[derive(Clone, Debug)]
pub(crate) struct Collisions {
    pub obstacle: Option<Obstacle>,
    /// The refined surface that must clear the obstacle, when the caller gave one.
    pub surface: Option<Surface>,
    cloth: Hierarchy,
    /// The body contacts of the current substep.
    pub contacts: Vec<Contact>,
    /// Vertices whose contact pulled them towards the body in the last substep.
    pulling: Vec<bool>,
    /// The inverse masses of the self-collision passes: zero for vertices held by the body.
    held: Vec<f64>,
    /// The self-collision queries' answers, reused.
    layers: self_collision::Buffers,
}

/// The moving garment of one substep: start positions, and end positions and velocities the
/// response changes.
pub(crate) struct Motion<'a> {
    pub h: f64,
    pub x0: &'a [Point],
    pub x: &'a mut [Point],
    pub v: &'a mut [Vec3],
    pub inverse_mass: &'a [f64],
}

impl Motion<'_> {
    /// Positions again from velocities, x = x₀ + h v, for every movable vertex.
    fn sync_positions(&mut self) {
        for (i, x) in self.x.iter_mut().enumerate() {
            if self.inverse_mass[i] > 0.0 {
                *x = self.x0[i] + self.v[i] * self.h;
            }
        }
    }

    /// Applies the impulse along unit `normal` that brings the relative normal velocity
    /// Σ αₖ vₖ · n of `vertices` up to `target`, if it is below; each vertex's share is
    /// αₖ / mₖ. Returns whether it changed anything.
    fn push_apart(
        &mut self,
        vertices: [u32; 4],
        alpha: [f64; 4],
        normal: Vec3,
        target: f64,
    ) -> bool {
        let mut relative = 0.0;
        let mut weight = 0.0;
        for (&k, &a) in vertices.iter().zip(&alpha) {
            relative += a * self.v[k as usize].dot(&normal);
            weight += a * a * self.inverse_mass[k as usize];
        }
        if relative >= target || weight <= 0.0 {
            return false;
        }
        let impulse = (target - relative) / weight;
        for (&k, &a) in vertices.iter().zip(&alpha) {
            let k = k as usize;
            self.v[k] += normal * (a * impulse * self.inverse_mass[k]);
        }
        true
    }
}

impl Collisions {
    /// No obstacle yet; the garment's hierarchy built at rest.
    pub fn new(model: &Model) -> Result<Self, ClothError> {
        let n = model.vertex_count();
        Ok(Self {
            obstacle: None,
            surface: None,
            cloth: Hierarchy::build(&model.rest, &model.face_offsets, &model.face_vertices)?,
            contacts: Vec::new(),
            pulling: vec![false; n],
            held: Vec::with_capacity(n),
            layers: self_collision::Buffers::default(),
        })
    }

    /// Vertices whose contact pulled them towards the body in the last substep.
    pub fn pulling(&self) -> &[bool] {
        &self.pulling
    }

    /// Restores [`Self::pulling`] (from a checkpoint).
    pub fn set_pulling(&mut self, flags: &[bool]) {
        self.pulling.copy_from_slice(flags);
    }

    /// Finds the body contacts for the substep of length `h` from time `t0`.
    pub fn before_solve(
        &mut self,
        settings: &Settings,
        t0: f64,
        h: f64,
        x0: &[Point],
        v0: &[Vec3],
    ) -> Result<(), CollideError> {
        self.contacts.clear();
        if let Some(obstacle) = &mut self.obstacle {
            obstacle.begin_substep(t0, h);
            obstacle.find_contacts(settings, h, x0, v0, &self.pulling, &mut self.contacts)?;
        }
        Ok(())
    }

    /// Coulomb friction on the body contacts (step 2 of the module docs); `residual` is
    /// M (v₀ − v) + h f at the end of the solve.
    pub fn friction(&mut self, settings: &Settings, residual: &[Vec3], motion: &mut Motion) {
        if self.obstacle.is_some() {
            obstacle::friction(
                &self.contacts,
                residual,
                settings.friction,
                motion,
                &mut self.pulling,
            );
        }
    }

    /// The passes after friction (steps 3–5 of the module docs) on the end positions and
    /// velocities. Returns how many impacts and projections they made.
    pub fn resolve(
        &mut self,
        settings: &Settings,
        motion: &mut Motion,
    ) -> Result<u32, CollideError> {
        let thickness = settings.thickness;
        let mut resolved = 0;
        if settings.self_collision {
            // Cloth resting on the body is held by it: the layers above give way instead, so
            // the self passes do not push it into the body for the body passes to push back
            // out through the layer above.
            self.held.clear();
            self.held.extend_from_slice(motion.inverse_mass);
            for c in &self.contacts {
                self.held[c.vertex as usize] /= HELD_MASS;
            }
            let mut layers = Motion {
                h: motion.h,
                x0: motion.x0,
                x: &mut *motion.x,
                v: &mut *motion.v,
                inverse_mass: &self.held,
            };
            let buffers = &mut self.layers;
            self_collision::repel(&mut self.cloth, thickness, &mut layers, buffers)?;
            resolved +=
                self_collision::resolve_impacts(&mut self.cloth, thickness, &mut layers, buffers)?;
        }
        if let Some(obstacle) = &mut self.obstacle {
            resolved += obstacle.resolve_impacts(&mut self.cloth, thickness, motion)?;
            resolved += obstacle.project(thickness, motion)?;
            if let Some(surface) = &mut self.surface {
                resolved += obstacle.clear_surface(surface, thickness, motion)?;
            }
        }
        Ok(resolved)
    }
}
