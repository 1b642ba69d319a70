//! The deforming meshes both benchmarks run on, built the same way for tailor and parry.

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use tailor_collide::{Hierarchy, Point};

use crate::common::{Mesh, bent_tube, sheet, wave};

/// Triangle counts to run: 10k and 100k, and 1M with `TAILOR_BENCH_1M` set.
pub fn sizes() -> Vec<usize> {
    let mut sizes = vec![10_000, 100_000];
    if std::env::var_os("TAILOR_BENCH_1M").is_some() {
        sizes.push(1_000_000);
    }
    sizes
}

/// A triangulated sheet of about `triangles` triangles and two wave frames a small step apart
/// (vertices move up to about 6 mm, as in one step of a fast motion).
pub fn waving_sheet(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let n = ((triangles / 2) as f64).sqrt().round() as u32;
    let m = sheet(n, |_, _| 0.0).triangulated();
    let frames = [0.0, 0.02].map(|t| m.mapped(|p| wave(p, t)));
    (m, frames)
}

/// A triangulated tube of about `triangles` triangles, straight and slightly bent.
pub fn bending_tube(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let k = ((triangles / 2) as f64 / 8.0).sqrt().round() as u32 * 2;
    let n = (triangles / (2 * k as usize)) as u32 + 1;
    let frames = [0.5, 0.503].map(|bend| bent_tube(n, k, 0.05, bend).positions);
    (bent_tube(n, k, 0.05, 0.5).triangulated(), frames)
}

/// A triangulated sheet of about `triangles` triangles rolled into a spiral of about two
/// turns, 2 cm between layers, and the roll tightening by 5% over the step (vertices move up to
/// about 3 mm): a surface the normal cones cannot clear whole, so the exact tests run along
/// every seam between the subtrees they do clear, as in a wrinkled or folded garment.
pub fn rolled_sheet(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let n = ((triangles / 2) as f64).sqrt().round() as u32;
    let m = sheet(n, |_, _| 0.0).triangulated();
    let roll = |gap: f64, turn: f64| {
        // Arc length along the spiral r = r0 + c θ is about r0 θ + c θ² / 2.
        let (r0, c) = (0.05, gap / std::f64::consts::TAU);
        m.mapped(move |p| {
            let theta = ((r0 * r0 + 2.0 * c * p.x).sqrt() - r0) / c;
            let r = r0 + c * theta;
            let (s, co) = (theta + turn).sin_cos();
            Point::new(r * co, p.y, r * s)
        })
    };
    let frames = [roll(0.02, 0.0), roll(0.019, 0.005)];
    (m, frames)
}

/// The deforming meshes benchmarked.
pub const SHAPES: [&str; 3] = ["sheet", "tube", "rolled"];

/// The mesh and frames of shape `name` at about `triangles` triangles.
pub fn shape(name: &str, triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    match name {
        "sheet" => waving_sheet(triangles),
        "tube" => bending_tube(triangles),
        _ => rolled_sheet(triangles),
    }
}

/// Positions as parry's glam vectors.
pub fn glam(points: &[Point]) -> Vec<DVec3> {
    points.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect()
}

/// The hierarchy of `m` at `positions`.
pub fn tailor(m: &Mesh, positions: &[Point]) -> Hierarchy {
    Hierarchy::build(positions, &m.offsets, &m.corners).unwrap()
}

/// Parry's deformable `TriMesh` of `m` (already triangulated) at `positions`.
pub fn parry(m: &Mesh, positions: &[Point]) -> TriMesh {
    let indices = m
        .corners
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    TriMesh::with_flags(glam(positions), indices, TriMeshFlags::DEFORMABLE).unwrap()
}

/// Parry's `Bvh` (binned build) over the boxes of the triangles of `m` (already triangulated)
/// around their corners in every one of `frames`, each loosened by `pad`: the boxes that a
/// self-query over that motion, within a distance of `2 pad`, must pair up. The swept boxes of
/// a step for continuous impacts, the end positions for intersections, and those loosened by
/// half the thickness for proximity, as tailor's traversal compares them.
pub fn parry_boxes(m: &Mesh, frames: &[&[Point]], pad: f64) -> Bvh {
    let frames: Vec<Vec<DVec3>> = frames.iter().map(|f| glam(f)).collect();
    let leaves: Vec<Aabb> = m
        .corners
        .chunks_exact(3)
        .map(|t| {
            let corners = frames.iter().flat_map(|f| t.iter().map(|&v| f[v as usize]));
            Aabb::from_points(corners).loosened(pad)
        })
        .collect();
    Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves)
}

/// The number of pairs of leaves of `bvh` whose boxes overlap: parry's sequential
/// self-traversal, with no test on the pairs.
pub fn parry_pairs(bvh: &Bvh, workspace: &mut BvhWorkspace) -> usize {
    let mut pairs = 0usize;
    bvh.traverse_bvtt_single_tree::<false>(workspace, &mut |_, _| pairs += 1);
    pairs
}
