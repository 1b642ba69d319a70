//! Clearance of the subdivided surface: the surface that renders, not only its control
//! points, keeps the thickness from the body.
//!
//! The particles are the control points (DeRose, Kass & Truong 1998, §5), but what the camera
//! sees, and what `tailor check` measures, is the Catmull-Clark surface they define. That
//! surface does not pass through its control points: where the cloth wraps a shoulder it lies
//! inside the control polygon by about a²/6R (edge length a, radius R; 2 mm for 2 cm edges
//! round a 3 cm arm), and between two control points resting on the body it can dip into a
//! bulge the control points straddle. So after the control-point passes, the refined points
//! r = S x (the caller's stencil table S, [`tailor_subdiv::StencilTable`]) are measured against
//! the body, and each refined point k closer than the thickness by δₖ along the direction n̂ₖ
//! away from the body asks for the control points of its stencil to move by δₖ n̂ₖ / Σⱼ wₖⱼ
//! (the translation of its movable points that clears it exactly, since its weights sum to
//! one). A control point j takes the average of the requests on it, weighted by wₖⱼ: a lone
//! violation is cleared exactly, a uniform one is a uniform lift. A few rounds, each
//! re-measured, settle overlapping requests. The move's velocity into the body, relative to the
//! body's at the refined point, is removed, as the control-point projection does.
//!
//! Every sum runs in a fixed order, so the result does not depend on the thread count.

use tailor_collide::{Closest, CollideError, DistanceBounds, Hierarchy};
use tailor_subdiv::{Point, Refreshed, StencilTable};

use super::obstacle::away_from;
use super::surface_layers::SurfaceLayers;
use crate::energy::Vec3;
use crate::substep::Substep;

/// Most rounds of measure-and-lift per substep; the pass stops at the first round that finds
/// nothing to lift. Overlapping requests settle geometrically (each round lifts a control
/// point by the mean of its requests): 8 rounds left the 13² drape's surface 0.03 mm inside
/// the thickness under a 1% change of the CG tolerance.
const ROUNDS: usize = 32;

/// The radius, in thicknesses, within which a refined point measured again is asked for the
/// body: a point found nothing within it skips the queries until it or the body has moved by
/// the difference from the thickness.
const REACH: f64 = 2.0;

/// How far past the thickness a lifted refined point is aimed, relative to it, so that the
/// distance measured afterwards is not below the thickness by rounding.
const SLACK: f64 = 0.01;

/// How far past the thickness a refined point must lie to count as clear, relative to the
/// sum of the largest coordinates of the body and of the cloth: 2⁻²¹. Written as `f32` (the
/// output's default precision), each coordinate of a refined point and of the body's vertices
/// moves by up to 2⁻²⁴ of its magnitude, and read back into `f64` (as `tailor check` reads)
/// by as much again, so a distance by less than √3 · 2⁻²³ times that sum; twice that keeps a
/// point the simulation left clear clear in the files (1.4 µm for a body and a cloth within
/// 1.5 m of the origin, against a thickness of millimetres).
const ROUNDING: f64 = 1.0 / (1u64 << 21) as f64;

/// The refined surface of the garment and the buffers of its pass.
#[derive(Clone, Debug)]
pub(crate) struct Surface {
    stencils: StencilTable,
    /// The refined faces, when the surface must not pass through itself either.
    layers: Option<SurfaceLayers>,
    /// The refined points, computed again where the control points moved.
    points: Refreshed<Point>,
    /// What the body's hierarchy answered for each refined point at its last measure: its
    /// closest point within the thickness.
    closest: Vec<Option<Closest>>,
    /// The refined points that have one, in ascending order: the lift's rounds visit these
    /// alone (a few thousand of a garment's tens of thousands of points rest on the body) rather
    /// than every answer, and in the same order.
    near: Vec<u32>,
    /// The list `near` is rebuilt into.
    spare: Vec<u32>,
    /// Lower bounds of the refined points' distances from the body, as of their positions and
    /// the body's at the last measure.
    bounds: DistanceBounds,
    /// The refined points to measure, and their answers.
    moved: Vec<u32>,
    queries: Vec<Point>,
    answers: Vec<Option<Closest>>,
    /// Per control point: weighted sums of requested moves and of body velocities, and of the
    /// weights; zero but for the control points `lifted` lists, while a round sums them.
    lift: Vec<Vec3>,
    body: Vec<Vec3>,
    weight: Vec<f64>,
    lifted: Vec<u32>,
}

