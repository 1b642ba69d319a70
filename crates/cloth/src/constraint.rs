//! Constraints the implicit solve enforces exactly: pins, attachments and contact planes.
//!
//! Baraff & Witkin 1998, §5.3: instead of stiff penalty springs, each particle carries a
//! filter S (zero for a particle whose velocity is prescribed in all three directions,
//! I − n nᵀ for one held against a plane, I for a free one) and a target velocity z; the
//! solve leaves the constrained components at z exactly (the private `pcg` module). Per substep of
//! length h ending at time t, a particle that must be at a goal position g gets
//! z = (g − x_start)/h and, after the step, is *placed* at g, so pins are exact to the last bit
//! rather than to a solver tolerance.
//!
//! - **Pins** fix a vertex at its rest position, or move it rigidly with a scripted transform
//!   of time ([`Motion`]): the goal is T(t) applied to the vertex's rest position.
//! - **Attachments** bind a vertex to a point the caller moves, e.g. a point given by
//!   barycentric coordinates on the animated body's triangle: the caller supplies its position
//!   and velocity at a time, and the goal follows that line.
//! - **Contacts** hold a vertex against a plane with unit normal n moving with a velocity, its
//!   normal velocity prescribed and tangential velocity free: those the caller sets, plus those
//!   the collision pass (the `collision` module) finds before each substep.
//!
//! When one vertex has several, pins win over attachments, attachments over contacts.

use std::fmt;
use std::sync::Arc;

use nalgebra::Isometry3;
use tailor_subdiv::Point;

use crate::ClothError;
use crate::energy::{Mat3, Vec3};

/// A rigid transform of time (seconds), applied to pinned vertices' rest positions.
#[derive(Clone)]
pub enum Motion {
    /// The identity: the vertices stay at their rest positions.
    Fixed,
    /// Transforms at increasing times, interpolated linearly in translation and spherically
    /// in rotation, held constant before the first and after the last.
    Keyframes(Vec<(f64, Isometry3<f64>)>),
    /// Any function of time.
    Script(Arc<dyn Fn(f64) -> Isometry3<f64> + Send + Sync>),
}

impl fmt::Debug for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Fixed => f.write_str("Fixed"),
            Self::Keyframes(k) => f.debug_tuple("Keyframes").field(k).finish(),
            Self::Script(_) => f.write_str("Script(..)"),
        }
    }
}

impl Motion {
    /// The transform at time `t` (seconds).
    #[must_use]
    pub fn at(&self, t: f64) -> Isometry3<f64> {
        match self {
            Self::Fixed => Isometry3::identity(),
            Self::Script(f) => f(t),
            Self::Keyframes(keys) => {
                let next = keys.partition_point(|(time, _)| *time <= t);
                match (next.checked_sub(1).map(|i| &keys[i]), keys.get(next)) {
                    (Some((_, a)), None) | (None, Some((_, a))) => *a,
                    (Some((ta, a)), Some((tb, b))) => a.lerp_slerp(b, (t - ta) / (tb - ta)),
                    (None, None) => Isometry3::identity(),
                }
            }
        }
    }

    fn validate(&self) -> Result<(), ClothError> {
        if let Self::Keyframes(keys) = self {
            for (i, (t, _)) in keys.iter().enumerate() {
                if !t.is_finite() || (i > 0 && *t <= keys[i - 1].0) {
                    return Err(ClothError::BadValue {
                        what: "keyframe time (must be finite and increasing)",
                        value: *t,
                    });
                }
            }
        }
        Ok(())
    }
}

/// A vertex bound to a moving point: at time `t` its goal is
/// `position + velocity · (t − time)`, with `time` given to [`Constraints::set_attachments`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attachment {
    /// The cloth vertex.
    pub vertex: u32,
    /// The point's position at the given time, m.
    pub position: Point,
    /// The point's velocity, m/s.
    pub velocity: Vec3,
}

/// A vertex held against a plane: its velocity along `normal` is prescribed to that of
/// `velocity`, its tangential velocity is free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// The cloth vertex.
    pub vertex: u32,
    /// Unit normal of the plane.
    pub normal: Vec3,
    /// Velocity of the obstacle at the contact, m/s.
    pub velocity: Vec3,
}

const NONE: u32 = u32::MAX;

/// The constraints of one garment and their per-substep filters.
#[derive(Clone, Debug)]
pub struct Constraints {
    pin_motion: Vec<u32>,
    motions: Vec<Motion>,
    transforms: Vec<Isometry3<f64>>,
    attachments: Vec<Attachment>,
    attachment_time: f64,
    contacts: Vec<Contact>,
}

/// Per-vertex filter S, target velocity z, and the goal position of fully constrained ones.
#[derive(Clone, Debug)]
pub(crate) struct Filter {
    pub s: Vec<Mat3>,
    pub z: Vec<Vec3>,
    pub goal: Vec<Point>,
    pub placed: Vec<bool>,
}

impl Filter {
    pub fn new(n: usize) -> Self {
        Self {
            s: vec![Mat3::identity(); n],
            z: vec![Vec3::zeros(); n],
            goal: vec![Point::origin(); n],
            placed: vec![false; n],
        }
    }

    /// Whether vertex `i` is unconstrained: its filter is the identity.
    pub fn is_free(&self, i: usize) -> bool {
        self.s[i] == Mat3::identity()
    }
}

fn check_vertex(what: &'static str, vertex: u32, count: usize) -> Result<(), ClothError> {
    if (vertex as usize) < count {
        Ok(())
    } else {
        Err(ClothError::VertexOutOfRange {
            what,
            vertex,
            count,
        })
    }
}

