//! Sharpness and the vertex rule (OpenSubdiv `Sdc::Crease`).
//!
//! Sharpness is a per-edge and per-vertex number: 0 is smooth, 10 and above infinitely sharp,
//! anything between semi-sharp. A semi-sharp feature is refined with sharp rules for as many
//! levels as its sharpness, then with smooth ones; a fractional part blends the two for one level
//! (DeRose, Kass & Truong 1998, section 3). OpenSubdiv stores and decays sharpness in single
//! precision; we do the same so that fractional weights such as 0.7 match it to the last bit.
//!
//! The rule of a vertex follows from its sharpness and the number of sharp incident edges:
//! a sharp vertex or more than two sharp edges is a CORNER, two a CREASE, one a DART, none SMOOTH.

use crate::options::CreaseMethod;

/// Sharpness at and above which a feature is infinitely sharp.
pub const INFINITE: f32 = 10.0;

/// The refinement rule of a vertex (`Sdc::Crease::Rule`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Rule {
    /// No sharp edges: the smooth Catmull-Clark vertex rule.
    #[default]
    Smooth,
    /// Exactly one sharp edge: treated as smooth.
    Dart,
    /// Exactly two sharp edges: the cubic B-spline curve rule along them.
    Crease,
    /// A sharp vertex or more than two sharp edges: the vertex stays put.
    Corner,
}

impl Rule {
    /// The rule implied by a vertex sharpness and a count of sharp incident edges.
    #[must_use]
    #[inline]
    pub fn of(vertex_sharpness: f32, sharp_edges: usize) -> Self {
        if is_sharp(vertex_sharpness) {
            return Self::Corner;
        }
        match sharp_edges {
            0 => Self::Smooth,
            1 => Self::Dart,
            2 => Self::Crease,
            _ => Self::Corner,
        }
    }

    /// The rule implied by a vertex sharpness and the sharpness of every incident edge.
    #[must_use]
    pub fn from_sharpness(vertex_sharpness: f32, edges: &[f32]) -> Self {
        Self::of(
            vertex_sharpness,
            edges.iter().filter(|&&s| is_sharp(s)).count(),
        )
    }

    /// Smooth and dart vertices use the smooth masks.
    #[must_use]
    #[inline]
    pub fn is_smooth(self) -> bool {
        matches!(self, Self::Smooth | Self::Dart)
    }
}

/// Sharper than smooth (semi-sharp or infinite).
#[must_use]
#[inline]
pub fn is_sharp(s: f32) -> bool {
    s > 0.0
}

/// Infinitely sharp.
#[must_use]
#[inline]
pub fn is_infinite(s: f32) -> bool {
    s >= INFINITE
}

/// Semi-sharp: sharp but not infinitely.
#[must_use]
#[inline]
pub fn is_semi_sharp(s: f32) -> bool {
    s > 0.0 && s < INFINITE
}

/// Uniform decay: semi-sharp values drop by one per level, clamped at smooth; infinite stays.
#[must_use]
#[inline]
pub fn decrement(s: f32) -> f32 {
    if s <= 0.0 {
        0.0
    } else if is_infinite(s) {
        INFINITE
    } else if s > 1.0 {
        s - 1.0
    } else {
        0.0
    }
}

/// The sharpness of the child edges at one vertex, from the sharpness of the parent edges around
/// it (`Sdc::Crease::SubdivideEdgeSharpnessesAroundVertex`).
///
/// Chaikin: a semi-sharp edge's child gets ¾ of its own sharpness plus ¼ of the average of the
/// other semi-sharp edges at the vertex, minus one. Uniform: [`decrement`].
pub fn subdivide_edges_around_vertex(method: CreaseMethod, parent: &[f32], child: &mut [f32]) {
    debug_assert_eq!(parent.len(), child.len());
    if method == CreaseMethod::Uniform || parent.len() < 2 {
        for (c, &p) in child.iter_mut().zip(parent) {
            *c = decrement(p);
        }
        return;
    }
    let (sum, count) = parent
        .iter()
        .filter(|&&s| is_semi_sharp(s))
        .fold((0.0f32, 0u32), |(sum, n), &s| (sum + s, n + 1));
    for (c, &p) in child.iter_mut().zip(parent) {
        *c = if p <= 0.0 {
            0.0
        } else if is_infinite(p) {
            INFINITE
        } else if count == 1 {
            decrement(p)
        } else {
            let others = (sum - p) / (count - 1) as f32;
            let s = (0.75 * p + 0.25 * others) - 1.0;
            if s > 0.0 { s } else { 0.0 }
        };
    }
}

