//! What several cloth test files share.

#![allow(dead_code)] // Each test file uses what it needs.

use tailor_cloth::{Material, Model, Settings, Simulator, State, Vec3};
use tailor_subdiv::Mesh;

/// One frame at 24 fps, s.
pub const FRAME: f64 = 1.0 / 24.0;

/// A simulator of `garment` made of `material`, stepping with `settings`, and the garment at
/// rest.
pub fn simulator(garment: &Mesh, material: &Material, settings: Settings) -> (Simulator, State) {
    let model = Model::new(garment, material).unwrap();
    let sim = Simulator::new(model, settings).unwrap();
    let state = State::at_rest(sim.model());
    (sim, state)
}

/// Makes `body`, resting at its positions, the obstacle of `sim`.
pub fn set_obstacle(sim: &mut Simulator, body: &Mesh) {
    sim.set_obstacle(body.positions(), body.face_offsets(), body.face_vertices())
        .unwrap();
}

/// `mesh` moved by `offset`.
pub fn moved(mesh: &Mesh, offset: Vec3) -> Mesh {
    let mut moved = mesh.clone();
    let positions: Vec<_> = mesh.positions().iter().map(|p| p + offset).collect();
    moved.set_positions(&positions).unwrap();
    moved
}

/// The largest distance between the vertices of two states.
pub fn farthest(a: &State, b: &State) -> f64 {
    a.positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}
