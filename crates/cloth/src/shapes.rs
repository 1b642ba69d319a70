//! Simple garments and obstacles for tests, benchmarks and demos.

use tailor_subdiv::{Mesh, Point};

use crate::energy::Vec3;

/// A flat rectangular sheet of `columns × rows` vertices (at least 2 × 2) in the plane y = 0,
/// spanning `[0, width] × [0, depth]` in x and z, made of quads facing +y. Vertex `i + columns·j`
/// sits at x = i·width/(columns − 1), z = j·depth/(rows − 1).
///
/// # Panics
/// If `columns` or `rows` is below 2.
#[must_use]
pub fn sheet(columns: u32, rows: u32, width: f64, depth: f64) -> Mesh {
    assert!(
        columns >= 2 && rows >= 2,
        "a sheet needs at least 2 × 2 vertices"
    );
    let (dx, dz) = (width / f64::from(columns - 1), depth / f64::from(rows - 1));
    let positions = (0..rows)
        .flat_map(|j| {
            (0..columns).map(move |i| Point::new(f64::from(i) * dx, 0.0, f64::from(j) * dz))
        })
        .collect();
    let mut faces = Vec::with_capacity(((columns - 1) * (rows - 1)) as usize);
    for j in 0..rows - 1 {
        for i in 0..columns - 1 {
            let a = i + columns * j;
            faces.push([a, a + columns, a + columns + 1, a + 1]);
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a sheet is a valid mesh")
}

/// A square [`sheet`] of `n × n` vertices and side `side`, flat at y = 0 and centred over the
/// origin in x and z: the garment of issue 4's drape.
///
/// # Panics
/// If `n` is below 2.
#[must_use]
pub fn centred_sheet(n: u32, side: f64) -> Mesh {
    let mut mesh = sheet(n, n, side, side);
    let half = Vec3::new(0.5 * side, 0.0, 0.5 * side);
    let centred: Vec<Point> = mesh.positions().iter().map(|p| p - half).collect();
    mesh.set_positions(&centred).expect("same vertex count");
    mesh
}

/// A closed polygon sphere of `rings` latitude bands (at least 2) and `segments` longitude
/// bands (at least 3): quads, with triangle fans at the poles (on the y axis). Faces wind
/// counter-clockwise seen from outside, as an obstacle needs.
///
/// # Panics
/// If `rings < 2` or `segments < 3`.
#[must_use]
pub fn sphere(center: Point, radius: f64, rings: u32, segments: u32) -> Mesh {
    assert!(
        rings >= 2 && segments >= 3,
        "a sphere needs 2 rings and 3 segments"
    );
    let mut positions = vec![center + Vec3::y() * radius];
    for j in 1..rings {
        let polar = std::f64::consts::PI * f64::from(j) / f64::from(rings);
        for i in 0..segments {
            let azimuth = std::f64::consts::TAU * f64::from(i) / f64::from(segments);
            let direction = Vec3::new(
                polar.sin() * azimuth.cos(),
                polar.cos(),
                polar.sin() * azimuth.sin(),
            );
            positions.push(center + direction * radius);
        }
    }
    positions.push(center - Vec3::y() * radius);
    let bottom = positions.len() as u32 - 1;
    let ring = |j: u32, i: u32| 1 + (j - 1) * segments + i % segments;
    let mut faces = Vec::new();
    for i in 0..segments {
        faces.push(vec![0, ring(1, i), ring(1, i + 1)]);
        for j in 1..rings - 1 {
            faces.push(vec![
                ring(j, i),
                ring(j + 1, i),
                ring(j + 1, i + 1),
                ring(j, i + 1),
            ]);
        }
        faces.push(vec![ring(rings - 1, i), bottom, ring(rings - 1, i + 1)]);
    }
    outward(positions, faces, center)
}

/// A closed box (six quads) between corners `low` and `high`, faces winding counter-clockwise
/// seen from outside.
#[must_use]
pub fn block(low: Point, high: Point) -> Mesh {
    let corner = |k: u32| {
        let pick = |bit: u32, lo: f64, hi: f64| if k & bit == 0 { lo } else { hi };
        Point::new(
            pick(1, low.x, high.x),
            pick(2, low.y, high.y),
            pick(4, low.z, high.z),
        )
    };
    let positions = (0..8).map(corner).collect();
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ]
    .map(Vec::from)
    .to_vec();
    outward(positions, faces, nalgebra::center(&low, &high))
}

/// The mesh of a shape star-shaped around `center`, each face turned to wind
/// counter-clockwise seen from outside.
fn outward(positions: Vec<Point>, mut faces: Vec<Vec<u32>>, center: Point) -> Mesh {
    for face in &mut faces {
        let p = |k: usize| positions[face[k] as usize];
        let normal = (p(1) - p(0)).cross(&(p(2) - p(0)));
        if normal.dot(&(p(0) - center)) < 0.0 {
            face.reverse();
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a closed shape is a valid mesh")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_faces_point_up() {
        let mesh = sheet(3, 2, 2.0, 1.0);
        assert_eq!(mesh.vertex_count(), 6);
        assert_eq!(mesh.face_count(), 2);
        let p = mesh.positions();
        let f = mesh.face(1);
        let n = (p[f[1] as usize] - p[f[0] as usize]).cross(&(p[f[2] as usize] - p[f[1] as usize]));
        assert!(n.y > 0.0);
        assert_eq!(p[5], Point::new(2.0, 0.0, 1.0));
    }

    #[test]
    fn obstacles_are_closed_and_face_outwards() {
        for mesh in [
            sphere(Point::new(1.0, 2.0, 3.0), 0.5, 6, 8),
            block(Point::new(-1.0, 0.0, 0.0), Point::new(1.0, 0.5, 2.0)),
        ] {
            let h = tailor_collide::Hierarchy::build(
                mesh.positions(),
                mesh.face_offsets(),
                mesh.face_vertices(),
            )
            .unwrap();
            assert!(h.is_closed());
            let far = Point::new(10.0, 10.0, 10.0);
            let centroid = Point::from(
                mesh.positions().iter().map(|p| p.coords).sum::<Vec3>()
                    / mesh.vertex_count() as f64,
            );
            let d = h.signed_distances(&[far, centroid]).unwrap();
            assert!(d[0] > 0.0 && d[1] < 0.0, "{d:?}");
        }
    }
}
