//! The refined surface against itself: the surface that renders never passes through itself.
//!
//! Self-collision on the control points ([`super::self_collision`]) keeps the control mesh
//! free of crossings, but the Catmull-Clark surface the control points define is not the
//! control mesh. Where the cloth folds tightly (a hem crumpled against itself, its faces
//! folded back 130–170° onto their neighbours) the refined faces of two folds can cross while
//! the control faces keep the thickness apart: the 64² drape wrote dozens of crossing face
//! pairs at level 1 with a clean control mesh on every frame. So, as DeRose, Kass & Truong
//! (1998, §5) collide the refined surface rather than the control points, the continuous
//! tests of Bridson, Fedkiw & Anderson (2002, §7.4) run once more on the refined points
//! r = S x (the caller's stencil table S over the straight control paths, so the refined
//! points move on straight paths too).
//!
//! An impact of refined points k with weights αₖ (vertex–triangle or edge–edge, as on the
//! control mesh) is an impact of the control points j with weights βⱼ = Σₖ αₖ Sₖⱼ, since the
//! relative velocity of the two refined contact points is Σₖ αₖ Σⱼ Sₖⱼ vⱼ. Its inelastic
//! impulse acts on those control points ([`Substep::push_apart`] over the β's), each by its
//! weight over its mass. The fail-safe merges into one impact zone all the control points of
//! the stencils of the refined points that still meet: a zone translates rigidly, and a
//! refined point whose stencil lies in one zone (its weights sum to one) translates with it,
//! so two refined features of a zone cannot meet if they did not touch at the start.
//!
//! The start of every substep is the end of the one before, so by induction the refined
//! surface is free of crossings on every frame the simulation writes, from a rest shape free of
//! them.

use tailor_collide::{CollideError, Hierarchy};
use tailor_subdiv::{Point, Refreshed, StencilTable};

use super::self_collision::{Pair, SEPARATION, SelfImpacts, ZONE_ROUNDS, Zones};
use crate::substep::Substep;

/// The refined surface's hierarchy, its positions at the start and end of the substep, and the
/// buffers of its queries.
#[derive(Clone, Debug)]
pub(super) struct SurfaceLayers {
    hierarchy: Hierarchy,
    start: Vec<Point>,
    /// The refined points at the end of the straight paths, computed again where the control
    /// points moved.
    end: Refreshed<Point>,
    impacts: SelfImpacts,
    /// The control points an impulse round changed.
    touched: Vec<bool>,
    /// One impact's control points and weights, and the terms they are summed from.
    vertices: Vec<u32>,
    alpha: Vec<f64>,
    terms: Vec<(u32, f64)>,
}

impl SurfaceLayers {
    /// The refined faces of `hierarchy` over the points `stencils` gives, the hierarchy refit
    /// at the refined `rest` positions; `end` evaluates `stencils` (nothing evaluated yet).
    pub fn new(
        stencils: &StencilTable,
        rest: &[Point],
        mut hierarchy: Hierarchy,
        end: Refreshed<Point>,
    ) -> Result<Self, CollideError> {
        let mut start = vec![Point::origin(); stencils.len()];
        stencils.apply(rest, &mut start);
        hierarchy.refit(&start, 0.0)?;
        Ok(Self {
            hierarchy,
            end,
            start,
            impacts: SelfImpacts::default(),
            touched: vec![false; rest.len()],
            vertices: Vec::new(),
            alpha: Vec::new(),
            terms: Vec::new(),
        })
    }

    /// The refined points at the substep's start `x0`, for the passes that follow.
    pub fn begin(&mut self, stencils: &StencilTable, x0: &[Point]) {
        stencils.apply(x0, &mut self.start);
    }

    /// The refined impacts of the straight paths from the start to the control points `x`;
    /// whether there is any.
    fn query(&mut self, stencils: &StencilTable, x: &[Point]) -> Result<bool, CollideError> {
        let end = self.end.update(stencils, x);
        self.impacts.query(&mut self.hierarchy, &self.start, end)
    }

    /// One round of impulses, as [`super::self_collision::impulse_round`] on the control
    /// mesh: `None` when the refined surface has no impact; else how many impacts it handled
    /// and the control points whose velocities it changed.
    pub fn impulse_round(
        &mut self,
        stencils: &StencilTable,
        thickness: f64,
        m: &mut Substep,
    ) -> Result<Option<(u32, &[bool])>, CollideError> {
        if !self.query(stencils, m.x)? {
            return Ok(None);
        }
        let Self {
            hierarchy,
            start,
            end,
            impacts,
            touched,
            vertices,
            alpha,
            terms,
        } = self;
        touched.fill(false);
        let mut handled = 0;
        for pair in Pair::list(hierarchy, &impacts.impacts) {
            let Some((normal, gap)) = pair.normal_and_gap(start, end.points()) else {
                continue;
            };
            control_weights(stencils, &pair, terms, vertices, alpha);
            let target = (SEPARATION * thickness - gap) / m.h;
            if m.push_apart(vertices, alpha, normal, target) {
                for &k in vertices.iter() {
                    touched[k as usize] = true;
                }
            }
            handled += 1;
        }
        m.sync_positions();
        Ok(Some((handled, touched)))
    }

