//! Collision response: what a substep does around its implicit solve so that the garment
//! neither passes through the animated obstacle (the body) nor through itself, and no edge
//! stays stretched, after Bridson, Fedkiw & Anderson, "Robust treatment of collisions, contact
//! and friction for cloth animation" (SIGGRAPH 2002), with contact handled inside the implicit
//! solve as Baraff & Witkin do ("Large Steps in Cloth Simulation", 1998, §5.3), and strain
//! limiting after Provot 1995 ([`crate::strain_limit`]). [`Response`] owns the collision state
//! ([`Collisions`], whose passes the [`crate::collision`] module holds) and the strain limiter,
//! and runs the passes in order.
//!
//! Every substep of length h, around the implicit solve:
//!
//! 1. **Body contacts, before the solve** (`Obstacle::find_contacts`). Each cloth vertex whose
//!    closest body point is near enough that, moving on, it would end the substep closer than
//!    the thickness becomes a contact constraint of the filter ([`crate::constraint`]): the
//!    plane through the closest point, its normal velocity prescribed to the body's (or to an
//!    approach that ends exactly at the thickness), the tangential velocity free, or held too
//!    when the contact sticks; a sliding contact feels kinetic friction as a force of the
//!    solve (the `collision::friction` module). A vertex whose contact pulled it towards the
//!    body stays free until it is within the thickness again (Baraff & Witkin's release
//!    rule). **A second look after the solve** ([`Collisions::missed_contacts`]): a
//!    free vertex the solution takes closer than half the thickness to its start's body plane
//!    (released, or pulled in by the cloth faster than its own velocity foretold) becomes a
//!    contact too, and the simulator solves the same system again from the last solution.
//!    Without it the projection of step 5 put such vertices back by up to a centimetre at
//!    two substeps a frame, straining the edges around them by 15–35%.
//! 2. **Coulomb's law on the solve's contact impulses** ([`Collisions::friction`]). The
//!    constraint impulse j is what the linear solve's residual leaves on a contact vertex,
//!    b − A Δv (the right-hand side the constraint filter kept the solve from meeting there);
//!    it decides which contacts stick, slide or let go in the next substep, and a contact that
//!    starts to stick loses its tangential velocity (velocities only: positions stay the
//!    solve's). Strain is limited next ([`StrainLimiter::limit`]); vertices near the body are
//!    kept above a floor at three quarters of the thickness ([`Collisions::floors`]), so the
//!    limiter does not push them in for the projection to push back out.
//! 3. **Self repulsion** ([`Collisions::repel`]): for every vertex within the thickness of a
//!    face of the garment, and every edge within it of another edge, an impulse that stops the
//!    pair approaching and starts separating it by a tenth of the overlap per step (Bridson
//!    et al. §7.1), except the pairs the rest shape itself puts that near (see the
//!    `self_collision` module). The pairs are those of the substep's start, which the
//!    simulator finds while it solves ([`crate::collision::Garment::find_near`]). Stopping an
//!    approach at once strains the edges around the pair, so strain limiting runs again with
//!    the vertices it moved a hundred times heavier: the cloth around them takes up the slack.
//! 4. **Self impacts, the fail-safe** ([`Collisions::impulse_round`],
//!    [`Collisions::impact_zones`]): continuous vertex–triangle and edge–edge tests over the
//!    straight-line motion; each impact gets an inelastic impulse at the time of contact, each
//!    round of impulses is followed by strain limiting around them as in step 3 (the next
//!    round's query sees whether that crossed anything); a few rounds, then the remaining
//!    colliding vertices are merged into impact zones that move together (Bridson et al.
//!    §7.4, with zones that translate rather than rotate), which the collision-free start
//!    guarantees collision-free. Without the limiting in steps 3 and 4 the 64² drape's pleats
//!    ended 37% strained.
//! 5. **Body impacts and the final projection** ([`Collisions::push_out`]): any vertex whose
//!    path enters a body triangle from the front is put back on that triangle's front at the
//!    end of the substep, however fast the body moved, and any vertex closer than half the
//!    thickness is pushed out to it. Every later projection also seeks, within how far it
//!    moved, a vertex the passes in between moved farther than the thickness, which may have
//!    gone that deep into the body (see `Obstacle::project`).
//! 6. **The refined surface** ([`Collisions::clear_surface`]), when the caller gave its
//!    stencils: the control points are lifted until every point of the subdivided surface,
//!    the one that renders, is at least the thickness from the body. A lift strains the edges
//!    around the lifted points as a push does (the demo's cape went from 5% to 11% strain in
//!    one substep), so strain limiting relaxes around every vertex steps 5 and 6 moved, and
//!    step 5's projection runs once more after it; step 8 lifts again.
//! 7. **Self impacts again** (`Response::recheck_layers`), with self-collision on and
//!    when step 5 pushed or step 6 lifted anything: a push can fold a layer lying on the body
//!    through the one above it (the fold scenario's lower layer: two of its faces crossed after
//!    a push under two of three 1% changes of the CG tolerance), and the strain limiting after
//!    a lift can pull one layer through another (the 64² drape at five substeps, the sphere
//!    moved by 3 nm: the control mesh crossed itself on 3 frames), so step 4 runs again on the
//!    positions steps 5 and 6 left, the vertices they moved a hundred times heavier, and the
//!    projection once more for what that moved.
//! 8. **Settling** (`Response::settle`): rounds of the refined surface against itself (with
//!    self-collision on and the refined faces given: the continuous self tests of step 4 on
//!    the points of the subdivided surface, their impulses and impact zones acting on the
//!    control points through the stencils, the `collision::surface_layers` module, as in step
//!    7), the lift of step 6 with strain limiting around what it lifted, and the control
//!    mesh's own self impacts of step 7 on what those moved, until a round moves nothing, so
//!    that all of them hold together. A round also relaxes strain around what impact zones
//!    moved since the last round (a zone translates whole and strains the edges from it to
//!    the cloth around: up to 150% on a crumpled pile, left for the next substep, and written
//!    when the zones came in a frame's last substep: 19% and 32% on a frame of two piles), the
//!    zones' vertices held, and the control mesh's self impacts then check what that moved.
//!    The control mesh can be free of crossings while the surface it defines is not: where a
//!    hem crumples, the refined faces of two folds crossed on 12 of 61 frames of the 64²
//!    drape. And the refined pass and the lift move control points the control mesh's tests
//!    have not seen: without the control mesh's tests in these rounds it ended crossed on 50
//!    of 61 frames of the 128² drape, and at one substep a frame the next substeps could not
//!    undo it and the 64² drape tangled (47% strain, the written surface crossed on 47
//!    frames). The projection that follows those tests moves
//!    vertices they have not seen too, so a round that projected anything is followed by
//!    another, whose tests hold what it projected heavier, and rounds that run out end with
//!    the control mesh's tests: the 128² drape at one substep a frame ended frame 22 with
//!    five crossing pairs its last projection made, which stayed to the last frame; checked
//!    again with the projected vertex as light as the rest, it ran 30 rounds pushing one
//!    vertex back and forth and ended the frame at 11.4% strain.
//!
//! Friction acts in the integrator's own solve (step 2 only changes the velocities of
//! contacts that start to stick; see the `simulator` module). The other passes (strain
//! limiting, repulsion, impacts, projection) work on the straight path from x₀ to x₁ and its
//! velocity u = (x₁ − x₀)/h, as Bridson et al.'s response does; a vertex they leave alone ends
//! with the integrator's v₁, one they change with the velocity u of its corrected path.

