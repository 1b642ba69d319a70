//! Pairs of leaves whose boxes overlap, within one hierarchy or between two: the simultaneous
//! descent of Gottschalk, Lin & Manocha (1996), with self-collision organised as Volino &
//! Magnenat-Thalmann (1994) do it: the pairs inside a node are those inside each child plus
//! those across the two children, and a node the normal cones clear is skipped whole.
//!
//! The descent reads the boxes as the refit stored them, two to a record and in single
//! precision, already loosened by the contact tolerance of the exact tests (see the
//! hierarchy's refit), so a box test is six comparisons. Subtrees run in parallel
//! (`rayon::join`) and their results are concatenated in a fixed order, so the output does
//! not depend on the number of threads.

use crate::cones::NormalCones;
use crate::hierarchy::Hierarchy;
use crate::hierarchy::boxes::{LEAF, SmallBox};

/// Subtrees with fewer leaves than this are walked on one thread.
const GRAIN: u32 = 1024;

/// Visits every unordered pair of distinct leaves of `h` with overlapping boxes, each leaf with
/// itself too when `same_leaf`, skipping nodes that `cones` clear. Boxes are compared loosened
/// together by the distance `pad` (a proximity query's reach). `visit(f, g, out)` pushes the
/// results of faces `f` and `g` to `out`.
pub(crate) fn self_pairs<T: Send, V>(
    h: &Hierarchy,
    cones: Option<&NormalCones>,
    same_leaf: bool,
    pad: f64,
    dirty: Option<&[bool]>,
    visit: &V,
) -> Vec<T>
where
    V: Fn(u32, u32, &mut Vec<T>) + Sync,
{
    let mut out = Vec::new();
    let walk = Walk {
        ha: h,
        hb: h,
        pad: single_pad(pad),
        dirty,
        visit,
    };
    SelfWalk {
        walk,
        cones,
        same_leaf,
    }
    .node(root(h).0, &mut out);
    out
}

/// Visits every pair (leaf of `a`, leaf of `b`) with overlapping boxes.
pub(crate) fn cross_pairs<T: Send, V>(a: &Hierarchy, b: &Hierarchy, visit: &V) -> Vec<T>
where
    V: Fn(u32, u32, &mut Vec<T>) + Sync,
{
    let mut out = Vec::new();
    let walk = Walk {
        ha: a,
        hb: b,
        pad: 0.0,
        dirty: None,
        visit,
    };
    walk.cross(root(a), root(b), &mut out);
    out
}

/// A node as its parent's record refers to it (a record index, or `LEAF | face`), with its box.
type Boxed = (u32, SmallBox);

/// The root of `h` with its box.
fn root(h: &Hierarchy) -> Boxed {
    let boxes = h.boxes();
    let root = if boxes.is_single_face() {
        LEAF
    } else {
        h.root() - h.face_count() as u32
    };
    (root, boxes.root_box())
}

/// `pad` rounded up to single precision. Rounding is monotonic, so when a box's low
/// coordinate `a` lies within `pad` of another's high one `b` (`a ≤ b + pad`), the sum in
/// single precision is still no less than `a`: `b + pad` rounds up to at least `a`, itself a
/// single-precision number, and rounding the pad up only adds to the sum.
fn single_pad(pad: f64) -> f32 {
    let rounded = pad as f32;
    if f64::from(rounded) < pad {
        rounded.next_up()
    } else {
        rounded
    }
}

/// Whether two boxes come within `pad` (from [`single_pad`]) of each other: six comparisons
/// in single precision, with no box within the pad ever missed. All six are made and then
/// combined, without a branch between them: with a branch after each, the 64² drape's run
/// took 0.3% more instructions.
#[inline(always)]
fn overlap(a: &SmallBox, b: &SmallBox, pad: f32) -> bool {
    (a[0] <= b[3] + pad)
        & (b[0] <= a[3] + pad)
        & (a[1] <= b[4] + pad)
        & (b[1] <= a[4] + pad)
        & (a[2] <= b[5] + pad)
        & (b[2] <= a[5] + pad)
}

