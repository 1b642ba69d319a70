//! Refined surfaces evaluated every frame through stencils built once (OpenSubdiv's `Far`
//! split: topology once, a sparse gather per frame), with the collision hierarchy that
//! `tailor check`'s test and the attachments query.
//!
//! Both the garment (for `cloth_####.obj`) and the body (for attachment, collision and the
//! check) are Catmull-Clark control meshes. The body is refined to `[body] subdivision_level`,
//! 2 by default: 16 quads per control quad (7168 for the mannequin), and the surface the
//! garments in `assets/` are modelled against (1–2 cm off it, `assets/README.md`). Level 1
//! is a quarter of the work but lies further from the limit surface a renderer shows, so cloth
//! resting on it would float off (or sink into) the rendered body where it curves.

use std::io::{self, Write};
use std::path::Path;

use anyhow::{Context, Result};
use nalgebra::Vector3;
use tailor_collide::Hierarchy;
use tailor_subdiv::obj::{self, Group};
use tailor_subdiv::{Mesh, Point, Refiner, StencilTable};

use crate::output::write_atomically;

/// A refined surface of a fixed control topology.
pub struct Surface {
    stencils: StencilTable,
    /// Limit tangent stencils, when normals are written.
    tangents: Option<[StencilTable; 2]>,
    mesh: Mesh,
    hierarchy: Hierarchy,
}

impl Surface {
    /// The surface of `control` refined `level` times, at the control mesh's positions.
    ///
    /// # Errors
    /// When the refined mesh cannot carry a collision hierarchy.
    pub fn new(control: &Mesh, level: u32, normals: bool) -> Result<Self> {
        let refiner = Refiner::new(control, level as usize);
        let stencils = refiner.stencils();
        let tangents = normals.then(|| {
            let [_, t1, t2] = refiner.limit_stencils();
            [t1, t2]
        });
        let uvs = control
            .uvs()
            .and_then(|uvs| refiner.refine_uvs(&uvs.values));
        let mut positions = vec![Point::origin(); stencils.len()];
        stencils.apply(control.positions(), &mut positions);
        let mesh = refiner.refined_mesh(positions, uvs);
        let hierarchy =
            Hierarchy::build(mesh.positions(), mesh.face_offsets(), mesh.face_vertices())
                .context("building the collision hierarchy of a refined surface")?;
        Ok(Self {
            stencils,
            tangents,
            mesh,
            hierarchy,
        })
    }

    /// The stencils of the refined points over the control points.
    #[must_use]
    pub fn stencils(&self) -> &StencilTable {
        &self.stencils
    }

    /// The refined positions for control points `control`.
    #[must_use]
    pub fn refine(&self, control: &[Point]) -> Vec<Point> {
        let mut out = vec![Point::origin(); self.stencils.len()];
        self.stencils.apply(control, &mut out);
        out
    }

    /// Moves the surface to refined positions `refined` (from [`Self::refine`]) and refits
    /// the hierarchy.
    ///
    /// # Errors
    /// When a position is not finite.
    pub fn set(&mut self, refined: &[Point]) -> Result<()> {
        self.mesh.set_positions(refined)?;
        self.hierarchy.refit(refined, 0.0)?;
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

    /// Writes the refined mesh (with limit normals of control points `control` when the
    /// surface was made with normals) atomically to `path`.
    ///
    /// # Errors
    /// Any I/O error, naming the file.
    pub fn write(&self, path: &Path, control: &[Point]) -> Result<()> {
        let normals = self.tangents.as_ref().map(|[t1, t2]| {
            let coords: Vec<Vector3<f64>> = control.iter().map(|p| p.coords).collect();
            let mut a = vec![Vector3::zeros(); t1.len()];
            let mut b = vec![Vector3::zeros(); t2.len()];
            t1.apply(&coords, &mut a);
            t2.apply(&coords, &mut b);
            a.iter()
                .zip(&b)
                .map(|(a, b)| tailor_subdiv::limit::normal(a, b))
                .collect::<Vec<_>>()
        });
        write_atomically(path, |w| obj::write(&self.mesh, normals.as_deref(), w))
    }
}

/// Writes a control mesh with its OBJ groups: [`obj::write`]'s output with a `g` line before
/// each run of faces whose group memberships differ from the previous face's.
///
/// # Errors
/// Any I/O error.
pub fn write_with_groups(mesh: &Mesh, groups: &[Group], out: &mut impl Write) -> io::Result<()> {
    let mut names: Vec<Vec<&str>> = vec![Vec::new(); mesh.face_count()];
    for g in groups {
        for &f in &g.faces {
            names[f as usize].push(&g.name);
        }
    }
    let mut hole = vec![false; mesh.face_count()];
    for &f in mesh.holes() {
        hole[f as usize] = true;
    }
    let mut written = (0..mesh.face_count()).filter(|&f| !hole[f]);
    let mut text = Vec::new();
    obj::write(mesh, None, &mut text)?;
    let mut current: &[&str] = &[];
    for line in text.split_inclusive(|&b| b == b'\n') {
        if line.starts_with(b"f ")
            && let Some(f) = written.next()
            && names[f] != current
        {
            current = &names[f];
            writeln!(out, "g {}", current.join(" "))?;
        }
        out.write_all(line)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_survive_a_round_trip() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n\
                    g cape attach\nf 1 2 3 4\ng cape\nf 2 5 6 3\n";
        let doc = obj::parse(text, "t.obj").unwrap();
        let mut out = Vec::new();
        write_with_groups(&doc.mesh, &doc.groups, &mut out).unwrap();
        let back = obj::parse(&String::from_utf8(out).unwrap(), "back.obj").unwrap();
        assert_eq!(back, doc);
    }
}
