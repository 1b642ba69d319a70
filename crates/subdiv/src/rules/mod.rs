//! Subdivision rules: pure functions from a local configuration to weights, after OpenSubdiv's
//! `Sdc` layer. No mesh, no allocation beyond the mask being filled.
//!
//! - [`bspline`]: the uniform cubic B-spline curve rules that Catmull-Clark reduces to on a
//!   regular grid, as weights over a span;
//! - [`crease`]: sharpness values, their decay from level to level (uniform and Chaikin) and the
//!   vertex [`Rule`] they imply;
//! - [`masks`]: the Catmull-Clark refinement masks (face, edge and vertex points) with semi-sharp
//!   blending, and the limit position and tangent masks.
//!
//! The exact behaviour, including OpenSubdiv's single-precision sharpness arithmetic, is
//! documented in `../shared/reference/opensubdiv/RULES.md`.

pub mod bspline;
pub mod crease;
pub mod masks;

pub use crease::Rule;
pub use masks::Mask;
