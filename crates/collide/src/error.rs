//! What can be wrong with the meshes and positions handed to the collision queries.
//!
//! Every entry point validates its input first, so no query panics on user data: indices out of
//! range, short faces, non-finite coordinates and position arrays of the wrong length all come
//! back as a [`CollideError`] naming the face or vertex to fix.

/// Why a mesh or a set of positions cannot be used for collision queries.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CollideError {
    /// The mesh has no faces.
    #[error("the mesh has no faces")]
    Empty,
    /// The face offsets do not describe a valid CSR table.
    #[error("face offsets must start at 0, never decrease and end at {corners} (the corner count)")]
    BadOffsets {
        /// How many face corners (`face_vertices.len()`) there are.
        corners: usize,
    },
    /// A face has fewer than three corners.
    #[error("face {face} has {corners} vertices; a face needs at least 3")]
    TooFewVertices {
        /// 0-based face index.
        face: usize,
        /// How many it has.
        corners: usize,
    },
    /// A face uses the same vertex twice.
    #[error("face {face} uses vertex {vertex} more than once")]
    RepeatedVertex {
        /// 0-based face index.
        face: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// A face names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but there are {count} positions")]
    VertexOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The vertex named.
        vertex: u32,
        /// How many positions were given.
        count: usize,
    },
    /// A position has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinitePosition {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// A query point has a NaN or infinite coordinate.
    #[error("query point {point} has a non-finite coordinate")]
    NonFiniteQuery {
        /// 0-based index among the query points.
        point: usize,
    },
    /// A distance, margin or thickness is negative or NaN.
    #[error("{what} is {value}; it must be a number >= 0")]
    BadDistance {
        /// Which parameter.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A position array does not match the mesh the hierarchy was built for.
    #[error("{given} positions given for a mesh of {expected} vertices")]
    PositionCount {
        /// How many vertices the mesh has.
        expected: usize,
        /// How many positions were given.
        given: usize,
    },
    /// A partial swept refit was asked of a hierarchy whose last refit was not swept.
    #[error("the ends of a swept refit were moved, but the last refit was not swept")]
    NotSwept,
    /// Inside/outside was asked of a mesh that does not enclose a volume.
    #[error("the mesh is not closed: {open_edges} edges do not have exactly two triangles")]
    NotClosed {
        /// How many triangle edges are on a boundary or shared by more than two triangles.
        open_edges: usize,
    },
}
