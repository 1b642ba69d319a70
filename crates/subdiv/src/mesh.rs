//! The control mesh: polygons of any size, their tags, and optional face-varying UVs.
//!
//! A [`Mesh`] is what an artist models: positions, faces as vertex loops (counter-clockwise seen
//! from outside), and OpenSubdiv's tags (edge creases, corner vertices, holes) plus the
//! [`Options`]. It is validated once when built, so every later stage can trust it: indices in
//! range, faces with at least three distinct vertices, finite coordinates, non-negative
//! sharpness. Everything is stored flat (CSR offsets) as the rest of the crate expects.
//!
//! Faces that use a vertex twice (`f 4 3 5 5`) are rejected by default: they are almost always
//! a modelling mistake. OpenSubdiv accepts them (`Vtr::Level::completeTopologyFromFaceVertices`
//! makes each repeated corner pair a *degenerate edge*, tagged non-manifold and so infinitely
//! sharp), and four of its regression shapes rely on it; [`Validation::allow_degenerate_faces`]
//! opts in to the same treatment (see [`crate::topology`]).

use std::collections::HashSet;

use nalgebra::{Point3, Vector2};

use crate::options::Options;

/// A point in space, in metres.
pub type Point = Point3<f64>;

/// A texture coordinate.
pub type Uv = Vector2<f64>;

/// Sharpness at or above this value is infinite (`Sdc::Crease::SHARPNESS_INFINITE`).
pub const SHARPNESS_INFINITE: f64 = 10.0;

/// Face-varying UVs: a table of values and, for every face corner, the index of its value.
///
/// Corners of neighbouring faces that share a vertex but not a value form a UV seam.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceVarying {
    /// The distinct UV values.
    pub values: Vec<Uv>,
    /// One value index per face corner, parallel to [`Mesh::face_vertices`].
    pub indices: Vec<u32>,
}

/// A sharp edge, named by its two end vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crease {
    /// The two end vertices, in either order.
    pub vertices: [u32; 2],
    /// Sharpness: 0 smooth, up to 10 (infinite).
    pub sharpness: f64,
}

/// A sharp vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// The vertex.
    pub vertex: u32,
    /// Sharpness: 0 smooth, up to 10 (infinite).
    pub sharpness: f64,
}

/// Why a set of polygons and tags is not a valid control mesh.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// There are no faces.
    #[error("the mesh has no faces")]
    Empty,
    /// A position has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinitePosition {
        /// 0-based vertex index.
        vertex: usize,
    },
    /// A UV has a NaN or infinite coordinate.
    #[error("texture coordinate {value} is not finite")]
    NonFiniteUv {
        /// 0-based UV value index.
        value: usize,
    },
    /// A face has fewer than three corners.
    #[error("face {face} has {corners} vertices; a face needs at least 3")]
    TooFewVertices {
        /// 0-based face index.
        face: usize,
        /// How many it has.
        corners: usize,
    },
    /// A face has more corners than local indices (`u16`, as in OpenSubdiv) can number.
    #[error("face {face} has {corners} vertices; a face may have at most 65536")]
    TooManyVertices {
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
    /// A face corner names a vertex that does not exist.
    #[error("face {face} names vertex {vertex}, but the mesh has {count} vertices")]
    VertexOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The vertex named.
        vertex: u32,
        /// How many vertices exist.
        count: usize,
    },
    /// A face corner names a UV that does not exist.
    #[error("face {face} names texture coordinate {value}, but the mesh has {count}")]
    UvOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The UV named.
        value: u32,
        /// How many UVs exist.
        count: usize,
    },
    /// UV indices do not cover every face corner.
    #[error("{given} texture-coordinate indices for {corners} face corners")]
    UvCountMismatch {
        /// How many were given.
        given: usize,
        /// How many face corners there are.
        corners: usize,
    },
    /// A tag names a vertex that does not exist.
    #[error("{tag} tag names vertex {vertex}, but the mesh has {count} vertices")]
    TagVertexOutOfRange {
        /// `crease` or `corner`.
        tag: &'static str,
        /// The vertex named.
        vertex: u32,
        /// How many vertices exist.
        count: usize,
    },
    /// A crease names two vertices that no face joins by an edge.
    #[error("crease tag names vertices {0} and {1}, which share no edge")]
    CreaseNotAnEdge(u32, u32),
    /// A hole tag names a face that does not exist.
    #[error("hole tag names face {face}, but the mesh has {count} faces")]
    HoleOutOfRange {
        /// The face named.
        face: u32,
        /// How many faces exist.
        count: usize,
    },
    /// A sharpness is negative or NaN.
    #[error("{tag} tag has sharpness {sharpness}; sharpness must be a number >= 0")]
    BadSharpness {
        /// `crease` or `corner`.
        tag: &'static str,
        /// The value given.
        sharpness: f64,
    },
}