    /// Merges the control points of the stencils of every remaining refined impact into
    /// impact zones until none is left; returns how many merges it made.
    pub fn impact_zones(
        &mut self,
        stencils: &StencilTable,
        m: &mut Substep,
    ) -> Result<u32, CollideError> {
        let mut zones = Zones::new(m.v.len());
        for _ in 0..ZONE_ROUNDS {
            if !self.query(stencils, m.x)? {
                break;
            }
            let before = zones.merged;
            for pair in Pair::list(&self.hierarchy, &self.impacts.impacts) {
                // Every control point of the four stencils, even one whose weights cancel in
                // the pair's β: each refined point must translate with the zone.
                self.vertices.clear();
                for &k in &pair.vertices {
                    let (columns, weights) = stencils.rows.row(k as usize);
                    let support = columns.iter().zip(weights).filter(|&(_, &w)| w != 0.0);
                    self.vertices.extend(support.map(|(&j, _)| j));
                }
                zones.merge_all(&self.vertices);
            }
            if zones.merged == before {
                break;
            }
            zones.move_together(m);
        }
        Ok(zones.merged)
    }
}

/// The control points of a refined `pair` and their weights βⱼ = Σₖ αₖ Sₖⱼ, in ascending
/// order of control point, those whose weights cancel left out.
fn control_weights(
    stencils: &StencilTable,
    pair: &Pair,
    terms: &mut Vec<(u32, f64)>,
    vertices: &mut Vec<u32>,
    alpha: &mut Vec<f64>,
) {
    terms.clear();
    for (&k, &a) in pair.vertices.iter().zip(&pair.alpha) {
        let (columns, weights) = stencils.rows.row(k as usize);
        terms.extend(columns.iter().zip(weights).map(|(&j, &w)| (j, a * w)));
    }
    terms.sort_unstable_by_key(|&(j, _)| j);
    vertices.clear();
    alpha.clear();
    for &(j, w) in terms.iter() {
        if vertices.last() == Some(&j) {
            *alpha.last_mut().expect("a weight per vertex") += w;
        } else {
            vertices.push(j);
            alpha.push(w);
        }
    }
    let mut kept = 0;
    for i in 0..vertices.len() {
        if alpha[i] != 0.0 {
            vertices[kept] = vertices[i];
            alpha[kept] = alpha[i];
            kept += 1;
        }
    }
    vertices.truncate(kept);
    alpha.truncate(kept);
}

#[cfg(test)]
mod tests {
    use tailor_subdiv::Refiner;

    use super::*;
    use crate::energy::Vec3;
    use crate::shapes::centred_sheet;

    /// The relative velocity of a refined pair's contact points, Σₖ αₖ (S v)ₖ, is
    /// Σⱼ βⱼ vⱼ over the control points and weights `control_weights` gives, each control point
    /// once, for pairs whose stencils overlap (neighbours, whose weights partly cancel) and
    /// pairs apart.
    #[test]
    fn control_weights_give_the_refined_pairs_relative_velocity() {
        let sheet = centred_sheet(5, 1.0);
        let stencils = Refiner::new(&sheet, 2).stencils();
        let control = stencils.control_points;
        let v: Vec<Point> = (0..control)
            .map(|j| {
                let t = j as f64;
                Point::new((1.3 * t).sin(), (0.7 * t).cos(), (2.9 * t).sin() * 0.5)
            })
            .collect();
        let mut refined = vec![Point::origin(); stencils.len()];
        stencils.apply(&v, &mut refined);
        let (mut terms, mut vertices, mut alpha) = (Vec::new(), Vec::new(), Vec::new());
        let last = stencils.len() as u32 - 1;
        for (first, spread) in [(40, 1), (40, 17), (3, 90), (0, last / 3)] {
            let pair = Pair {
                vertices: [
                    first,
                    first + spread,
                    first + 2 * spread,
                    first + 3 * spread,
                ],
                alpha: [1.0, -0.2, -0.5, -0.3],
                time: 0.5,
                triangle: true,
            };
            control_weights(&stencils, &pair, &mut terms, &mut vertices, &mut alpha);
            let refined_sum: Vec3 = pair
                .vertices
                .iter()
                .zip(&pair.alpha)
                .map(|(&k, &a)| refined[k as usize].coords * a)
                .sum();
            let control_sum: Vec3 = vertices
                .iter()
                .zip(&alpha)
                .map(|(&j, &b)| v[j as usize].coords * b)
                .sum();
            assert!(
                (refined_sum - control_sum).norm() < 1e-12,
                "{refined_sum} against {control_sum}"
            );
            assert!(vertices.windows(2).all(|w| w[0] < w[1]), "{vertices:?}");
            assert!(alpha.iter().all(|&b| b != 0.0));
        }
    }
}
