//! Cloth at rest stays at rest, and where it rests does not depend on the substep: a small
//! Cusick drape (BS 5058, ISO 9073-9, at half the standard's size: a 15 cm disc of cotton on a
//! 9 cm pedestal, thickness 2 mm, friction 0.3, self-collision on) settles until every vertex
//! moves slower than 1 mm/s, and its drape coefficient agrees to ±0.02 at 2, 5 and 10 substeps
//! a frame. The full-size drape is `examples/cusick.rs`, where the substep moves the
//! coefficient more than at this size.
//!
//! Both fail today and are ignored: friction acts after the solve one vertex at a time, so
//! holding a vertex back strains the stiff springs around it (h² k / m ≈ 10⁵ times the kinetic
//! energy it removes, for denim) and the next substep releases that energy; and contacts near
//! the pedestal's rim, where a bending-stiff fabric lifts off, are released and taken again on
//! alternate substeps.
//!
//! Measured on the full-size drape at 5 substeps a frame (15 s; today cotton moves at
//! 0.15 / 5.2 mm/s median / fastest, denim at 1.2 / 99 mm/s):
//!
//! - Friction after the solve is what keeps it moving. With it left only on the contacts the
//!   second look adds, contacts before the solve taken only within the thickness, and a
//!   contact that pulls released within its own substep (no flag carried to the next), both
//!   rest: every vertex slower than 0.2 mm/s from 8 s on (cotton 0.06, denim 0.04 mm/s at
//!   15 s).
//! - Those contact rules with friction after the solve kept: denim 0.42 / 6.5 mm/s, cotton
//!   0.34 / 12 mm/s; and the fold of `tests/collisions.rs` crosses faces (a lower layer lifted
//!   past the thickness is no contact, so it is light in the self-collision passes). Taking
//!   vertices that move towards the body as contacts too mends the fold, but denim then
//!   moves at 6.4 / 93 mm/s.
//! - Friction as a regularized damper inside the solve (k = μ jₙ / max(|uₜ|, 0.1 mm/s) on the
//!   vertex's diagonal block, jₙ estimated from the solve's right-hand side, k lowered to the
//!   local Coulomb solution and the system solved again where a solve exceeded μ jₙ) keeps
//!   the incline test of `tests/collisions.rs`, but cotton trembles at 9 / 43 mm/s and denim
//!   slides off the pedestal within 7 s; on the small drape, 75 / 56 / 0.2 mm/s at 2 / 5 / 10
//!   substeps. Its hold is a hundred times a vertex's mass, and lowering it after a solve
//!   moves the whole sheet.
//!
//! Static friction belongs inside the solve, then, but as something that does not move the
//! sheet each time a vertex starts to slide.

use tailor_cloth::shapes::{cylinder, disc, drape_coefficient};
use tailor_cloth::{Integrator, Material, Settings, Vec3};
use tailor_subdiv::Point;

use common::{moved, set_obstacle, simulator};

mod common;

const FPS: f64 = 24.0;
const PEDESTAL: f64 = 0.045;

/// The drape after `seconds` at `substeps` a frame: the fastest vertex's speed over the last
/// frame (m/s, its displacement over the frame's length) and the drape coefficient.
fn drape(substeps: u32, seconds: u32) -> (f64, f64) {
    let thickness = 0.002;
    let fabric = moved(&disc(0.075, 12, 4), Vec3::y() * thickness);
    let settings = Settings {
        max_substep: 1.0 / (FPS * f64::from(substeps)),
        thickness,
        friction: 0.3,
        self_collision: true,
        // What a `tailor` scene steps with.
        integrator: Integrator::Bdf2,
        ..Settings::default()
    };
    let (mut sim, mut state) = simulator(&fabric, &Material::COTTON, settings);
    let stand = cylinder(Point::new(0.0, -0.1, 0.0), PEDESTAL, 0.1, 48);
    set_obstacle(&mut sim, &stand);
    let mut last = state.positions.clone();
    for _ in 0..seconds * FPS as u32 {
        last.clone_from(&state.positions);
        sim.step(&mut state, 1.0 / FPS).unwrap();
    }
    let fastest = state
        .positions
        .iter()
        .zip(&last)
        .map(|(p, q)| (p - q).norm() * FPS)
        .fold(0.0, f64::max);
    (
        fastest,
        drape_coefficient(&fabric, &state.positions, PEDESTAL),
    )
}

#[test]
#[ignore = "open defect: the drape does not come to rest (29 mm/s after 4 s); friction after the solve and chattering contacts keep it moving"]
fn a_draped_disc_comes_to_rest() {
    let (fastest, _) = drape(5, 4);
    assert!(fastest < 1e-3, "a vertex still moves at {fastest} m/s");
}

#[test]
#[ignore = "open defect: the drape coefficient is 0.566, 0.577 and 0.623 at 2, 5 and 10 substeps"]
fn the_resting_drape_does_not_depend_on_the_substep() {
    let coefficients = [2, 5, 10].map(|substeps| drape(substeps, 4).1);
    let mean = coefficients.iter().sum::<f64>() / 3.0;
    assert!(
        coefficients.iter().all(|c| (c - mean).abs() <= 0.02),
        "drape coefficients {coefficients:?}"
    );
}
