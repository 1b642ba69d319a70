//! Collision detection and its passes: the garment against an animated obstacle (the body)
//! and against itself, after Bridson, Fedkiw & Anderson, "Robust treatment of collisions,
//! contact and friction for cloth animation" (SIGGRAPH 2002), with contact handled inside the
//! implicit solve as Baraff & Witkin do ("Large Steps in Cloth Simulation", 1998, §5.3).
//!
//! [`Collisions`] keeps the state they share from substep to substep: the garment's hierarchy,
//! the obstacle ([`obstacle`]) and the refined surface that must clear it ([`surface`]), the
//! body contacts of the substep, the vertices whose contact pulled, and the self-collision
//! queries' buffers ([`self_collision`]). Each pass is one method; [`crate::response`] runs
//! them in the order its docs number, which the passes' docs refer to, with strain limiting
//! between them.
//!
//! The body is one-sided: its faces' counter-clockwise normals point outwards (a closed
//! character), so a vertex behind a face is inside and is pushed to the front. Impulses are
//! applied one after another in the sorted order the hierarchy reports, so results do not
//! depend on the thread count. Pinned and attached vertices have infinite mass here.

mod friction;
mod obstacle;
mod self_collision;
mod surface;
mod surface_layers;

pub use friction::ContactState;
use friction::Friction;
use obstacle::Obstacle;
use surface::Surface;
use surface_layers::SurfaceLayers;

use tailor_collide::{CollideError, Hierarchy};
use tailor_subdiv::{Point, Refreshed, StencilTable};

use crate::constraint::{Contact, Filter};
use crate::energy::Vec3;
use crate::settings::Settings;
use crate::substep::{Floor, Impulses, Substep};
use crate::{ClothError, Model};

/// Which surface the self-collision passes keep from passing through itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layers {
    /// The control mesh.
    Garment,
    /// The refined surface that renders ([`surface_layers`]).
    Surface,
}

/// The collision state of one simulator: the garment's hierarchy, the obstacle, and the
/// buffers of the current substep.
#[derive(Clone, Debug)]
pub(crate) struct Collisions {
    obstacle: Option<Obstacle>,
    /// The refined surface that must clear the obstacle, when the caller gave one.
    surface: Option<Surface>,
    /// The garment's hierarchy and self-collision buffers; out only while
    /// [`Self::take_garment`] lent them.
    garment: Option<Garment>,
    /// The body contacts of the current substep.
    contacts: Vec<Contact>,
    /// Friction on the body contacts, and what it carries between substeps.
    friction: Friction,
}

/// The garment's hierarchy and the self-collision queries' answers, reused from substep to
/// substep: what repulsion's pairs need ([`Garment::find_near`]), so that the simulator can
/// lend them out to find those pairs beside its solve ([`Collisions::take_garment`]).
#[derive(Clone, Debug)]
pub(crate) struct Garment {
    cloth: Hierarchy,
    layers: self_collision::Buffers,
}

impl Garment {
    /// Repulsion's pairs at the substep's start `x0` (see [`self_collision::find_near`]), for
    /// [`Collisions::repel`] after the solve.
    pub fn find_near(&mut self, thickness: f64, x0: &[Point]) -> Result<(), CollideError> {
        self_collision::find_near(&mut self.cloth, thickness, x0, &mut self.layers)
    }
}

