//! The one place where nalgebra's [`Point`](crate::Point) meets parry's glam `DVec3`.
//!
//! The public API speaks nalgebra (as the rest of tailor does); parry 0.31 and the inner loops
//! speak glam. nalgebra's `convert-glam033` feature provides the conversions.

use parry3d_f64::math::Vector as DVec3;

use crate::{Point, Vector};

/// A nalgebra point as a glam vector.
#[inline]
pub(crate) fn to_glam(p: &Point) -> DVec3 {
    DVec3::from(*p)
}

/// A glam vector as a nalgebra point.
#[inline]
pub(crate) fn to_point(v: DVec3) -> Point {
    Point::from(v)
}

/// A glam vector as a nalgebra vector.
#[inline]
pub(crate) fn to_vector(v: DVec3) -> Vector {
    Vector::from(v)
}
