//! Re-evaluating a fixed topology every frame: B-spline patches where the control mesh is
//! regular, stencil rows everywhere else.
//!
//! A stencil table ([`StencilTable`]) stores, for every refined point, the control points and
//! weights it combines: at level 2 about ten (column, weight) pairs per point, so a frame reads
//! some 45 bytes of table and gathers ten control points per 24-byte point it writes. On a
//! regular control quad (four smooth interior corners of valence four, no sharpness near;
//! `patches.rs` says exactly when) all those rows are one tensor product: Catmull-Clark is
//! uniform bicubic B-spline subdivision there (Stam 1998, §2), so the `(2^N + 1)²` level-`N`
//! points over the quad are `W P Wᵀ` for the quad's 4 × 4 control points `P` and the fixed
//! `(2^N + 1) × 4` matrix `W` of the curve rules ([`crate::rules::bspline::span_weights`]).
//! OpenSubdiv makes the same split for limit evaluation: `Far::PatchTable` keeps regular faces
//! as `REGULAR` B-spline patches and only the others as Gregory patches or stencils.
//!
//! The [`Evaluator`] gathers a regular quad's 16 control points (64 bytes of indices), refines
//! its four control columns (`W P`), then the points it writes, a line of constant `x` at a
//! time: the points `(x, 1..=2^N)` are `Σ_b W[x][b] · (W P)[.., b]`, one weighted sum of four
//! contiguous runs of numbers, which the compiler turns into full-width (two-lane SSE2) vector
//! arithmetic, three or four products per point with the zeros of `W` skipped. The points land
//! in a small grid, and from there in their blocks of the output, one contiguous run per
//! segment (`patches.rs`). Faces come in the order of the control mesh; when a quad follows
//! its left neighbour, the same way round (the common case in a grid-like garment), three of
//! its columns are the neighbour's (kept in a ring) and only one is gathered and refined. At
//! level 1 a quad owns three points, too few to pay for its 16 gathers, so there (and above
//! level 4) the evaluator applies the stencil table as it is.
//!
//! Each refined point has one writer: a point inside a regular quad, or on an edge that first
//! appears in a regular quad, that quad; a control vertex's vertex point the first regular quad
//! of its run with that corner; any other point its stencil row (copied, in the order they are
//! used, next to the patches). Writers are grouped in fixed runs of faces that own disjoint
//! ranges of the output, so evaluation is parallel, and every point is computed by the same
//! arithmetic whatever the thread count. Results equal the stencil table's to rounding (about
//! 1e-16 relative; the tests hold them to 1e-12).
//!
//! A level-2 frame of a 100k-quad mesh writes 38 MB, more than a 32 MB L3 cache holds; on two
//! cores the evaluator takes a little over twice as long as writing that much and nothing else
//! (`write_floor` in `benches/refine.rs`), the rest being the arithmetic.

use rayon::prelude::*;

use crate::patches::{CORNER_POINTS, Patch, RegularPatches};
use crate::refiner::Refiner;
use crate::rules::bspline;
use crate::sparse::{Primvar, weighted_sum};
use crate::stencil::StencilTable;

/// Refined points of a fixed topology as a function of its control points, for evaluation
/// every frame: same results as [`Refiner::stencils`] applied with [`StencilTable::apply`],
/// faster where the mesh is regular.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluator {
    stencils: StencilTable,
    patches: Option<RegularPatches>,
}

impl Evaluator {
    /// Builds the stencil table of `refiner`'s last level and the regular patches of its
    /// control mesh.
    #[must_use]
    pub fn new(refiner: &Refiner) -> Self {
        let stencils = refiner.stencils();
        let patches = refiner.steps().last().and_then(|last| {
            RegularPatches::new(
                refiner.level(0),
                refiner.levels(),
                &last.child.face_verts,
                &stencils.rows,
            )
        });
        Self { stencils, patches }
    }