/// The garment of `slot`, which is back from every loan before a pass needs it.
fn lent_back(slot: &mut Option<Garment>) -> &mut Garment {
    slot.as_mut()
        .expect("the garment is given back before the passes after the solve")
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
            garment: Some(Garment { cloth, layers }),
            contacts: Vec::new(),
            friction: Friction::new(n),
        })
    }

    /// Makes the polygon mesh with CSR faces `face_offsets`/`face_vertices`, resting at
    /// `positions`, the obstacle (see [`Obstacle::new`]), replacing any earlier one.
    pub fn set_obstacle(
        &mut self,
        positions: &[Point],
        face_offsets: &[u32],
        face_vertices: &[u32],
    ) -> Result<(), ClothError> {
        self.obstacle = Some(Obstacle::new(positions, face_offsets, face_vertices)?);
        Ok(())
    }

    /// Moves the obstacle for the next frame (see [`Obstacle::set_motion`]).
    pub fn set_obstacle_motion(
        &mut self,
        t0: f64,
        start: &[Point],
        t1: f64,
        end: &[Point],
    ) -> Result<(), ClothError> {
        match &mut self.obstacle {
            Some(obstacle) => obstacle.set_motion(t0, start, t1, end),
            None => Err(ClothError::NoObstacle),
        }
    }

    /// Makes the refined surface `stencils` evaluates the one that must clear the obstacle,
    /// and with `faces` (its hierarchy) itself too ([`surface_layers`]), refit at the
    /// garment's `rest` positions.
    pub fn set_surface(
        &mut self,
        stencils: StencilTable,
        faces: Option<&Hierarchy>,
        rest: &[Point],
    ) -> Result<(), CollideError> {
        // Which refined points read each control point is found once, for the lift's points
        // and the layers' ends.
        let points = Refreshed::new(&stencils);
        let layers = faces
            .map(|faces| SurfaceLayers::new(&stencils, rest, faces.clone(), points.clone()))
            .transpose()?;
        self.surface = Some(Surface::new(stencils, points, layers));
        Ok(())
    }

    /// Whether the refined surface must clear itself.
    pub fn has_surface_layers(&self) -> bool {
        self.surface.as_ref().is_some_and(Surface::has_layers)
    }

    /// Whether there is an obstacle.
    pub fn has_obstacle(&self) -> bool {
        self.obstacle.is_some()
    }

    /// The body contacts of the current substep, constraints of its solve.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// What friction carries from one substep to the next.
    pub fn contact_state(&self) -> &ContactState {
        &self.friction.state
    }

    /// Restores [`Self::contact_state`] (from a checkpoint).
    pub fn set_contact_state(&mut self, state: &ContactState) {
        self.friction.state.clone_from(state);
    }

    /// The kinetic friction forces of the current substep, which the solve includes.
    pub fn friction_force(&self) -> &[Vec3] {
        self.friction.force()
    }

    /// The sticking contacts whose grip in the solve's `residual` exceeds Coulomb's cone slide
    /// within the substep (see [`Friction::slip`]); whether any did.
    pub fn slip(
        &mut self,
        settings: &Settings,
        residual: &[Vec3],
        h: f64,
        rhs: &mut [Vec3],
    ) -> bool {
        self.friction
            .slip(&self.contacts, residual, settings.friction, h, rhs)
    }

    /// Holds the sticking contacts' whole velocity in `filter`.
    pub fn stick(&self, filter: &mut Filter) {
        self.friction.stick(&self.contacts, filter);
    }

    /// Finds the body contacts for the substep of length `h` from time `t0`, and which of
    /// them stick and which slide under what friction force (vertex masses `mass`).
    pub fn before_solve(
        &mut self,
        settings: &Settings,
        t0: f64,
        h: f64,
        x0: &[Point],
        v0: &[Vec3],
        mass: &[f64],
    ) -> Result<(), CollideError> {
        self.contacts.clear();
        if let Some(surface) = &mut self.surface {
            surface.begin_substep(x0);
        }
        if let Some(obstacle) = &mut self.obstacle {
            obstacle.begin_substep(t0, h);
            let lifted = &mut self.friction.state.lifted;
            obstacle.find_contacts(settings, h, x0, v0, lifted, &mut self.contacts)?;
        }
        let (gravity, mu) = (settings.gravity, settings.friction);
        self.friction
            .prepare(&self.contacts, v0, mass, gravity, mu, h);
        Ok(())
    }

    /// Adds to [`Self::contacts`] the body contacts the solve missed (see
    /// [`Obstacle::missed_contacts`]) for the vertices `filter` leaves free, given the
    /// solve's end positions `x`; returns how many.
    pub fn missed_contacts(
        &mut self,
        settings: &Settings,
        h: f64,
        x0: &[Point],
        x: &[Point],
        filter: &Filter,
    ) -> usize {
        self.obstacle.as_ref().map_or(0, |obstacle| {
            obstacle.missed_contacts(settings.thickness, h, x0, x, filter, &mut self.contacts)
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

    /// Coulomb friction on the body contacts after the solve (step 2 of [`crate::response`],
    /// see the `friction` module), from the solve's contact impulses.
    pub fn friction(&mut self, settings: &Settings, contact: Impulses, motion: &mut Substep) {
        self.friction
            .after_solve(&self.contacts, contact, settings.friction, motion);
    }

    /// Lends out the garment's hierarchy and self-collision buffers, to find repulsion's pairs
    /// at the start of a substep ([`Garment::find_near`]) while the solve runs; give them back
    /// with [`Self::give_back`] before the passes after it.
    pub fn take_garment(&mut self) -> Garment {
        self.garment
            .take()
            .expect("the garment is lent out once at a time")
    }

    /// Takes back what [`Self::take_garment`] lent.
    pub fn give_back(&mut self, garment: Garment) {
        self.garment = Some(garment);
    }

    /// Self repulsion (step 3 of [`crate::response`]) on `motion`, on the pairs
    /// [`Garment::find_near`] found at the substep's start; `moved` flags the vertices whose
    /// velocities it changed.
    pub fn repel(&mut self, thickness: f64, motion: &mut Substep, moved: &mut [bool]) {
        let Garment { cloth, layers } = lent_back(&mut self.garment);
        self_collision::repel(cloth, thickness, motion, layers, moved);
    }

    /// One round of self-impact impulses of `layers` (steps 4 and 8 of [`crate::response`],
    /// see [`self_collision::impulse_round`]): `None` when there was no impact, else how many
    /// it handled and the control points it changed.
    pub fn impulse_round(
        &mut self,
        layers: Layers,
        thickness: f64,
        motion: &mut Substep,
    ) -> Result<Option<(u32, &[bool])>, CollideError> {
        match layers {
            Layers::Garment => {
                let Garment { cloth, layers } = lent_back(&mut self.garment);
                self_collision::impulse_round(cloth, thickness, motion, layers)
            }
            Layers::Surface => match self.surface.as_mut().and_then(Surface::layers) {
                Some((stencils, surface)) => surface.impulse_round(stencils, thickness, motion),
                None => Ok(None),
            },
        }
    }

    /// The impact zones that end steps 4 and 8 of [`crate::response`] for `layers` (see
    /// [`self_collision::impact_zones`]); returns how many merges they made.
    pub fn impact_zones(
        &mut self,
        layers: Layers,
        motion: &mut Substep,
    ) -> Result<u32, CollideError> {
        match layers {
            Layers::Garment => {
                let Garment { cloth, layers } = lent_back(&mut self.garment);
                self_collision::impact_zones(cloth, motion, layers)
            }
            Layers::Surface => match self.surface.as_mut().and_then(Surface::layers) {
                Some((stencils, surface)) => surface.impact_zones(stencils, motion),
                None => Ok(0),
            },
        }
    }

    /// Body impacts, then the projection (step 5 of [`crate::response`]); returns how many
    /// vertices they moved, none without an obstacle.
    pub fn push_out(&mut self, thickness: f64, motion: &mut Substep) -> Result<u32, CollideError> {
        match &mut self.obstacle {
            Some(obstacle) => Ok(obstacle.resolve_impacts(
                &mut lent_back(&mut self.garment).cloth,
                thickness,
                motion,
            )? + obstacle.project(thickness, motion)?),
            None => Ok(0),
        }
    }

    /// The projection alone (see [`Obstacle::project`]).
    pub fn project(&mut self, thickness: f64, motion: &mut Substep) -> Result<u32, CollideError> {
        self.obstacle
            .as_mut()
            .map_or(Ok(0), |obstacle| obstacle.project(thickness, motion))
    }

    /// The lift of the refined surface (step 6 of [`crate::response`]), when there is an
    /// obstacle and a surface: the garment is lifted until the surface clears the body by
    /// `thickness` at the substep's end ([`surface`]); call after [`Self::project`] or
    /// [`Self::push_out`], which refit the body's hierarchy there. Returns how many
    /// control-point moves it made.
    pub fn clear_surface(
        &mut self,
        thickness: f64,
        motion: &mut Substep,
    ) -> Result<u32, CollideError> {
        match (&self.obstacle, &mut self.surface) {
            (Some(obstacle), Some(surface)) => surface.clear(
                obstacle.hierarchy(),
                |c| obstacle.velocity_at(c),
                thickness,
                motion,
            ),
            _ => Ok(0),
        }
    }
}
