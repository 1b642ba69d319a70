//! Building the coarsening hierarchy (DeRose, Kass & Truong 1998, §5.1).
//!
//! Level 0 is the faces. At each level the adjacency graph of the current superfaces is matched
//! greedily, cheapest pair first, where a pair costs the isoperimetric ratio of the superface it
//! would make counted in the mesh's own units, `(boundary edges)² / faces` (16 for a square of
//! four quads, 18 for a domino, 25 for four quads in a row, an L or an S; 16 again for a 4 × 4
//! and 25 for a 2 × 8): round superfaces merge first, slivers and crooked shapes last. Equal
//! costs are exactly equal, so ties go to the pair first in mesh order, and a grid's dominoes
//! all lie the same way and pair into squares; the children of a subdivided face, numbered
//! together, become one square. Roundness is what the normal cones need ([`crate::cones`]): a
//! round patch of a smooth surface has the narrowest spread of normals for its area and a
//! star-shaped contour, where an S of four quads is not star-shaped even flat. Counting edges
//! rather than measuring lengths keeps the tree the same whatever pose it is built at, and
//! free of the rounding noise that breaks ties at random (a bounding box would find a strip
//! along a fold as compact as a square across it). Every matched pair becomes a parent
//! superface; an unmatched superface waits for the next level. Superfaces with no neighbour
//! left (the last of a disconnected piece), and every unmatched one when a level merged fewer
//! than two thirds of the superfaces, are paired with their neighbour in Morton order instead,
//! so pieces join and the tree stays balanced: the count shrinks by at least a third per level,
//! giving depth O(log n). Each level sorts its edges once, so the build is O(n log n).
//!
//! The boundary chain of a node is the boundary of the 2-chain of its oriented faces: its polygon
//! edges, directed as the faces wind, with opposite edges cancelled. The normal-cone test
//! ([`crate::cones`]) reads it to decide whether a superface can fold onto itself.

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::math::Vector as DVec3;
use rayon::prelude::*;

use super::Hierarchy;
use crate::topology::Topology;

/// The shape of the tree: children of the internal nodes, and where each level starts.
pub(super) struct Tree {
    pub(super) children: Vec<[u32; 2]>,
    pub(super) level_offsets: Vec<u32>,
}

/// A superface's size in the mesh's own units: its faces, and the polygon edges of its
/// boundary.
#[derive(Clone, Copy)]
struct Shape {
    faces: u32,
    sides: u32,
}

impl Shape {
    /// The union of two superfaces whose boundaries share `seam` edges. An edge of three or
    /// more faces, or a face repeated, is a seam of several pairs: the count stops at zero.
    fn merged(self, other: Self, seam: u32) -> Self {
        Self {
            faces: self.faces + other.faces,
            sides: (self.sides + other.sides).saturating_sub(2 * seam),
        }
    }

    /// The isoperimetric ratio `sides² / faces`, the same for the same counts to the bit.
    fn roundness_cost(self) -> f64 {
        f64::from(self.sides).powi(2) / f64::from(self.faces)
    }
}

/// The number of polygon edges faces `f` and `g` share.
fn seam(topology: &Topology, f: u32, g: u32) -> u32 {
    fn sides(c: &[u32]) -> impl Iterator<Item = [u32; 2]> + '_ {
        (0..c.len()).map(move |i| [c[i], c[(i + 1) % c.len()]])
    }
    let other = topology.face(g);
    sides(topology.face(f))
        .filter(|&[p, q]| sides(other).any(|e| e == [q, p] || e == [p, q]))
        .count() as u32
}

