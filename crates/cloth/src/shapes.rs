//! Simple garments for tests, benchmarks and demos.

use tailor_subdiv::{Mesh, Point};

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
}