    /// The refined points for control points `control`, into `out`, in parallel.
    ///
    /// # Panics
    /// If `control` or `out` do not have the sizes of [`Self::stencils`].
    pub fn apply<T: Primvar>(&self, control: &[T], out: &mut [T]) {
        let Some(patches) = &self.patches else {
            self.stencils.apply(control, out);
            return;
        };
        assert_eq!(
            control.len(),
            self.stencils.control_points,
            "control point count"
        );
        assert_eq!(out.len(), self.stencils.len(), "destination length");
        match control.first().map_or(0, |c| c.components().len()) {
            1 => by_level::<T, 1>(patches, control, out),
            2 => by_level::<T, 2>(patches, control, out),
            3 => by_level::<T, 3>(patches, control, out),
            _ => self.stencils.apply(control, out),
        }
    }

    /// The stencil table: every refined point's weights over the control points.
    #[must_use]
    pub fn stencils(&self) -> &StencilTable {
        &self.stencils
    }

    /// The stencil table, dropping the patches.
    #[must_use]
    pub fn into_stencils(self) -> StencilTable {
        self.stencils
    }

    /// Number of refined points.
    #[must_use]
    pub fn len(&self) -> usize {
        self.stencils.len()
    }

    /// True when there are no refined points.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.stencils.is_empty()
    }

    /// Number of control points.
    #[must_use]
    pub fn control_points(&self) -> usize {
        self.stencils.control_points
    }

    /// Control faces evaluated as B-spline patches.
    #[must_use]
    pub fn regular_faces(&self) -> usize {
        self.patches.as_ref().map_or(0, |p| p.patches.len())
    }

    /// Memory held, in bytes (the stencil table included).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.stencils.bytes() + self.patches.as_ref().map_or(0, RegularPatches::bytes)
    }
}

/// Evaluates values of `D` components with patches.
fn by_level<T: Primvar, const D: usize>(p: &RegularPatches, control: &[T], out: &mut [T]) {
    match p.levels {
        2 => apply_patches::<T, D, 5>(p, control, out),
        3 => apply_patches::<T, D, 9>(p, control, out),
        4 => apply_patches::<T, D, 17>(p, control, out),
        _ => unreachable!("patches are built for levels 2 to 4"),
    }
}

/// Evaluates values of `D` components with patches whose grids have `S` points a side
/// (`S = 2^levels + 1`).
fn apply_patches<T: Primvar, const D: usize, const S: usize>(
    p: &RegularPatches,
    control: &[T],
    out: &mut [T],
) {
    // Cut every segment into the runs' ranges, run-major.
    let segments = &p.segments;
    let runs = p.chunks.len() - 1;
    let mut pieces: Vec<&mut [T]> = (0..runs * segments.len()).map(|_| &mut [][..]).collect();
    let mut rest = out;
    for (s, seg) in segments.iter().enumerate() {
        for (c, run) in p.chunks.windows(2).enumerate() {
            let len = seg.block(run[1].index(seg.owner)) - seg.block(run[0].index(seg.owner));
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut(len);
            pieces[c * segments.len() + s] = piece;
            rest = tail;
        }
    }
    pieces
        .par_chunks_mut(segments.len())
        .enumerate()
        .for_each(|(c, slices)| {
            let (lo, hi) = (&p.chunks[c], &p.chunks[c + 1]);
            let mut kernel = Kernel::<D, S>::new();
            for patch in &p.patches[lo.patch as usize..hi.patch as usize] {
                kernel.patch(control, patch);
                let grid = kernel.grid.as_flattened();
                p.patch_runs(lo, patch, |s, start, points| {
                    let block = &mut slices[s][start..start + points.len()];
                    for (out, &g) in block.iter_mut().zip(points) {
                        out.components_mut().copy_from_slice(&grid[usize::from(g)]);
                    }
                });
                for (j, &k) in CORNER_POINTS.iter().enumerate() {
                    if patch.corners & (1 << j) != 0 {
                        let [x, y] = Kernel::<D, S>::corner(j);
                        let v = (patch.points[k] - lo.vertex) as usize;
                        slices[0][v]
                            .components_mut()
                            .copy_from_slice(&kernel.grid[x][y]);
                    }
                }
            }
            // The rest of the run's points, in increasing order, from their rows.
            let mut s = 0;
            for k in lo.irregular as usize..hi.irregular as usize {
                let i = p.irregular[k] as usize;
                while i >= segments[s].block(hi.index(segments[s].owner)) {
                    s += 1;
                }
                let start = segments[s].block(lo.index(segments[s].owner));
                slices[s][i - start] = weighted_sum(p.irregular_rows.row(k), control);
            }
        });
}

