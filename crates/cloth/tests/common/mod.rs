//! What several cloth test files share.

#![allow(dead_code)] // Each test file uses what it needs.

use tailor_cloth::State;

/// The largest distance between the vertices of two states.
pub fn farthest(a: &State, b: &State) -> f64 {
    a.positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}