fn collect<T>(f: impl FnOnce(&mut Vec<T>)) -> Vec<T> {
    let mut out = Vec::new();
    f(&mut out);
    out
}

struct Walk<'a, V> {
    ha: &'a Hierarchy,
    hb: &'a Hierarchy,
    /// Per node of a self walk, whether a vertex below it moved: pairs of nodes where none did
    /// are not visited.
    dirty: Option<&'a [bool]>,
    /// The pad from [`single_pad`].
    pad: f32,
    visit: &'a V,
}

/// The number of faces below a node reference of `h`.
#[inline(always)]
fn size(h: &Hierarchy, node: u32) -> u32 {
    if node & LEAF != 0 {
        1
    } else {
        h.leaf_counts[h.face_count() + node as usize]
    }
}

/// The children of a record reference of `h`, with their boxes, or `None` for a leaf.
#[inline(always)]
fn children(h: &Hierarchy, node: u32) -> Option<[Boxed; 2]> {
    (node & LEAF == 0).then(|| {
        let (child, boxes) = h.boxes().record(node);
        [(child[0], boxes[0]), (child[1], boxes[1])]
    })
}

/// Node pairs still to cross on one thread, the next one last (see [`Walk::cross_serial`]).
type Pending = Vec<(Boxed, Boxed)>;

impl<V: Sync> Walk<'_, V> {
    /// Whether the pair of nodes `a` of `ha` and `b` of `hb` can hold overlapping leaves: their
    /// boxes overlap, and in a walk of what moved, one of them moved.
    #[inline(always)]
    fn meets(&self, a: &Boxed, b: &Boxed) -> bool {
        !self
            .dirty
            .is_some_and(|d| !d[self.ha.node_id(a.0)] && !d[self.hb.node_id(b.0)])
            && overlap(&a.1, &b.1, self.pad)
    }

    /// The two pairs that split `(a, b)`, the larger side split (`a` on ties), or `None` when
    /// both are leaves. A leaf covers one face and an internal node at least two, so when the
    /// larger side is a leaf both are. Also the sizes of `a` and `b`.
    #[inline(always)]
    fn split(&self, a: Boxed, b: Boxed) -> (Option<[(Boxed, Boxed); 2]>, u32, u32) {
        let (size_a, size_b) = (size(self.ha, a.0), size(self.hb, b.0));
        let halves = if size_a >= size_b
            && let Some([a0, a1]) = children(self.ha, a.0)
        {
            Some([(a0, b), (a1, b)])
        } else {
            children(self.hb, b.0).map(|[b0, b1]| [(a, b0), (a, b1)])
        };
        (halves, size_a, size_b)
    }

    /// Visits the overlapping leaf pairs below node `a` of `ha` and node `b` of `hb`. The
    /// boxes travel with the nodes: a child's box is read from its parent's record.
    fn cross<T: Send>(&self, a: Boxed, b: Boxed, out: &mut Vec<T>)
    where
        V: Fn(u32, u32, &mut Vec<T>),
    {
        if !self.meets(&a, &b) {
            return;
        }
        match self.split(a, b) {
            (Some([x, y]), size_a, size_b)
                if size_a.min(size_b) >= GRAIN / 4 && size_a.max(size_b) >= GRAIN =>
            {
                let (mut first, mut second) = rayon::join(
                    || collect(|o| self.cross(x.0, x.1, o)),
                    || collect(|o| self.cross(y.0, y.1, o)),
                );
                out.append(&mut first);
                out.append(&mut second);
            }
            _ => self.cross_serial(&mut vec![(a, b)], out),
        }
    }

    /// Crosses the node pairs of `pending`, which meet, on this thread, depth first: a loop
    /// over a stack of the pairs whose boxes overlap, rather than a call for every pair of
    /// children. Both sides of a pair split at once, as in parry's `Bvh` traversal: four box
    /// tests for the two records read, where splitting one side at a time reads each record
    /// twice and takes half again as many steps.
    fn cross_serial<T>(&self, pending: &mut Pending, out: &mut Vec<T>)
    where
        V: Fn(u32, u32, &mut Vec<T>),
    {
        while let Some((a, b)) = pending.pop() {
            let mut push = |x: Boxed, y: Boxed| {
                if self.meets(&x, &y) {
                    pending.push((x, y));
                }
            };
            // Pushed last to first, so that the pairs are crossed in the order listed.
            match (children(self.ha, a.0), children(self.hb, b.0)) {
                (None, None) => (self.visit)(a.0 & !LEAF, b.0 & !LEAF, out),
                (Some([a0, a1]), None) => {
                    push(a1, b);
                    push(a0, b);
                }
                (None, Some([b0, b1])) => {
                    push(a, b1);
                    push(a, b0);
                }
                (Some([a0, a1]), Some([b0, b1])) => {
                    push(a1, b1);
                    push(a1, b0);
                    push(a0, b1);
                    push(a0, b0);
                }
            }
        }
    }
}

