//! The obstacle: a polygon mesh of fixed topology (the body) whose positions the caller gives at
//! the start and end of each frame; substeps interpolate linearly between them, so every body
//! vertex moves with the constant velocity (end − start) / (t₁ − t₀) (see [`crate::response`]
//! for where each pass sits in the step).
//!
//! Contacts and the final projection use the closest body point of each cloth vertex
//! ([`Hierarchy::closest_points`]); the direction away from the body is from that point to the
//! vertex when the vertex is in front of the face, the face's outward normal when it is behind
//! (inside the body). The continuous pass refits both hierarchies over the substep's motion
//! ([`Hierarchy::refit_swept`]) and asks for vertex–triangle impacts
//! ([`Hierarchy::impacts_with`]), so a vertex cannot cross a body face between two substeps
//! however fast either moves (Bridson, Fedkiw & Anderson 2002, §6).

use tailor_collide::{Closest, CollideError, DistanceBounds, Hierarchy, VertexTriangleImpact};
use tailor_subdiv::Point;

use crate::ClothError;
use crate::constraint::{Contact, Filter};
use crate::energy::Vec3;
use crate::settings::Settings;
use crate::substep::{Floor, Substep};

/// Rounds of the continuous pass: each re-tests the paths the last one changed.
const IMPACT_ROUNDS: usize = 4;

/// How far past half the thickness the projection puts a vertex, relative to it, so that the
/// distance measured afterwards is not below half the thickness by rounding.
const PROJECTION_SLACK: f64 = 1e-6;

/// Height of strain limiting's floor above the body, in thicknesses: above the half that the
/// projection enforces, below the whole that contacts hold.
const FLOOR: f64 = 0.75;

/// How far from the body, in thicknesses, a vertex counts as resting on it: the first look
/// for contacts adds gravity's pull over the substep to such a vertex's velocity. A resting
/// vertex sits at the thickness or a little above it (the refined-surface lift raises control
/// points by the sag of the surface between them). Farther away, gravity's pull (g h², 4 mm
/// at 1/48 s) took vertices up to three thicknesses off the body as contacts, and a
/// contact's approach velocity then drew them onto it: the rim of a pedestal held a draped
/// skirt out. A free vertex the solve brings closer than half the thickness becomes a contact
/// at the second look.
const RESTING: f64 = 1.2;

/// A moving polygon mesh the garment collides with.
#[derive(Clone, Debug)]
pub(crate) struct Obstacle {
    hierarchy: Hierarchy,
    /// Times of the frame's start and end positions.
    times: [f64; 2],
    frame: [Vec<Point>; 2],
    /// Positions at the current substep's start and end.
    substep: [Vec<Point>; 2],
    /// Velocity of each body vertex over the current substep.
    velocity: Vec<Vec3>,
    /// The continuous pass's impacts, kept to reuse the allocation.
    impacts: Vec<VertexTriangleImpact>,
    /// The closest body point of each vertex at the start of the substep, within the reach
    /// of [`Self::find_contacts`].
    closest: Vec<Option<Closest>>,
    /// Lower bounds of those vertices' distances from the body, and the buffers of the
    /// vertices [`Self::find_contacts`] measures again (see [`Self::measure_start`]).
    bounds: DistanceBounds,
    stale: Vec<u32>,
    measured: Vec<u32>,
    measured_points: Vec<Point>,
    seeds: Vec<Option<u32>>,
    answers: Vec<Option<Closest>>,
    /// Where the last continuous pass or projection of the substep left the cloth, outside
    /// the body, and the buffers of the projection's deeper look ([`Self::project`]).
    checked: Vec<Point>,
    deep: Vec<usize>,
    deep_points: Vec<Point>,
    deep_answers: Vec<Option<Closest>>,
    /// The vertices a projection looks at, their positions and what it finds.
    asked: Vec<usize>,
    asked_points: Vec<Point>,
    projected: Vec<Option<Closest>>,
    /// Per vertex, whether the last projection of the substep found it at least half the
    /// thickness clear of the body (or nothing within the thickness) at `checked`; and that
    /// thickness. Empty when no projection has run since the body or `checked` moved.
    clear: Vec<bool>,
    clear_thickness: f64,
}

