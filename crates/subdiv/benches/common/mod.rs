//! The benchmark mesh, shared by `benches/refine.rs` and the OpenSubdiv comparison
//! (`compare-osd`), so both time the same surface.

use tailor_subdiv::{Mesh, Point};

/// An `n` × `n` grid of quads over the unit square, gently waved so no weight is trivially zero.
#[must_use]
pub fn grid(n: usize) -> Mesh {
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            positions.push(Point::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()));
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let faces: Vec<[u32; 4]> = (0..n)
        .flat_map(|j| (0..n).map(move |i| [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]))
        .collect();
    Mesh::from_polygons(positions, &faces).expect("grid is valid")
}
