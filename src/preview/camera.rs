//! A fixed perspective camera that frames a set of points: every vertex of every chosen frame.
//!
//! The camera looks at the centre of the points' bounding box from a direction given by an
//! azimuth about +Y (0° is the front, +Z, where the mannequin faces; 90° is its left side, +X)
//! and an elevation above the horizon, Y up, as in the look-at construction of Foley, van Dam,
//! Feiner & Hughes, *Computer Graphics: Principles and Practice* (2nd ed., §6.5). It stands
//! back `r / sin(15°)` from the centre, `r` the box's circumradius, so every point lies in
//! front of it and the perspective is the same for any size of scene.
//!
//! Framing: every point is projected onto the image plane at distance 1 and the 2-D bounding
//! box of the projections is scaled (uniformly) and centred into the image, less a margin — an
//! off-axis perspective, so the picture is filled however the scene sits in the box. Every
//! point lands inside the image, and because the points are those of all the chosen frames, the
//! framing does not jump from frame to frame.

use nalgebra::{Point3, Vector3};

/// Half the vertical and horizontal field of view of the frustum the camera stands back for.
const HALF_FOV: f64 = 15.0 * std::f64::consts::PI / 180.0;

/// The fraction of the image kept empty at each side.
const MARGIN: f64 = 0.04;

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    min: Point3<f64>,
    max: Point3<f64>,
}

impl Bounds {
    /// The box of `points`, or `None` when there are none.
    fn of<'a>(points: impl IntoIterator<Item = &'a Point3<f64>>) -> Option<Self> {
        let mut points = points.into_iter();
        let first = *points.next()?;
        Some(points.fold(
            Self {
                min: first,
                max: first,
            },
            |b, p| Self {
                min: b.min.inf(p),
                max: b.max.sup(p),
            },
        ))
    }
}

/// A point projected to the image: pixel coordinates (x right, y down, pixel `(i, j)` covering
/// `[i, i + 1) × [j, j + 1)`) and its depth along the viewing direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Column coordinate in pixels.
    pub x: f64,
    /// Row coordinate in pixels.
    pub y: f64,
    /// Distance in front of the camera along its viewing direction (positive).
    pub depth: f64,
}

/// A perspective camera and its image.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    eye: Point3<f64>,
    right: Vector3<f64>,
    up: Vector3<f64>,
    forward: Vector3<f64>,
    /// Pixels per unit of the image plane at distance 1.
    scale: f64,
    /// Pixel position of the image-plane origin.
    centre: (f64, f64),
}