impl Obstacle {
    /// Builds the obstacle's hierarchy once, resting at `positions`.
    pub fn new(
        positions: &[Point],
        face_offsets: &[u32],
        face_vertices: &[u32],
    ) -> Result<Self, ClothError> {
        let hierarchy = Hierarchy::build(positions, face_offsets, face_vertices)?;
        let n = positions.len();
        Ok(Self {
            hierarchy,
            times: [0.0, 0.0],
            frame: [positions.to_vec(), positions.to_vec()],
            substep: [positions.to_vec(), positions.to_vec()],
            velocity: vec![Vec3::zeros(); n],
            impacts: Vec::new(),
            closest: Vec::new(),
            bounds: DistanceBounds::default(),
            stale: Vec::new(),
            measured: Vec::new(),
            measured_points: Vec::new(),
            seeds: Vec::new(),
            answers: Vec::new(),
            checked: Vec::new(),
            deep: Vec::new(),
            deep_points: Vec::new(),
            deep_answers: Vec::new(),
            asked: Vec::new(),
            asked_points: Vec::new(),
            projected: Vec::new(),
            clear: Vec::new(),
            clear_thickness: 0.0,
        })
    }

    /// The body at `start` at time `t0` and at `end` at time `t1`.
    pub fn set_motion(
        &mut self,
        t0: f64,
        start: &[Point],
        t1: f64,
        end: &[Point],
    ) -> Result<(), ClothError> {
        let expected = self.hierarchy.vertex_count();
        for (what, p) in [("obstacle start", start), ("obstacle end", end)] {
            if p.len() != expected {
                return Err(ClothError::WrongLength {
                    what,
                    given: p.len(),
                    expected,
                });
            }
            if let Some(bad) = p.iter().find(|q| !q.iter().all(|c| c.is_finite())) {
                return Err(ClothError::BadValue {
                    what: "obstacle position",
                    value: bad.coords.norm(),
                });
            }
        }
        if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
            return Err(ClothError::BadValue {
                what: "obstacle frame end time (must follow the start time)",
                value: t1,
            });
        }
        self.times = [t0, t1];
        self.frame[0].copy_from_slice(start);
        self.frame[1].copy_from_slice(end);
        Ok(())
    }

    /// Interpolates the body at the start and end of the substep `[t0, t0 + h]`; before and
    /// after the frame it holds still.
    pub fn begin_substep(&mut self, t0: f64, h: f64) {
        let [ta, tb] = self.times;
        let fraction = |t: f64| {
            if tb > ta {
                ((t - ta) / (tb - ta)).clamp(0.0, 1.0)
            } else {
                1.0
            }
        };
        let [start, end] = &self.frame;
        for (out, t) in self.substep.iter_mut().zip([t0, t0 + h]) {
            let s = fraction(t);
            for ((o, a), b) in out.iter_mut().zip(start).zip(end) {
                *o = a + (b - a) * s;
            }
        }
        let [a, b] = &self.substep;
        for ((v, a), b) in self.velocity.iter_mut().zip(a).zip(b) {
            *v = (b - a) / h;
        }
        self.clear.clear();
    }

    /// The body's velocity at a closest point.
    pub fn velocity_at(&self, c: &Closest) -> Vec3 {
        (0..3)
            .map(|k| self.velocity[c.vertices[k] as usize] * c.barycentric[k])
            .sum()
    }

    /// Contact constraints for the substep (step 1 of [`crate::response`]): every vertex that
    /// would end closer than the thickness if it kept its velocity (plus gravity's pull when
    /// it rests on the body, see [`RESTING`]), except those `lifted` off the body (see the
    /// `friction` module) while they are farther than the thickness; a lifted vertex within
    /// it is no longer lifted. Looks as far as the fastest cloth vertex and body vertex can
    /// close in one substep.
    pub fn find_contacts(
        &mut self,
        settings: &Settings,
        h: f64,
        x0: &[Point],
        v0: &[Vec3],
        lifted: &mut [bool],
        out: &mut Vec<Contact>,
    ) -> Result<(), CollideError> {
        let thickness = settings.thickness;
        let fastest = |v: &[Vec3]| v.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let reach = h * (fastest(v0) + h * settings.gravity.norm() + fastest(&self.velocity));
        self.hierarchy.refit(&self.substep[0], 0.0)?;
        self.measure_start(x0, thickness + reach)?;
        for (i, c) in self.closest.iter().enumerate() {
            let Some(c) = c else {
                lifted[i] = false;
                continue;
            };
            let (normal, distance) = away_from(x0[i], c);
            if lifted[i] {
                if distance >= thickness {
                    continue;
                }
                lifted[i] = false;
            }
            let body = self.velocity_at(c);
            // Gravity's pull only for a vertex resting on the body (see `RESTING`).
            let pull = if distance <= RESTING * thickness {
                settings.gravity * h
            } else {
                Vec3::zeros()
            };
            let closing = (v0[i] + pull - body).dot(&normal);
            if distance + h * closing < thickness {
                out.push(contact(i, normal, distance, body, thickness, h));
            }
        }
        Ok(())
    }

    /// The closest body point within `limit` of each of the positions `x0` into
    /// [`Self::closest`], the same bits as asking of them all
    /// ([`Hierarchy::closest_points_into`]), at less cost: a vertex whose distance bound
    /// ([`DistanceBounds`]: its last distance, or the radius nothing was found within, less
    /// how far it and the body moved since) is past `limit` has none, and the others are asked
    /// starting from the face of their last answer ([`Hierarchy::closest_points_seeded_into`]),
    /// a few millimetres from the new one at most in a drape. On the 64² drape at one substep a
    /// frame, two vertices in five hang farther from the sphere than the reach, and the seeded
    /// walks take 10–20% less time.
    fn measure_start(&mut self, x0: &[Point], limit: f64) -> Result<(), CollideError> {
        let n = x0.len();
        if self.closest.len() != n {
            self.closest.clear();
            self.closest.resize(n, None);
            self.bounds.forget();
        }
        // Lowers every bound by the motions since the last call (the listed vertices are
        // asked below like any whose bound is not past the limit).
        self.bounds
            .stale(&self.hierarchy, x0, limit, &mut self.stale);
        self.measured.clear();
        self.measured_points.clear();
        self.seeds.clear();
        for (i, c) in self.closest.iter_mut().enumerate() {
            if self.bounds.past(i as u32, limit) {
                *c = None;
            } else {
                self.measured.push(i as u32);
                self.measured_points.push(x0[i]);
                self.seeds.push(c.map(|c| c.face));
            }
        }
        self.hierarchy.closest_points_seeded_into(
            &self.measured_points,
            limit,
            &self.seeds,
            &mut self.answers,
        )?;
        for (&i, answer) in self.measured.iter().zip(&self.answers) {
            self.closest[i as usize] = *answer;
            self.bounds.set(i, answer.map_or(limit, |c| c.distance));
        }
        Ok(())
    }

    /// Contacts the solve missed (step 1's second look): each vertex `filter` leaves free
    /// that ends the substep at `x` closer than half the thickness to the moving
    /// plane of its start's closest body point (found by the last [`Self::find_contacts`])
    /// gets the contact that call would have given it, appended to `out`. Returns how many.
    pub fn missed_contacts(
        &self,
        thickness: f64,
        h: f64,
        x0: &[Point],
        x: &[Point],
        filter: &Filter,
        out: &mut Vec<Contact>,
    ) -> usize {
        let before = out.len();
        for (i, c) in self.closest.iter().enumerate() {
            let Some(c) = c else { continue };
            if !filter.is_free(i) {
                continue;
            }
            let (normal, distance) = away_from(x0[i], c);
            let body = self.velocity_at(c);
            if (x[i] - c.point - body * h).dot(&normal) < 0.5 * thickness {
                out.push(contact(i, normal, distance, body, thickness, h));
            }
        }
        out.len() - before
    }

    /// For every vertex with a closest body point at the last [`Self::find_contacts`], the
    /// floor of strain limiting: the plane through that point as the body carries it to the
    /// end of the substep of length `h`, raised by [`FLOOR`] times the thickness.
    pub fn floors(&self, thickness: f64, h: f64, x0: &[Point], out: &mut [Floor]) {
        for (i, c) in self.closest.iter().enumerate() {
            if let Some(c) = c {
                let (normal, _) = away_from(x0[i], c);
                let end = c.point + self.velocity_at(c) * h;
                out[i] = Floor {
                    normal,
                    offset: normal.dot(&end.coords) + FLOOR * thickness,
                };
            }
        }
    }

    /// Puts back on the front of a body face every vertex whose path over the substep enters
    /// that face from the front (step 5 of [`crate::response`]), at the thickness, with no
    /// velocity into the face. Returns how many vertices it moved.
    pub fn resolve_impacts(
        &mut self,
        cloth: &mut Hierarchy,
        thickness: f64,
        m: &mut Substep,
    ) -> Result<u32, CollideError> {
        let [start, end] = &self.substep;
        self.hierarchy.refit_swept(start, end, 0.0)?;
        let triangles = self.hierarchy.triangles();
        let mut moved = 0;
        for _ in 0..IMPACT_ROUNDS {
            cloth.refit_swept(m.x0, m.x, 0.0)?;
            cloth.vertex_impacts_with_into(&self.hierarchy, &mut self.impacts);
            let mut changed = false;
            // Sorted by vertex: take each vertex's earliest impact.
            for group in self.impacts.chunk_by(|a, b| a.vertex == b.vertex) {
                let hit = group
                    .iter()
                    .min_by(|a, b| a.time.total_cmp(&b.time))
                    .expect("chunks are not empty");
                let i = hit.vertex as usize;
                if m.inverse_mass[i] == 0.0 {
                    continue;
                }
                let corners = triangles[hit.triangle as usize].map(|k| k as usize);
                let point = |p: &[Point]| -> Point {
                    let w = hit.barycentric;
                    Point::from(
                        p[corners[0]].coords * w[0]
                            + p[corners[1]].coords * w[1]
                            + p[corners[2]].coords * w[2],
                    )
                };
                let normal_at = |t: f64| {
                    let c = corners.map(|k| start[k] + (end[k] - start[k]) * t);
                    (c[1] - c[0]).cross(&(c[2] - c[0])).normalize()
                };
                let relative = (m.x[i] - m.x0[i]) - (point(end) - point(start));
                if relative.dot(&normal_at(hit.time)) >= 0.0 {
                    continue; // leaving the body through this face
                }
                let normal = normal_at(1.0);
                if !normal.iter().all(|c| c.is_finite()) {
                    continue;
                }
                m.x[i] = point(end) + normal * thickness;
                m.stop_approach(i, normal, (point(end) - point(start)) / m.h);
                changed = true;
                moved += 1;
            }
            if !changed {
                break;
            }
        }
        self.checked.clear();
        self.checked.extend_from_slice(m.x);
        self.clear.clear();
        Ok(moved)
    }

    /// Pushes every vertex closer to the body than half the thickness (or behind a face) out
    /// to half the thickness, removing its velocity into the body. Returns how many it moved.
    ///
    /// Call after [`Self::resolve_impacts`] in the same substep: the passes between (strain
    /// limiting, the self impacts and their impact zones) can move a vertex into the body
    /// deeper than the thickness, where a search within the thickness would not find it and
    /// every later look would leave it inside (the 64² drape at one substep a frame: four
    /// vertices 7 mm inside the sphere from frame 15 on). So a vertex that has moved farther
    /// than the thickness since the continuous pass or the last projection left it outside is
    /// sought within how far it moved, which reaches its closest point however deep it went.
    /// A vertex an earlier projection of the substep found clear, and that has not moved
    /// since, is not sought again: the body has not moved either, so the answer would be the
    /// same.
    pub fn project(&mut self, thickness: f64, m: &mut Substep) -> Result<u32, CollideError> {
        self.hierarchy.refit(&self.substep[1], 0.0)?;
        let n = m.x.len();
        let checked = self.checked.len() == n;
        // A vertex the last projection of the substep found clear, and that has not moved
        // since, would be found clear again.
        let known = checked && self.clear.len() == n && self.clear_thickness == thickness;
        if !known {
            self.clear.clear();
            self.clear.resize(n, false);
            self.clear_thickness = thickness;
        }
        self.asked.clear();
        self.asked_points.clear();
        for (i, x) in m.x.iter().enumerate() {
            if !(known && self.clear[i] && *x == self.checked[i]) {
                self.asked.push(i);
                self.asked_points.push(*x);
            }
        }
        self.hierarchy
            .closest_points_into(&self.asked_points, thickness, &mut self.projected)?;
        if checked {
            self.deep.clear();
            let mut reach = 0.0_f64;
            for (k, &i) in self.asked.iter().enumerate() {
                let moved = (m.x[i] - self.checked[i]).norm();
                if moved > thickness {
                    self.deep.push(k);
                    reach = reach.max(moved);
                }
            }
            if !self.deep.is_empty() {
                self.deep_points.clear();
                self.deep_points
                    .extend(self.deep.iter().map(|&k| self.asked_points[k]));
                self.hierarchy.closest_points_into(
                    &self.deep_points,
                    reach,
                    &mut self.deep_answers,
                )?;
                for (&k, answer) in self.deep.iter().zip(&self.deep_answers) {
                    self.projected[k] = *answer;
                }
            }
        }
        let floor = 0.5 * thickness;
        let mut moved = 0;
        for (&i, c) in self.asked.iter().zip(&self.projected) {
            let Some(c) = c else {
                self.clear[i] = true;
                continue;
            };
            let (normal, distance) = away_from(m.x[i], c);
            self.clear[i] = distance >= floor;
            if distance >= floor || m.inverse_mass[i] == 0.0 {
                continue;
            }
            m.x[i] = c.point + normal * (floor * (1.0 + PROJECTION_SLACK));
            m.stop_approach(i, normal, self.velocity_at(c));
            moved += 1;
        }
        self.checked.clear();
        self.checked.extend_from_slice(m.x);
        Ok(moved)
    }

    /// The body's hierarchy, refit where the last [`Self::project`] left it: at the
    /// substep's end.
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hierarchy
    }
}