/// Evaluates patches one after another: `W P Wᵀ` for a patch's 4 × 4 control points `P` and
/// the 1D rule `W` (`S × 4`, a compile-time table), control columns first (`W P`, kept), then
/// the grid points the patch writes, line by line: the points `(x, y)` of a line of constant
/// `x` are `Σ_b W[x][b] · (W P)[y][b]`, one combination of four contiguous runs of numbers,
/// which the compiler turns into full-width vector arithmetic. The caller copies the points
/// out of the grid into their blocks. A patch that follows its neighbour across edge 3 shares
/// three control columns with it, so only its new column is gathered and refined; the columns
/// are a ring, so none is moved.
///
/// Sizes are constants, so the compiler unrolls the arithmetic on a run of points into
/// straight-line vector code; the zeros of `W` are skipped ([`Row`]: a level-2 point combines
/// three or four columns, not always four).
struct Kernel<const D: usize, const S: usize> {
    /// `W P` by control column: column `b` of the current patch is `columns[(head + b) % 4]`,
    /// indexed by `y`.
    columns: [[[f64; D]; S]; 4],
    head: usize,
    /// The current patch's refined points, `grid[x][y]`: current where the patch writes.
    grid: [[[f64; D]; S]; S],
}

/// Points of a line computed at once (twelve numbers, six SSE2 registers, for a point of three
/// components): `S − 1 = 2^levels` is a multiple of four from level 2 on.
const RUN: usize = 4;

/// A row of `W` and the range of its non-zero weights (contiguous for a B-spline rule),
/// known at compile time.
#[derive(Clone, Copy)]
struct Row {
    /// Weights of the four control columns (or rows).
    w: [f64; 4],
    /// The non-zero weights are `w[first..end]`.
    first: usize,
    end: usize,
}

impl Row {
    /// The rows of [`bspline::span_table`].
    const fn table<const S: usize>() -> [Self; S] {
        let w = bspline::span_table::<S>();
        let mut rows = [Self {
            w: [0.0; 4],
            first: 0,
            end: 0,
        }; S];
        let mut i = 0;
        while i < S {
            let (mut first, mut end) = (0, 4);
            while w[i][first] == 0.0 {
                first += 1;
            }
            while w[i][end - 1] == 0.0 {
                end -= 1;
            }
            rows[i] = Self {
                w: w[i],
                first,
                end,
            };
            i += 1;
        }
        rows
    }
}

impl<const D: usize, const S: usize> Kernel<D, S> {
    const W: [Row; S] = Row::table::<S>();

    fn new() -> Self {
        Self {
            columns: [[[0.0; D]; S]; 4],
            head: 0,
            grid: [[[0.0; D]; S]; S],
        }
    }

    /// Makes the grid points `patch` writes: its interior and the points of the edges it
    /// owns (edge j's run from corner j: `(t, 0)`, `(S − 1, t)`, `(t, S − 1)`, `(0, t)`).
    /// Lines run over `y = 1..S`, edge 2's point and corners included whether or not the
    /// patch writes them; edge 0 is made point by point.
    #[inline]
    fn patch<T: Primvar>(&mut self, control: &[T], patch: &Patch) {
        if patch.follows {
            self.head = (self.head + 1) % 4;
            self.column(control, patch, 3);
        } else {
            for b in 0..4 {
                self.column(control, patch, b);
            }
        }
        let owns = |j: u8| patch.owned & (1 << j) != 0;
        for x in 1..S - 1 {
            self.line(x);
        }
        if owns(1) {
            self.line(S - 1);
        }
        if owns(3) {
            self.line(0);
        }
        if owns(0) {
            for x in 1..S - 1 {
                self.point(x, 0);
            }
        }
        for j in 0..4 {
            if patch.corners & (1 << j) != 0 {
                let [x, y] = Self::corner(j);
                self.point(x, y);
            }
        }
    }

