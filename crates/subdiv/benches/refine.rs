//! Subdivision benchmarks on square grids of 10k and 100k quads at levels 1 to 3:
//! topology refinement (every level complete, and with the minimal last level that evaluation
//! needs), refinement of positions (minimal topology plus positions), stencil table
//! construction, and applying a stencil table to new positions (the per-frame cost of a cloth
//! simulation) against the [`Evaluator`] (regular faces as B-spline patches)
//! that replaces it, and the floor under both (writing as many points). `compare-osd/` times
//! the same cases against OpenSubdiv itself. Throughput is in refined faces per second; the
//! allocation profiler's "max alloc" row is the peak memory a run holds.
//!
//! `cargo bench -p tailor-subdiv --bench refine` (set `RAYON_NUM_THREADS=1` for one thread).
//! The 100k-quad level-3 cases need several GB and are skipped unless `TAILOR_BENCH_LARGE` is set.

use common::grid;
use divan::counter::ItemsCount;
use divan::{AllocProfiler, Bencher, black_box};
use rayon::prelude::*;
use tailor_subdiv::{Evaluator, Mesh, Point, Refiner};

mod common;

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

/// (grid side, level): 100² = 10k quads and 316² ≈ 100k quads.
fn cases() -> Vec<(usize, usize)> {
    let large = std::env::var_os("TAILOR_BENCH_LARGE").is_some();
    [(100, 1), (100, 2), (100, 3), (316, 1), (316, 2), (316, 3)]
        .into_iter()
        .filter(|&(side, level)| large || side < 300 || level < 3)
        .collect()
}

/// Times `build` (a way of making a [`Refiner`]) on the grid.
fn bench_topology(bencher: Bencher, side: usize, level: usize, build: fn(&Mesh, usize) -> Refiner) {
    let mesh = grid(side);
    bencher
        .counter(refined_faces(side, level))
        .bench(|| black_box(build(&mesh, level)));
}

#[divan::bench(args = cases(), sample_count = 5)]
fn topology(bencher: Bencher, &(side, level): &(usize, usize)) {
    bench_topology(bencher, side, level, Refiner::new);
}

#[divan::bench(args = cases(), sample_count = 5)]
fn topology_for_evaluation(bencher: Bencher, &(side, level): &(usize, usize)) {
    bench_topology(bencher, side, level, Refiner::for_evaluation);
}

#[divan::bench(args = cases(), sample_count = 5)]
fn topology_and_positions(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    bencher.counter(refined_faces(side, level)).bench(|| {
        let refiner = Refiner::for_evaluation(&mesh, level);
        black_box(refiner.refine(mesh.positions()))
    });
}

#[divan::bench(args = cases(), sample_count = 5)]
fn stencil_build(bencher: Bencher, &(side, level): &(usize, usize)) {
    let refiner = Refiner::for_evaluation(&grid(side), level);
    bencher.bench(|| black_box(refiner.stencils()));
}

#[divan::bench(args = cases(), sample_count = 10)]
fn stencil_apply(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    let stencils = Refiner::new(&mesh, level).stencils();
    let mut out = vec![Point::origin(); stencils.len()];
    bencher
        .counter(refined_faces(side, level))
        .bench_local(|| stencils.apply(black_box(mesh.positions()), &mut out));
}

#[divan::bench(args = cases(), sample_count = 10)]
fn evaluator_build(bencher: Bencher, &(side, level): &(usize, usize)) {
    let refiner = Refiner::for_evaluation(&grid(side), level);
    bencher.bench(|| black_box(Evaluator::new(&refiner)));
}

#[divan::bench(args = cases(), sample_count = 10)]
fn evaluator_apply(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    let evaluator = Evaluator::new(&Refiner::for_evaluation(&mesh, level));
    let mut out = vec![Point::origin(); evaluator.len()];
    bencher
        .counter(refined_faces(side, level))
        .bench_local(|| evaluator.apply(black_box(mesh.positions()), &mut out));
}

/// The floor under `evaluator_apply`: writing as many points, a constant in parallel chunks.
#[divan::bench(args = cases(), sample_count = 10)]
fn write_floor(bencher: Bencher, &(side, level): &(usize, usize)) {
    let points = Evaluator::new(&Refiner::for_evaluation(&grid(side), level)).len();
    let mut out = vec![Point::origin(); points];
    bencher.counter(refined_faces(side, level)).bench_local(|| {
        let value = black_box(Point::new(1.0, 2.0, 3.0));
        out.par_chunks_mut(4096).for_each(|chunk| chunk.fill(value));
    });
}

#[divan::bench(args = cases(), sample_count = 10)]
fn level_by_level_apply(bencher: Bencher, &(side, level): &(usize, usize)) {
    let mesh = grid(side);
    let refiner = Refiner::new(&mesh, level);
    bencher.bench_local(|| black_box(refiner.refine(black_box(mesh.positions()))));
}
