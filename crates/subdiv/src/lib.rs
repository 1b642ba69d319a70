//! Catmull-Clark subdivision of arbitrary polygon meshes, exact to OpenSubdiv 3.6.
//!
//! The crate follows OpenSubdiv's three layers (see `../shared/STYLE.md`):
//! - **rules** ([`rules`]): pure functions from a local configuration (valence, sharpness,
//!   boundary) to weights, after OpenSubdiv's `Sdc`;
//! - **topology** ([`topology`], [`refine`]): connectivity tables built once per mesh and per
//!   level, after `Vtr`;
//! - **evaluation** ([`stencil`], [`limit`], [`evaluator`]): sparse weights over the control
//!   points that turn a new frame's positions into the refined or limit surface, after `Far`,
//!   and B-spline patches (`patches`) that re-evaluate regular regions faster.
//!
//! The control mesh ([`Mesh`]) carries OpenSubdiv's tags (creases, corners, holes) and
//! [`Options`]; [`obj`] reads and writes it.
#![warn(missing_docs)]

pub mod conformance;
pub mod evaluator;
pub mod fvar;
pub mod limit;
pub mod mesh;
pub mod obj;
pub mod options;
mod patches;
pub mod refine;
pub mod refiner;
pub mod rules;
pub mod sparse;
pub mod stencil;
pub mod topology;

pub use evaluator::Evaluator;
pub use mesh::{
    Corner, Crease, FaceVarying, Mesh, MeshError, Point, SHARPNESS_INFINITE, Uv, Validation,
};
pub use options::{BoundaryInterpolation, CreaseMethod, FVarLinear, Options, TriangleRule};
pub use refiner::{Limit, Refiner, subdivide};
pub use sparse::{Primvar, SharedRows, SparseRows};
pub use stencil::StencilTable;