/// Coarsens the faces of `topology` into a binary tree of round superfaces; `positions` order
/// the pieces that have no neighbour left.
pub(super) fn coarsen(topology: &Topology, positions: &[DVec3]) -> Tree {
    let faces = topology.face_count();
    let mut node: Vec<u32> = (0..faces as u32).collect();
    let mut boxes: Vec<Aabb> = (0..faces as u32)
        .map(|f| Aabb::from_points(topology.face(f).iter().map(|&v| positions[v as usize])))
        .collect();
    let whole = boxes.iter().skip(1).fold(boxes[0], |a, b| a.merged(b));
    let mut shapes: Vec<Shape> = (0..faces as u32)
        .map(|f| Shape {
            faces: 1,
            sides: topology.face(f).len() as u32,
        })
        .collect();
    // The adjacency graph, each edge with the number of polygon edges its superfaces share.
    let mut edges: Vec<([u32; 2], u32)> = topology
        .adjacency
        .par_iter()
        .map(|&[f, g]| ([f, g], seam(topology, f, g)))
        .collect();
    let mut children = Vec::with_capacity(faces.saturating_sub(1));
    let mut level_offsets = vec![0u32];

    while node.len() > 1 {
        let count = node.len();
        // Phase 1: greedy matching on the adjacency graph, round pairs first.
        // A ratio is a non-negative float, whose bits sort as its value does.
        let mut order: Vec<(u64, [u32; 2])> = edges
            .par_iter()
            .map(|&([a, b], seam)| {
                let merged = shapes[a as usize].merged(shapes[b as usize], seam);
                (merged.roundness_cost().to_bits(), [a, b])
            })
            .collect();
        order.par_sort_unstable();
        let mut matched = vec![false; count];
        let mut pairs = Vec::with_capacity(count / 2);
        for (_, [a, b]) in order {
            if !matched[a as usize] && !matched[b as usize] {
                matched[a as usize] = true;
                matched[b as usize] = true;
                pairs.push([a, b]);
            }
        }

        // Phase 2: pair the stranded superfaces by Morton order of their centres.
        let mut degree = vec![0u32; count];
        for &([a, b], _) in &edges {
            degree[a as usize] += 1;
            degree[b as usize] += 1;
        }
        let slow = pairs.len() * 3 < count;
        let mut stranded: Vec<(u64, u32)> = (0..count as u32)
            .filter(|&c| !matched[c as usize] && (slow || degree[c as usize] == 0))
            .map(|c| (morton(boxes[c as usize].center(), &whole), c))
            .collect();
        stranded.sort_unstable();
        for pair in stranded.chunks_exact(2) {
            matched[pair[0].1 as usize] = true;
            matched[pair[1].1 as usize] = true;
            pairs.push([pair[0].1, pair[1].1]);
        }

        // Phase 3: the next level: new parents first, in the order of their first child (so
        // nodes stay in mesh order, close in memory to their neighbours), then the superfaces
        // that wait.
        pairs.sort_unstable_by_key(|&[a, b]| a.min(b));
        let mut next = vec![0u32; count];
        let mut next_node = Vec::with_capacity(count - pairs.len());
        let mut next_boxes = Vec::with_capacity(count - pairs.len());
        let mut next_shapes = Vec::with_capacity(count - pairs.len());
        for &[a, b] in &pairs {
            next[a as usize] = next_node.len() as u32;
            next[b as usize] = next_node.len() as u32;
            next_node.push((faces + children.len()) as u32);
            next_boxes.push(boxes[a as usize].merged(&boxes[b as usize]));
            next_shapes.push(shapes[a as usize].merged(shapes[b as usize], 0));
            children.push([node[a as usize], node[b as usize]]);
        }
        for c in (0..count).filter(|&c| !matched[c]) {
            next[c] = next_node.len() as u32;
            next_node.push(node[c]);
            next_boxes.push(boxes[c]);
            next_shapes.push(shapes[c]);
        }
        level_offsets.push(children.len() as u32);

        // Phase 4: the adjacency between the new superfaces, the seam between the children
        // of a pair taken off its boundary, and the seams between two superfaces summed.
        let mut seams = Vec::with_capacity(edges.len());
        for ([a, b], seam) in edges {
            let (a, b) = (next[a as usize], next[b as usize]);
            if a == b {
                let sides = &mut next_shapes[a as usize].sides;
                *sides = sides.saturating_sub(2 * seam);
            } else {
                seams.push(([a.min(b), a.max(b)], seam));
            }
        }
        seams.par_sort_unstable();
        edges = seams
            .chunk_by(|x, y| x.0 == y.0)
            .map(|group| (group[0].0, group.iter().map(|&(_, s)| s).sum()))
            .collect();
        node = next_node;
        boxes = next_boxes;
        shapes = next_shapes;
    }
    Tree {
        children,
        level_offsets,
    }
}

