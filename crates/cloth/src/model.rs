//! The mass-spring model of a garment, built once from its control mesh.
//!
//! As in the paper (§5, "all the mass is concentrated at the control points"), the particles
//! are the control vertices. Masses are lumped from the rest area: each polygon's (vector) area
//! is split equally among its corners and multiplied by the area density, so refining a garment
//! does not make it heavier. The elements, all from the topology tables of
//! [`tailor_subdiv::topology::Level`]:
//! - a **spring** on every edge (stretch, eq. 4, and the lesson's damper, eq. 3);
//! - a **shear** element on every quad, over its two diagonals (eq. 5). Triangles get none:
//!   their three edge springs already fix their shape. Polygons of five or more sides get none
//!   either: the paper defines E_d for quads, and garments are modelled in quads;
//! - a **bend** element on every thread triple (the private `threads` module, eq. 6–7).
//!
//! Each element's stiffness is the material's modulus times its rest geometry (see
//! [`crate::material`]) times the mean of its vertices' multipliers for that energy: the paper
//! stiffened Geri's lapels and shoulder pads this way ([`Model::set_multipliers`]).

use tailor_subdiv::topology::Level;
use tailor_subdiv::{Mesh, Point};

use crate::energy::Vec3;
use crate::{ClothError, Material};

/// Which energy a per-vertex stiffness multiplier scales.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stiffness {
    /// Edge springs (stretch, compression and their damping).
    Stretch = 0,
    /// Quad diagonals.
    Shear = 1,
    /// Thread triples.
    Bend = 2,
}

/// Springs on edges.
#[derive(Clone, Debug, Default)]
pub(crate) struct Springs {
    pub verts: Vec<[u32; 2]>,
    pub rest: Vec<f64>,
    /// Area beside the edge (each face gives 2/n of its area to each of its n edges).
    pub area: Vec<f64>,
    /// Stretch and compression weights of E_s (J), and the damper k_d (N·s/m).
    pub stiffness: Vec<[f64; 3]>,
}

/// Shear elements on quads: corners p0..p3, diagonals p0 − p2 and p1 − p3.
#[derive(Clone, Debug, Default)]
pub(crate) struct Quads {
    pub verts: Vec<[u32; 4]>,
    pub rest: Vec<[f64; 2]>,
    pub area: Vec<f64>,
    /// Weight of E_d (J).
    pub stiffness: Vec<f64>,
}

/// Bend elements on thread triples.
#[derive(Clone, Debug, Default)]
pub(crate) struct Triples {
    pub verts: Vec<[u32; 3]>,
    /// e = Σ coef_a p_a = (p3 − p2)/L23 − (p2 − p1)/L12.
    pub coef: Vec<[f64; 3]>,
    /// C* = |e| at rest.
    pub rest: Vec<f64>,
    /// Area over squared length (dimensionless).
    pub shape: Vec<f64>,
    /// Weight of E_p (J).
    pub stiffness: Vec<f64>,
}

/// A garment's particles and elements. Topology and rest geometry are fixed at construction.
#[derive(Clone, Debug)]
pub struct Model {
    pub(crate) rest: Vec<Point>,
    pub(crate) mass: Vec<f64>,
    pub(crate) area: Vec<f64>,
    pub(crate) material: Material,
    pub(crate) springs: Springs,
    pub(crate) quads: Quads,
    pub(crate) triples: Triples,
    /// The control mesh's faces as CSR (offsets, corners), for the collision hierarchy.
    pub(crate) face_offsets: Vec<u32>,
    pub(crate) face_vertices: Vec<u32>,
    multipliers: [Vec<f64>; 3],
}