/// The weight of the parent rule when a vertex's rule changes from parent to child
/// (`Sdc::Crease::ComputeFractionalWeightAtVertex`): the average of the sharpness values that
/// decayed to zero in this step, clamped to 1.
#[must_use]
pub fn fractional_weight_at_vertex(
    method: CreaseMethod,
    parent_vertex: f32,
    child_vertex: f32,
    parent_edges: &[f32],
    child_edges: &[f32],
) -> f32 {
    let mut count = 0u32;
    let mut sum = 0.0f32;
    if is_sharp(parent_vertex) && !is_sharp(child_vertex) {
        count = 1;
        sum = parent_vertex;
    }
    for (&p, &c) in parent_edges.iter().zip(child_edges) {
        let decayed = match method {
            CreaseMethod::Uniform => p <= 1.0,
            CreaseMethod::Chaikin => !is_sharp(c),
        };
        if is_sharp(p) && decayed {
            sum += p;
            count += 1;
        }
    }
    if count == 0 {
        return 0.0;
    }
    (sum / count as f32).min(1.0)
}

/// The positions of the first and the last sharp edge around a crease vertex
/// (`Sdc::Crease::GetSharpEdgePairOfCrease`).
#[must_use]
pub fn sharp_edge_pair(edges: &[f32]) -> [usize; 2] {
    let first = edges.iter().position(|&s| is_sharp(s)).unwrap_or(0);
    let last = edges.iter().rposition(|&s| is_sharp(s)).unwrap_or(0);
    [first, last]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule_from_counts() {
        assert_eq!(Rule::of(0.0, 0), Rule::Smooth);
        assert_eq!(Rule::of(0.0, 1), Rule::Dart);
        assert_eq!(Rule::of(0.0, 2), Rule::Crease);
        assert_eq!(Rule::of(0.0, 3), Rule::Corner);
        assert_eq!(Rule::of(0.5, 0), Rule::Corner);
    }

    #[test]
    fn uniform_decay() {
        assert_eq!(decrement(2.5), 1.5);
        assert_eq!(decrement(1.0), 0.0);
        assert_eq!(decrement(0.3), 0.0);
        assert_eq!(decrement(12.0), INFINITE);
    }

    #[test]
    fn chaikin_averages_semi_sharp_neighbours() {
        // Edges 3 and 1 meet at a vertex with a smooth and an infinite edge:
        // 0.75 * 3 + 0.25 * 1 - 1 = 1.5 and 0.75 * 1 + 0.25 * 3 - 1 = 0.5.
        let mut child = [0.0; 4];
        subdivide_edges_around_vertex(CreaseMethod::Chaikin, &[3.0, 0.0, 1.0, 10.0], &mut child);
        assert_eq!(child, [1.5, 0.0, 0.5, 10.0]);
        // A lone semi-sharp edge decays uniformly.
        subdivide_edges_around_vertex(CreaseMethod::Chaikin, &[3.0, 0.0, 0.0, 10.0], &mut child);
        assert_eq!(child, [2.0, 0.0, 0.0, 10.0]);
    }

    #[test]
    fn fractional_weight_averages_decaying_values() {
        let w = fractional_weight_at_vertex(
            CreaseMethod::Uniform,
            0.0,
            0.0,
            &[0.5, 0.0, 0.25, 3.0],
            &[0.0, 0.0, 0.0, 2.0],
        );
        assert_eq!(w, 0.375);
        let w = fractional_weight_at_vertex(CreaseMethod::Uniform, 0.7, 0.0, &[], &[]);
        assert_eq!(w, 0.7);
        assert_eq!(
            fractional_weight_at_vertex(CreaseMethod::Uniform, 3.0, 2.0, &[], &[]),
            0.0
        );
    }

    #[test]
    fn crease_pair_is_first_and_last_sharp() {
        assert_eq!(sharp_edge_pair(&[0.0, 2.0, 0.0, 1.0, 0.0]), [1, 3]);
    }
}