/// The unit direction away from the body at the closest point `c` to `q`, and the signed
/// distance along it (negative behind the face, i.e. inside the body).
/// The contact of vertex `i`, `distance` from the body along `normal` at the start of a
/// substep of length `h`, the body point moving at `body`: its normal velocity follows the
/// body's, plus the approach that ends it at the thickness when it is farther.
fn contact(i: usize, normal: Vec3, distance: f64, body: Vec3, thickness: f64, h: f64) -> Contact {
    let approach = (distance - thickness).max(0.0) / h;
    Contact {
        vertex: i as u32,
        normal,
        velocity: body - normal * approach,
    }
}

pub(super) fn away_from(q: Point, c: &Closest) -> (Vec3, f64) {
    let offset = q - c.point;
    if offset.dot(&c.normal) > 0.0 && c.distance > 0.0 {
        (offset / c.distance, c.distance)
    } else {
        (c.normal, -c.distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Mat3;
    use crate::shapes::block;

    /// A floor whose top is y = 0 (a 2 m box), as an obstacle.
    fn floor() -> Obstacle {
        let floor = block(Point::new(-1.0, -1.0, -1.0), Point::new(1.0, 0.0, 1.0));
        Obstacle::new(
            floor.positions(),
            floor.face_offsets(),
            floor.face_vertices(),
        )
        .expect("a box")
    }

    /// Over moving cloth points, a body that moves on some substeps and holds still on
    /// others, and a reach that grows and shrinks, the closest points the contacts are found
    /// from, measured again only where the distance bounds require and from last answers'
    /// faces, are the same bits as asking of every point afresh; and the bounds spare some of
    /// the asking.
    #[test]
    fn the_start_is_measured_as_asking_of_every_vertex() {
        let sphere = crate::shapes::sphere(Point::origin(), 0.5, 8, 12);
        let (offsets, vertices) = (sphere.face_offsets(), sphere.face_vertices());
        let mut obstacle = Obstacle::new(sphere.positions(), offsets, vertices).expect("a sphere");
        let mut rng = crate::testing::Rng::new(3);
        let mut x0: Vec<Point> = (0..300).map(|_| Point::from(rng.vec3() * 0.8)).collect();
        let (mut asked, mut offset) = (0, Vec3::zeros());
        for step in 0..12u32 {
            let before = offset;
            if step % 3 != 1 {
                offset += rng.vec3() * 0.01;
            }
            let at = |d: Vec3| sphere.positions().iter().map(|p| p + d).collect::<Vec<_>>();
            let (t0, t1) = (f64::from(step), f64::from(step) + 1.0);
            obstacle
                .set_motion(t0, &at(before), t1, &at(offset))
                .unwrap();
            obstacle.begin_substep(t0, 1.0);
            obstacle.hierarchy.refit(&obstacle.substep[0], 0.0).unwrap();
            for (i, p) in x0.iter_mut().enumerate() {
                if i % 4 != 0 || step % 2 == 0 {
                    *p += rng.vec3() * 0.02;
                }
            }
            let limit = [0.05, 0.2, 0.1][step as usize % 3];
            obstacle.measure_start(&x0, limit).unwrap();
            asked += obstacle.measured.len();
            let want = obstacle.hierarchy.closest_points(&x0, limit).unwrap();
            assert_eq!(obstacle.closest, want, "step {step}");
        }
        assert!(asked < 12 * x0.len(), "{asked} measured");
    }

    #[test]
    fn a_vertex_the_solve_takes_into_the_body_becomes_a_contact_on_its_start_plane() {
        // A floor whose top is y = 0; substeps of 10 ms, thickness 5 mm.
        let mut obstacle = floor();
        let settings = Settings::default();
        let h = 0.01;
        obstacle.begin_substep(0.0, h);
        // Vertex 0 falls at 1 m/s from 2 cm (the first look reaches 1.1 cm), vertex 1 rests
        // 12 mm up, vertex 2 rests 12 mm up but is pinned: none is expected to reach the
        // thickness, so there are no contacts before the solve.
        let x0 = [0.02, 0.012, 0.012].map(|y| Point::new(0.0, y, 0.0));
        let v0 = [-Vec3::y(), Vec3::zeros(), Vec3::zeros()];
        let mut contacts = Vec::new();
        obstacle
            .find_contacts(&settings, h, &x0, &v0, &mut [false; 3], &mut contacts)
            .expect("finite");
        assert!(contacts.is_empty());
        // The solve ends vertex 0 at 1 cm, vertex 1 and 2 at 1 mm (pulled in by the cloth).
        let x = [0.01, 0.001, 0.001].map(|y| Point::new(0.0, y, 0.0));
        let mut filter = Filter::new(3);
        filter.s[2] = Mat3::zeros();
        let added =
            obstacle.missed_contacts(settings.thickness, h, &x0, &x, &filter, &mut contacts);
        assert_eq!(added, 1);
        let c = &contacts[0];
        assert_eq!(c.vertex, 1);
        assert!((c.normal - Vec3::y()).norm() < 1e-12);
        // Its normal velocity brings it from 12 mm to the thickness over the substep.
        let expected = -(0.012 - settings.thickness) / h;
        assert!(
            (c.velocity - Vec3::y() * expected).norm() < 1e-9,
            "{:?}",
            c.velocity
        );
    }

    /// Runs `test` on [`floor`] at the start of a 10 ms substep and an `n` × `n` sheet 20 cm
    /// square at `height` above its top, every vertex free and moving at `velocity`, after
    /// the continuous pass: the obstacle, the thickness (5 mm) and the substep.
    fn sheet_above_floor(
        n: u32,
        height: f64,
        velocity: Vec3,
        test: impl FnOnce(&mut Obstacle, f64, &mut Substep),
    ) {
        let mut obstacle = floor();
        let thickness = 0.005;
        let h = 0.01;
        obstacle.begin_substep(0.0, h);
        let sheet = crate::shapes::centred_sheet(n, 0.2);
        let x0: Vec<Point> = sheet
            .positions()
            .iter()
            .map(|p| p + Vec3::y() * height)
            .collect();
        let mut cloth =
            Hierarchy::build(&x0, sheet.face_offsets(), sheet.face_vertices()).expect("a sheet");
        let mut x = x0.clone();
        let mut v = vec![velocity; x.len()];
        let inverse_mass = vec![1.0; x.len()];
        let mut m = Substep {
            h,
            x0: &x0,
            x: &mut x,
            v: &mut v,
            inverse_mass: &inverse_mass,
        };
        // At rest or moving up, above the floor: the continuous pass moves nothing.
        assert_eq!(
            obstacle.resolve_impacts(&mut cloth, thickness, &mut m),
            Ok(0)
        );
        test(&mut obstacle, thickness, &mut m);
    }

    /// A vertex the passes after the continuous one move deeper into the body than the
    /// thickness is still found and put out; one that moved as far but stays out is left.
    #[test]
    fn the_projection_finds_a_vertex_moved_deep_into_the_body() {
        // A 3 × 3 sheet 1 cm above the floor, at rest.
        sheet_above_floor(3, 0.01, Vec3::zeros(), |obstacle, thickness, m| {
            // A self pass then takes the middle vertex 2 cm into the floor, a corner 3 mm
            // into it and another corner 3 cm up.
            m.x[4].y = -0.02;
            m.x[0].y = -0.003;
            m.x[8].y = 0.04;
            assert_eq!(obstacle.project(thickness, m), Ok(2));
            for i in [0, 4] {
                assert!(
                    (m.x[i].y - 0.5 * thickness).abs() < 1e-6 * thickness,
                    "vertex {i} at {}",
                    m.x[i]
                );
                assert!(m.v[i].y >= 0.0, "vertex {i} still moves in: {}", m.v[i]);
            }
            assert_eq!(m.x[8].y, 0.04);
        });
    }

    /// A second projection in the substep skips the vertices the first found clear and that
    /// have not moved since, and ends as one that looks at every vertex.
    #[test]
    fn a_projection_again_gives_the_bytes_of_a_full_one() {
        // A 5 × 5 sheet 4 mm above the floor (within the thickness, outside its half),
        // moving up, so that a vertex's velocity shows whether a projection stopped its
        // approach.
        sheet_above_floor(5, 0.004, Vec3::y(), |obstacle, thickness, m| {
            m.x[3].y = -0.001;
            assert_eq!(obstacle.project(thickness, m), Ok(1));
            // Then passes move vertices: into the body, deep into it, within half the
            // thickness, and along it; the rest stay where the projection found them clear.
            m.x[7].y = -0.002;
            m.x[12].y = -0.03;
            m.x[18].y = 0.001;
            m.x[20].x += 0.001;
            let mut full = obstacle.clone();
            full.clear.clear();
            let (mut x_full, mut v_full) = (m.x.to_vec(), m.v.to_vec());
            let mut m_full = Substep {
                h: m.h,
                x0: m.x0,
                x: &mut x_full,
                v: &mut v_full,
                inverse_mass: m.inverse_mass,
            };
            let again = obstacle.project(thickness, m);
            assert_eq!(again, Ok(3));
            assert_eq!(full.project(thickness, &mut m_full), again);
            assert_eq!(m.x, m_full.x);
            assert_eq!(m.v, m_full.v);
            // Vertex 3, put out by the first projection, is looked at again: where it was
            // put is not known to be clear.
            assert_eq!(obstacle.asked, [3, 7, 12, 18, 20]);
            assert_eq!(full.asked.len(), 25);
        });
    }

    #[test]
    fn gravity_draws_only_resting_vertices_into_contact_before_the_solve() {
        // A floor whose top is y = 0; substeps of 1/48 s, over which gravity pulls a vertex
        // at rest down by g h² = 4.3 mm; thickness 5 mm.
        let mut obstacle = floor();
        let settings = Settings::default();
        let h = 1.0 / 48.0;
        obstacle.begin_substep(0.0, h);
        // At rest 5.5 mm up (resting on the floor: gravity counts) and 7 mm up (not resting:
        // it would take gravity's pull to the thickness; the second look is for that).
        let x0 = [0.0055, 0.007].map(|y| Point::new(0.0, y, 0.0));
        let v0 = [Vec3::zeros(); 2];
        let mut contacts = Vec::new();
        obstacle
            .find_contacts(&settings, h, &x0, &v0, &mut [false; 2], &mut contacts)
            .expect("finite");
        let vertices: Vec<u32> = contacts.iter().map(|c| c.vertex).collect();
        assert_eq!(vertices, [0]);
    }
}