use tailor_collide::CollideError;
use tailor_subdiv::Point;

use crate::collision::{Collisions, Layers};
use crate::constraint::Contact;
use crate::energy::Vec3;
use crate::model::Springs;
use crate::settings::Settings;
use crate::strain_limit::StrainLimiter;
use crate::substep::{Floor, HELD_MASS, Impulses, Substep};
use crate::{ClothError, Model};

/// Rounds of self-impact impulses before impact zones take over (rigid zones strain the cloth
/// around them: with 6 rounds the 64² drape needed zones in its pleats and ended 13% strained).
const IMPULSE_ROUNDS: usize = 12;

/// Most rounds of step 8 (the refined surface's self impacts, the lift and strain limiting,
/// the control mesh's self impacts). At two substeps a frame the 64² drape needs a second round
/// in half its substeps and a third in 3 of 120, the 128² drape a fourth once; at one substep
/// a frame (10 cm a step) the 64² drape needs five once, the 128² drape up to fourteen, and
/// with eight, the sphere moved by 1 nm, it left the written surface crossed on 24 frames. A
/// round costs only where the one before it moved something.
const SETTLE_ROUNDS: usize = 32;

/// The collision response of one simulator: the collision state, the strain limiter, and the
/// buffers of the current substep.
#[derive(Clone, Debug)]
pub(crate) struct Response {
    collisions: Collisions,
    strain: Limiting,
    /// The inverse masses of the self-collision passes (see [`hold`]).
    held: Vec<f64>,
    /// The vertices the last repulsion or body push moved.
    moved: Vec<bool>,
    /// End positions before the body passes.
    before: Vec<Point>,
    /// End positions before the last impact zones.
    before_zones: Vec<Point>,
    /// The vertices impact zones moved since the settling last relaxed strain around them.
    zoned: Vec<bool>,
    /// The velocities of [`Self::recheck_layers`]: the substep's own, and those that reach
    /// the positions the body passes left.
    own_velocity: Vec<Vec3>,
    reaching: Vec<Vec3>,
    /// Each vertex's velocity along its straight path, (x − x₀)/h, as the passes start, and
    /// what the integrator's end velocity adds to it.
    straight: Vec<Vec3>,
    excess: Vec<Vec3>,
}