impl Surface {
    /// The surface `stencils` evaluates through `points` (made for them, nothing evaluated
    /// yet), with `layers` its faces when it must clear itself.
    pub fn new(
        stencils: StencilTable,
        points: Refreshed<Point>,
        layers: Option<SurfaceLayers>,
    ) -> Self {
        let n = stencils.control_points;
        Self {
            points,
            closest: vec![None; stencils.len()],
            near: Vec::new(),
            spare: Vec::new(),
            bounds: DistanceBounds::default(),
            moved: Vec::new(),
            queries: Vec::new(),
            answers: Vec::new(),
            stencils,
            layers,
            lift: vec![Vec3::zeros(); n],
            body: vec![Vec3::zeros(); n],
            weight: vec![0.0; n],
            lifted: Vec::new(),
        }
    }

    /// Lifts the control points of `m` until every refined point is at least `thickness` from
    /// `body` (refit at the substep's end), with `velocity_at` the body's velocity at a closest
    /// point, and by a margin for rounding ([`ROUNDING`]). Returns how many control-point
    /// moves it made.
    pub fn clear(
        &mut self,
        body: &Hierarchy,
        velocity_at: impl Fn(&tailor_collide::Closest) -> Vec3,
        thickness: f64,
        m: &mut Substep,
    ) -> Result<u32, CollideError> {
        let mut moved = 0;
        // The margin, from the positions before any lift (which moves the cloth by about the
        // thickness, far less than the margin's factor of two covers).
        let mut clear = thickness;
        for round in 0..ROUNDS {
            let points = self.points.update(&self.stencils, m.x);
            if round == 0 {
                let cloth = points.iter().map(|p| p.coords.amax());
                let largest = cloth.fold(0.0, f64::max) + body.largest_coordinate();
                clear += ROUNDING * largest;
            }
            let target = clear + thickness * SLACK;
            self.measure(body, clear)?;
            let mut any = false;
            for &k in &self.near {
                let k = k as usize;
                let Some(c) = &self.closest[k] else { continue };
                let (normal, distance) = away_from(self.points.points()[k], c);
                if distance >= clear {
                    continue;
                }
                let (cols, weights) = self.stencils.rows.row(k);
                let movable: f64 = cols
                    .iter()
                    .zip(weights)
                    .filter(|&(&j, &w)| w > 0.0 && m.inverse_mass[j as usize] > 0.0)
                    .map(|(_, &w)| w)
                    .sum();
                if movable <= 0.0 {
                    continue;
                }
                let request = normal * ((target - distance) / movable);
                let velocity = velocity_at(c);
                for (&j, &w) in cols.iter().zip(weights) {
                    let j = j as usize;
                    if w > 0.0 && m.inverse_mass[j] > 0.0 {
                        if self.weight[j] == 0.0 {
                            self.lifted.push(j as u32);
                        }
                        self.lift[j] += request * w;
                        self.body[j] += velocity * w;
                        self.weight[j] += w;
                    }
                }
                any = true;
            }
            if !any {
                break;
            }
            // Each control point's move depends on its own sums alone: the order is free.
            for j in self.lifted.drain(..) {
                let j = j as usize;
                let w = std::mem::take(&mut self.weight[j]);
                let lift = std::mem::take(&mut self.lift[j]) / w;
                let body = std::mem::take(&mut self.body[j]);
                let Some(normal) = lift.try_normalize(0.0) else {
                    continue;
                };
                m.x[j] += lift;
                m.stop_approach(j, normal, body / w);
                moved += 1;
            }
        }
        Ok(moved)
    }