/// The Morton code (21 bits per axis) of `p` inside `whole`.
fn morton(p: DVec3, whole: &Aabb) -> u64 {
    let extent = (whole.maxs - whole.mins).max(DVec3::splat(f64::MIN_POSITIVE));
    let unit = ((p - whole.mins) / extent).clamp(DVec3::ZERO, DVec3::ONE);
    let spread = |x: f64| {
        let mut v = (x * ((1u64 << 21) - 1) as f64) as u64;
        v = (v | (v << 32)) & 0x001f_0000_0000_ffff;
        v = (v | (v << 16)) & 0x001f_0000_ff00_00ff;
        v = (v | (v << 8)) & 0x100f_00f0_0f00_f00f;
        v = (v | (v << 4)) & 0x10c3_0c30_c30c_30c3;
        (v | (v << 2)) & 0x1249_2492_4924_9249
    };
    spread(unit.x) | (spread(unit.y) << 1) | (spread(unit.z) << 2)
}

/// The boundary chain of every node, as CSR over nodes: a leaf's polygon edges in winding order,
/// and for a parent the union of its children's chains with opposite edges cancelled.
pub(super) fn boundary_chains(hierarchy: &Hierarchy) -> (Vec<u32>, Vec<[u32; 2]>) {
    let faces = hierarchy.face_count();
    let mut offsets = Vec::with_capacity(faces + hierarchy.children.len() + 1);
    let mut chain = Vec::new();
    offsets.push(0u32);
    for f in 0..faces as u32 {
        let corners = hierarchy.topology.face(f);
        for (i, &v) in corners.iter().enumerate() {
            chain.push([v, corners[(i + 1) % corners.len()]]);
        }
        offsets.push(chain.len() as u32);
    }
    let mut merged = Vec::new();
    for &[a, b] in &hierarchy.children {
        merged.clear();
        for child in [a, b] {
            let c = child as usize;
            merged.extend_from_slice(&chain[offsets[c] as usize..offsets[c + 1] as usize]);
        }
        cancel_opposite(&mut merged);
        chain.extend_from_slice(&merged);
        offsets.push(chain.len() as u32);
    }
    chain.shrink_to_fit();
    (offsets, chain)
}