/// What [`Mesh`] validation accepts beyond the strict rules.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Validation {
    /// Accept faces that use a vertex more than once, as OpenSubdiv does: consecutive equal
    /// corners form a degenerate edge, and every edge a face repeats is non-manifold (both
    /// infinitely sharp). Off by default: such a face is [`MeshError::RepeatedVertex`].
    pub allow_degenerate_faces: bool,
}

/// A validated Catmull-Clark control mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    positions: Vec<Point>,
    face_offsets: Vec<u32>,
    face_vertices: Vec<u32>,
    uvs: Option<FaceVarying>,
    creases: Vec<Crease>,
    corners: Vec<Corner>,
    holes: Vec<u32>,
    /// Subdivision options.
    pub options: Options,
}

impl Mesh {
    /// Builds a mesh from positions and faces (vertex loops), with no tags and default options.
    ///
    /// # Errors
    /// Any [`MeshError`] about positions or faces.
    pub fn from_polygons<F: AsRef<[u32]>>(
        positions: Vec<Point>,
        faces: &[F],
    ) -> Result<Self, MeshError> {
        let mut face_offsets = Vec::with_capacity(faces.len() + 1);
        let mut face_vertices = Vec::new();
        face_offsets.push(0);
        for f in faces {
            face_vertices.extend_from_slice(f.as_ref());
            face_offsets.push(to_u32(face_vertices.len()));
        }
        Self::from_flat(positions, face_offsets, face_vertices)
    }

    /// Builds a mesh from CSR face tables: face `f` is
    /// `face_vertices[face_offsets[f]..face_offsets[f + 1]]`.
    ///
    /// # Errors
    /// Any [`MeshError`] about positions or faces.
    pub fn from_flat(
        positions: Vec<Point>,
        face_offsets: Vec<u32>,
        face_vertices: Vec<u32>,
    ) -> Result<Self, MeshError> {
        Self::from_flat_with(
            positions,
            face_offsets,
            face_vertices,
            Validation::default(),
        )
    }

    /// As [`Self::from_flat`], accepting what `validation` allows.
    ///
    /// # Errors
    /// Any [`MeshError`] about positions or faces that `validation` does not allow.
    pub fn from_flat_with(
        positions: Vec<Point>,
        face_offsets: Vec<u32>,
        face_vertices: Vec<u32>,
        validation: Validation,
    ) -> Result<Self, MeshError> {
        let mesh = Self {
            positions,
            face_offsets,
            face_vertices,
            uvs: None,
            creases: Vec::new(),
            corners: Vec::new(),
            holes: Vec::new(),
            options: Options::default(),
        };
        mesh.validate_faces(validation)?;
        Ok(mesh)
    }