impl Model {
    /// Builds the model of `mesh` at rest in its current positions.
    ///
    /// # Errors
    /// [`ClothError::BadMaterial`], [`ClothError::NoMass`] for a vertex in no face (or only in
    /// faces of zero area), [`ClothError::ZeroRestLength`] for a collapsed edge or diagonal.
    pub fn new(mesh: &Mesh, material: &Material) -> Result<Self, ClothError> {
        material.validate()?;
        let level = Level::from_mesh(mesh);
        let rest = mesh.positions().to_vec();
        let n = rest.len();
        let face_area: Vec<f64> = (0..mesh.face_count())
            .map(|f| polygon_area(&rest, mesh.face(f)))
            .collect();
        let mut area = vec![0.0; n];
        for (f, &a) in face_area.iter().enumerate() {
            let corners = mesh.face(f);
            for &v in corners {
                area[v as usize] += a / corners.len() as f64;
            }
        }
        if let Some(vertex) = area.iter().position(|&a| a <= 0.0) {
            return Err(ClothError::NoMass { vertex });
        }
        let length = |a: u32, b: u32| -> Result<f64, ClothError> {
            let l = (rest[a as usize] - rest[b as usize]).norm();
            if l > 0.0 {
                Ok(l)
            } else {
                Err(ClothError::ZeroRestLength { a, b })
            }
        };
        let mut springs = Springs::default();
        for (e, &[a, b]) in level.edge_verts().iter().enumerate() {
            springs.verts.push([a, b]);
            springs.rest.push(length(a, b)?);
            let beside = level
                .edge_faces()
                .row(e)
                .iter()
                .map(|&f| 2.0 * face_area[f as usize] / mesh.face(f as usize).len() as f64);
            springs.area.push(beside.sum());
        }
        let mut quads = Quads::default();
        for (f, &a) in face_area.iter().enumerate() {
            if let &[p0, p1, p2, p3] = mesh.face(f) {
                quads.verts.push([p0, p1, p2, p3]);
                quads.rest.push([length(p0, p2)?, length(p1, p3)?]);
                quads.area.push(a);
            }
        }
        let mut triples = Triples::default();
        for [p1, p2, p3] in crate::threads::triples(&level) {
            let (l12, l23) = (length(p1, p2)?, length(p2, p3)?);
            let coef = [1.0 / l12, -(1.0 / l12 + 1.0 / l23), 1.0 / l23];
            let e = rest[p1 as usize].coords * coef[0]
                + rest[p2 as usize].coords * coef[1]
                + rest[p3 as usize].coords * coef[2];
            let edge_area = |a: u32, b: u32| {
                let edges = level.vert_edges().row(a as usize).iter();
                let edge = edges
                    .copied()
                    .find(|&e| level.other_end(e, a) == b)
                    .expect("thread edge");
                springs.area[edge as usize]
            };
            let mean_length = 0.5 * (l12 + l23);
            triples.verts.push([p1, p2, p3]);
            triples.coef.push(coef);
            triples.rest.push(e.norm());
            triples
                .shape
                .push(0.5 * (edge_area(p1, p2) + edge_area(p2, p3)) / (mean_length * mean_length));
        }
        let mass = area.iter().map(|a| a * material.density).collect();
        let mut model = Self {
            rest,
            mass,
            area,
            material: *material,
            springs,
            quads,
            triples,
            face_offsets: mesh.face_offsets().to_vec(),
            face_vertices: mesh.face_vertices().to_vec(),
            multipliers: [vec![1.0; n], vec![1.0; n], vec![1.0; n]],
        };
        model.update_stiffness();
        Ok(model)
    }

    /// Sets the per-vertex multipliers of one energy's stiffness (1 everywhere by default).
    /// Each element uses the mean over its vertices.
    ///
    /// # Errors
    /// [`ClothError::WrongLength`] or [`ClothError::BadMultiplier`].
    pub fn set_multipliers(&mut self, which: Stiffness, values: &[f64]) -> Result<(), ClothError> {
        if values.len() != self.vertex_count() {
            return Err(ClothError::WrongLength {
                what: "stiffness multipliers",
                given: values.len(),
                expected: self.vertex_count(),
            });
        }
        if let Some(vertex) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(ClothError::BadMultiplier {
                vertex,
                value: values[vertex],
            });
        }
        self.multipliers[which as usize].copy_from_slice(values);
        self.update_stiffness();
        Ok(())
    }

    /// The per-vertex multipliers of one energy's stiffness.
    #[must_use]
    pub fn multipliers(&self, which: Stiffness) -> &[f64] {
        &self.multipliers[which as usize]
    }

    fn mean<const N: usize>(&self, which: Stiffness, verts: &[u32; N]) -> f64 {
        let m = &self.multipliers[which as usize];
        verts.iter().map(|&v| m[v as usize]).sum::<f64>() / N as f64
    }

    fn update_stiffness(&mut self) {
        let mat = self.material;
        let s = &self.springs;
        let springs: Vec<[f64; 3]> = (0..s.verts.len())
            .map(|e| {
                let scale = self.mean(Stiffness::Stretch, &s.verts[e]) * s.area[e];
                let rest_stiffness = mat.stretch * scale / (s.rest[e] * s.rest[e]);
                [
                    mat.stretch * scale,
                    mat.compression * scale,
                    mat.damping * rest_stiffness,
                ]
            })
            .collect();
        let q = &self.quads;
        let quads = (0..q.verts.len())
            .map(|f| mat.shear * q.area[f] * self.mean(Stiffness::Shear, &q.verts[f]))
            .collect();
        let t = &self.triples;
        let triples = (0..t.verts.len())
            .map(|i| mat.bend * t.shape[i] * self.mean(Stiffness::Bend, &t.verts[i]))
            .collect();
        self.springs.stiffness = springs;
        self.quads.stiffness = quads;
        self.triples.stiffness = triples;
    }

    /// Number of particles (control vertices).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// Rest positions (the mesh's positions when the model was built).
    #[must_use]
    pub fn rest_positions(&self) -> &[Point] {
        &self.rest
    }

    /// Lumped masses, kg.
    #[must_use]
    pub fn masses(&self) -> &[f64] {
        &self.mass
    }

    /// Lumped rest areas, m² (mass over density; used for drag).
    #[must_use]
    pub fn areas(&self) -> &[f64] {
        &self.area
    }

    /// The material.
    #[must_use]
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// The edge springs' end vertices.
    #[must_use]
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.springs.verts
    }

    /// The edge springs' rest lengths, m.
    #[must_use]
    pub fn rest_lengths(&self) -> &[f64] {
        &self.springs.rest
    }

    /// The quads carrying shear elements.
    #[must_use]
    pub fn shear_quads(&self) -> &[[u32; 4]] {
        &self.quads.verts
    }

    /// The bend triples (p1, p2, p3), p2 in the middle.
    #[must_use]
    pub fn bend_triples(&self) -> &[[u32; 3]] {
        &self.triples.verts
    }

    /// Largest relative change of edge length, |l/L − 1|, at the given positions.
    #[must_use]
    pub fn max_strain(&self, positions: &[Point]) -> f64 {
        self.worst_edge(positions).map_or(0.0, |(_, strain)| strain)
    }

    /// The edge of [`Self::max_strain`] (its two vertices; the first of equals) and its
    /// strain, so a report can say where the cloth stretched. `None` when there is no edge
    /// or every strain is NaN.
    #[must_use]
    pub fn worst_edge(&self, positions: &[Point]) -> Option<([u32; 2], f64)> {
        let s = &self.springs;
        let mut worst = None;
        for (&[a, b], &l) in s.verts.iter().zip(&s.rest) {
            let strain = ((positions[a as usize] - positions[b as usize]).norm() / l - 1.0).abs();
            // NaN never compares greater, so it is skipped as `f64::max` skips it.
            if strain > worst.map_or(-1.0, |(_, w)| w) {
                worst = Some(([a, b], strain));
            }
        }
        worst
    }
}

