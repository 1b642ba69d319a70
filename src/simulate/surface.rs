//! Refined surfaces evaluated every frame through an [`Evaluator`] built once (OpenSubdiv's
//! `Far` split: topology once, per frame bicubic patches on regular faces and a sparse gather
//! of stencil rows elsewhere), with the collision hierarchy that `tailor check`'s test and the
//! attachments query.
//!
//! Both the garment (for `cloth_####.obj`) and the body (for attachment, collision and the
//! check) are Catmull-Clark control meshes. The body is refined to `[body] subdivision_level`,
//! 2 by default: 16 quads per control quad (7168 for the mannequin), and the surface the
//! garments in `assets/` are modelled against (1–2 cm off it, `assets/README.md`). Level 1
//! is a quarter of the work but lies further from the limit surface a renderer shows, so cloth
//! resting on it would float off (or sink into) the rendered body where it curves.
//!
//! What `tailor check`'s test finds on the garment's refined surface is fixed on its control
//! mesh, so a surface also says which control vertex a refined vertex follows most (its
//! stencil's largest weight) and which control face a refined face lies in (from the order in
//! which uniform refinement numbers its faces).

use std::io::{self, Write};
use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::Vector3;
use tailor_collide::{Hierarchy, triangles_apart, triangles_intersect};
use tailor_subdiv::obj::{Frames, Precision};
use tailor_subdiv::{Evaluator, Mesh, Point, Refiner, StencilTable};

use crate::output::write_atomically;

/// How many times [`Surface::round_crossings_apart`] rounds the crossing faces apart and
/// looks again; a corner two pairs want rounded opposite ways is settled by the next try.
const ROUNDING_APART_TRIES: usize = 4;

/// A refined surface of a fixed control topology.
#[derive(Clone)]
pub struct Surface {
    /// The refined points over the control points: regular faces as bicubic patches, stencil
    /// rows elsewhere (the same points as the stencil table's, faster).
    evaluator: Evaluator,
    /// Limit tangent stencils, when normals are written.
    tangents: Option<[StencilTable; 2]>,
    mesh: Mesh,
    hierarchy: Hierarchy,
    /// The control mesh's face offsets ([`Mesh::face_offsets`]), for [`Self::control_face`].
    control_faces: Vec<u32>,
    level: u32,
}

impl Surface {
    /// The surface of `control` refined `level` times, at the control mesh's positions.
    ///
    /// # Errors
    /// When the refined mesh cannot carry a collision hierarchy.
    pub fn new(control: &Mesh, level: u32, normals: bool) -> Result<Self> {
        let refiner = Refiner::new(control, level as usize);
        let evaluator = Evaluator::new(&refiner);
        let tangents = normals.then(|| {
            let [_, t1, t2] = refiner.limit_stencils();
            [t1, t2]
        });
        let uvs = control
            .uvs()
            .and_then(|uvs| refiner.refine_uvs(&uvs.values));
        let mut positions = vec![Point::origin(); evaluator.len()];
        evaluator.apply(control.positions(), &mut positions);
        let mesh = refiner.refined_mesh(positions, uvs);
        let hierarchy =
            Hierarchy::build(mesh.positions(), mesh.face_offsets(), mesh.face_vertices())
                .context("building the collision hierarchy of a refined surface")?;
        Ok(Self {
            evaluator,
            tangents,
            mesh,
            hierarchy,
            control_faces: control.face_offsets().to_vec(),
            level,
        })
    }

    /// The control vertex with the largest weight in refined vertex `v`'s stencil (the lowest
    /// index of equals, as for the face point of a quad); `None` when there is no vertex `v`.
    #[must_use]
    pub fn control_vertex(&self, v: u32) -> Option<u32> {
        let v = v as usize;
        let stencils = self.evaluator.stencils();
        if v >= stencils.len() {
            return None;
        }
        let (columns, weights) = stencils.rows.row(v);
        let heaviest = columns.iter().zip(weights).reduce(|best, next| {
            let better = next.1 > best.1 || (next.1 == best.1 && next.0 < best.0);
            if better { next } else { best }
        });
        heaviest.map(|(&c, _)| c)
    }

    /// The control face that refined face `f` lies in; `None` when there is no face `f`.
    ///
    /// Uniform refinement numbers child faces parent by parent (`tailor_subdiv::refine`):
    /// level 1 makes one quad per corner of each control face, so its face `k` lies in the
    /// control face holding corner `k`; every later level makes four consecutive quads per
    /// face, so face `f` of level `l` lies in face `f / 4^(l − 1)` of level 1.
    #[must_use]
    pub fn control_face(&self, f: u32) -> Option<u32> {
        if f as usize >= self.mesh.face_count() {
            return None;
        }
        if self.level == 0 {
            return Some(f);
        }
        let corner = f.checked_shr(2 * (self.level - 1)).unwrap_or(0);
        let after = self.control_faces.partition_point(|&o| o <= corner);
        u32::try_from(after.checked_sub(1)?).ok()
    }

