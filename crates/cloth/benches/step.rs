//! Milliseconds per frame (24 fps, the default two substeps) of the sphere drape: a 2 m square
//! sheet of n² vertices falling 0.5 m onto a sphere of radius 0.5 m, with self-collision off
//! and on, the same at Blender's five substeps a frame, and a curtain pinned at two corners
//! with no obstacle. The measured frames are mid-drape, with the sheet in contact. Run:
//! `cargo bench -p tailor-cloth --bench step`.

use tailor_cloth::shapes::{centred_sheet, sphere};
use tailor_cloth::{Material, Model, Motion, Settings, Simulator, State};
use tailor_subdiv::Point;

fn main() {
    divan::main();
}

/// The simulator after `warm` frames of `n`² sheet, set up by `setup`.
fn settled(
    n: u32,
    warm: u32,
    settings: Settings,
    setup: impl FnOnce(&mut Simulator),
) -> (Simulator, State) {
    let garment = centred_sheet(n, 2.0);
    let model = Model::new(&garment, &Material::COTTON).expect("valid sheet");
    let mut sim = Simulator::new(model, settings).expect("valid settings");
    setup(&mut sim);
    let mut state = State::at_rest(sim.model());
    for _ in 0..warm {
        sim.step(&mut state, 1.0 / 24.0).expect("stable");
    }
    (sim, state)
}

fn drape(n: u32, self_collision: bool, substeps: Option<u32>) -> (Simulator, State) {
    let defaults = Settings::default();
    let settings = Settings {
        self_collision,
        max_substep: substeps.map_or(defaults.max_substep, |s| 1.0 / (24.0 * f64::from(s))),
        ..defaults
    };
    // Contact begins at frame 8; measure from frame 16 on.
    settled(n, 16, settings, |sim| {
        let ball = sphere(Point::new(0.0, -1.0, 0.0), 0.5, 24, 48);
        sim.set_obstacle(ball.positions(), ball.face_offsets(), ball.face_vertices())
            .expect("valid sphere");
    })
}

#[divan::bench(args = [32, 64, 128], sample_count = 5, sample_size = 1)]
fn sphere_drape(bencher: divan::Bencher, n: u32) {
    let (mut sim, mut state) = drape(n, false, None);
    bencher.bench_local(|| sim.step(&mut state, 1.0 / 24.0).expect("stable"));
}

#[divan::bench(args = [32, 64, 128], sample_count = 5, sample_size = 1)]
fn sphere_drape_self_collision(bencher: divan::Bencher, n: u32) {
    let (mut sim, mut state) = drape(n, true, None);
    bencher.bench_local(|| sim.step(&mut state, 1.0 / 24.0).expect("stable"));
}

/// The drape at Blender's five substeps a frame, self-collision off and on.
#[divan::bench(args = [(64, false), (128, false), (64, true), (128, true)], sample_count = 5, sample_size = 1)]
fn sphere_drape_5_substeps(bencher: divan::Bencher, (n, self_collision): (u32, bool)) {
    let (mut sim, mut state) = drape(n, self_collision, Some(5));
    bencher.bench_local(|| sim.step(&mut state, 1.0 / 24.0).expect("stable"));
}

#[divan::bench(args = [32, 64, 128], sample_count = 5, sample_size = 1)]
fn curtain(bencher: divan::Bencher, n: u32) {
    let (mut sim, mut state) = settled(n, 3, Settings::default(), |sim| {
        sim.pin(&[0, n - 1], Motion::Fixed).expect("corners exist");
    });
    bencher.bench_local(|| sim.step(&mut state, 1.0 / 24.0).expect("stable"));
}