/// Area of a polygon: half the norm of its vector area (exact for planar polygons, a
/// projection-independent estimate for skew ones).
fn polygon_area(positions: &[Point], corners: &[u32]) -> f64 {
    let first = positions[corners[0] as usize].coords;
    let mut twice: Vec3 = Vec3::zeros();
    for w in corners[1..].windows(2) {
        let (b, c) = (
            positions[w[0] as usize].coords,
            positions[w[1] as usize].coords,
        );
        twice += (b - first).cross(&(c - first));
    }
    0.5 * twice.norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::sheet;

    #[test]
    fn mass_is_density_times_area_at_any_resolution() {
        for n in [2, 5, 17] {
            let model = Model::new(&sheet(n, n, 2.0, 1.5), &Material::COTTON).unwrap();
            let total: f64 = model.masses().iter().sum();
            assert!((total - 0.15 * 3.0).abs() < 1e-12, "{n}: {total}");
        }
    }

    #[test]
    fn grid_stretch_stores_half_y_eps_squared_per_area() {
        // A regular grid: edge area is L², so the E_s weight of an interior edge is Y·L².
        let model = Model::new(&sheet(5, 5, 1.0, 1.0), &Material::COTTON).unwrap();
        let s = &model.springs;
        let interior = (0..s.verts.len()).find(|&e| (s.area[e] - 1.0 / 16.0).abs() < 1e-12);
        let e = interior.expect("an interior edge");
        assert!((s.stiffness[e][0] - 2.0e3 / 16.0).abs() < 1e-9);
        assert_eq!(model.shear_quads().len(), 16);
        assert_eq!(model.edges().len(), 40);
    }

    #[test]
    fn worst_edge_is_the_edge_of_max_strain() {
        let model = Model::new(&sheet(3, 3, 1.0, 1.0), &Material::COTTON).unwrap();
        let mut positions = model.rest_positions().to_vec();
        assert_eq!(model.worst_edge(&positions).map(|(_, s)| s), Some(0.0));
        // Corner vertex 0 pulled half an edge away from one neighbour: its other edge is
        // perpendicular and stretches only by √1.25 − 1.
        let corner = *model.edges().iter().find(|e| e.contains(&0)).unwrap();
        let other = corner[0] + corner[1];
        let pull = (positions[0] - positions[other as usize]) * 0.5;
        positions[0] += pull;
        let (edge, strain) = model.worst_edge(&positions).unwrap();
        assert_eq!(edge, corner);
        assert!((strain - 0.5).abs() < 1e-12);
        assert_eq!(model.max_strain(&positions), strain);
    }

    #[test]
    fn multipliers_scale_stiffness_and_are_validated() {
        let mut model = Model::new(&sheet(3, 3, 1.0, 1.0), &Material::COTTON).unwrap();
        let before = model.triples.stiffness.clone();
        model.set_multipliers(Stiffness::Bend, &[2.0; 9]).unwrap();
        for (a, b) in before.iter().zip(&model.triples.stiffness) {
            assert!((2.0 * a - b).abs() < 1e-15);
        }
        assert!(model.set_multipliers(Stiffness::Shear, &[1.0; 3]).is_err());
        let mut bad = [1.0; 9];
        bad[4] = f64::NAN;
        assert!(matches!(
            model.set_multipliers(Stiffness::Shear, &bad),
            Err(ClothError::BadMultiplier { vertex: 4, .. })
        ));
    }
}