    /// The stencils of the refined points over the control points.
    #[must_use]
    pub fn stencils(&self) -> &StencilTable {
        self.evaluator.stencils()
    }

    /// The refined positions for control points `control`.
    #[must_use]
    pub fn refine(&self, control: &[Point]) -> Vec<Point> {
        let mut out = vec![Point::origin(); self.evaluator.len()];
        self.evaluator.apply(control, &mut out);
        out
    }

    /// Moves the surface to refined positions `refined` (from [`Self::refine`]) as a file
    /// written at `precision` holds them, and refits the hierarchy: what is checked, and then
    /// written, is what a reader of the file gets, not the simulation's `f64` before rounding.
    ///
    /// # Errors
    /// When a position is not finite.
    pub fn set(&mut self, mut refined: Vec<Point>, precision: Precision) -> Result<()> {
        for p in &mut refined {
            p.coords.apply(|x| *x = precision.round(*x));
        }
        self.mesh.set_positions(&refined)?;
        self.hierarchy.refit(&refined, 0.0)?;
        Ok(())
    }

    /// Rounds again, apart, the corners of the faces `crossing` lists in pairs (the faces
    /// [`Hierarchy::self_intersections`] finds at the positions [`Self::set`] rounded): for
    /// each pair of their triangles that meets as rounded but not at `exact` (the points
    /// before rounding), each coordinate of each corner is rounded towards the side
    /// [`triangles_apart`] parts the two to ([`Precision::round_toward`]), rather than to the
    /// nearest. Each coordinate stays within two `f32` steps of the simulation's, and the two
    /// triangles stay apart: at the default precision two layers less than an `f32` step
    /// apart (tens of nanometres within a metre of the origin) can otherwise round into each
    /// other. Refits the hierarchy; returns how many triangle pairs it parted. Not for full
    /// precision, whose rounding is the identity.
    ///
    /// # Errors
    /// When a position is not finite.
    fn round_apart(
        &mut self,
        exact: &[Point],
        crossing: &[[u32; 2]],
        precision: Precision,
    ) -> Result<usize> {
        let rounded = self.mesh.positions();
        let mut parted = rounded.to_vec();
        let triangles = self.hierarchy.triangles();
        let faces = self.hierarchy.triangle_faces();
        let fan = |f: u32| faces.partition_point(|&g| g < f)..faces.partition_point(|&g| g <= f);
        let corners = |t: usize, x: &[Point]| triangles[t].map(|v| x[v as usize]);
        let mut count = 0;
        for &[f, g] in crossing {
            for (s, t) in fan(f).flat_map(|s| fan(g).map(move |t| (s, t))) {
                if !triangles_intersect(corners(s, rounded), corners(t, rounded)) {
                    continue;
                }
                let Some(n) = triangles_apart(corners(s, exact), corners(t, exact)) else {
                    continue;
                };
                for (t, sign) in [(s, 1.0), (t, -1.0)] {
                    for v in triangles[t] {
                        let v = v as usize;
                        for k in 0..3 {
                            parted[v][k] = precision.round_toward(exact[v][k], n[k] * sign);
                        }
                    }
                }
                count += 1;
            }
        }
        if count > 0 {
            self.mesh.set_positions(&parted)?;
            self.hierarchy.refit(&parted, 0.0)?;
        }
        Ok(count)
    }

    /// [`Self::round_apart`] on the faces [`Hierarchy::self_intersections`] finds, until none
    /// cross, nothing is parted, or [`ROUNDING_APART_TRIES`] runs; `exact` as there. Nothing
    /// at full precision, which parts nothing, so the query would be asked for nothing.
    ///
    /// # Errors
    /// As [`Self::round_apart`].
    pub fn round_crossings_apart(&mut self, exact: &[Point], precision: Precision) -> Result<()> {
        if precision == Precision::Full {
            return Ok(());
        }
        for _ in 0..ROUNDING_APART_TRIES {
            let crossing = self.hierarchy.self_intersections();
            if crossing.is_empty() || self.round_apart(exact, &crossing, precision)? == 0 {
                break;
            }
        }
        Ok(())
    }