/// Strain limiting between the collision passes: the limiter, the floors of the current
/// substep, and the corrections made since they were last taken.
#[derive(Clone, Debug)]
struct Limiting {
    limiter: StrainLimiter,
    /// The floors above the body (none without an obstacle).
    floors: Vec<Floor>,
    corrections: u32,
}

impl Limiting {
    /// Strain limiting after a collision pass that moved the vertices `moved` flags, the cloth
    /// around them taking up the strain (see [`StrainLimiter::limit_around`]); nothing when
    /// limiting is off (`limit` 0) or the pass moved nothing.
    fn around(&mut self, springs: &Springs, limit: f64, m: &mut Substep, moved: &[bool]) {
        if limit > 0.0 && moved.contains(&true) {
            self.corrections += self
                .limiter
                .limit_around(springs, limit, m, &self.floors, moved);
        }
    }
}

/// The inverse masses of the self-collision passes into `held`: cloth resting on the body
/// (the vertices of `contacts`, and those `also` flags) is held by it, [`HELD_MASS`] times
/// heavier, so the layers above give way instead and the self passes do not push it into the
/// body for the body passes to push back out through the layer above.
fn hold(held: &mut Vec<f64>, inverse_mass: &[f64], contacts: &[Contact], also: Option<&[bool]>) {
    held.clear();
    held.extend_from_slice(inverse_mass);
    for c in contacts {
        held[c.vertex as usize] /= HELD_MASS;
    }
    if let Some(also) = also {
        for (held, &heavier) in held.iter_mut().zip(also) {
            if heavier {
                *held /= HELD_MASS;
            }
        }
    }
}

impl Response {
    /// No obstacle yet (see [`Collisions::new`]); the strain limiter of the model's edges.
    pub fn new(model: &Model, settings: &Settings) -> Result<Self, ClothError> {
        let n = model.vertex_count();
        Ok(Self {
            collisions: Collisions::new(model, settings)?,
            strain: Limiting {
                limiter: StrainLimiter::new(&model.springs, n),
                floors: vec![Floor::NONE; n],
                corrections: 0,
            },
            held: Vec::with_capacity(n),
            moved: vec![false; n],
            before: Vec::with_capacity(n),
            before_zones: Vec::with_capacity(n),
            zoned: vec![false; n],
            own_velocity: Vec::with_capacity(n),
            reaching: Vec::with_capacity(n),
            straight: vec![Vec3::zeros(); n],
            excess: vec![Vec3::zeros(); n],
        })
    }