    fn validate_faces(&self, validation: Validation) -> Result<(), MeshError> {
        if self.face_count() == 0 {
            return Err(MeshError::Empty);
        }
        if let Some(vertex) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinitePosition { vertex });
        }
        let count = self.positions.len();
        for face in 0..self.face_count() {
            let fv = self.face(face);
            if fv.len() < 3 {
                return Err(MeshError::TooFewVertices {
                    face,
                    corners: fv.len(),
                });
            }
            if fv.len() > usize::from(u16::MAX) + 1 {
                return Err(MeshError::TooManyVertices {
                    face,
                    corners: fv.len(),
                });
            }
            for (i, &v) in fv.iter().enumerate() {
                if v as usize >= count {
                    return Err(MeshError::VertexOutOfRange {
                        face,
                        vertex: v,
                        count,
                    });
                }
                if !validation.allow_degenerate_faces && fv[..i].contains(&v) {
                    return Err(MeshError::RepeatedVertex { face, vertex: v });
                }
            }
        }
        Ok(())
    }

    /// Attaches face-varying UVs.
    ///
    /// # Errors
    /// [`MeshError::UvCountMismatch`], [`MeshError::UvOutOfRange`] or
    /// [`MeshError::NonFiniteUv`].
    pub fn with_uvs(mut self, uvs: FaceVarying) -> Result<Self, MeshError> {
        if uvs.indices.len() != self.face_vertices.len() {
            return Err(MeshError::UvCountMismatch {
                given: uvs.indices.len(),
                corners: self.face_vertices.len(),
            });
        }
        if let Some(value) = uvs
            .values
            .iter()
            .position(|uv| !uv.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteUv { value });
        }
        let count = uvs.values.len();
        for face in 0..self.face_count() {
            let range = self.face_range(face);
            if let Some(&value) = uvs.indices[range].iter().find(|&&i| i as usize >= count) {
                return Err(MeshError::UvOutOfRange { face, value, count });
            }
        }
        self.uvs = Some(uvs);
        Ok(self)
    }

    /// Sets the sharp edges. A later entry for the same edge replaces an earlier one.
    ///
    /// # Errors
    /// [`MeshError::TagVertexOutOfRange`], [`MeshError::BadSharpness`] or
    /// [`MeshError::CreaseNotAnEdge`].
    pub fn with_creases(mut self, creases: Vec<Crease>) -> Result<Self, MeshError> {
        let edges = self.edges_among(&creases);
        for c in &creases {
            check_sharpness("crease", c.sharpness)?;
            for v in c.vertices {
                self.check_tag_vertex("crease", v)?;
            }
            let [a, b] = c.vertices;
            if !edges.contains(&(a.min(b), a.max(b))) {
                return Err(MeshError::CreaseNotAnEdge(c.vertices[0], c.vertices[1]));
            }
        }
        self.creases = creases;
        Ok(self)
    }

    /// Sets the sharp vertices. A later entry for the same vertex replaces an earlier one.
    ///
    /// # Errors
    /// [`MeshError::TagVertexOutOfRange`] or [`MeshError::BadSharpness`].
    pub fn with_corners(mut self, corners: Vec<Corner>) -> Result<Self, MeshError> {
        for c in &corners {
            check_sharpness("corner", c.sharpness)?;
            self.check_tag_vertex("corner", c.vertex)?;
        }
        self.corners = corners;
        Ok(self)
    }

    /// Sets the hole faces: they stay in the topology but produce no surface.
    ///
    /// # Errors
    /// [`MeshError::HoleOutOfRange`].
    pub fn with_holes(mut self, holes: Vec<u32>) -> Result<Self, MeshError> {
        let count = self.face_count();
        if let Some(&face) = holes.iter().find(|&&f| f as usize >= count) {
            return Err(MeshError::HoleOutOfRange { face, count });
        }
        self.holes = holes;
        Ok(self)
    }

    /// Reverses the winding of every face, keeping its first corner first (how OpenSubdiv reads a
    /// left-handed mesh): face `[a, b, c, d]` becomes `[a, d, c, b]`, UV corners likewise.
    #[must_use]
    pub fn with_reversed_faces(mut self) -> Self {
        for f in 0..self.face_count() {
            let r = self.face_range(f);
            self.face_vertices[r.start + 1..r.end].reverse();
            if let Some(uvs) = &mut self.uvs {
                uvs.indices[r.start + 1..r.end].reverse();
            }
        }
        self
    }

    fn check_tag_vertex(&self, tag: &'static str, vertex: u32) -> Result<(), MeshError> {
        let count = self.positions.len();
        if vertex as usize >= count {
            return Err(MeshError::TagVertexOutOfRange { tag, vertex, count });
        }
        Ok(())
    }

    /// The vertex pairs of `creases` that are edges of a face, as (smaller, larger) pairs. One
    /// pass over the faces that looks up only the edges whose smaller vertex starts a crease
    /// pair, so a refined mesh with few creases (or none) costs a scan, not a set of all its
    /// edges.
    fn edges_among(&self, creases: &[Crease]) -> HashSet<(u32, u32)> {
        let pair = |p: u32, q: u32| (p.min(q), p.max(q));
        let wanted: HashSet<(u32, u32)> = creases
            .iter()
            .map(|c| pair(c.vertices[0], c.vertices[1]))
            .collect();
        if wanted.is_empty() {
            return wanted;
        }
        let mut starts = vec![false; self.positions.len()];
        for &(a, _) in &wanted {
            if let Some(start) = starts.get_mut(a as usize) {
                *start = true;
            }
        }
        let mut found = HashSet::new();
        for f in 0..self.face_count() {
            let fv = self.face(f);
            for (j, &p) in fv.iter().enumerate() {
                let edge = pair(p, fv[(j + 1) % fv.len()]);
                if starts[edge.0 as usize] && wanted.contains(&edge) {
                    found.insert(edge);
                }
            }
        }
        found
    }

    /// The control points.
    #[must_use]
    pub fn positions(&self) -> &[Point] {
        &self.positions
    }

    /// Replaces the control points, keeping the topology (the per-frame path of a cloth
    /// simulation).
    ///
    /// # Errors
    /// [`MeshError::NonFinitePosition`]; the count must not change (that is a programming error
    /// and panics).
    pub fn set_positions(&mut self, positions: &[Point]) -> Result<(), MeshError> {
        assert_eq!(
            positions.len(),
            self.positions.len(),
            "vertex count changed"
        );
        if let Some(vertex) = positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinitePosition { vertex });
        }
        self.positions.copy_from_slice(positions);
        Ok(())
    }

    /// Number of vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces (holes included).
    #[must_use]
    pub fn face_count(&self) -> usize {
        self.face_offsets.len().saturating_sub(1)
    }

    /// CSR offsets of the faces; `face_count() + 1` entries.
    #[must_use]
    pub fn face_offsets(&self) -> &[u32] {
        &self.face_offsets
    }

    /// All face corners, face after face.
    #[must_use]
    pub fn face_vertices(&self) -> &[u32] {
        &self.face_vertices
    }

    /// The corner range of face `f` in [`Self::face_vertices`].
    #[must_use]
    pub fn face_range(&self, f: usize) -> std::ops::Range<usize> {
        self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize
    }

    /// The vertex loop of face `f`.
    #[must_use]
    pub fn face(&self, f: usize) -> &[u32] {
        &self.face_vertices[self.face_range(f)]
    }

    /// Face-varying UVs, if any.
    #[must_use]
    pub fn uvs(&self) -> Option<&FaceVarying> {
        self.uvs.as_ref()
    }

    /// Drops the UVs.
    pub fn clear_uvs(&mut self) {
        self.uvs = None;
    }

    /// Sharp edges as tagged.
    #[must_use]
    pub fn creases(&self) -> &[Crease] {
        &self.creases
    }

    /// Sharp vertices as tagged.
    #[must_use]
    pub fn corners(&self) -> &[Corner] {
        &self.corners
    }

    /// Hole faces as tagged.
    #[must_use]
    pub fn holes(&self) -> &[u32] {
        &self.holes
    }
}

