//! The sphere drape as a scene for `tailor simulate`: a 2 m square sheet of n × n vertices
//! 0.5 m above a sphere of radius 0.5 m (24 rings, 48 segments), cotton, 5 mm thick, friction
//! 0.3, self-collision on, 24 fps: the drape `bench/blender_drape.py` builds in Blender, and
//! the shot of `tests/written_surface.rs`.

use std::fs;
use std::io;
use std::path::Path;

use nalgebra::Vector3;
use tailor_cloth::shapes;
use tailor_subdiv::obj::{self, Precision};
use tailor_subdiv::{Mesh, Point};

/// One drape: the sheet's vertices a side, substeps a frame, the subdivision level written,
/// the frames simulated, and how far the sphere is moved along x from under the sheet's
/// centre (metres).
pub struct Drape {
    pub n: u32,
    pub substeps: u32,
    pub level: u32,
    pub frames: u32,
    pub nudge: f64,
}

impl Drape {
    /// Writes `sheet.obj` and `sphere.obj` into `dir`.
    pub fn write_meshes(&self, dir: &Path) -> io::Result<()> {
        write_mesh(&dir.join("sheet.obj"), &shapes::centred_sheet(self.n, 2.0))?;
        let mut sphere = shapes::sphere(Point::new(0.0, -1.0, 0.0), 0.5, 24, 48);
        if self.nudge != 0.0 {
            let moved: Vec<Point> = sphere
                .positions()
                .iter()
                .map(|p| p + Vector3::x() * self.nudge)
                .collect();
            sphere.set_positions(&moved).expect("the same vertex count");
        }
        write_mesh(&dir.join("sphere.obj"), &sphere)
    }

    /// The scene, reading the meshes beside it and writing into `out` beside it.
    pub fn scene(&self) -> String {
        let Self {
            frames,
            substeps,
            level,
            ..
        } = self;
        format!(
            "[scene]\nfps = 24\nframes = {frames}\nsubsteps = {substeps}\n\n\
             [cloth]\nmesh = \"sheet.obj\"\nmaterial = \"cotton\"\nthickness = 0.005\n\
             friction = 0.3\nself_collision = true\n\n\
             [body]\nmesh = \"sphere.obj\"\nsubdivision_level = 0\n\n\
             [output]\ndir = \"out\"\nsubdivision_level = {level}\n"
        )
    }
}

/// Writes `mesh` to `path` at full precision.
fn write_mesh(path: &Path, mesh: &Mesh) -> io::Result<()> {
    let mut text = Vec::new();
    obj::write(mesh, None, Precision::Full, &mut text)?;
    fs::write(path, text)
}
