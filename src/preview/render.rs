//! One picture per frame, all from the same camera: the cloth in colour (a different colour on
//! its inside), then the body in neutral grey (where they coincide exactly, the z-buffer's
//! first-drawn-wins rule shows the cloth), rendered at twice the resolution and box-filtered
//! down (supersampling against jagged edges), labelled with the frame number.
//!
//! Tiles are independent, so they are rendered in parallel; each is drawn in a fixed order
//! (cloth, then body, faces in file order), so the bytes do not depend on the thread count.

use rayon::prelude::*;

use super::camera::Camera;
use super::picture::Picture;
use super::raster::{Rgb, Side, Surface};
use super::shade::{self, Light, Material};
use super::{FrameMeshes, MeshView, Options, Shading, sheet};

/// Samples per pixel along each axis.
const SUPERSAMPLE: u32 = 2;
/// The backdrop.
const BACKGROUND: Rgb = [228, 230, 235];
/// The body: neutral grey.
const BODY: Material = Material {
    front: [172, 172, 172],
    back: [172, 172, 172],
};
/// The cloth: a deep red outside, a gold lining inside.
const CLOTH: Material = Material {
    front: [204, 48, 56],
    back: [214, 170, 84],
};

/// Renders each frame as one `options.width × options.height` picture, all from one camera
/// framing every vertex of every frame.
#[must_use]
pub fn render_frames(frames: &[FrameMeshes], options: &Options) -> Vec<Picture> {
    let points: Vec<&[nalgebra::Point3<f64>]> = frames
        .iter()
        .flat_map(|f| f.body.iter().chain([&f.cloth]))
        .map(|m| m.positions)
        .collect();
    let (w, h) = (options.width * SUPERSAMPLE, options.height * SUPERSAMPLE);
    let camera = Camera::framing(&points, w, h, options.azimuth, options.elevation);
    let light = Light::for_camera(&camera);
    frames
        .par_iter()
        .map(|frame| {
            let mut surface = Surface::new(w as usize, h as usize, BACKGROUND);
            let cloth = &frame.cloth;
            draw(
                &mut surface,
                &camera,
                &light,
                cloth,
                &CLOTH,
                options.shading,
            );
            if let Some(body) = &frame.body {
                draw(&mut surface, &camera, &light, body, &BODY, options.shading);
            }
            let pixels = surface.downsample(SUPERSAMPLE as usize);
            let mut tile = Picture::from_bytes(options.width, options.height, pixels)
                .expect("the downsampled surface has the tile's size");
            sheet::label(&mut tile, frame.frame);
            tile
        })
        .collect()
}

/// Draws `mesh`'s polygons, each fanned into triangles from its first vertex.
fn draw(
    surface: &mut Surface,
    camera: &Camera,
    light: &Light,
    mesh: &MeshView,
    material: &Material,
    shading: Shading,
) {
    let projected: Vec<_> = mesh.positions.iter().map(|p| camera.project(p)).collect();
    let faces = shade::face_normals(mesh);
    let vertex_normals: Vec<_> = match shading {
        Shading::Flat => Vec::new(),
        Shading::Phong => shade::vertex_normals(mesh, &faces)
            .iter()
            .map(shade::unit)
            .collect(),
    };
    for (w, face_normal) in mesh.face_offsets.windows(2).zip(&faces) {
        let face = &mesh.face_vertices[w[0] as usize..w[1] as usize];
        let normal = shade::unit(face_normal);
        let flat = [Side::Front, Side::Back].map(|side| light.shade(material, side, &normal));
        for i in 1..face.len().saturating_sub(1) {
            let t = [face[0], face[i], face[i + 1]].map(|v| v as usize);
            surface.fill_triangle(t.map(|v| projected[v]), |side, b| match shading {
                Shading::Flat => flat[usize::from(side == Side::Back)],
                Shading::Phong => {
                    let n = vertex_normals[t[0]] * b[0]
                        + vertex_normals[t[1]] * b[1]
                        + vertex_normals[t[2]] * b[2];
                    light.shade(material, side, &shade::unit(&n))
                }
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    /// A unit square facing the camera, seen head-on, fills the tile less its margins: 92 % of
    /// 100 pixels a side, to within a pixel row on each side.
    #[test]
    fn a_unit_square_fills_the_framed_area() {
        let corners = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let square = MeshView {
            positions: &corners,
            face_offsets: &[0, 4],
            face_vertices: &[0, 1, 2, 3],
        };
        let options = Options {
            width: 100,
            height: 100,
            azimuth: 0.0,
            elevation: 0.0,
            ..Options::default()
        };
        for body in [None, Some(square)] {
            let frame = FrameMeshes {
                frame: 0,
                cloth: square,
                body,
            };
            let tile = &render_frames(&[frame], &options)[0];
            let covered = tile
                .bytes()
                .chunks_exact(3)
                .filter(|p| *p != BACKGROUND)
                .count() as f64;
            assert!((covered - 92.0 * 92.0).abs() <= 4.0 * 92.0, "{covered}");
            // The cloth is drawn over a body in the same place: the centre is red.
            let centre = tile.get(50, 50);
            assert!(centre[0] > centre[1] + 50, "{centre:?}");
        }
    }
}
