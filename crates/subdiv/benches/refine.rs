//! Subdivision benchmarks on square grids of 10k and 100k quads at levels 1 to 3:
//! topology refinement (all levels' tables and weights), full refinement (topology plus
//! positions), stencil table construction, and applying a stencil table to new positions
//! (the per-frame cost of a cloth simulation). Throughput is in refined faces per second; the
//! allocation profiler's "max alloc" row is the peak memory a run holds.
//!
//! `cargo bench -p tailor-subdiv --bench refine` (set `RAYON_NUM_THREADS=1` for one thread).
//! The 100k-quad level-3 cases need several GB and are skipped unless `TAILOR_BENCH_LARGE` is set.

use divan::counter::ItemsCount;
use divan::{AllocProfiler, Bencher, black_box};
use tailor_subdiv::{Mesh, Point, Refiner};

/// Reports allocations per benchmark, including the peak ("max alloc") held at once.
#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();

fn main() {
    divan::main();
}

/// Refined faces, for a faces/second throughput column.
fn refined_faces(side: usize, level: usize) -> ItemsCount {
    ItemsCount::new(side * side * 4usize.pow(level as u32))
}

fn grid(n: usize) -> Mesh {
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            positions.push(Point::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()));
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let faces: Vec<[u32; 4]> = (0..n)
        .flat_map(|j| (0..n).map(move |i| [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]))
        .collect();
    Mesh::from_polygons(positions, &faces).expect("grid is valid")
}

/// (grid side, level): 100² = 10k quads and 316² ≈ 100k quads.
fn cases() -> Vec<(usize, usize)> {
    let large = std::env::var_os("TAILOR_BENCH_LARGE").is_some();
    [(100, 1), (100, 2), (100, 3), (316, 1), (316, 2), (316, 3)]
        .into_iter()
        .filter(|&(side, level)| large || side < 300 || level < 3)
        .collect()
}

#[divan::bench(args = cases(), sample_count = 5)]
fn topology(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    bencher
        .counter(refined_faces(side, level))
        .bench(|| black_box(Refiner::new(&mesh, level)));
}

#[divan::bench(args = cases(), sample_count = 5)]
fn topology_and_positions(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    bencher.counter(refined_faces(side, level)).bench(|| {
        let refiner = Refiner::new(&mesh, level);
        black_box(refiner.refine(mesh.positions()))
    });
}

#[divan::bench(args = cases(), sample_count = 5)]
fn stencil_build(bencher: Bencher, &(side, level): &(usize, usize)) {
    let refiner = Refiner::new(&grid(side), level);
    bencher.bench(|| black_box(refiner.stencils()));
}

#[divan::bench(args = cases(), sample_count = 10)]
fn stencil_apply(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    let stencils = Refiner::new(&mesh, level).stencils();
    let mut out = vec![Point::origin(); stencils.len()];
    bencher.bench_local(|| stencils.apply(black_box(mesh.positions()), &mut out));
}

#[divan::bench(args = cases(), sample_count = 10)]
fn level_by_level_apply(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    let refiner = Refiner::new(&mesh, level);
    bencher.bench_local(|| black_box(refiner.refine(black_box(mesh.positions()))));
}