    /// The collision state: the obstacle, the refined surface, the body contacts.
    pub fn collisions(&self) -> &Collisions {
        &self.collisions
    }

    /// The collision state, to set the obstacle and find the contacts of the solve.
    pub fn collisions_mut(&mut self) -> &mut Collisions {
        &mut self.collisions
    }

    /// Steps 2–8 of the module docs, after the solve of the substep of length `h` from `x0`.
    /// `integrator` is the solve's own step (from x̂ over ĥ, to its end positions and
    /// velocities, which the response corrects); `residual` its b − A Δv, the contact
    /// impulses friction reads; `springs` the edges strain limiting keeps. Returns how many
    /// impacts and projections the collision fail-safes made; the strain corrections are
    /// counted for [`Self::take_strain_corrections`], made before an error too.
    pub fn after_solve(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        mut integrator: Substep,
        x0: &[Point],
        h: f64,
        contact: Impulses,
    ) -> Result<u32, CollideError> {
        // What zones moved is relaxed within the substep; the settling's last round may leave
        // some when it runs out of rounds, which the next substep must not inherit (it is no
        // part of the state a checkpoint keeps).
        self.zoned.fill(false);
        // Coulomb's law on the solve's contact impulses first: strain limiting and the
        // collision passes have the last word.
        self.collisions.friction(settings, contact, &mut integrator);
        let Substep {
            x, v, inverse_mass, ..
        } = integrator;
        // The other passes see the straight path from x₀ to x and its velocity
        // u = (x − x₀) / h (backward Euler's own).
        for i in 0..x.len() {
            let average = (x[i] - x0[i]) / h;
            self.excess[i] = v[i] - average;
            v[i] = average;
            self.straight[i] = average;
        }
        let mut motion = Substep {
            h,
            x0,
            x,
            v,
            inverse_mass,
        };
        let limit = settings.strain_limit;
        if limit > 0.0 {
            let strain = &mut self.strain;
            self.collisions.floors(settings, h, x0, &mut strain.floors);
            strain.corrections += strain
                .limiter
                .limit(springs, limit, &mut motion, &strain.floors);
        }
        let mut impacts = 0;
        if settings.self_collision {
            hold(
                &mut self.held,
                motion.inverse_mass,
                self.collisions.contacts(),
                None,
            );
            self.collisions.repel(
                settings.thickness,
                &mut motion.weighted(&self.held),
                &mut self.moved,
            );
            // Collision impulses stop features approaching at once, which strains the edges
            // around them: limit again after them, the cloth around taking up the slack.
            self.strain.around(springs, limit, &mut motion, &self.moved);
            impacts +=
                self.layer_impacts(settings, springs, &mut motion, false, Layers::Garment)?;
        }
        // The vertices the body passes move, for the self passes after them.
        self.moved.fill(false);
        let mut unchecked = 0;
        if self.collisions.has_obstacle() {
            let resolved;
            (resolved, unchecked) = self.body_passes(settings, springs, &mut motion)?;
            impacts += resolved;
        }
        impacts += self.settle(settings, springs, &mut motion, unchecked)?;
        // A vertex the passes left alone ends with the integrator's velocity; one they
        // changed (stopped by an impact, pushed, limited) with the velocity of its corrected
        // path, as backward Euler's would: the impulse that changed its path also took the
        // acceleration the path no longer has.
        for ((v, excess), average) in motion.v.iter_mut().zip(&self.excess).zip(&self.straight) {
            if v == average {
                *v += excess;
            }
        }
        Ok(impacts)
    }

    /// The edge corrections strain limiting made since the last call.
    pub fn take_strain_corrections(&mut self) -> u32 {
        std::mem::take(&mut self.strain.corrections)
    }