struct SelfWalk<'a, V> {
    walk: Walk<'a, V>,
    cones: Option<&'a NormalCones>,
    same_leaf: bool,
}

impl<V: Sync> SelfWalk<'_, V> {
    /// Whether the node `id` is left out: nothing below it moved in a walk of what moved, or
    /// the normal cones clear it.
    fn skipped(&self, id: usize) -> bool {
        self.walk.dirty.is_some_and(|d| !d[id])
            || self
                .cones
                .is_some_and(|c| c.cannot_self_collide(self.walk.ha, id as u32))
    }

    /// The pairs within the node that the reference `node` names.
    fn node<T: Send>(&self, node: u32, out: &mut Vec<T>)
    where
        V: Fn(u32, u32, &mut Vec<T>),
    {
        let h = self.walk.ha;
        let large = (size(h, node) >= GRAIN).then(|| children(h, node));
        let Some(Some([a, b])) = large else {
            return self.node_serial(node, &mut Pending::new(), out);
        };
        if self.skipped(h.node_id(node)) {
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

    /// [`Self::node`] on this thread, for a node below [`GRAIN`] faces; `pending` is the empty
    /// stack its crossings share.
    fn node_serial<T>(&self, node: u32, pending: &mut Pending, out: &mut Vec<T>)
    where
        V: Fn(u32, u32, &mut Vec<T>),
    {
        let h = self.walk.ha;
        let id = h.node_id(node);
        if self.skipped(id) {
            return;
        }
        let Some([a, b]) = children(h, node) else {
            if self.same_leaf {
                (self.walk.visit)(id as u32, id as u32, out);
            }
            return;
        };
        self.node_serial(a.0, pending, out);
        self.node_serial(b.0, pending, out);
        if self.walk.meets(&a, &b) {
            pending.push((a, b));
            self.walk.cross_serial(pending, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Boxes apart by exactly the pad meet, where the pad rounded to the nearest single does
    /// not reach: a high side at -1 and a low side at 2⁻³⁰ are 1 + 2⁻³⁰ apart, which rounds
    /// to 1.
    #[test]
    fn boxes_apart_by_the_pad_meet() {
        let tiny = 2f32.powi(-30);
        let low: SmallBox = [-2.0, 0.0, 0.0, -1.0, 1.0, 1.0];
        let high: SmallBox = [tiny, 0.0, 0.0, 1.0, 1.0, 1.0];
        let gap = 1.0 + f64::from(tiny);
        assert!(overlap(&low, &high, single_pad(gap)));
        assert!(overlap(&high, &low, single_pad(gap)));
        assert!(!overlap(&low, &high, single_pad(0.999)));
        assert_eq!(single_pad(0.0), 0.0);
        assert_eq!(single_pad(0.25), 0.25);
    }
}
