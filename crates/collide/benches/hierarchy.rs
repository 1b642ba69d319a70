//! Build, refit, proximity and self-collision on deforming meshes (a waving sheet, a bending
//! tube) of 10k and 100k triangles (1M with `TAILOR_BENCH_1M=1`), against parry's `TriMesh`
//! with `TriMeshFlags::DEFORMABLE` (refit through `set_vertices`, point projection) and parry's
//! `Bvh` self-traversal, in the same run. Both sides get the same triangles.
//!
//! Run with `cargo bench -p tailor-collide --bench hierarchy`.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Mesh, bent_tube, sheet, wave};
use divan::Bencher;
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::partitioning::BvhWorkspace;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use rayon::prelude::*;
use tailor_collide::{Hierarchy, Point};

fn main() {
    divan::main();
}

/// Triangle counts to run.
fn sizes() -> Vec<usize> {
    let mut sizes = vec![10_000, 100_000];
    if std::env::var_os("TAILOR_BENCH_1M").is_some() {
        sizes.push(1_000_000);
    }
    sizes
}

/// A triangulated sheet of about `triangles` triangles and two wave frames a small step apart
/// (vertices move up to about 6 mm, as in one step of a fast motion).
fn waving_sheet(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let n = ((triangles / 2) as f64).sqrt().round() as u32;
    let m = sheet(n, |_, _| 0.0).triangulated();
    let frames = [0.0, 0.02].map(|t| m.mapped(|p| wave(p, t)));
    (m, frames)
}

/// A triangulated tube of about `triangles` triangles, straight and slightly bent.
fn bending_tube(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let k = ((triangles / 2) as f64 / 8.0).sqrt().round() as u32 * 2;
    let n = (triangles / (2 * k as usize)) as u32 + 1;
    let frames = [0.5, 0.503].map(|bend| bent_tube(n, k, 0.05, bend).positions);
    (bent_tube(n, k, 0.05, 0.5).triangulated(), frames)
}

const SHAPES: [&str; 2] = ["sheet", "tube"];

fn shape(name: &str, triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    if name == "sheet" {
        waving_sheet(triangles)
    } else {
        bending_tube(triangles)
    }
}

fn glam(points: &[Point]) -> Vec<DVec3> {
    points.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect()
}

fn tailor(m: &Mesh, positions: &[Point]) -> Hierarchy {
    Hierarchy::build(positions, &m.offsets, &m.corners).unwrap()
}

fn parry(m: &Mesh, positions: &[Point]) -> TriMesh {
    let indices = m
        .corners
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    TriMesh::with_flags(glam(positions), indices, TriMeshFlags::DEFORMABLE).unwrap()
}

#[divan::bench_group]
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

#[divan::bench_group]
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
#[divan::bench_group]
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

/// Self-collision of the deforming mesh: tailor's normal-cone-culled self-intersection test
/// (exact triangle tests included) and continuous self-impacts over the step, against parry's
/// `Bvh` self-traversal (overlapping leaf pairs only, no exact test).
#[divan::bench_group(sample_count = 20)]
mod self_collision {
    use super::*;

    #[divan::bench(args = sizes(), consts = [0, 1])]
    fn tailor_self_intersections<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let h = tailor(&m, &frames[1]);
        bencher.bench(|| h.self_intersections());
    }

    #[divan::bench(args = sizes(), consts = [0, 1])]
    fn tailor_self_impacts<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let mut h = tailor(&m, &frames[0]);
        h.refit_swept(&frames[0], &frames[1], 0.0).unwrap();
        bencher.bench(|| h.self_impacts());
    }

    #[divan::bench(args = sizes(), consts = [0, 1])]
    fn parry_bvh_self_traversal<const SHAPE: usize>(bencher: Bencher, triangles: usize) {
        let (m, frames) = shape(SHAPES[SHAPE], triangles);
        let mesh = parry(&m, &frames[1]);
        let mut workspace = BvhWorkspace::default();
        bencher.bench_local(|| {
            let mut pairs = 0usize;
            mesh.bvh()
                .traverse_bvtt_single_tree::<false>(&mut workspace, &mut |_, _| pairs += 1);
            pairs
        });
    }
}
