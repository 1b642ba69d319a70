//! The same comparisons as the `hierarchy` benchmark, as ratios that survive a busy machine:
//! each of tailor's runs is followed at once by parry's on the same input, and each side keeps
//! its fastest run, so a burst of load elsewhere slows both or is forgotten. Prints one line
//! per operation and size: tailor's time, parry's, and parry's over tailor's (above 1 when
//! tailor is faster), and the hierarchy's heap bytes per face. Build, refit and proximity run
//! on the waving sheet and the bending tube; self-collision also on the rolling sheet and on
//! the folded drape (quads, as a refined cloth surface; parry gets their fan triangles),
//! whose self-proximity (every vertex against the faces within a cloth thickness, leaving out
//! the faces around it in the rest shape as the cloth's repulsion does) is timed too. First of
//! all, `proximity draped sphere` times the closest points of a body (a UV sphere) to a sheet
//! of points draped over it, within a cloth thickness.
//!
//! The parry side of every self-collision line is its sequential `Bvh` self-traversal
//! (overlapping leaf pairs only, no exact test) over the boxes tailor's query has to pair:
//! each triangle's box swept over the step for the impacts, at the end of the step for the
//! intersections, and loosened by half the thickness for the proximity (two boxes overlap
//! then exactly when they come within the thickness). Tailor answers the full question, exact
//! tests included, on the rayon pool; `RAYON_NUM_THREADS=1` times it on one thread.
//!
//! Run with `cargo bench -p tailor-collide --bench ratios` (`TAILOR_BENCH_1M=1` adds 1M); an
//! argument after `--` runs only the operations whose name contains it.

#[path = "../tests/common/mod.rs"]
mod common;
mod shapes;

use std::hint::black_box;
use std::time::Instant;

use common::Mesh;
use parry3d_f64::partitioning::BvhWorkspace;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::TriMesh;
use rayon::prelude::*;
use shapes::{
    SHAPES, draped_points, glam, parry, parry_boxes, parry_pairs, shape, sizes, tailor, uv_sphere,
};
use tailor_collide::{Hierarchy, Point};

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

/// Whether the operation named `what` is to run: every one, or those whose name contains the
/// first argument that is not a flag (`cargo bench --bench ratios -- "self impacts"`).
fn wanted(what: &str) -> bool {
    std::env::args()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .is_none_or(|filter| what.contains(&filter))
}

/// Times `ours` against `theirs` (see [`fastest`]) when `what` is wanted, and prints a line.
fn measure(what: &str, triangles: usize, runs: usize, ours: impl FnMut(), theirs: impl FnMut()) {
    if !wanted(what) {
        return;
    }
    let (ours, theirs) = fastest(runs, ours, theirs);
    println!(
        "{what:26} {triangles:>8}  tailor {ours:10.3} ms  parry {theirs:10.3} ms  parry/tailor {:6.2}",
        theirs / ours
    );
}

fn main() {
    draped_on_sphere();
    for triangles in sizes() {
        let runs = if triangles >= 1_000_000 { 5 } else { 20 };
        for name in SHAPES {
            let (m, [f0, f1]) = shape(name, triangles);
            let (mut h, mut mesh) = (tailor(&m, &f0), parry(&m, &f0));
            if wanted("memory") {
                println!(
                    "memory {name:19} {:>8}  tailor {:10.1} bytes per face",
                    h.face_count(),
                    h.memory_bytes() as f64 / h.face_count() as f64
                );
            }
            if matches!(name, "sheet" | "tube") {
                static_queries(name, triangles, runs, &m, [&f0, &f1], &mut h, &mut mesh);
            }
            let mut workspace = BvhWorkspace::default();
            let swept = parry_boxes(&m, &[&f0, &f1], 0.0);
            h.refit_swept(&f0, &f1, 0.0).unwrap();
            measure(
                &format!("self impacts {name}"),
                triangles,
                runs,
                || drop(black_box(h.self_impacts())),
                || {
                    black_box(parry_pairs(&swept, &mut workspace));
                },
            );
            let end = parry_boxes(&m, &[&f1], 0.0);
            h.refit(&f1, 0.0).unwrap();
            measure(
                &format!("self intersections {name}"),
                triangles,
                runs,
                || drop(black_box(h.self_intersections())),
                || {
                    black_box(parry_pairs(&end, &mut workspace));
                },
            );
            if matches!(name, "rolled" | "folded") && wanted("self proximity") {
                let local = tailor(&m, &m.positions)
                    .local_faces(REST_MARGIN * THICKNESS)
                    .unwrap();
                let near = parry_boxes(&m, &[&f1], THICKNESS / 2.0);
                measure(
                    &format!("self proximity {name}"),
                    triangles,
                    runs,
                    || drop(black_box(h.self_proximity(THICKNESS, &local).unwrap())),
                    || {
                        black_box(parry_pairs(&near, &mut workspace));
                    },
                );
            }
        }
    }
}

/// The closest point of a body to every point of a cloth draped over it, within a cloth
/// thickness: a UV sphere of 1106 vertices (1056 quads, 96 triangles, 30 cm radius) under a
/// 128 × 128 sheet of points, the middle resting 0 to 50 mm off the sphere and the rest
/// hanging far from it, as a refined cloth surface in a drape.
fn draped_on_sphere() {
    let what = "proximity draped sphere";
    if !wanted(what) {
        return;
    }
    let body = uv_sphere(23, 48, 0.3);
    let (h, mesh) = (
        tailor(&body, &body.positions),
        parry(&body, &body.positions),
    );
    let queries = draped_points(128, 0.3);
    let glam_queries = glam(&queries);
    measure(
        what,
        mesh.indices().len(),
        200,
        || drop(black_box(h.closest_points(&queries, THICKNESS).unwrap())),
        || {
            let projections: Vec<_> = glam_queries
                .par_iter()
                .map(|&p| mesh.project_local_point_with_max_dist(p, false, THICKNESS))
                .collect();
            drop(black_box(projections));
        },
    );
}

/// Cloth thickness for self-proximity, in metres.
const THICKNESS: f64 = 0.005;

/// Within how many thicknesses of each other in the rest shape (the flat sheet) a vertex and a
/// face are left out of self-proximity ([`Hierarchy::local_faces`]), as the cloth's repulsion
/// leaves them.
const REST_MARGIN: f64 = 1.5;

/// Build, refit and proximity of every vertex (a point 1 cm above it, within 5 cm) on one
/// deforming mesh.
fn static_queries(
    name: &str,
    triangles: usize,
    runs: usize,
    m: &Mesh,
    frames: [&Vec<Point>; 2],
    h: &mut Hierarchy,
    mesh: &mut TriMesh,
) {
    let [f0, f1] = frames;
    measure(
        &format!("build {name}"),
        triangles,
        runs.min(10),
        || drop(black_box(tailor(m, f0))),
        || drop(black_box(parry(m, f0))),
    );
    let glam_frames = [glam(f0), glam(f1)];
    let (mut i, mut j) = (0, 0);
    measure(
        &format!("refit {name}"),
        triangles,
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
    h.refit(f1, 0.0).unwrap();
    mesh.set_vertices(&glam_frames[1]);
    let queries: Vec<Point> = f1
        .iter()
        .map(|p| Point::new(p.x, p.y, p.z + 0.01))
        .collect();
    let glam_queries = glam(&queries);
    measure(
        &format!("proximity {name}"),
        triangles,
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
}