impl Constraints {
    /// No constraints on `n` vertices.
    #[must_use]
    pub fn new(n: usize) -> Self {
        Self {
            pin_motion: vec![NONE; n],
            motions: Vec::new(),
            transforms: Vec::new(),
            attachments: Vec::new(),
            attachment_time: 0.0,
            contacts: Vec::new(),
        }
    }

    /// Pins `vertices` to follow `motion` (replacing earlier pins of those vertices).
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`], or [`ClothError::BadValue`] for keyframes out of order.
    pub fn pin(&mut self, vertices: &[u32], motion: Motion) -> Result<(), ClothError> {
        motion.validate()?;
        for &v in vertices {
            check_vertex("pin", v, self.pin_motion.len())?;
        }
        let id = self.motions.len() as u32;
        self.motions.push(motion);
        for &v in vertices {
            self.pin_motion[v as usize] = id;
        }
        Ok(())
    }

    /// Whether `vertex` is pinned.
    #[must_use]
    pub fn is_pinned(&self, vertex: u32) -> bool {
        self.pin_motion
            .get(vertex as usize)
            .is_some_and(|&m| m != NONE)
    }

    /// Replaces the attachments; their positions are those at `time` (seconds).
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`] or [`ClothError::BadValue`] for a non-finite time.
    pub fn set_attachments(
        &mut self,
        time: f64,
        attachments: &[Attachment],
    ) -> Result<(), ClothError> {
        if !time.is_finite() {
            return Err(ClothError::BadValue {
                what: "attachment time",
                value: time,
            });
        }
        for a in attachments {
            check_vertex("attachment", a.vertex, self.pin_motion.len())?;
        }
        self.attachments.clear();
        self.attachments.extend_from_slice(attachments);
        self.attachment_time = time;
        Ok(())
    }

    /// Replaces the contact planes.
    ///
    /// # Errors
    /// [`ClothError::VertexOutOfRange`].
    pub fn set_contacts(&mut self, contacts: &[Contact]) -> Result<(), ClothError> {
        for c in contacts {
            check_vertex("contact", c.vertex, self.pin_motion.len())?;
        }
        self.contacts.clear();
        self.contacts.extend_from_slice(contacts);
        Ok(())
    }

    /// Fills `filter` for a substep of length `h` ending at time `t`, from positions `start`,
    /// with the substep's `collisions` after the caller's contacts.
    pub(crate) fn prepare(
        &mut self,
        rest: &[Point],
        start: &[Point],
        t: f64,
        h: f64,
        collisions: &[Contact],
        filter: &mut Filter,
    ) {
        filter.s.fill(Mat3::identity());
        filter.z.fill(Vec3::zeros());
        filter.placed.fill(false);
        for c in self.contacts.iter().chain(collisions) {
            let i = c.vertex as usize;
            filter.s[i] = Mat3::identity() - c.normal * c.normal.transpose();
            filter.z[i] = c.velocity;
        }
        let place = |i: usize, goal: Point, filter: &mut Filter| {
            filter.s[i] = Mat3::zeros();
            filter.z[i] = (goal - start[i]) / h;
            filter.goal[i] = goal;
            filter.placed[i] = true;
        };
        for a in &self.attachments {
            let goal = a.position + a.velocity * (t - self.attachment_time);
            place(a.vertex as usize, goal, filter);
        }
        self.transforms.clear();
        self.transforms.extend(self.motions.iter().map(|m| m.at(t)));
        for (i, &m) in self.pin_motion.iter().enumerate() {
            if m != NONE {
                let goal = match self.motions[m as usize] {
                    Motion::Fixed => rest[i],
                    _ => self.transforms[m as usize] * rest[i],
                };
                place(i, goal, filter);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn keyframes_interpolate_and_hold() {
        let a = Isometry3::identity();
        let b = Isometry3::from_parts(
            Translation3::new(2.0, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 1.0, 0.0),
        );
        let m = Motion::Keyframes(vec![(1.0, a), (2.0, b)]);
        assert_eq!(m.at(0.0), a);
        assert_eq!(m.at(5.0), b);
        let mid = m.at(1.5);
        assert!((mid.translation.vector.x - 1.0).abs() < 1e-12);
        assert!((mid.rotation.angle() - 0.5).abs() < 1e-12);
        assert!(
            Motion::Keyframes(vec![(1.0, a), (1.0, b)])
                .validate()
                .is_err()
        );
    }

    #[test]
    fn pins_beat_attachments_beat_contacts() {
        let rest = [Point::origin(); 3];
        let mut c = Constraints::new(3);
        let up = Vec3::y();
        c.set_contacts(&[
            Contact {
                vertex: 0,
                normal: up,
                velocity: up,
            },
            Contact {
                vertex: 1,
                normal: up,
                velocity: up,
            },
        ])
        .unwrap();
        let moving = Attachment {
            vertex: 1,
            position: Point::new(1.0, 0.0, 0.0),
            velocity: Vec3::x(),
        };
        c.set_attachments(
            0.0,
            &[
                moving,
                Attachment {
                    vertex: 2,
                    ..moving
                },
            ],
        )
        .unwrap();
        c.pin(&[2], Motion::Fixed).unwrap();
        assert!(c.pin(&[3], Motion::Fixed).is_err());
        let mut f = Filter::new(3);
        c.prepare(&rest, &rest, 1.0, 0.5, &[], &mut f);
        assert_eq!(f.s[0], Mat3::identity() - up * up.transpose());
        assert_eq!(f.z[0], up);
        assert_eq!(f.goal[1], Point::new(2.0, 0.0, 0.0));
        assert_eq!(f.z[1], Vec3::new(4.0, 0.0, 0.0));
        assert!(f.placed[2] && f.goal[2] == rest[2]);
    }
}
