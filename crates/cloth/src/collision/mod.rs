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
//!    release rule). **A second look after the solve** ([`Collisions::missed_contacts`]): a
//!    free vertex the solution takes closer than half the thickness to its start's body plane
//!    (released, or pulled in by the cloth faster than its own velocity foretold) becomes a
//!    contact too, and the simulator solves the same system again from the last solution.
//!    Without it the projection of step 5 put such vertices back by up to a centimetre at
//!    two substeps a frame, straining the edges around them by 15–35%.
//! 2. **Friction, after the solve** ([`Collisions::friction`]). The constraint impulse j is
//!    what the linear solve's residual leaves on a contact vertex, b − A Δv (the right-hand
//!    side the constraint filter kept the solve from meeting there); Coulomb friction
//!    removes up to μ jₙ / m of the tangential velocity relative to the body (Bridson et al.
//!    §7.2). The simulator then limits strain (`crate::strain_limit`), so friction cannot hold
//!    an edge stretched; vertices near the body are kept above a floor at three quarters of
//!    the thickness ([`Collisions::floors`]), so the limiter does not push them in for the
//!    projection to push back out.
//! 3. **Self repulsion** ([`Collisions::repel`]): for every vertex within the thickness of a
//!    face of the garment, an impulse that stops the pair approaching and starts separating it
//!    by a tenth of the overlap per step (Bridson et al. §7.1), except the pairs the rest shape
//!    itself puts that near (see the `self_collision` module). Stopping an
//!    approach at once strains the edges around the pair, so strain limiting runs again with
//!    the vertices it moved a hundred times heavier: the cloth around them takes up the slack.
//! 4. **Self impacts, the fail-safe** ([`self_collision::resolve_impacts`]): continuous
//!    vertex–triangle and edge–edge tests over the straight-line motion; each impact gets an
//!    inelastic impulse at the time of contact, each round of impulses is followed by strain
//!    limiting around them as in step 3 (the next round's query sees whether that crossed
//!    anything); a few rounds, then the remaining colliding vertices are merged into impact
//!    zones that move together (Bridson et al. §7.4, with zones that translate rather than
//!    rotate), which the collision-free start guarantees collision-free. Without the
//!    limiting in steps 3 and 4 the 64² drape's pleats ended 37% strained.
//! 5. **Body impacts and the final projection** ([`Obstacle::resolve_impacts`],
//!    [`Obstacle::project`]): any vertex whose path enters a body triangle from the front is put
//!    back on that triangle's front at the end of the substep, however fast the body moved,
//!    and any vertex closer than half the thickness is pushed out to it.
//! 6. **The refined surface** ([`surface`]), when the caller gave its stencils: the control
//!    points are lifted until every point of the subdivided surface, the one that renders,
//!    is at least the thickness from the body. A lift strains the edges around the lifted
//!    points as a push does (the demo's cape went from 5% to 11% strain in one substep), so
//!    strain limiting relaxes around every vertex steps 5 and 6 moved, and steps 5's
//!    projection and 6 run once more after it.
//! 7. **Self impacts again** (`Collisions::recheck_layers`), with self-collision on and
//!    when step 5 pushed anything: a push can fold a layer lying on the body through the one
//!    above it (the fold scenario's lower layer: two of its faces crossed after a push
//!    under two of three 1% changes of the CG tolerance), so step 4 runs again on the
//!    positions steps 5 and 6 left, the vertices they moved a hundred times heavier, and the
//!    projection once more for what that moved.
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
use crate::substep::{Floor, HELD_MASS, Substep};
use crate::{ClothError, Model, Settings};

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
    /// The vertices the last repulsion or body push moved.
    moved: Vec<bool>,
    /// End positions before the body passes.
    before: Vec<Point>,
    /// The velocities of [`Self::recheck_layers`]: the substep's own, and those that reach
    /// the positions the body passes left.
    own_velocity: Vec<Vec3>,
    reaching: Vec<Vec3>,
}