impl Camera {
    /// The camera that frames every finite point of `sets` in a `width × height` image, seen
    /// from `azimuth` degrees about +Y (0 = from +Z) and `elevation` degrees above the horizon
    /// (strictly between −90 and 90).
    #[must_use]
    pub fn framing(
        sets: &[&[Point3<f64>]],
        width: u32,
        height: u32,
        azimuth: f64,
        elevation: f64,
    ) -> Self {
        let points = || {
            sets.iter()
                .flat_map(|s| s.iter())
                .filter(|p| p.iter().all(|c| c.is_finite()))
        };
        let bounds = Bounds::of(points()).unwrap_or(Bounds {
            min: Point3::origin(),
            max: Point3::origin(),
        });
        let (az, el) = (azimuth.to_radians(), elevation.to_radians());
        let towards_eye = Vector3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos());
        let forward = -towards_eye;
        let right = forward.cross(&Vector3::y()).normalize();
        let up = right.cross(&forward);
        let target = nalgebra::center(&bounds.min, &bounds.max);
        // A point or a flat box still needs a distance the coordinates can resolve.
        let least = 1e-6 * (1.0 + target.coords.abs().max());
        let radius = ((bounds.max - bounds.min).norm() / 2.0).max(least);
        let eye = target + towards_eye * (radius / HALF_FOV.sin());
        let mut camera = Self {
            eye,
            right,
            up,
            forward,
            scale: 1.0,
            centre: (0.0, 0.0),
        };
        let (mut u0, mut u1, mut v0, mut v1) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
        for (i, p) in points().enumerate() {
            let (u, v) = camera.image_plane(p);
            (u0, u1, v0, v1) = if i == 0 {
                (u, u, v, v)
            } else {
                (u0.min(u), u1.max(u), v0.min(v), v1.max(v))
            };
        }
        let (w, h) = (f64::from(width), f64::from(height));
        let usable = 1.0 - 2.0 * MARGIN;
        camera.scale = (w * usable / (u1 - u0).max(1e-9)).min(h * usable / (v1 - v0).max(1e-9));
        camera.centre = (
            w / 2.0 - camera.scale * (u0 + u1) / 2.0,
            h / 2.0 + camera.scale * (v0 + v1) / 2.0,
        );
        camera
    }

    /// Where `p` falls on the plane at distance 1 in front of the eye (x right, y up).
    fn image_plane(&self, p: &Point3<f64>) -> (f64, f64) {
        let d = p - self.eye;
        let depth = d.dot(&self.forward);
        (d.dot(&self.right) / depth, d.dot(&self.up) / depth)
    }

    /// Projects `p` to the image.
    #[must_use]
    pub fn project(&self, p: &Point3<f64>) -> Projected {
        let d = p - self.eye;
        let depth = d.dot(&self.forward);
        Projected {
            x: self.centre.0 + self.scale * d.dot(&self.right) / depth,
            y: self.centre.1 - self.scale * d.dot(&self.up) / depth,
            depth,
        }
    }

    /// The unit vector from the scene towards the eye.
    #[must_use]
    pub fn towards_eye(&self) -> Vector3<f64> {
        -self.forward
    }

    /// A unit vector in the scene pointing to the camera's right and up by the given amounts
    /// and towards the eye by `back`: used to place lights relative to the view.
    #[must_use]
    pub fn relative(&self, right: f64, up: f64, back: f64) -> Vector3<f64> {
        (self.right * right + self.up * up - self.forward * back).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter of points: a tall, thin, off-centre cloud.
    fn cloud() -> Vec<Point3<f64>> {
        (0..500u32)
            .map(|i| {
                let t = f64::from(i);
                Point3::new(
                    0.3 + 0.5 * (t * 0.37).sin(),
                    1.8 * (t * 0.61).sin().abs(),
                    -0.2 + 0.4 * (t * 0.23).cos(),
                )
            })
            .collect()
    }

    /// Every point projects inside the image and in front of the camera, for several views and
    /// aspect ratios, and the cloud touches the margin on at least one side (it is framed, not
    /// lost in a corner).
    #[test]
    fn frames_every_point() {
        let points = cloud();
        let (head, tail) = points.split_at(200);
        for (w, h) in [(320, 400), (400, 100), (64, 64)] {
            for (az, el) in [(0.0, 0.0), (150.0, 15.0), (-60.0, 60.0), (90.0, -30.0)] {
                let camera = Camera::framing(&[head, tail], w, h, az, el);
                let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
                for q in points.iter().map(|p| camera.project(p)) {
                    assert!(q.depth > 0.0);
                    (x0, x1) = (x0.min(q.x), x1.max(q.x));
                    (y0, y1) = (y0.min(q.y), y1.max(q.y));
                }
                let (w, h) = (f64::from(w), f64::from(h));
                assert!(
                    x0 >= 0.0 && y0 >= 0.0 && x1 <= w && y1 <= h,
                    "{w}x{h} {az} {el}"
                );
                let tight = (x0 - MARGIN * w).abs() < 1e-6 || (y0 - MARGIN * h).abs() < 1e-6;
                assert!(tight, "{w}x{h} {az} {el}: {x0} {y0}");
            }
        }
    }

    #[test]
    fn front_view_is_upright_and_unmirrored() {
        let corners = [Point3::new(-1.0, -1.0, -1.0), Point3::new(1.0, 1.0, 1.0)];
        let camera = Camera::framing(&[&corners], 100, 100, 0.0, 0.0);
        let left = camera.project(&Point3::new(-1.0, 0.0, 0.0));
        let right = camera.project(&Point3::new(1.0, 0.0, 0.0));
        let top = camera.project(&Point3::new(0.0, 1.0, 0.0));
        assert!(left.x < right.x && top.y < left.y);
        assert!(camera.project(&Point3::new(0.0, 0.0, 1.0)).depth < left.depth);
    }

    #[test]
    fn a_single_point_still_projects() {
        let p = [Point3::new(1.0, 2.0, 3.0)];
        let q = Camera::framing(&[&p], 10, 10, 0.0, 0.0).project(&p[0]);
        assert!(q.x.is_finite() && q.y.is_finite() && q.depth > 0.0);
        let nothing = Camera::framing(&[], 10, 10, 0.0, 0.0);
        assert!(nothing.project(&Point3::origin()).depth > 0.0);
    }
}