    /// Where corner `j` is in the grid.
    #[inline(always)]
    fn corner(j: usize) -> [usize; 2] {
        [[0, 0], [S - 1, 0], [S - 1, S - 1], [0, S - 1]][j]
    }

    /// Grid point `(x, y)` on its own.
    #[inline(always)]
    fn point(&mut self, x: usize, y: usize) {
        let columns = ring(&self.columns, self.head);
        combine(
            &Self::W[x],
            columns.map(|c| std::array::from_ref(&c[y])),
            std::array::from_mut(&mut self.grid[x][y]),
        );
    }

    /// Grid line `x`, points `1..S`, [`RUN`] at a time.
    #[inline(always)]
    fn line(&mut self, x: usize) {
        let runs = ring(&self.columns, self.head).map(|c| c[1..].as_chunks::<RUN>().0);
        let (out, _) = self.grid[x][1..].as_chunks_mut::<RUN>();
        for (k, out) in out.iter_mut().enumerate() {
            combine(&Self::W[x], runs.map(|r| &r[k]), out);
        }
    }

    /// `W` times control column `b` of `patch`, into its place in the ring.
    #[inline(always)]
    fn column<T: Primvar>(&mut self, control: &[T], patch: &Patch, b: usize) {
        let p: [[[f64; D]; 1]; 4] = std::array::from_fn(|a| {
            let mut value = [0.0; D];
            value.copy_from_slice(control[patch.points[4 * a + b] as usize].components());
            [value]
        });
        let column = &mut self.columns[(self.head + b) % 4];
        for (out, w) in column.iter_mut().zip(&Self::W) {
            combine(w, [&p[0], &p[1], &p[2], &p[3]], std::array::from_mut(out));
        }
    }
}

/// Control columns `0..4` of the current patch, in the ring `columns` that starts at `head`.
#[inline(always)]
fn ring<const D: usize, const S: usize>(
    columns: &[[[f64; D]; S]; 4],
    head: usize,
) -> [&[[f64; D]; S]; 4] {
    std::array::from_fn(|b| &columns[(head + b) % 4])
}

/// `out = Σ_k w[k] · values[k]` elementwise over the non-zero weights of `row`, in order of
/// `k`: a loop over three or four weights around straight-line, full-width arithmetic on `N`
/// points, whether or not the row is known at compile time.
#[inline(always)]
fn combine<const D: usize, const N: usize>(
    row: &Row,
    values: [&[[f64; D]; N]; 4],
    out: &mut [[f64; D]; N],
) {
    let Row { w, first, end } = *row;
    let mut sum = [[0.0; D]; N];
    for (s, v) in sum.iter_mut().zip(values[first]) {
        for (s, &v) in s.iter_mut().zip(v) {
            *s = w[first] * v;
        }
    }
    for k in first + 1..end {
        for (s, v) in sum.iter_mut().zip(values[k]) {
            for (s, &v) in s.iter_mut().zip(v) {
                *s += w[k] * v;
            }
        }
    }
    *out = sum;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_two_rows_skip_their_zeros() {
        let taps: Vec<(usize, usize)> =
            Row::table::<5>().iter().map(|r| (r.first, r.end)).collect();
        assert_eq!(taps, [(0, 3), (0, 3), (0, 4), (1, 4), (1, 4)]);
        for (row, w) in Row::table::<9>().iter().zip(bspline::span_weights(3)) {
            assert_eq!(row.w, w);
            assert!(
                w[..row.first]
                    .iter()
                    .chain(&w[row.end..])
                    .all(|&x| x == 0.0)
            );
            assert!(w[row.first..row.end].iter().all(|&x| x > 0.0));
        }
    }
}
