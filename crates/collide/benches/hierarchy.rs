//! Build, refit, proximity and self-collision on deforming meshes (a waving sheet, a bending
//! tube; self-collision also on a sheet rolling up and on a folded, wrinkled drape of quads)
//! of 10k and 100k triangles (1M with `TAILOR_BENCH_1M=1`), against parry's `TriMesh`
//! with `TriMeshFlags::DEFORMABLE` (refit through `set_vertices`, point projection) and parry's
//! `Bvh` self-traversal, in the same run. Both sides get the same triangles. Before the timings
//! it prints the hierarchy's heap bytes per face at each size. Proximity also runs on a sheet
//! of points draped over a sphere, the body of a drape.
//!
//! Every benchmark stops after [`MAX_TIME`] seconds even if it has fewer samples than asked:
//! the 10k and 100k sizes always get their full count, the 1M size fewer.
//!
//! Run with `cargo bench -p tailor-collide --bench hierarchy`.

#[path = "../tests/common/mod.rs"]
mod common;
mod shapes;

use divan::Bencher;
use parry3d_f64::partitioning::BvhWorkspace;
use parry3d_f64::query::PointQuery;
use rayon::prelude::*;
use shapes::{
    SHAPES, draped_points, glam, parry, parry_boxes, parry_pairs, shape, sizes, tailor, uv_sphere,
    waving_sheet,
};
use tailor_collide::Point;

/// Seconds after which a benchmark stops sampling.
const MAX_TIME: u64 = 15;

fn main() {
    for name in SHAPES {
        for triangles in sizes() {
            let (m, frames) = shape(name, triangles);
            let h = tailor(&m, &frames[0]);
            let bytes = h.memory_bytes();
            println!(
                "memory {name:5} {:>8} triangles: {:>6.1} MB, {:>5.1} bytes per face",
                h.face_count(),
                bytes as f64 / 1e6,
                bytes as f64 / h.face_count() as f64
            );
        }
    }
    divan::main();
}

#[divan::bench_group(max_time = MAX_TIME)]
mod build {
    use super::*;

    #[divan::bench(args = sizes())]
    fn tailor_hierarchy(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        bencher.bench(|| tailor(&m, &frames[0]));
    }

    #[divan::bench(args = sizes())]
    fn parry_trimesh(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        bencher.bench(|| parry(&m, &frames[0]));
    }
}

#[divan::bench_group(max_time = MAX_TIME)]
mod refit {
    use super::*;

    #[divan::bench(args = sizes())]
    fn tailor_hierarchy(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        let mut h = tailor(&m, &frames[0]);
        let mut i = 0;
        bencher.bench_local(|| {
            i ^= 1;
            h.refit(&frames[i], 0.0).unwrap();
        });
    }

    #[divan::bench(args = sizes())]
    fn parry_set_vertices(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        let frames = [glam(&frames[0]), glam(&frames[1])];
        let mut mesh = parry(&m, &m.positions);
        let mut i = 0;
        bencher.bench_local(|| {
            i ^= 1;
            mesh.set_vertices(&frames[i]);
        });
    }
}

/// Every vertex of a second sheet hovering 1 cm above, within 5 cm.
#[divan::bench_group(max_time = MAX_TIME)]
mod proximity {
    use super::*;

    fn queries(frame: &[Point]) -> Vec<Point> {
        frame
            .iter()
            .map(|p| Point::new(p.x, p.y, p.z + 0.01))
            .collect()
    }

    #[divan::bench(args = sizes())]
    fn tailor_closest_points(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        let h = tailor(&m, &frames[1]);
        let q = queries(&frames[1]);
        bencher.bench(|| h.closest_points(&q, 0.05).unwrap());
    }

    #[divan::bench(args = sizes())]
    fn parry_project_point(bencher: Bencher, triangles: usize) {
        let (m, frames) = waving_sheet(triangles);
        let mesh = parry(&m, &frames[1]);
        let q = glam(&queries(&frames[1]));
        bencher.bench(|| {
            q.par_iter()
                .map(|&p| mesh.project_local_point_with_max_dist(p, false, 0.05))
                .collect::<Vec<_>>()
        });
    }
}

/// The points of a 128 × 128 sheet draped over a UV sphere of 1106 vertices (resting 0 to
/// 50 mm off it in the middle, hanging far from it elsewhere), within a cloth thickness (5 mm).
#[divan::bench_group(max_time = MAX_TIME)]
mod draped {
    use super::*;

    #[divan::bench]
    fn tailor_closest_points(bencher: Bencher) {
        let body = uv_sphere(23, 48, 0.3);
        let h = tailor(&body, &body.positions);
        let q = draped_points(128, 0.3);
        bencher.bench(|| h.closest_points(&q, 0.005).unwrap());
    }

    #[divan::bench]
    fn parry_project_point(bencher: Bencher) {
        let body = uv_sphere(23, 48, 0.3);
        let mesh = parry(&body, &body.positions);
        let q = glam(&draped_points(128, 0.3));
        bencher.bench(|| {
            q.par_iter()
                .map(|&p| mesh.project_local_point_with_max_dist(p, false, 0.005))
                .collect::<Vec<_>>()
        });
    }
}

/// Self-collision of the deforming mesh: tailor's normal-cone-culled self-intersection test
/// (exact triangle tests included) and continuous self-impacts over the step, against parry's
/// `Bvh` self-traversal (overlapping leaf pairs only, no exact test).
#[divan::bench_group(sample_count = 20, max_time = MAX_TIME)]
mod self_collision {
    use super::*;

    #[divan::bench(args = sizes(), consts = [0, 1, 2, 3])]
    fn tailor_self_intersections<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let h = tailor(&m, &frames[1]);
        bencher.bench(|| h.self_intersections());
    }

    #[divan::bench(args = sizes(), consts = [0, 1, 2, 3])]
    fn tailor_self_impacts<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let mut h = tailor(&m, &frames[0]);
        h.refit_swept(&frames[0], &frames[1], 0.0).unwrap();
        bencher.bench(|| h.self_impacts());
    }

    /// Over the boxes at the end of the step, the ones the intersections pair.
    #[divan::bench(args = sizes(), consts = [0, 1, 2, 3])]
    fn parry_bvh_self_traversal<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let bvh = parry_boxes(&m, &[&frames[1]], 0.0);
        let mut workspace = BvhWorkspace::default();
        bencher.bench_local(|| parry_pairs(&bvh, &mut workspace));
    }

    /// Over the boxes swept over the step, the ones the impacts pair.
    #[divan::bench(args = sizes(), consts = [0, 1, 2, 3])]
    fn parry_bvh_swept_self_traversal<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let bvh = parry_boxes(&m, &[&frames[0], &frames[1]], 0.0);
        let mut workspace = BvhWorkspace::default();
        bencher.bench_local(|| parry_pairs(&bvh, &mut workspace));
    }
}