    /// The continuous self impacts (step 4), with the body's contact vertices [`HELD_MASS`]
    /// times heavier, and with `pushed_heavier` the vertices the body passes moved too:
    /// rounds of impulses, strain limiting around what each changed, then impact zones.
    /// Returns how many impacts and merges it handled.
    fn layer_impacts(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
        pushed_heavier: bool,
        which: Layers,
    ) -> Result<u32, CollideError> {
        let also = pushed_heavier.then_some(self.moved.as_slice());
        hold(
            &mut self.held,
            motion.inverse_mass,
            self.collisions.contacts(),
            also,
        );
        let mut layers = motion.weighted(&self.held);
        let mut handled = 0;
        for _ in 0..IMPULSE_ROUNDS {
            let round = self
                .collisions
                .impulse_round(which, settings.thickness, &mut layers)?;
            let Some((count, touched)) = round else {
                return Ok(handled);
            };
            handled += count;
            self.strain
                .around(springs, settings.strain_limit, &mut layers, touched);
        }
        self.before_zones.clear();
        self.before_zones.extend_from_slice(layers.x);
        let zoned = self.collisions.impact_zones(which, &mut layers)?;
        if zoned > 0 {
            for ((z, a), b) in self
                .zoned
                .iter_mut()
                .zip(&self.before_zones)
                .zip(layers.x.iter())
            {
                *z |= a != b;
            }
        }
        Ok(handled + zoned)
    }

    /// Steps 5–7: the body impacts and projection, the refined surface's lift, strain limiting
    /// around what they moved, and the self impacts again when they moved anything. Returns
    /// how many impacts and projections they made, and how many vertices the projection after
    /// the self impacts moved, which the control mesh's self impacts have not seen.
    fn body_passes(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
    ) -> Result<(u32, u32), CollideError> {
        let thickness = settings.thickness;
        self.before.clear();
        self.before.extend_from_slice(motion.x);
        let pushed = self.collisions.push_out(thickness, motion)?;
        let mut resolved = pushed;
        if pushed > 0 {
            // The pushes strain the edges around the pushed vertices.
            resolved += self.relax_what_moved(settings, springs, motion)?;
        }
        let lifted = self.collisions.clear_surface(thickness, motion)?;
        if lifted > 0 {
            // Lifting control points strains the edges around them as much as a push (on the
            // cape, from 5% to 11% in one substep); the rounds of step 8 lift again after it.
            resolved += self.relax_what_moved(settings, springs, motion)?;
        }
        resolved += lifted;
        let mut unchecked = 0;
        if settings.self_collision && pushed + lifted > 0 {
            resolved += self.recheck_layers(settings, springs, motion, Layers::Garment)?;
            unchecked = self.project_marking(settings, motion)?;
        }
        Ok((resolved + unchecked, unchecked))
    }

    /// Step 8: rounds of the refined surface's self impacts, as [`Self::recheck_layers`] (with
    /// self-collision on and the refined faces given), the lift of step 6 and strain limiting
    /// around what it lifted, and the control mesh's self impacts of step 7 on what those
    /// moved (with self-collision on), until a round moves nothing, so all of them hold: the
    /// self passes since the lift (step 7's and these) can bring the refined surface back
    /// within the thickness of the body (on the 128² drape's landing, by 1.2 mm), the strain
    /// limiting after a lift can put it back too, and the refined impulses and the lift move
    /// control points the control mesh's tests have not seen. The projection after those
    /// tests, which puts back what they moved into the body, moves vertices they have not
    /// seen either (`unchecked` of them before the first round, from step 7), so a round
    /// that projected anything is followed by another; and the rounds end with the control
    /// mesh's tests when the last one projected, leaving a vertex within half the thickness
    /// of the body for the next substep rather than a crossing, which no later substep
    /// undoes. Returns how many impacts and lifts they made.
    fn settle(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
        mut unchecked: u32,
    ) -> Result<u32, CollideError> {
        let surface = settings.self_collision && self.collisions.has_surface_layers();
        let mut resolved = 0;
        for _ in 0..SETTLE_ROUNDS {
            let impacts = if surface {
                self.recheck_layers(settings, springs, motion, Layers::Surface)?
            } else {
                0
            };
            self.before.clear();
            self.before.extend_from_slice(motion.x);
            let lifted = self.collisions.clear_surface(settings.thickness, motion)?;
            if lifted > 0 {
                // As after step 6: the cloth around the lifted points takes up their strain.
                resolved += self.relax_what_moved(settings, springs, motion)?;
            }
            let relaxed = self.relax_zones(settings, springs, motion)?;
            let garment = if settings.self_collision && impacts + lifted + relaxed + unchecked > 0 {
                self.recheck_layers(settings, springs, motion, Layers::Garment)?
            } else {
                0
            };
            unchecked = if garment > 0 {
                self.project_marking(settings, motion)?
            } else {
                0
            };
            resolved += impacts + lifted + garment + unchecked;
            if impacts + lifted + relaxed + garment + unchecked == 0 {
                return Ok(resolved);
            }
        }
        if settings.self_collision && unchecked > 0 {
            resolved += self.recheck_layers(settings, springs, motion, Layers::Garment)?;
        }
        Ok(resolved)
    }