    /// The stencils, and the refined faces when the surface must clear itself.
    pub fn layers(&mut self) -> Option<(&StencilTable, &mut SurfaceLayers)> {
        let stencils = &self.stencils;
        self.layers.as_mut().map(|layers| (stencils, layers))
    }

    /// A new substep from control positions `x0`: the refined surface's start is taken for its
    /// self passes.
    pub fn begin_substep(&mut self, x0: &[Point]) {
        if let Some(layers) = &mut self.layers {
            layers.begin(&self.stencils, x0);
        }
    }

    /// The body's closest point within `clear` of every refined point into
    /// [`Self::closest`]. Only the points whose distance bound ([`DistanceBounds`]) is not past
    /// `clear` and that moved, or that the body moved under, are measured again; they are
    /// asked for the body within [`REACH`] times `clear`, so that the next bound is the
    /// distance found or that radius. Each query's answer depends on its point alone (the
    /// hierarchy's answers do not depend on the radius beyond the answer, on which other
    /// points are asked with it, or on the thread count), so the answers are the same bits as
    /// measuring every point within `clear`.
    fn measure(&mut self, body: &Hierarchy, clear: f64) -> Result<(), CollideError> {
        self.bounds
            .stale(body, self.points.points(), clear, &mut self.moved);
        self.queries.clear();
        self.queries
            .extend(self.moved.iter().map(|&k| self.points.points()[k as usize]));
        let reach = REACH * clear;
        body.closest_points_into(&self.queries, reach, &mut self.answers)?;
        for (&k, answer) in self.moved.iter().zip(&self.answers) {
            self.closest[k as usize] = answer.filter(|c| c.distance <= clear);
            self.bounds.set(k, answer.map_or(reach, |c| c.distance));
        }
        self.update_near();
        Ok(())
    }

    /// Brings [`Self::near`] up to date with the answers of the points just measured
    /// ([`Self::moved`]; both lists ascend): a merge of the two, keeping the points that have
    /// an answer.
    fn update_near(&mut self) {
        let (near, moved, closest) = (&self.near, &self.moved, &self.closest);
        debug_assert!(moved.is_sorted());
        self.spare.clear();
        let (mut i, mut j) = (0, 0);
        loop {
            let k = match (near.get(i), moved.get(j)) {
                (Some(&a), Some(&b)) if a <= b => {
                    i += 1;
                    j += usize::from(a == b);
                    a
                }
                (_, Some(&b)) => {
                    j += 1;
                    b
                }
                (Some(&a), None) => {
                    i += 1;
                    a
                }
                (None, None) => break,
            };
            if closest[k as usize].is_some() {
                self.spare.push(k);
            }
        }
        std::mem::swap(&mut self.near, &mut self.spare);
    }

    /// Whether the surface must clear itself.
    pub fn has_layers(&self) -> bool {
        self.layers.is_some()
    }
}

#[cfg(test)]
mod tests {
    use tailor_subdiv::Refiner;

    use super::*;
    use crate::shapes::{block, centred_sheet};

    /// A 5² sheet's level-1 surface at rest at y = 0, its control points free, and a 1 m box
    /// whose top is at `top`.
    fn sheet_and_box(top: f64) -> (Surface, Vec<Point>, Hierarchy) {
        let sheet = centred_sheet(5, 1.0);
        let stencils = Refiner::new(&sheet, 1).stencils();
        let surface = Surface::new(stencils.clone(), Refreshed::new(&stencils), None);
        let low = Point::new(-0.5, top - 1.0, -0.5);
        let body = block(low, low + Vec3::new(1.0, 1.0, 1.0));
        let hierarchy =
            Hierarchy::build(body.positions(), body.face_offsets(), body.face_vertices()).unwrap();
        (surface, sheet.positions().to_vec(), hierarchy)
    }

