//! Normals, lights and materials: how a point of a surface is coloured.
//!
//! Flat shading uses one normal per polygon; Phong shading (Phong, "Illumination for Computer
//! Generated Pictures", CACM 1975) interpolates per-vertex normals across each triangle and
//! lights every pixel with the interpolated, renormalized normal. A vertex normal is the sum of
//! the area-weighted normals of the faces around it; a polygon's area-weighted normal is
//! Newell's (Sutherland, Sproull & Schumacker 1974), exact for planar polygons and a
//! best-fit for the non-planar quads of a deformed mesh.
//!
//! One key light placed relative to the camera (above, to the left and in front, so whatever
//! the view the visible side is lit), an ambient term, and a Blinn–Phong highlight (Blinn,
//! "Models of Light Reflection for Computer Synthesized Pictures", SIGGRAPH 1977) with the
//! viewer at infinity. Surfaces are two-sided: a back face is lit with its normal reversed, so
//! the inside of a cape is lit like its outside, and may have its own colour.

use nalgebra::{Point3, Vector3};

use super::MeshView;
use super::camera::Camera;
use super::raster::{Rgb, Side};

/// Fraction of the colour lit by the ambient term.
const AMBIENT: f64 = 0.28;
/// Fraction lit by the key light face on.
const DIFFUSE: f64 = 0.72;
/// Strength and exponent of the highlight.
const SPECULAR: (f64, i32) = (0.18, 40);

/// The colours of a surface's two sides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Material {
    /// The side facing where the polygons wind counter-clockwise (the outside).
    pub front: Rgb,
    /// The other side.
    pub back: Rgb,
}

/// The key light and the view direction, in scene coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    to_light: Vector3<f64>,
    halfway: Vector3<f64>,
}

impl Light {
    /// The key light for `camera`: up and to the left of it, in front of the scene.
    #[must_use]
    pub fn for_camera(camera: &Camera) -> Self {
        let to_light = camera.relative(-0.4, 0.6, 0.9);
        Self {
            to_light,
            halfway: (to_light + camera.towards_eye()).normalize(),
        }
    }

    /// The colour of `material` on `side` at a point with unit normal `normal` (pointing out of
    /// the front side).
    #[must_use]
    pub fn shade(&self, material: &Material, side: Side, normal: &Vector3<f64>) -> Rgb {
        let (base, n) = match side {
            Side::Front => (material.front, *normal),
            Side::Back => (material.back, -normal),
        };
        let diffuse = n.dot(&self.to_light).max(0.0);
        let highlight = if diffuse > 0.0 {
            SPECULAR.0 * n.dot(&self.halfway).max(0.0).powi(SPECULAR.1)
        } else {
            0.0
        };
        let lit = AMBIENT + DIFFUSE * diffuse;
        base.map(|c| {
            (f64::from(c) * lit + 255.0 * highlight)
                .round()
                .clamp(0.0, 255.0) as u8
        })
    }
}

/// The area-weighted normal of each face (Newell's method), not normalized.
#[must_use]
pub fn face_normals(mesh: &MeshView) -> Vec<Vector3<f64>> {
    mesh.face_offsets
        .windows(2)
        .map(|w| {
            let face = &mesh.face_vertices[w[0] as usize..w[1] as usize];
            let p = |i: usize| -> &Point3<f64> { &mesh.positions[face[i % face.len()] as usize] };
            (0..face.len()).fold(Vector3::zeros(), |n, i| {
                let (a, b) = (p(i), p(i + 1));
                n + Vector3::new(
                    (a.y - b.y) * (a.z + b.z),
                    (a.z - b.z) * (a.x + b.x),
                    (a.x - b.x) * (a.y + b.y),
                ) / 2.0
            })
        })
        .collect()
}

/// The normal of each vertex: the sum of its faces' area-weighted normals, not normalized.
#[must_use]
pub fn vertex_normals(mesh: &MeshView, faces: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let mut normals = vec![Vector3::zeros(); mesh.positions.len()];
    for (w, n) in mesh.face_offsets.windows(2).zip(faces) {
        for &v in &mesh.face_vertices[w[0] as usize..w[1] as usize] {
            normals[v as usize] += n;
        }
    }
    normals
}

/// `v` scaled to unit length, or zero when it has none.
#[must_use]
pub fn unit(v: &Vector3<f64>) -> Vector3<f64> {
    v.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newell_normal_of_a_counter_clockwise_square_points_out_with_its_area() {
        let positions = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(2.0, 2.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
            Point3::new(0.0, 0.0, 2.0),
        ];
        let mesh = MeshView {
            positions: &positions,
            face_offsets: &[0, 4, 7],
            face_vertices: &[0, 1, 2, 3, 0, 4, 1],
        };
        let faces = face_normals(&mesh);
        assert_eq!(faces[0], Vector3::new(0.0, 0.0, 4.0));
        assert_eq!(faces[1], Vector3::new(0.0, 2.0, 0.0));
        let vertices = vertex_normals(&mesh, &faces);
        assert_eq!(vertices[0], Vector3::new(0.0, 2.0, 4.0));
        assert_eq!(vertices[2], Vector3::new(0.0, 0.0, 4.0));
    }

    #[test]
    fn both_sides_are_lit_and_facing_the_light_is_brighter() {
        let corners = [Point3::new(-1.0, -1.0, -1.0), Point3::new(1.0, 1.0, 1.0)];
        let camera = Camera::framing(&[&corners], 10, 10, 0.0, 0.0);
        let light = Light::for_camera(&camera);
        let grey = Material {
            front: [200, 200, 200],
            back: [200, 200, 200],
        };
        let towards = camera.towards_eye();
        let front = light.shade(&grey, Side::Front, &towards);
        let back = light.shade(&grey, Side::Back, &-towards);
        assert_eq!(front, back);
        let away = light.shade(&grey, Side::Front, &-towards);
        assert!(front[0] > away[0] && away[0] > 0);
    }
}
