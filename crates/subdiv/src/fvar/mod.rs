//! Face-varying data (UVs) refined exactly as OpenSubdiv 3.6 refines it, in all six
//! [`FVarLinear`](crate::FVarLinear) modes.
//!
//! Face-varying values live on face corners, not vertices: where neighbouring faces use
//! different values at a shared vertex the UV layout has a seam, and each side is refined on its
//! own. OpenSubdiv (`Vtr::FVarLevel`, `Vtr::FVarRefinement`, `Far::PrimvarRefiner::
//! InterpolateFaceVarying`; sources `opensubdiv/vtr/fvarLevel.cpp`, `fvarRefinement.cpp`,
//! `far/primvarRefiner.h`) does it in three parts, mirrored here:
//! - `level`: the base level's value topology: values per vertex ("siblings"), seams, which
//!   values no longer match their vertex's topology and how each is treated (corner, crease,
//!   semi-sharp, dependent-sharp), as the interpolation mode dictates;
//! - `child`: the child level's value topology, inherited from the parent's;
//! - `weights`: the weight of every child value over the parent values, applied like a
//!   vertex refinement step;
//! - `limit`: limit values of the last level.
//!
//! Where a value matches its vertex, it is refined with the vertex's own mask, so a mesh
//! without seams in mode `None` refines UVs exactly as it refines positions. Values are numbered
//! as OpenSubdiv numbers them: per child vertex in child-vertex order (vertex points, face
//! points, edge points), that vertex's values consecutively.

mod child;
mod level;
mod limit;
mod weights;

use crate::mesh::{FaceVarying, Mesh, Uv};
use crate::refine::{ChildLayout, Refinement, apply_two_phase};
use crate::sparse::SparseRows;
use crate::topology::Level;
use level::{FVarLevel, Mode};

/// Face-varying refinement of one topology: per-step weight tables built once, applied to any
/// set of control values with the same indices.
#[derive(Clone, Debug)]
pub struct FVarRefiner {
    control_values: usize,
    steps: Vec<(SparseRows, ChildLayout)>,
    last: FVarLevel,
    linear: bool,
}

impl FVarRefiner {
    /// Builds the tables for `uvs` on `mesh` (whose options choose the mode), given the base
    /// level and the refinement steps of [`crate::Refiner`].
    ///
    /// # Panics
    /// If `uvs` does not have one index per face corner of `base`.
    #[must_use]
    pub fn new(mesh: &Mesh, uvs: &FaceVarying, base: &Level, steps: &[Refinement]) -> Self {
        assert_eq!(
            uvs.indices.len(),
            base.face_verts.items.len(),
            "one UV per corner"
        );
        let mode = Mode::new(&mesh.options);
        let mut fvar = FVarLevel::base(base, uvs, &mode);
        let mut tables = Vec::with_capacity(steps.len());
        let mut parent = base;
        for refinement in steps {
            let child = fvar.refine(parent, refinement, &mode);
            let step = weights::Step {
                parent,
                refinement,
                parent_fvar: &fvar,
                child_fvar: &child,
                mode,
                method: mesh.options.crease_method,
            };
            tables.push((step.weights(), step.layout()));
            fvar = child;
            parent = &refinement.child;
        }
        Self {
            control_values: uvs.values.len(),
            steps: tables,
            last: fvar,
            linear: mode.linear,
        }
    }

    /// Number of values of the last level.
    #[must_use]
    pub fn value_count(&self) -> usize {
        self.steps
            .last()
            .map_or(self.control_values, |(w, _)| w.rows())
    }

    /// Refines `control` (the control mesh's values, indexed as the [`FaceVarying`] given to
    /// [`Self::new`]) to the last level: its values and one index per face corner, faces in
    /// level order.
    ///
    /// # Panics
    /// If `control` does not have as many values as the control mesh's UVs.
    #[must_use]
    pub fn refine(&self, control: &[Uv]) -> FaceVarying {
        assert_eq!(control.len(), self.control_values, "control value count");
        let mut current = control.to_vec();
        for (weights, layout) in &self.steps {
            let mut next = vec![Uv::zeros(); weights.rows()];
            apply_two_phase(weights, *layout, &current, &mut next);
            current = next;
        }
        FaceVarying {
            values: current,
            indices: self.last.face_values.clone(),
        }
    }

    /// Moves refined values (from [`Self::refine`]) to their limit; `last` is the last level
    /// of the refinement these tables were built for.
    ///
    /// # Panics
    /// If `refined` is not this refinement's last level of values.
    #[must_use]
    pub fn limit(&self, last: &Level, refined: &FaceVarying) -> FaceVarying {
        assert_eq!(
            refined.values.len(),
            self.value_count(),
            "refined value count"
        );
        let weights = self.last.limit_weights(last, self.linear);
        let mut values = vec![Uv::zeros(); weights.rows()];
        weights.apply(&refined.values, &mut values);
        FaceVarying {
            values,
            indices: refined.indices.clone(),
        }
    }
}
