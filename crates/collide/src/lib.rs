//! Collision detection for cloth over polygon meshes, after the coarsening hierarchies of
//! DeRose, Kass & Truong, "Subdivision Surfaces in Character Animation" (SIGGRAPH 1998, §5).
//!
//! A [`Hierarchy`] is built once per mesh topology: faces are the leaves, and adjacent faces are
//! merged pairwise into superfaces, level by level, until one root remains. Every step the
//! animation moves the vertices, so the boxes are refit bottom-up ([`Hierarchy::refit`],
//! [`Hierarchy::refit_swept`]) without touching the tree. Queries then run in parallel over query
//! points or over subtrees, and their results do not depend on the number of threads:
//!
//! - proximity ([`Hierarchy::closest_points`], [`Hierarchy::faces_within`],
//!   [`Hierarchy::self_proximity`], [`Hierarchy::edge_proximity`]) for repulsion and for the
//!   body's inside test ([`Hierarchy::signed_distances`]), with the faces around each vertex on
//!   the surface ([`Hierarchy::local_faces`]) for repulsion to leave alone, and the points a
//!   caller need not measure again as the mesh and they move ([`DistanceBounds`]);
//! - exact triangle–triangle crossings ([`Hierarchy::self_intersections`]);
//! - continuous collisions over a step ([`Hierarchy::self_impacts`], [`Hierarchy::impacts_with`],
//!   and [`Hierarchy::vertex_impacts_with`] for the vertex–triangle part alone), after Bridson,
//!   Fedkiw & Anderson 2002.
//!
//! The queries a simulation runs every step also come as `_into` variants
//! ([`Hierarchy::closest_points_into`], [`Hierarchy::self_impacts_into`], …) that refill a
//! buffer the caller keeps from step to step instead of allocating the answer. The hierarchy
//! itself takes memory linear in the faces ([`Hierarchy::memory_bytes`]).
//!
//! Self-collision queries skip every superface whose normals fit in a cone narrower than a
//! half-space and whose boundary does not fold back (Volino & Magnenat-Thalmann 1994, Provot
//! 1997), so a smooth sheet costs almost nothing. Polygons are fan-triangulated for the exact
//! tests. Positions are [`Point`]s (nalgebra); parry3d-f64 supplies the triangle projection and
//! the boxes, and the conversion to its glam types lives in one private module.
//!
//! A hierarchy over one square, built once, asked for the nearest point of a query within
//! a distance, refit after the square moves, and asked again:
//!
//! ```
//! use tailor_collide::{Hierarchy, Point};
//!
//! let mut square = [
//!     Point::new(0.0, 0.0, 0.0),
//!     Point::new(1.0, 0.0, 0.0),
//!     Point::new(1.0, 1.0, 0.0),
//!     Point::new(0.0, 1.0, 0.0),
//! ];
//! let mut hierarchy = Hierarchy::build(&square, &[0, 4], &[0, 1, 2, 3])?;
//! let query = [Point::new(0.25, 0.5, 0.2)];
//! let near = hierarchy.closest_points(&query, 1.0)?[0].expect("within 1 m");
//! assert!((near.distance - 0.2).abs() < 1e-12);
//! for p in &mut square {
//!     p.z -= 0.3;
//! }
//! hierarchy.refit(&square, 0.0)?;
//! let near = hierarchy.closest_points(&query, 1.0)?[0].expect("within 1 m");
//! assert!((near.distance - 0.5).abs() < 1e-12);
//! assert!(hierarchy.closest_points(&query, 0.4)?[0].is_none());
//! # Ok::<(), tailor_collide::CollideError>(())
//! ```
#![warn(missing_docs)]

mod ccd;
mod cones;
mod continuous;
mod convert;
mod distance_bounds;
mod edges;
mod error;
mod hierarchy;
mod inside;
mod intersect;
mod local;
mod memory;
mod proximity;
mod topology;
mod traverse;
mod triangle;

pub use ccd::{edge_edge_impact, vertex_triangle_impact};
pub use continuous::{EdgeEdgeImpact, Impacts, VertexTriangleImpact};
pub use distance_bounds::{DistanceBounds, same_bits};
pub use edges::{EdgeProximity, segments_closest_points};
pub use error::CollideError;
pub use hierarchy::Hierarchy;
pub use proximity::{Closest, LocalFaces, Neighbours};
pub use triangle::{triangles_apart, triangles_intersect};

/// A point in space, in metres.
pub type Point = nalgebra::Point3<f64>;

/// A direction or displacement.
pub type Vector = nalgebra::Vector3<f64>;
