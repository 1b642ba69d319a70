//! The deforming meshes both benchmarks run on, built the same way for tailor and parry.

use parry3d_f64::math::Vector as DVec3;
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

/// The deforming meshes benchmarked.
pub const SHAPES: [&str; 2] = ["sheet", "tube"];

/// The mesh and frames of shape `name` at about `triangles` triangles.
pub fn shape(name: &str, triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    if name == "sheet" {
        waving_sheet(triangles)
    } else {
        bending_tube(triangles)
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
