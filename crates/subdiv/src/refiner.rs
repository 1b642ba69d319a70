//! Uniform refinement of a control mesh to a chosen level (`Far::TopologyRefiner` with
//! `RefineUniform`, plus `Far::PrimvarRefiner`).
//!
//! [`Refiner::new`] builds every level's topology once. Positions, UVs or any per-vertex field
//! are then refined level by level ([`Refiner::refine`]), or through a [`StencilTable`] built once
//! ([`Refiner::stencils`]), or an [`Evaluator`](crate::Evaluator) that also takes regular faces as B-spline
//! patches (`Evaluator::new(&refiner)`, as OpenSubdiv's factories take a refiner), when the same
//! topology is evaluated every frame.
//!
//! As in OpenSubdiv (`UniformOptions::fullTopologyInLastLevel`), evaluation needs only the last
//! level's faces and tags, not its edges and incidences, which are most of its cost:
//! [`Refiner::for_evaluation`] builds that minimal last level (about 40% of the time and memory
//! of a complete one at level 2) and completes it only if a method needs it.

use std::sync::OnceLock;

use nalgebra::Vector3;

use crate::fvar::FVarRefiner;
use crate::limit::LimitMasks;
use crate::mesh::{Corner, Crease, FaceVarying, Mesh, Point, Uv, Validation};
use crate::options::{BoundaryInterpolation, Options};
use crate::refine::Refinement;
use crate::rules::crease;
use crate::sparse::Primvar;
use crate::stencil::StencilTable;
use crate::topology::Level;

/// The topology of every level of a uniform refinement.
#[derive(Clone, Debug)]
pub struct Refiner {
    options: Options,
    base: Level,
    steps: Vec<Refinement>,
    /// The last level with every relation, when the last step built faces and tags only.
    full_last: OnceLock<Level>,
    fvar: Option<FVarRefiner>,
}

impl Refiner {
    /// Builds the topology of `levels` uniform refinements of `mesh`, every level complete
    /// (OpenSubdiv's `fullTopologyInLastLevel`).
    #[must_use]
    pub fn new(mesh: &Mesh, levels: usize) -> Self {
        Self::build(mesh, levels, true)
    }

    /// Builds the topology of `levels` uniform refinements of `mesh` for evaluation: the last
    /// level gets its faces and tags only, which is all [`Self::refine`] and [`Self::stencils`]
    /// read (OpenSubdiv's default minimal last level), saving most of its time and memory.
    /// The other methods give the same results as with [`Self::new`]; those that need the
    /// last level's other relations ([`Self::last`], limits, [`Self::refined_mesh`]) complete
    /// a copy of it on first use. A mesh with UVs gets the full last level up front, which its
    /// face-varying refinement needs.
    #[must_use]
    pub fn for_evaluation(mesh: &Mesh, levels: usize) -> Self {
        Self::build(mesh, levels, mesh.uvs().is_some())
    }

    fn build(mesh: &Mesh, levels: usize, full_last: bool) -> Self {
        let options = mesh.options;
        let base = Level::from_mesh(mesh);
        let mut steps: Vec<Refinement> = Vec::with_capacity(levels);
        for l in 0..levels {
            let parent = steps.last().map_or(&base, |s| &s.child);
            let full = full_last || l + 1 < levels;
            steps.push(Refinement::with_topology(parent, &options, full));
        }
        let fvar = mesh
            .uvs()
            .map(|uvs| FVarRefiner::new(mesh, uvs, &base, &steps));
        Self {
            options,
            base,
            steps,
            full_last: OnceLock::new(),
            fvar,
        }
    }

    /// Refines the control mesh's UVs (or other values with the same indices) to the last
    /// level; `None` when the mesh has no UVs.
    ///
    /// # Panics
    /// If `control` does not have as many values as the mesh's UVs.
    #[must_use]
    pub fn refine_uvs(&self, control: &[Uv]) -> Option<FaceVarying> {
        self.fvar.as_ref().map(|f| f.refine(control))
    }

    /// The limit of UVs refined by [`Self::refine_uvs`]; `None` when the mesh has no UVs.
    #[must_use]
    pub fn limit_uvs(&self, refined: &FaceVarying) -> Option<FaceVarying> {
        self.fvar.as_ref().map(|f| f.limit(self.last(), refined))
    }

    /// Number of refinement levels.
    #[must_use]
    pub fn levels(&self) -> usize {
        self.steps.len()
    }

    /// The topology of level `l` (0 is the control mesh), complete.
    #[must_use]
    pub fn level(&self, l: usize) -> &Level {
        if l == self.levels() {
            self.last()
        } else {
            self.parent_level(l)
        }
    }

    /// Level `l` as stored: complete below the last level, perhaps faces and tags only there.
    fn parent_level(&self, l: usize) -> &Level {
        if l == 0 {
            &self.base
        } else {
            &self.steps[l - 1].child
        }
    }

    /// The last level, complete (built on first call after [`Self::for_evaluation`]).
    #[must_use]
    pub fn last(&self) -> &Level {
        match self.steps.split_last() {
            None => &self.base,
            Some((step, _)) if step.has_full_child() => &step.child,
            Some((step, _)) => self
                .full_last
                .get_or_init(|| step.full_child(self.parent_level(self.levels() - 1))),
        }
    }

    /// The refinement steps, level 0→1 first. After [`Self::for_evaluation`] the last step's
    /// child has faces and tags only; [`Self::last`] is the complete last level.
    #[must_use]
    pub fn steps(&self) -> &[Refinement] {
        &self.steps
    }

