//! Milliseconds per frame (24 fps, 5 substeps) of a 2 m square sheet pinned at two corners,
//! falling from horizontal; no collisions yet. Run:
//! `cargo bench -p tailor-cloth --bench step`.

use tailor_cloth::shapes::sheet;
use tailor_cloth::{Material, Model, Motion, Settings, Simulator, State};

fn main() {
    divan::main();
}

/// The sheet settled for `warm` frames, so the measured frames are mid-drape.
fn curtain(n: u32, warm: u32) -> (Simulator, State) {
    let model = Model::new(&sheet(n, n, 2.0, 2.0), &Material::COTTON).expect("valid sheet");
    let mut sim = Simulator::new(model, Settings::default()).expect("valid settings");
    sim.pin(&[0, n - 1], Motion::Fixed).expect("corners exist");
    let mut state = State::at_rest(sim.model());
    for _ in 0..warm {
        sim.step(&mut state, 1.0 / 24.0).expect("stable");
    }
    (sim, state)
}

#[divan::bench(args = [32, 64, 128], sample_count = 5, sample_size = 1)]
fn frame(bencher: divan::Bencher, n: u32) {
    let (mut sim, mut state) = curtain(n, 3);
    bencher.bench_local(|| sim.step(&mut state, 1.0 / 24.0).expect("stable"));
}