/// Cancels pairs of opposite directed edges (`a→b` with `b→a`), keeping the net multiplicity.
fn cancel_opposite(edges: &mut Vec<[u32; 2]>) {
    edges.sort_unstable_by_key(|&[a, b]| (a.min(b), a.max(b)));
    let mut kept = Vec::with_capacity(edges.len());
    for group in
        edges.chunk_by(|x, y| (x[0].min(x[1]), x[0].max(x[1])) == (y[0].min(y[1]), y[0].max(y[1])))
    {
        let [low, high] = [group[0][0].min(group[0][1]), group[0][0].max(group[0][1])];
        let net: i64 = group.iter().map(|e| if e[0] == low { 1 } else { -1 }).sum();
        let edge = if net > 0 { [low, high] } else { [high, low] };
        kept.extend(std::iter::repeat_n(edge, net.unsigned_abs() as usize));
    }
    *edges = kept;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Point;
    use crate::hierarchy::grid;

    fn collect_leaves(h: &Hierarchy, node: u32, out: &mut Vec<u32>) {
        match h.node_children(node) {
            None => out.push(node),
            Some([a, b]) => {
                collect_leaves(h, a, out);
                collect_leaves(h, b, out);
            }
        }
    }

    #[test]
    fn every_face_is_one_leaf_under_the_root() {
        for copies in [1, 3] {
            let (p, o, c) = grid(16, copies);
            let h = Hierarchy::build(&p, &o, &c).unwrap();
            let mut leaves = Vec::new();
            collect_leaves(&h, h.root(), &mut leaves);
            leaves.sort_unstable();
            assert_eq!(leaves, (0..h.face_count() as u32).collect::<Vec<_>>());
            assert_eq!(h.leaf_counts[h.root() as usize] as usize, h.face_count());
            // The depth-first numbering gives every node exactly its own faces.
            for node in 0..=h.root() {
                let mut below = Vec::new();
                collect_leaves(&h, node, &mut below);
                assert_eq!(h.leaves_below(node), below.as_slice());
            }
        }
    }

    /// The nodes marked for a set of moved vertices are exactly those with a face below them
    /// that has a moved corner: none, one vertex, a scattered few, all; one face and many.
    #[test]
    fn nodes_moved_are_those_with_a_moved_corner_below() {
        for (n, copies) in [(1, 1), (9, 2)] {
            let (p, o, c) = grid(n, copies);
            let h = Hierarchy::build(&p, &o, &c).unwrap();
            let vertices = h.vertex_count();
            let picks: [fn(usize, usize) -> bool; 4] = [
                |_, _| false,
                |v, n| v == n / 2,
                |v, _| v % 7 == 3,
                |_, _| true,
            ];
            for pick in picks {
                let moved: Vec<bool> = (0..vertices).map(|v| pick(v, vertices)).collect();
                let marked = h.nodes_moved(&moved);
                assert_eq!(marked.len(), h.root() as usize + 1);
                for node in 0..=h.root() {
                    let mut below = Vec::new();
                    collect_leaves(&h, node, &mut below);
                    let expected = below
                        .iter()
                        .any(|&f| h.topology.face(f).iter().any(|&v| moved[v as usize]));
                    assert_eq!(
                        marked[node as usize], expected,
                        "node {node} of {n}² × {copies}"
                    );
                }
            }
        }
    }

    #[test]
    fn grid_hierarchy_is_balanced() {
        let (p, o, c) = grid(32, 1);
        let h = Hierarchy::build(&p, &o, &c).unwrap();
        // 1024 faces: log2 = 10; greedy matching leaves a few faces waiting.
        assert!(h.depth() >= 10 && h.depth() <= 14, "depth {}", h.depth());
    }

    #[test]
    fn root_boundary_of_a_grid_is_its_rim() {
        let (p, o, c) = grid(4, 1);
        let h = Hierarchy::build(&p, &o, &c).unwrap();
        let rim = h.node_boundary(h.root());
        assert_eq!(rim.len(), 16);
        // The rim is one closed loop: every vertex starts exactly one edge and ends one.
        let mut starts: Vec<u32> = rim.iter().map(|e| e[0]).collect();
        let mut ends: Vec<u32> = rim.iter().map(|e| e[1]).collect();
        starts.sort_unstable();
        ends.sort_unstable();
        assert_eq!(starts, ends);
    }

    #[test]
    fn closed_surface_has_no_root_boundary() {
        // A tetrahedron, consistently oriented.
        let p = [
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(0.0, 0.0, 1.0),
        ];
        let c = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
        let h = Hierarchy::build(&p, &[0, 3, 6, 9, 12], &c).unwrap();
        assert!(h.node_boundary(h.root()).is_empty());
    }

    #[test]
    fn grid_coarsens_into_squares_whatever_its_pose() {
        let (p, o, c) = grid(16, 1);
        let h = Hierarchy::build(&p, &o, &c).unwrap();
        // Four quads are a 2 × 2 square (8 boundary edges, where an L, an S or a row of four
        // has 10), sixteen a 4 × 4 (16, where 2 × 8 has 20).
        for node in 0..=h.root() {
            let sides = h.node_boundary(node).len();
            match h.leaf_counts[node as usize] {
                4 => assert_eq!(sides, 8, "node {node}"),
                16 => assert_eq!(sides, 16, "node {node}"),
                _ => {}
            }
        }
        // Rolled up round a cylinder and sheared, the grid coarsens the same.
        let rolled: Vec<Point> = p
            .iter()
            .map(|q| {
                let (s, c) = (q.x / 3.0).sin_cos();
                Point::new(3.0 * s + 0.3 * q.y, q.y, 3.0 * c)
            })
            .collect();
        assert_eq!(
            Hierarchy::build(&rolled, &o, &c).unwrap().children,
            h.children
        );
    }

    #[test]
    fn repeated_faces_and_shared_edges_build() {
        // The same quad three times, and three triangles on one edge: every pair is a seam of
        // all the shared edges, more than the superface has.
        let p: Vec<Point> = [[0., 0.], [1., 0.], [1., 1.], [0., 1.], [0.5, -1.]]
            .iter()
            .map(|&[x, y]| Point::new(x, y, 0.0))
            .collect();
        let c = [
            0, 1, 2, 3, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 4, 1, 0, 2, 0, 1, 3,
        ];
        let h = Hierarchy::build(&p, &[0, 4, 8, 12, 15, 18, 21], &c).unwrap();
        assert_eq!(h.leaf_counts[h.root() as usize], 6);
    }

    #[test]
    fn morton_orders_along_each_axis() {
        let whole = Aabb::new(DVec3::ZERO, DVec3::ONE);
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            assert!(morton(axis * 0.25, &whole) < morton(axis * 0.75, &whole));
        }
    }
}