    /// Refines per-vertex values (positions, scalar fields) to the last level, level by level.
    #[must_use]
    pub fn refine<T: Primvar>(&self, control: &[T]) -> Vec<T> {
        let mut current = control.to_vec();
        for (l, step) in self.steps.iter().enumerate() {
            let mut next = vec![T::zero(); step.child.vertex_count];
            step.apply(self.parent_level(l), &current, &mut next);
            current = next;
        }
        current
    }

    /// Stencils of the last level's vertices over the control points.
    #[must_use]
    pub fn stencils(&self) -> StencilTable {
        let mut table = StencilTable::identity(self.base.vertex_count);
        for (l, step) in self.steps.iter().enumerate() {
            table = table.refine(self.parent_level(l), step);
        }
        table
    }

    /// Stencils of the limit positions and tangents of the last level's vertices over the
    /// control points: evaluate with [`StencilTable::apply`] and take
    /// [`crate::limit::normal`] of the two tangents.
    #[must_use]
    pub fn limit_stencils(&self) -> [StencilTable; 3] {
        let refined = self.stencils();
        let masks = self.limit_masks();
        [
            refined.then(&masks.position),
            refined.then(&masks.tangent1),
            refined.then(&masks.tangent2),
        ]
    }

    /// Limit masks of the last level's vertices over that level's vertices.
    #[must_use]
    pub fn limit_masks(&self) -> LimitMasks {
        LimitMasks::new(self.last())
    }

    /// The last level as a mesh: refined positions, quads (holes tagged), the sharpness that
    /// remains after refinement, refined UVs, and the control mesh's options.
    ///
    /// # Panics
    /// If `positions` is not the last level's vertex count.
    #[must_use]
    pub fn refined_mesh(&self, positions: Vec<Point>, uvs: Option<FaceVarying>) -> Mesh {
        // The last level as built, faces and tags only after `for_evaluation`: enough for the
        // mesh and its creases; a complete one is built only for corners when boundary
        // corners are interpolated (which tell topological corners apart).
        let corner_option = self.options.boundary == BoundaryInterpolation::EdgeAndCorner;
        let (level, creases) = match self.steps.split_last() {
            Some((step, _)) if !step.has_full_child() && !corner_option => {
                let parent = self.parent_level(self.levels() - 1);
                (&step.child, step.child_creases(parent))
            }
            _ => {
                let level = self.last();
                let creases = (0..level.edge_count())
                    .filter(|&e| {
                        crease::is_sharp(level.edge_sharpness[e])
                            && !level.is_boundary_edge(e)
                            && !level.edge_nonmanifold[e]
                    })
                    .map(|e| (level.edge_verts[e], level.edge_sharpness[e]))
                    .collect();
                (level, creases)
            }
        };
        assert_eq!(positions.len(), level.vertex_count);
        // Level 0 may keep the control mesh's degenerate faces; refined levels have none.
        let mut mesh = Mesh::from_flat_with(
            positions,
            level.face_verts.offsets.clone(),
            level.face_verts.items.clone(),
            Validation {
                allow_degenerate_faces: true,
            },
        )
        .expect("refined topology is valid");
        mesh.options = self.options;
        let creases = creases
            .into_iter()
            .map(|(vertices, sharpness)| Crease {
                vertices,
                sharpness: f64::from(sharpness),
            })
            .collect();
        let corners = (0..level.vertex_count)
            .filter(|&v| {
                let topological_corner =
                    || level.vert_faces.range(v).len() == 1 && level.vert_edges.range(v).len() == 2;
                crease::is_sharp(level.vertex_sharpness[v])
                    && !level.vertex_nonmanifold[v]
                    && !(corner_option && topological_corner())
            })
            .map(|v| Corner {
                vertex: crate::mesh::to_u32(v),
                sharpness: f64::from(level.vertex_sharpness[v]),
            })
            .collect();
        let holes = (0..level.face_count())
            .filter(|&f| level.face_hole[f])
            .map(crate::mesh::to_u32)
            .collect();
        let mut mesh = mesh
            .with_creases(creases)
            .and_then(|m| m.with_corners(corners))
            .and_then(|m| m.with_holes(holes))
            .expect("refined tags are valid");
        if let Some(uvs) = uvs {
            mesh = mesh.with_uvs(uvs).expect("refined UVs are valid");
        }
        mesh
    }
}

/// The limit surface at the refined vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct Limit {
    /// Limit position of every refined vertex.
    pub positions: Vec<Point>,
    /// Unit limit normal of every refined vertex (zero where the surface has no tangent plane).
    pub normals: Vec<Vector3<f64>>,
    /// Limit UVs, laid out as the refined UVs; `None` without UVs.
    pub uvs: Option<FaceVarying>,
}

/// Refines a mesh's positions and UVs to `levels`, and evaluates the limit surface at the
/// refined vertices when `limit` is set.
#[must_use]
pub fn subdivide(mesh: &Mesh, levels: usize, limit: bool) -> (Mesh, Option<Limit>) {
    let refiner = Refiner::for_evaluation(mesh, levels);
    let positions = refiner.refine(mesh.positions());
    let uvs = mesh.uvs().and_then(|uvs| refiner.refine_uvs(&uvs.values));
    let limit = limit.then(|| {
        let coords: Vec<Vector3<f64>> = positions.iter().map(|p| p.coords).collect();
        let (pos, normals) = refiner.limit_masks().evaluate(&coords);
        Limit {
            positions: pos.into_iter().map(Point::from).collect(),
            normals,
            uvs: uvs.as_ref().and_then(|uvs| refiner.limit_uvs(uvs)),
        }
    });
    (refiner.refined_mesh(positions, uvs), limit)
}