    /// Relaxes strain around the vertices impact zones moved since the last call (a zone
    /// translates whole, straining the edges from it to the cloth around: up to 150% on a
    /// crumpled pile), the zones' vertices held, and pushes out whatever that brought within
    /// half the thickness of the body; returns how many vertices the zones had moved.
    fn relax_zones(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
    ) -> Result<u32, CollideError> {
        let zoned = self.zoned.iter().filter(|&&z| z).count() as u32;
        if zoned > 0 {
            self.strain
                .around(springs, settings.strain_limit, motion, &self.zoned);
            self.zoned.fill(false);
            self.collisions.project(settings.thickness, motion)?;
        }
        Ok(zoned)
    }

    /// The projection after the control mesh's self impacts; marks in `moved` the vertices it
    /// moved, which the next self impacts hold [`HELD_MASS`] times heavier (else they push
    /// them back into the body, and the rounds ping-pong one vertex between the two passes),
    /// and returns how many.
    fn project_marking(
        &mut self,
        settings: &Settings,
        motion: &mut Substep,
    ) -> Result<u32, CollideError> {
        self.before.clear();
        self.before.extend_from_slice(motion.x);
        let projected = self.collisions.project(settings.thickness, motion)?;
        if projected > 0 {
            self.mark_moved(motion.x);
        }
        Ok(projected)
    }

    /// Marks in `moved` the vertices whose positions `x` differ from `before`.
    fn mark_moved(&mut self, x: &[Point]) {
        self.moved.clear();
        self.moved
            .extend(self.before.iter().zip(x).map(|(a, b)| a != b));
    }

    /// Marks in `moved` the vertices the body passes moved from `before`, relaxes strain around
    /// them, and pushes out whatever that brought back within half the thickness; returns how
    /// many the projection moved.
    fn relax_what_moved(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
    ) -> Result<u32, CollideError> {
        self.mark_moved(motion.x);
        self.strain
            .around(springs, settings.strain_limit, motion, &self.moved);
        self.collisions.project(settings.thickness, motion)
    }

    /// The self impacts again after the body passes: a push can fold a layer lying on the
    /// body through the one above it. The self pass changes velocities and puts positions
    /// at x₀ + h v, so for it each vertex takes the velocity that reaches the position the
    /// body passes left, (x − x₀)/h, and keeps its own plus what the pass changed; the
    /// vertices the body passes moved (pushed or lifted) count [`HELD_MASS`] times heavier.
    fn recheck_layers(
        &mut self,
        settings: &Settings,
        springs: &Springs,
        motion: &mut Substep,
        which: Layers,
    ) -> Result<u32, CollideError> {
        let h = motion.h;
        self.own_velocity.clear();
        self.own_velocity.extend_from_slice(motion.v);
        for ((v, x), x0) in motion.v.iter_mut().zip(motion.x.iter()).zip(motion.x0) {
            *v = (x - x0) / h;
        }
        self.reaching.clear();
        self.reaching.extend_from_slice(motion.v);
        let resolved = self.layer_impacts(settings, springs, motion, true, which)?;
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