    /// Lifts `x` (a substep of 0.01 s from `x`, at rest) off `body`; returns the moves made.
    fn lift(surface: &mut Surface, body: &Hierarchy, x: &mut [Point]) -> u32 {
        let x0 = x.to_vec();
        let mut v = vec![Vec3::zeros(); x.len()];
        let inverse_mass = vec![1.0; x.len()];
        let mut m = Substep {
            h: 0.01,
            x0: &x0,
            x,
            v: &mut v,
            inverse_mass: &inverse_mass,
        };
        surface
            .clear(body, |_| Vec3::zeros(), 0.005, &mut m)
            .unwrap()
    }

    /// The lift measures again only the refined points that may have come within the
    /// thickness, over a body that moves between substeps, and its answers and its lift are
    /// those of measuring every point.
    #[test]
    fn the_lift_measured_again_where_needed_lifts_as_measuring_everything() {
        let (mut surface, mut x, mut body) = sheet_and_box(-0.1);
        body.refit(&body_positions(-0.1), 0.0).unwrap();
        assert_eq!(
            lift(&mut surface, &body, &mut x),
            0,
            "10 cm below: nothing to lift"
        );
        // The next substep: the box rises to 2 mm below the sheet.
        body.refit(&body_positions(-0.002), 0.0).unwrap();
        surface.begin_substep(&x);
        let lifted = lift(&mut surface, &body, &mut x);
        assert!(lifted > 0, "the box 2 mm below must lift the sheet");
        // Measuring only what moved gives the same bits as measuring everything.
        let (mut fresh, mut y, _) = sheet_and_box(-0.1);
        lift(&mut fresh, &body, &mut y);
        assert_eq!(x, y);
        assert_eq!(surface.closest, fresh.closest);
        for (k, p) in fresh.points.points().iter().enumerate() {
            let c = fresh.closest[k].map_or(f64::INFINITY, |c| c.distance);
            assert!(
                c >= 0.005 * (1.0 - 1e-9),
                "refined point {k} at {p} is {c} m off"
            );
        }
    }

    /// The points the lift's rounds visit are exactly those with an answer, in order, as the
    /// answers come and go between measures.
    #[test]
    fn the_points_with_an_answer_are_listed_in_order() {
        let answered = |s: &Surface| -> Vec<u32> {
            (0..s.closest.len() as u32)
                .filter(|&k| s.closest[k as usize].is_some())
                .collect()
        };
        // The box's top 3 mm under the sheet: every refined point within 5 mm.
        let (mut surface, x, body) = sheet_and_box(-0.003);
        surface.points.update(&surface.stencils, &x);
        surface.measure(&body, 0.005).unwrap();
        let all = answered(&surface);
        assert_eq!(all.len(), surface.closest.len());
        assert_eq!(surface.near, all);
        // The first two rows of control points raised 1 mm (still within reach), then 10 cm
        // (out of it), then put back.
        let raised = |by: f64| -> Vec<Point> {
            let mut y = x.clone();
            for p in y.iter_mut().take(10) {
                p.y += by;
            }
            y
        };
        for (control, count) in [(raised(0.001), all.len()), (raised(0.1), 0), (x, all.len())] {
            surface.points.update(&surface.stencils, &control);
            surface.measure(&body, 0.005).unwrap();
            let now = answered(&surface);
            assert!(!now.is_empty());
            if count > 0 {
                assert_eq!(now.len(), count);
            } else {
                assert!(now.len() < all.len());
            }
            assert_eq!(surface.near, now);
        }
    }

    /// The vertices of [`sheet_and_box`]'s box with its top at `top`.
    fn body_positions(top: f64) -> Vec<Point> {
        let low = Point::new(-0.5, top - 1.0, -0.5);
        block(low, low + Vec3::new(1.0, 1.0, 1.0))
            .positions()
            .to_vec()
    }
}
