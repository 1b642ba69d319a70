//! What several test files build: grids of quads.

#![allow(dead_code)] // Each test file uses what it needs.

use tailor_subdiv::{Mesh, Point};

/// Vertex `(i, j)` of an `n` × `n` grid of quads, row by row.
pub fn at(n: usize, i: usize, j: usize) -> u32 {
    (j * (n + 1) + i) as u32
}

/// The faces of an `n` × `n` grid of quads, counter-clockwise, row by row.
pub fn grid_faces(n: usize) -> Vec<Vec<u32>> {
    (0..n)
        .flat_map(|j| {
            (0..n).map(move |i| {
                vec![
                    at(n, i, j),
                    at(n, i + 1, j),
                    at(n, i + 1, j + 1),
                    at(n, i, j + 1),
                ]
            })
        })
        .collect()
}

/// An `n` × `n` grid of quads whose vertex `(i, j)` is at `point(i, j)`.
pub fn grid_at(n: usize, point: impl Fn(usize, usize) -> Point) -> Mesh {
    let positions = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| (i, j)))
        .map(|(i, j)| point(i, j))
        .collect();
    Mesh::from_polygons(positions, &grid_faces(n)).unwrap()
}

/// The flat unit grid: vertex `(i, j)` at `(i, j, 0)`.
pub fn flat_grid(n: usize) -> Mesh {
    grid_at(n, |i, j| Point::new(i as f64, j as f64, 0.0))
}
