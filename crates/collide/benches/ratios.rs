//! The same comparisons as the `hierarchy` benchmark, as ratios that survive a busy machine:
//! each of tailor's runs is followed at once by parry's on the same input, and each side keeps
//! its fastest run, so a burst of load elsewhere slows both or is forgotten. Prints one line
//! per operation and size: tailor's time, parry's, and parry's over tailor's (above 1 when
//! tailor is faster).
//!
//! Run with `cargo bench -p tailor-collide --bench ratios` (`TAILOR_BENCH_1M=1` adds 1M).

#[path = "../tests/common/mod.rs"]
mod common;
mod shapes;

use std::hint::black_box;
use std::time::Instant;

use parry3d_f64::partitioning::BvhWorkspace;
use parry3d_f64::query::PointQuery;
use rayon::prelude::*;
use shapes::{SHAPES, glam, parry, shape, sizes, tailor, waving_sheet};
use tailor_collide::Point;

/// The fastest of `runs` alternating runs of `ours` and `theirs`, in milliseconds.
fn fastest(runs: usize, mut ours: impl FnMut(), mut theirs: impl FnMut()) -> (f64, f64) {
    let time = |f: &mut dyn FnMut()| {
        let t = Instant::now();
        f();
        t.elapsed().as_secs_f64() * 1e3
    };
    (0..runs).fold((f64::MAX, f64::MAX), |(a, b), _| {
        (a.min(time(&mut ours)), b.min(time(&mut theirs)))
    })
}

fn report(what: &str, triangles: usize, (ours, theirs): (f64, f64)) {
    println!(
        "{what:24} {triangles:>8}  tailor {ours:10.3} ms  parry {theirs:10.3} ms  parry/tailor {:6.2}",
        theirs / ours
    );
}

fn main() {
    for triangles in sizes() {
        let runs = if triangles >= 1_000_000 { 5 } else { 20 };
        let (m, [f0, f1]) = waving_sheet(triangles);
        let build = fastest(
            runs.min(10),
            || drop(black_box(tailor(&m, &f0))),
            || drop(black_box(parry(&m, &f0))),
        );
        report("build", triangles, build);

        let (mut h, mut mesh) = (tailor(&m, &f0), parry(&m, &f0));
        let frames = [&f0, &f1];
        let glam_frames = [glam(&f0), glam(&f1)];
        let (mut i, mut j) = (0, 0);
        let refit = fastest(
            5 * runs,
            || {
                i ^= 1;
                h.refit(frames[i], 0.0).unwrap();
            },
            || {
                j ^= 1;
                mesh.set_vertices(&glam_frames[j]);
            },
        );
        report("refit", triangles, refit);

        h.refit(&f1, 0.0).unwrap();
        mesh.set_vertices(&glam_frames[1]);
        let queries: Vec<Point> = f1
            .iter()
            .map(|p| Point::new(p.x, p.y, p.z + 0.01))
            .collect();
        let glam_queries = glam(&queries);
        let proximity = fastest(
            runs,
            || drop(black_box(h.closest_points(&queries, 0.05).unwrap())),
            || {
                let projections: Vec<_> = glam_queries
                    .par_iter()
                    .map(|&p| mesh.project_local_point_with_max_dist(p, false, 0.05))
                    .collect();
                drop(black_box(projections));
            },
        );
        report("proximity", triangles, proximity);

        for name in SHAPES {
            let (m, [f0, f1]) = shape(name, triangles);
            let (mut h, mesh) = (tailor(&m, &f0), parry(&m, &f1));
            let mut workspace = BvhWorkspace::default();
            let mut traverse = || {
                let mut pairs = 0usize;
                mesh.bvh()
                    .traverse_bvtt_single_tree::<false>(&mut workspace, &mut |_, _| pairs += 1);
                black_box(pairs);
            };
            h.refit_swept(&f0, &f1, 0.0).unwrap();
            let impacts = fastest(runs, || drop(black_box(h.self_impacts())), &mut traverse);
            report(&format!("self impacts {name}"), triangles, impacts);
            h.refit(&f1, 0.0).unwrap();
            let crossings = fastest(
                runs,
                || drop(black_box(h.self_intersections())),
                &mut traverse,
            );
            report(&format!("self intersections {name}"), triangles, crossings);
        }
    }
}
