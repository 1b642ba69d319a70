//! Pairs of leaves whose boxes overlap, within one hierarchy or between two: the simultaneous
//! descent of Gottschalk, Lin & Manocha (1996), with self-collision organised as Volino &
//! Magnenat-Thalmann (1994) do it: the pairs inside a node are those inside each child plus
//! those across the two children, and a node the normal cones clear is skipped whole.
//!
//! Subtrees run in parallel (`rayon::join`) and their results are concatenated in a fixed
//! order, so the output does not depend on the number of threads.

use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as DVec3;

use crate::cones::NormalCones;
use crate::hierarchy::Hierarchy;

/// Subtrees with fewer leaves than this are walked on one thread.
const GRAIN: u32 = 1024;

/// What to do with a pair of leaves (faces) whose boxes overlap: push results to the vector.
pub(crate) type Visit<'a, T> = &'a (dyn Fn(u32, u32, &mut Vec<T>) + Sync);

/// Visits every unordered pair of distinct leaves of `h` with overlapping boxes, each leaf with
/// itself too when `same_leaf`, skipping nodes that `cones` clear. Boxes are compared loosened
/// by `slack` and `pad` (see [`overlap`]).
pub(crate) fn self_pairs<T: Send>(
    h: &Hierarchy,
    cones: Option<&NormalCones>,
    same_leaf: bool,
    slack: f64,
    pad: f64,
    visit: Visit<'_, T>,
) -> Vec<T> {
    let mut out = Vec::new();
    let walk = Walk {
        ha: h,
        hb: h,
        slack,
        pad,
        visit,
    };
    SelfWalk {
        walk,
        cones,
        same_leaf,
    }
    .node(h.root(), &mut out);
    out
}

/// A node with its box.
type Boxed = (u32, Aabb);

/// Visits every pair (leaf of `a`, leaf of `b`) with overlapping boxes, loosened by `slack`.
pub(crate) fn cross_pairs<T: Send>(
    a: &Hierarchy,
    b: &Hierarchy,
    slack: f64,
    visit: Visit<'_, T>,
) -> Vec<T> {
    let mut out = Vec::new();
    let walk = Walk {
        ha: a,
        hb: b,
        slack,
        pad: 0.0,
        visit,
    };
    let root = |h: &Hierarchy| (h.root(), h.node_box(h.root()));
    walk.cross(root(a), root(b), &mut out);
    out
}

/// Whether two boxes overlap once each is loosened by `slack` times the sum of its extents (at
/// least its diagonal, without a square root: the contact tolerance of the exact tests is
/// relative to the size of the features) and together by the distance `pad` (a proximity
/// query's reach).
fn overlap(a: &Aabb, b: &Aabb, slack: f64, pad: f64) -> bool {
    let relative = slack * ((a.maxs - a.mins).element_sum() + (b.maxs - b.mins).element_sum());
    let pad = DVec3::splat(relative + pad);
    (a.mins - pad).cmple(b.maxs).all() && (b.mins - pad).cmple(a.maxs).all()
}

fn collect<T>(f: impl FnOnce(&mut Vec<T>)) -> Vec<T> {
    let mut out = Vec::new();
    f(&mut out);
    out
}

struct Walk<'a, T> {
    ha: &'a Hierarchy,
    hb: &'a Hierarchy,
    slack: f64,
    pad: f64,
    visit: Visit<'a, T>,
}

impl<T: Send> Walk<'_, T> {
    /// Visits the overlapping leaf pairs below node `a` of `ha` and node `b` of `hb`. The
    /// boxes travel with the nodes: a child's box is read from its parent's record.
    fn cross(&self, a: Boxed, b: Boxed, out: &mut Vec<T>) {
        let (ha, hb) = (self.ha, self.hb);
        if !overlap(&a.1, &b.1, self.slack, self.pad) {
            return;
        }
        let (size_a, size_b) = (ha.leaf_counts[a.0 as usize], hb.leaf_counts[b.0 as usize]);
        // Split the larger side, `a` on ties. A leaf covers one face and an internal node at
        // least two, so when the larger side is a leaf both are.
        let (x, y) = if size_a >= size_b
            && let Some([a0, a1]) = ha.children_boxed(a.0)
        {
            ((a0, b), (a1, b))
        } else if let Some([b0, b1]) = hb.children_boxed(b.0) {
            ((a, b0), (a, b1))
        } else {
            return (self.visit)(a.0, b.0, out);
        };
        if size_a.min(size_b) >= GRAIN / 4 && size_a.max(size_b) >= GRAIN {
            let (mut first, mut second) = rayon::join(
                || collect(|o| self.cross(x.0, x.1, o)),
                || collect(|o| self.cross(y.0, y.1, o)),
            );
            out.append(&mut first);
            out.append(&mut second);
        } else {
            self.cross(x.0, x.1, out);
            self.cross(y.0, y.1, out);
        }
    }
}

struct SelfWalk<'a, T> {
    walk: Walk<'a, T>,
    cones: Option<&'a NormalCones>,
    same_leaf: bool,
}

impl<T: Send> SelfWalk<'_, T> {
    fn node(&self, node: u32, out: &mut Vec<T>) {
        let h = self.walk.ha;
        if self.cones.is_some_and(|c| c.cannot_self_collide(h, node)) {
            return;
        }
        let Some([a, b]) = h.children_boxed(node) else {
            if self.same_leaf {
                (self.walk.visit)(node, node, out);
            }
            return;
        };
        if h.leaf_counts[node as usize] < GRAIN {
            self.node(a.0, out);
            self.node(b.0, out);
            self.walk.cross(a, b, out);
            return;
        }
        let (mut left, (mut right, mut across)) = rayon::join(
            || collect(|o| self.node(a.0, o)),
            || {
                rayon::join(
                    || collect(|o| self.node(b.0, o)),
                    || collect(|o| self.walk.cross(a, b, o)),
                )
            },
        );
        out.append(&mut left);
        out.append(&mut right);
        out.append(&mut across);
    }
}