fn check_sharpness(tag: &'static str, sharpness: f64) -> Result<(), MeshError> {
    if sharpness >= 0.0 {
        Ok(())
    } else {
        Err(MeshError::BadSharpness { tag, sharpness })
    }
}

/// Converts a table size to the `u32` index type, which bounds meshes at 4 billion corners.
#[inline]
pub(crate) fn to_u32(n: usize) -> u32 {
    u32::try_from(n).expect("mesh larger than u32 indices allow")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Point> {
        vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(1.0, 1.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn rejects_bad_faces() {
        assert_eq!(
            Mesh::from_polygons(square(), &[[0u32, 1]]).unwrap_err(),
            MeshError::TooFewVertices {
                face: 0,
                corners: 2
            }
        );
        assert_eq!(
            Mesh::from_polygons(square(), &[[0u32, 1, 1]]).unwrap_err(),
            MeshError::RepeatedVertex { face: 0, vertex: 1 }
        );
        let allow = Validation {
            allow_degenerate_faces: true,
        };
        assert!(Mesh::from_flat_with(square(), vec![0, 4], vec![0, 1, 2, 2], allow).is_ok());
        assert_eq!(
            Mesh::from_polygons(square(), &[[0u32, 1, 4]]).unwrap_err(),
            MeshError::VertexOutOfRange {
                face: 0,
                vertex: 4,
                count: 4
            }
        );
        assert_eq!(
            Mesh::from_polygons(square(), &[] as &[[u32; 3]]).unwrap_err(),
            MeshError::Empty
        );
        let mut p = square();
        p[2].y = f64::NAN;
        assert_eq!(
            Mesh::from_polygons(p, &[[0u32, 1, 2, 3]]).unwrap_err(),
            MeshError::NonFinitePosition { vertex: 2 }
        );
    }

    #[test]
    fn rejects_bad_tags() {
        let m = Mesh::from_polygons(square(), &[[0u32, 1, 2, 3]]).unwrap();
        let crease = |a, b, s| Crease {
            vertices: [a, b],
            sharpness: s,
        };
        assert_eq!(
            m.clone().with_creases(vec![crease(0, 2, 1.0)]).unwrap_err(),
            MeshError::CreaseNotAnEdge(0, 2)
        );
        assert!(matches!(
            m.clone()
                .with_creases(vec![crease(0, 1, -1.0)])
                .unwrap_err(),
            MeshError::BadSharpness { .. }
        ));
        assert!(matches!(
            m.clone()
                .with_creases(vec![crease(0, 1, f64::NAN)])
                .unwrap_err(),
            MeshError::BadSharpness { .. }
        ));
        assert!(m.clone().with_creases(vec![crease(1, 0, 2.0)]).is_ok());
        assert_eq!(
            m.clone().with_holes(vec![1]).unwrap_err(),
            MeshError::HoleOutOfRange { face: 1, count: 1 }
        );
        assert!(matches!(
            m.with_corners(vec![Corner {
                vertex: 9,
                sharpness: 1.0
            }])
            .unwrap_err(),
            MeshError::TagVertexOutOfRange { vertex: 9, .. }
        ));
    }
}
