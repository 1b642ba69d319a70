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

/// A sheet of quads (left as quads, as a Catmull-Clark refined cloth surface is) of about
/// `triangles` fan triangles, draped in folds: folded back over itself round a hinge, 4 cm
/// between the layers, and both layers wrinkled by ripples of three wavelengths and
/// directions (slopes up to about 40°). Over the step the ripples drift and the fold closes
/// by 5% (vertices move up to about 2 mm). The normal cones clear only patches a few ripples
/// wide, and the exact tests run along the seams between them, as on a draped garment.
pub fn folded_drape(triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    let n = ((triangles / 2) as f64).sqrt().round() as u32;
    let m = sheet(n, |_, _| 0.0);
    // Wave vectors (rad/m), amplitudes (m) and phases of the ripples.
    let ripples = [
        (125.0, 30.0, 0.003, 0.0),
        (-40.0, 75.0, 0.003, 1.0),
        (25.0, -45.0, 0.003, 2.0),
    ];
    let drape = |gap: f64, drift: f64| {
        m.mapped(move |p| {
            let w: f64 = ripples
                .iter()
                .map(|&(kx, ky, a, phase)| a * (kx * p.x + ky * p.y + phase + drift).sin())
                .sum();
            // Lower layer up to the hinge, a half circle of diameter `gap`, the upper layer
            // back over the lower; the ripples displace each layer along its normal.
            let (r, hinge) = (gap / 2.0, 0.45);
            let arc = std::f64::consts::PI * r;
            if p.x <= hinge {
                Point::new(p.x, p.y, w)
            } else if p.x <= hinge + arc {
                let (s, c) = ((p.x - hinge) / r).sin_cos();
                Point::new(hinge + (r - w) * s, p.y, r - (r - w) * c)
            } else {
                Point::new(hinge - (p.x - hinge - arc), p.y, gap - w)
            }
        })
    };
    let frames = [drape(0.04, 0.0), drape(0.038, 0.3)];
    (m, frames)
}

/// The deforming meshes benchmarked.
pub const SHAPES: [&str; 4] = ["sheet", "tube", "rolled", "folded"];

/// The mesh and frames of shape `name` at about `triangles` triangles.
pub fn shape(name: &str, triangles: usize) -> (Mesh, [Vec<Point>; 2]) {
    match name {
        "sheet" => waving_sheet(triangles),
        "tube" => bending_tube(triangles),
        "rolled" => rolled_sheet(triangles),
        _ => folded_drape(triangles),
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

/// Parry's deformable `TriMesh` of the fan triangles of `m` at `positions`.
pub fn parry(m: &Mesh, positions: &[Point]) -> TriMesh {
    let indices = m.triangles().into_iter().map(|(t, _)| t).collect();
    TriMesh::with_flags(glam(positions), indices, TriMeshFlags::DEFORMABLE).unwrap()
}

/// Parry's `Bvh` (binned build) over the boxes of the fan triangles of `m` around their corners in every one of `frames`, each loosened by `pad`: the boxes that a
/// self-query over that motion, within a distance of `2 pad`, must pair up. The swept boxes of
/// a step for continuous impacts, the end positions for intersections, and those loosened by
/// half the thickness for proximity, as tailor's traversal compares them.
pub fn parry_boxes(m: &Mesh, frames: &[&[Point]], pad: f64) -> Bvh {
    let frames: Vec<Vec<DVec3>> = frames.iter().map(|f| glam(f)).collect();
    let leaves: Vec<Aabb> = m
        .triangles()
        .into_iter()
        .map(|(t, _)| {
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

/// A UV sphere of radius `r` as a body is exported: quads between `rings` latitude rings of
/// `segments` vertices, and a fan of triangles to a vertex at each pole (23 rings of 48 give
/// 1106 vertices, 1056 quads and 96 triangles).
pub fn uv_sphere(rings: u32, segments: u32, r: f64) -> Mesh {
    let mut positions = vec![Point::new(0.0, 0.0, r)];
    for j in 0..rings {
        let phi = std::f64::consts::PI * (j as f64 + 1.0) / (rings as f64 + 1.0);
        for i in 0..segments {
            let theta = std::f64::consts::TAU * i as f64 / segments as f64;
            positions.push(Point::new(
                r * phi.sin() * theta.cos(),
                r * phi.sin() * theta.sin(),
                r * phi.cos(),
            ));
        }
    }
    let south = positions.len() as u32;
    positions.push(Point::new(0.0, 0.0, -r));
    let at = |j: u32, i: u32| 1 + j * segments + i % segments;
    let mut faces: Vec<Vec<u32>> = (0..segments)
        .map(|i| vec![0, at(0, i), at(0, i + 1)])
        .collect();
    for j in 0..rings - 1 {
        for i in 0..segments {
            faces.push(vec![at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1)]);
        }
    }
    faces.extend((0..segments).map(|i| vec![south, at(rings - 1, i + 1), at(rings - 1, i)]));
    let mut offsets = vec![0];
    let mut corners = Vec::new();
    for f in faces {
        corners.extend(f);
        offsets.push(corners.len() as u32);
    }
    Mesh {
        positions,
        offsets,
        corners,
    }
}

/// The points of an `n × n` sheet, 2 m square, draped over a sphere of radius `r` centred
/// under its middle: the middle lies on the sphere, each point lifted off it by 0 to 50 mm
/// (mostly a few millimetres: the lift is 50 mm times the cube of a pseudo-random fraction),
/// and the rest hangs straight down from the equator at the same lift, most of it far below.
pub fn draped_points(n: u32, r: f64) -> Vec<Point> {
    let mut points = Vec::with_capacity((n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (
                2.0 * i as f64 / (n - 1) as f64 - 1.0,
                2.0 * j as f64 / (n - 1) as f64 - 1.0,
            );
            let hash = ((i as f64 * 12.9898 + j as f64 * 78.233).sin() * 43_758.545).fract();
            let lift = 0.05 * hash.abs().powi(3);
            let (s, angle) = ((x * x + y * y).sqrt(), (y.atan2(x)));
            let (sin, cos) = angle.sin_cos();
            let polar = s / r;
            let p = if polar <= std::f64::consts::FRAC_PI_2 {
                let (ps, pc) = polar.sin_cos();
                let h = r + lift;
                Point::new(h * ps * cos, h * ps * sin, h * pc)
            } else {
                let h = r + lift;
                Point::new(h * cos, h * sin, -(s - r * std::f64::consts::FRAC_PI_2))
            };
            points.push(p);
        }
    }
    points
}