/// Marks in `moved` the vertices the body passes moved from `before`, relaxes strain around
/// them, and pushes out whatever that brought back within half the thickness; returns how
/// many the projection moved.
fn relax_what_moved(
    obstacle: &mut Obstacle,
    before: &[Point],
    moved: &mut Vec<bool>,
    thickness: f64,
    motion: &mut Substep,
    relax: &mut impl FnMut(&mut Substep, &[bool]),
) -> Result<u32, CollideError> {
    moved.clear();
    moved.extend(before.iter().zip(motion.x.iter()).map(|(a, b)| a != b));
    relax(motion, moved);
    obstacle.project(thickness, motion)
}

impl Collisions {
    /// No obstacle yet; the garment's hierarchy built at rest, and with self-collision the
    /// pairs its rest shape puts near each other, which repulsion leaves alone.
    pub fn new(model: &Model, settings: &Settings) -> Result<Self, ClothError> {
        let n = model.vertex_count();
        let mut cloth = Hierarchy::build(&model.rest, &model.face_offsets, &model.face_vertices)?;
        let layers = if settings.self_collision {
            self_collision::Buffers::new(&mut cloth, &model.rest, settings.thickness)?
        } else {
            self_collision::Buffers::default()
        };
        Ok(Self {
            obstacle: None,
            surface: None,
            cloth,
            contacts: Vec::new(),
            pulling: vec![false; n],
            held: Vec::with_capacity(n),
            layers,
            moved: vec![false; n],
            before: Vec::with_capacity(n),
            own_velocity: Vec::with_capacity(n),
            reaching: Vec::with_capacity(n),
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

    /// Adds to [`Self::contacts`] the body contacts the solve missed (see
    /// [`Obstacle::missed_contacts`]) for vertices `free` says are unconstrained, given the
    /// solve's end positions `x`; returns how many.
    pub fn missed_contacts(
        &mut self,
        settings: &Settings,
        h: f64,
        x0: &[Point],
        x: &[Point],
        free: impl Fn(usize) -> bool,
    ) -> usize {
        self.obstacle.as_ref().map_or(0, |obstacle| {
            obstacle.missed_contacts(settings.thickness, h, x0, x, free, &mut self.contacts)
        })
    }

    /// The floors of strain limiting for the substep of length `h` (see
    /// [`Obstacle::floors`]): none without an obstacle.
    pub fn floors(&self, settings: &Settings, h: f64, x0: &[Point], out: &mut [Floor]) {
        out.fill(Floor::NONE);
        if let Some(obstacle) = &self.obstacle {
            obstacle.floors(settings.thickness, h, x0, out);
        }
    }

    /// Coulomb friction on the body contacts (step 2 of the module docs); `residual` is the
    /// linear solve's b − A Δv, M (v₀ − v) + h f at the end of the solve linearized.
    pub fn friction(&mut self, settings: &Settings, residual: &[Vec3], motion: &mut Substep) {
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

    /// The inverse masses of the self-collision passes: cloth resting on the body is held by
    /// it, [`HELD_MASS`] times heavier, so the layers above give way instead and the self
    /// passes do not push it into the body for the body passes to push back out through the
    /// layer above.
    fn hold(&mut self, inverse_mass: &[f64]) {
        self.held.clear();
        self.held.extend_from_slice(inverse_mass);
        for c in &self.contacts {
            self.held[c.vertex as usize] /= HELD_MASS;
        }
    }

    /// Self repulsion (step 3 of the module docs), when self-collision is on; returns the
    /// vertices whose velocities it changed (all false when off).
    pub fn repel(
        &mut self,
        settings: &Settings,
        motion: &mut Substep,
    ) -> Result<&[bool], CollideError> {
        self.moved.resize(motion.x.len(), false);
        if settings.self_collision {
            self.hold(motion.inverse_mass);
            let mut layers = motion.weighted(&self.held);
            self_collision::repel(
                &mut self.cloth,
                settings.thickness,
                &mut layers,
                &mut self.layers,
                &mut self.moved,
            )?;
        } else {
            self.moved.fill(false);
        }
        Ok(&self.moved)
    }

    /// The passes after repulsion (steps 4–7 of the module docs) on the end positions and
    /// velocities, `relax` after each round of self impulses (see
    /// [`self_collision::resolve_impacts`]). Returns how many impacts and projections they
    /// made.
    pub fn resolve(
        &mut self,
        settings: &Settings,
        motion: &mut Substep,
        relax: &mut impl FnMut(&mut Substep, &[bool]),
    ) -> Result<u32, CollideError> {
        let thickness = settings.thickness;
        let mut resolved = 0;
        if settings.self_collision {
            resolved += self.layer_impacts(thickness, motion, relax, false)?;
        }
        if let Some(obstacle) = &mut self.obstacle {
            self.before.clear();
            self.before.extend_from_slice(motion.x);
            let pushed = obstacle.resolve_impacts(&mut self.cloth, thickness, motion)?
                + obstacle.project(thickness, motion)?;
            let (before, moved) = (&self.before, &mut self.moved);
            if pushed > 0 {
                // The pushes strain the edges around the pushed vertices.
                resolved += relax_what_moved(obstacle, before, moved, thickness, motion, relax)?;
            }
            resolved += pushed;
            if let Some(surface) = &mut self.surface {
                let lifted = obstacle.clear_surface(surface, thickness, motion)?;
                if lifted > 0 {
                    // Lifting control points strains the edges around them as much as a push
                    // (the cape's edges went from 5% to 11% in one substep); lift again after,
                    // so the collision passes keep the last word.
                    resolved +=
                        relax_what_moved(obstacle, before, moved, thickness, motion, relax)?;
                    resolved += obstacle.clear_surface(surface, thickness, motion)?;
                }
                resolved += lifted;
            }
            if settings.self_collision && pushed > 0 {
                resolved += self.recheck_layers(thickness, motion, relax)?;
                if let Some(obstacle) = &mut self.obstacle {
                    resolved += obstacle.project(thickness, motion)?;
                }
            }
        }
        Ok(resolved)
    }

    /// The continuous self impacts (step 4), with the body's contact vertices [`HELD_MASS`]
    /// times heavier, and with `pushed_heavier` the vertices the body passes moved too.
    fn layer_impacts(
        &mut self,
        thickness: f64,
        motion: &mut Substep,
        relax: &mut impl FnMut(&mut Substep, &[bool]),
        pushed_heavier: bool,
    ) -> Result<u32, CollideError> {
        self.hold(motion.inverse_mass);
        if pushed_heavier {
            for (held, &pushed) in self.held.iter_mut().zip(&self.moved) {
                if pushed {
                    *held /= HELD_MASS;
                }
            }
        }
        let mut layers = motion.weighted(&self.held);
        self_collision::resolve_impacts(
            &mut self.cloth,
            thickness,
            &mut layers,
            &mut self.layers,
            relax,
        )
    }

    /// The self impacts again after the body passes: a push can fold a layer lying on the
    /// body through the one above it. The self pass changes velocities and puts positions
    /// at x₀ + h v, so for it each vertex takes the velocity that reaches the position the
    /// body passes left, (x − x₀)/h, and keeps its own plus what the pass changed; the
    /// vertices the body passes moved (pushed or lifted) count [`HELD_MASS`] times heavier.
    fn recheck_layers(
        &mut self,
        thickness: f64,
        motion: &mut Substep,
        relax: &mut impl FnMut(&mut Substep, &[bool]),
    ) -> Result<u32, CollideError> {
        let h = motion.h;
        self.own_velocity.clear();
        self.own_velocity.extend_from_slice(motion.v);
        for ((v, x), x0) in motion.v.iter_mut().zip(motion.x.iter()).zip(motion.x0) {
            *v = (x - x0) / h;
        }
        self.reaching.clear();
        self.reaching.extend_from_slice(motion.v);
        let resolved = self.layer_impacts(thickness, motion, relax, true)?;
        for ((v, own), reaching) in motion
            .v
            .iter_mut()
            .zip(&self.own_velocity)
            .zip(&self.reaching)
        {
            *v = own + (*v - reaching);
        }
        Ok(resolved)
    }
}
