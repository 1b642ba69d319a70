//! Catmull-Clark subdivision of arbitrary polygon meshes, exact to OpenSubdiv 3.6.
//!
//! The crate follows OpenSubdiv's three layers (see `../shared/STYLE.md`):
//! - **rules** ([`rules`]): pure functions from a local configuration (valence, sharpness,
//!   boundary) to weights, after OpenSubdiv's `Sdc`;
//! - **topology** ([`topology`], [`refine`]): connectivity tables ([`csr`]) built once per mesh
//!   and per level, after `Vtr`;
//! - **evaluation** ([`stencil`], [`limit`], [`evaluator`]): sparse weights over the control
//!   points that turn a new frame's positions into the refined or limit surface, after `Far`,
//!   and B-spline patches (`patches`) that re-evaluate regular regions faster.
//!
//! The control mesh ([`Mesh`]) carries OpenSubdiv's tags (creases, corners, holes) and
//! [`Options`]; [`obj`] reads and writes it.
//!
//! A cube with one infinitely sharp edge, refined once and written back as OBJ:
//!
//! ```
//! use tailor_subdiv::{Refiner, obj};
//!
//! let cube = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
//!             f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n\
//!             t crease 2/1/0 0 1 10\n";
//! let mesh = obj::parse(cube, "cube.obj")?.mesh;
//! let refiner = Refiner::new(&mesh, 1);
//! let refined = refiner.refined_mesh(refiner.refine(mesh.positions()), None);
//! assert_eq!(refined.face_count(), 6 * 4);
//! // The sharp edge's point is its midpoint (a smooth edge's would move inwards).
//! let midpoint = tailor_subdiv::Point::new(0.5, 0.0, 0.0);
//! assert!(refined.positions().contains(&midpoint));
//! let mut text = Vec::new();
//! obj::write(&refined, None, obj::Precision::Single, &mut text)?;
//! assert!(text.starts_with(b"v "));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

#[cfg(feature = "conformance")]
pub mod conformance;
pub mod csr;
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
pub use stencil::{Refreshed, StencilTable};