    /// The refined mesh at its current positions.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The hierarchy, refit at the current positions.
    #[must_use]
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hierarchy
    }

    /// The text of the refined mesh but its positions and normals, for [`Self::write`], with
    /// coordinates at `precision`.
    #[must_use]
    pub fn frames(&self, precision: Precision) -> Frames {
        Frames::new(&self.mesh, &[], self.tangents.is_some(), precision)
    }

    /// Writes the refined mesh (with limit normals of control points `control` when the
    /// surface was made with normals) atomically to `path`, the rest of its text from `text`
    /// ([`Self::frames`]).
    ///
    /// # Errors
    /// Any I/O error, naming the file.
    pub fn write(&self, path: &Path, control: &[Point], text: &Frames) -> Result<u64> {
        write_atomically(path, |w| self.format(control, text, w))
    }

    /// The bytes [`Self::write`] writes.
    ///
    /// # Errors
    /// When `text` is not this surface's ([`Self::frames`]).
    pub fn text(&self, control: &[Point], text: &Frames) -> Result<Vec<u8>> {
        let mut bytes = Vec::new();
        self.format(control, text, &mut bytes)
            .context("formatting a refined surface")?;
        Ok(bytes)
    }

    /// The refined mesh's text, as [`Self::write`] describes, into `w`.
    fn format(&self, control: &[Point], text: &Frames, w: &mut impl Write) -> io::Result<()> {
        text.write(self.mesh.positions(), self.normals(control).as_deref(), w)
    }

    /// The limit normals at the refined points for control points `control`, when the surface
    /// was made with normals.
    fn normals(&self, control: &[Point]) -> Option<Vec<Vector3<f64>>> {
        self.tangents.as_ref().map(|[t1, t2]| {
            let coords: Vec<Vector3<f64>> = control.iter().map(|p| p.coords).collect();
            let mut a = vec![Vector3::zeros(); t1.len()];
            let mut b = vec![Vector3::zeros(); t2.len()];
            t1.apply(&coords, &mut a);
            t2.apply(&coords, &mut b);
            a.iter()
                .zip(&b)
                .map(|(a, b)| tailor_subdiv::limit::normal(a, b))
                .collect()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit quad (vertices 0-3) and a triangle (1, 4, 2) on its right, sharing edge 1-2.
    fn quad_and_triangle(level: u32) -> Surface {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0.5 0\nf 1 2 3 4\nf 2 5 3\n";
        let doc = tailor_subdiv::obj::parse(text, "t.obj").unwrap();
        Surface::new(&doc.mesh, level, false).unwrap()
    }

    #[test]
    fn refined_faces_lie_in_their_control_faces() {
        // Level 1: one quad per corner, the quad's 4 then the triangle's 3; each holds its
        // parent's face point (refined vertices 5 and 6, after the 5 vertex points).
        let one = quad_and_triangle(1);
        let parents: Vec<_> = (0..8).map(|f| one.control_face(f)).collect();
        assert_eq!(parents[..7], [0, 0, 0, 0, 1, 1, 1].map(Some));
        assert_eq!(parents[7], None);
        for f in 0..7 {
            let face_point = 5 + one.control_face(f).unwrap();
            assert!(
                one.mesh().face(f as usize).contains(&face_point),
                "face {f}"
            );
        }
        // Level 2: four per level-1 face; each holds its level-1 parent's face point (after
        // the 13 vertex points: 5 vertices, 2 faces and 6 edges of the control mesh).
        let two = quad_and_triangle(2);
        assert_eq!(two.control_face(15), Some(0));
        assert_eq!(two.control_face(16), Some(1));
        assert_eq!(two.control_face(27), Some(1));
        assert_eq!(two.control_face(28), None);
        for f in 0..28 {
            let parent = f / 4;
            assert!(
                two.mesh().face(f as usize).contains(&(13 + parent)),
                "face {f}"
            );
            assert_eq!(two.control_face(f), one.control_face(parent), "face {f}");
        }
        // Level 0: the control faces themselves.
        let zero = quad_and_triangle(0);
        assert_eq!(
            (zero.control_face(1), zero.control_face(2)),
            (Some(1), None)
        );
    }

    #[test]
    fn refined_vertices_follow_their_heaviest_control_vertex() {
        let one = quad_and_triangle(1);
        // Vertex points weigh their own vertex most (3/4 on a smooth boundary).
        for v in 0..5 {
            assert_eq!(one.control_vertex(v), Some(v));
        }
        // Face points weigh their corners alike: the lowest wins.
        assert_eq!(one.control_vertex(5), Some(0));
        assert_eq!(one.control_vertex(6), Some(1));
        assert_eq!(one.control_vertex(13), None);
        // At level 2 the face point of the level-1 quad at corner j of a control face weighs
        // that corner most (about 1/2, the other corners 7/32 or less): refined vertex 13 + k
        // for level-1 face k, the quad's corners 0-3 then the triangle's 1, 4, 2.
        let two = quad_and_triangle(2);
        let corners: Vec<_> = (13..20).map(|v| two.control_vertex(v)).collect();
        assert_eq!(corners, [0, 1, 2, 3, 1, 4, 2].map(Some));
    }
}
