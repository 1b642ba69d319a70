//! The mesh's threads: chains of edges that run straight through vertices, like the warp and
//! weft of a woven fabric, along which the paper's bend energy (eq. 6–7) acts on triples.
//!
//! Around a manifold interior vertex of valence n, `vert_edges` is ordered counter-clockwise
//! (`tailor_subdiv::topology`), so the edge "straight across" from edge i is edge i + ⌊n/2⌋: at
//! a regular valence-4 vertex that is the opposite edge (two threads cross), at even n there are
//! n/2 threads, at odd n (an extraordinary vertex with no true opposite) every edge i pairs with
//! i + ⌊n/2⌋, giving n triples that each edge joins twice. At a boundary vertex with two or
//! more faces, the two boundary edges (first and last in the order) continue one another, so a
//! garment's hem keeps its bending stiffness; threads arriving from the interior end there, as
//! they do at corners (one face) and at non-manifold vertices.

use tailor_subdiv::topology::Level;

/// Every bend triple (p1, p2, p3) of the mesh: p2 is the middle vertex, p1 and p3 the far ends
/// of two edges that continue one another through it. In vertex order, deterministic.
#[must_use]
pub fn triples(level: &Level) -> Vec<[u32; 3]> {
    let mut out = Vec::new();
    for v in 0..level.vertex_count() {
        if level.vertex_nonmanifold()[v] {
            continue;
        }
        let edges = level.vert_edges().row(v);
        let faces = level.vert_faces().range(v).len();
        let n = edges.len();
        let vi = v as u32;
        let mut push = |i: usize, j: usize| {
            out.push([
                level.other_end(edges[i], vi),
                vi,
                level.other_end(edges[j], vi),
            ]);
        };
        if n == faces {
            let skip = n / 2;
            let count = if n.is_multiple_of(2) { skip } else { n };
            for i in 0..count {
                push(i, (i + skip) % n);
            }
        } else if faces >= 2 && n == faces + 1 {
            push(0, n - 1);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::sheet;

    #[test]
    fn grid_threads_are_straight_rows_and_columns() {
        let mesh = sheet(4, 3, 1.0, 0.5);
        let level = Level::from_mesh(&mesh);
        let t = triples(&level);
        // 4×3 vertices: interior vertices (2 of them) carry 2 threads each; boundary vertices
        // with two faces (2 + 2 + 1 + 1 = 6) carry one; the 4 corners none.
        assert_eq!(t.len(), 2 * 2 + 6);
        for [a, b, c] in t {
            let p = mesh.positions();
            let (d1, d2) = (p[b as usize] - p[a as usize], p[c as usize] - p[b as usize]);
            assert!(
                (d1 - d2).norm() < 1e-12,
                "triple {a} {b} {c} is not straight"
            );
        }
    }

    #[test]
    fn odd_valence_pairs_each_edge_with_the_one_floor_n_over_2_away() {
        // A fan of three quads around vertex 0 (valence 3, interior).
        let p = |x: f64, y: f64| tailor_subdiv::Point::new(x, y, 0.0);
        let positions = vec![
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(1.0, 1.0),
            p(0.0, 1.0),
            p(-1.0, 0.0),
            p(-1.0, -1.0),
            p(0.5, -1.0),
        ];
        let faces: [&[u32]; 3] = [&[0, 1, 2, 3], &[0, 3, 4, 5], &[0, 5, 6, 1]];
        let mesh = tailor_subdiv::Mesh::from_polygons(positions, &faces).unwrap();
        let level = Level::from_mesh(&mesh);
        let mut at_center: Vec<[u32; 3]> =
            triples(&level).into_iter().filter(|t| t[1] == 0).collect();
        assert_eq!(at_center.len(), 3);
        for t in &mut at_center {
            let (lo, hi) = (t[0].min(t[2]), t[0].max(t[2]));
            *t = [lo, 0, hi];
        }
        at_center.sort_unstable();
        assert_eq!(at_center, vec![[1, 0, 3], [1, 0, 5], [3, 0, 5]]);
    }
}
