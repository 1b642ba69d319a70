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
//! its four control columns (`W P`), then computes each point it writes as a row of `W P`
//! times a row of `W`: four products per point instead of ten. Faces come in the order of the
//! control mesh; when a quad follows its left neighbour, the same way round (the common case in
//! a grid-like garment), three of its columns are the neighbour's and only one is gathered and
//! refined. At level 1 a quad owns three points, too few to pay for its 16 gathers, so there (and
//! above level 4) the evaluator applies the stencil table as it is.
//!
//! Each refined point has one writer: a control vertex's vertex point its stencil row; a point
//! inside a regular quad, or on an edge that first appears in a regular quad, that quad; any
//! other point its stencil row. Writers are grouped in fixed runs of faces that own disjoint
//! ranges of the output, so evaluation is parallel, and every point is computed by the same
//! arithmetic whatever the thread count. Results equal the stencil table's to rounding (about
//! 1e-16 relative; the tests hold them to 1e-12).

use rayon::prelude::*;

use crate::patches::{Patch, RegularPatches};
use crate::refiner::Refiner;
use crate::sparse::{Primvar, SharedRows, apply_rows, weighted_sum};
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
                last.child.vertex_count,
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
        let rows = &self.stencils.rows;
        match control.first().map_or(0, |c| c.components().len()) {
            1 => by_level::<T, 1>(patches, rows, control, out),
            2 => by_level::<T, 2>(patches, rows, control, out),
            3 => by_level::<T, 3>(patches, rows, control, out),
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
fn by_level<T: Primvar, const D: usize>(
    p: &RegularPatches,
    rows: &SharedRows,
    control: &[T],
    out: &mut [T],
) {
    match p.levels {
        2 => apply_patches::<T, D, 5>(p, rows, control, out),
        3 => apply_patches::<T, D, 9>(p, rows, control, out),
        4 => apply_patches::<T, D, 17>(p, rows, control, out),
        _ => unreachable!("patches are built for levels 2 to 4"),
    }
}

/// Evaluates values of `D` components with patches whose grids have `S` points a side
/// (`S = 2^levels + 1`).
fn apply_patches<T: Primvar, const D: usize, const S: usize>(
    p: &RegularPatches,
    rows: &SharedRows,
    control: &[T],
    out: &mut [T],
) {
    let weights: &[[f64; 4]; S] = p.weights.as_slice().try_into().expect("S = 2^levels + 1");
    let (vertex_points, mut rest) = out.split_at_mut(p.segments[1].start);
    // Cut every face and edge segment into the runs' ranges, run-major.
    let segments = &p.segments[1..];
    let runs = p.chunks.len() - 1;
    let mut pieces: Vec<&mut [T]> = (0..runs * segments.len()).map(|_| &mut [][..]).collect();
    for (s, seg) in segments.iter().enumerate() {
        for (c, run) in p.chunks.windows(2).enumerate() {
            let len = seg.block(run[1].index(seg.owner)) - seg.block(run[0].index(seg.owner));
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut(len);
            pieces[c * segments.len() + s] = piece;
            rest = tail;
        }
    }
    rayon::join(
        || apply_rows(vertex_points.len(), |i| rows.row(i), control, vertex_points),
        || {
            pieces
                .par_chunks_mut(segments.len())
                .enumerate()
                .for_each(|(c, slices)| {
                    let (lo, hi) = (&p.chunks[c], &p.chunks[c + 1]);
                    let mut kernel = Kernel::<D, S>::new(weights);
                    for patch in &p.patches[lo.patch as usize..hi.patch as usize] {
                        kernel.columns(control, patch);
                        p.patch_blocks(lo, patch, |s, start, points| {
                            let block = &mut slices[s][start..start + points.len()];
                            for (out, &[x, y]) in block.iter_mut().zip(points) {
                                let point = kernel.point(usize::from(x), usize::from(y));
                                out.components_mut().copy_from_slice(&point);
                            }
                        });
                    }
                    // The rest of the run's points, in increasing order, from their rows.
                    let mut s = 0;
                    for &i in &p.irregular[lo.irregular as usize..hi.irregular as usize] {
                        let i = i as usize;
                        while i >= segments[s].block(hi.index(segments[s].owner)) {
                            s += 1;
                        }
                        let start = segments[s].block(lo.index(segments[s].owner));
                        slices[s][i - start] = weighted_sum(rows.row(i), control);
                    }
                });
        },
    );
}

/// Evaluates patches one after another: `W P Wᵀ` for a patch's 4 × 4 control points `P` and
/// the 1D rule `W` (`S × 4`), control columns first (`W P`, kept), then each point written
/// (a row of `W P` times a row of `W`). A patch that follows its neighbour across edge 3
/// shares three control columns with it, so only its new column is gathered and refined.
/// Plain loops over small arrays of `D` numbers, which the compiler unrolls and keeps in
/// registers.
struct Kernel<'a, const D: usize, const S: usize> {
    w: &'a [[f64; 4]; S],
    /// `W P` by control column: `columns[b][y]`.
    columns: [[[f64; D]; S]; 4],
}

impl<'a, const D: usize, const S: usize> Kernel<'a, D, S> {
    fn new(w: &'a [[f64; 4]; S]) -> Self {
        Self {
            w,
            columns: [[[0.0; D]; S]; 4],
        }
    }

    /// Makes `W P` for `patch`.
    #[inline]
    fn columns<T: Primvar>(&mut self, control: &[T], patch: &Patch) {
        if patch.follows {
            self.columns.copy_within(1..4, 0);
            self.column(control, patch, 3);
        } else {
            for b in 0..4 {
                self.column(control, patch, b);
            }
        }
    }

    /// `W` times control column `b` of `patch`.
    #[inline]
    fn column<T: Primvar>(&mut self, control: &[T], patch: &Patch, b: usize) {
        let mut p = [[0.0; D]; 4];
        for (a, value) in p.iter_mut().enumerate() {
            value.copy_from_slice(control[patch.points[4 * a + b] as usize].components());
        }
        for (out, w) in self.columns[b].iter_mut().zip(self.w) {
            let mut value = [0.0; D];
            for (pa, &wa) in p.iter().zip(w) {
                for c in 0..D {
                    value[c] += wa * pa[c];
                }
            }
            *out = value;
        }
    }

    /// Refined point (x, y) of the current patch.
    #[inline]
    fn point(&self, x: usize, y: usize) -> [f64; D] {
        let w = &self.w[x];
        let [a, b, c, d] = [0, 1, 2, 3].map(|k| &self.columns[k][y]);
        let mut point = [0.0; D];
        for (k, p) in point.iter_mut().enumerate() {
            *p = w[0] * a[k] + w[1] * b[k] + w[2] * c[k] + w[3] * d[k];
        }
        point
    }
}
