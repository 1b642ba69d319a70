//! Scenarios with collisions: every frame, no cloth vertex closer to the obstacle than
//! half the thickness (nor inside it), no self-intersecting face pairs (the test `tailor check`
//! runs), edge stretch l/L − 1 at most 10% (the simulator's default strain limit), nothing
//! non-finite. Compression is left out: the limiter bounds it too, but the self-collision
//! passes run after it and may squash an edge of a buckling coarse mesh further. Sizes are small so the suite runs in debug builds; the benchmark (`benches/step.rs`) runs the drape at 32², 64² and 128².

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use tailor_cloth::shapes::{block, centred_sheet, sheet, sphere};
use tailor_cloth::{Integrator, Material, Motion, Settings, Simulator, State};
use tailor_collide::{Hierarchy, segments_closest_points};
use tailor_subdiv::{Mesh, Point, Refiner};

use common::{FRAME, farthest, moved, set_obstacle, simulator};

mod common;

fn hierarchy(mesh: &Mesh) -> Hierarchy {
    Hierarchy::build(mesh.positions(), mesh.face_offsets(), mesh.face_vertices()).unwrap()
}

/// The smallest signed distance of `points` from the surface of `h` (at its last refit).
fn nearest(h: &Hierarchy, points: &[Point]) -> f64 {
    h.signed_distances(points)
        .unwrap()
        .into_iter()
        .fold(f64::INFINITY, f64::min)
}

/// The checks of every frame, with the obstacle (if any) where it is; crossings only with
/// self-collision on (without it nothing prevents them).
struct Checker {
    cloth: Option<Hierarchy>,
    obstacle: Option<Hierarchy>,
    thickness: f64,
}

impl Checker {
    fn new(garment: &Mesh, obstacle: Option<&Mesh>, settings: &Settings) -> Self {
        Self {
            cloth: settings.self_collision.then(|| hierarchy(garment)),
            obstacle: obstacle.map(hierarchy),
            thickness: settings.thickness,
        }
    }

    fn check(&mut self, frame: u32, sim: &Simulator, state: &State, obstacle_at: Option<&[Point]>) {
        let p = &state.positions;
        let finite = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite());
        assert!(
            p.iter().all(|q| finite(&q.coords)) && state.velocities.iter().all(finite),
            "frame {frame}: non-finite"
        );
        let model = sim.model();
        let stretch = model
            .edges()
            .iter()
            .zip(model.rest_lengths())
            .map(|(&[a, b], l)| (p[a as usize] - p[b as usize]).norm() / l - 1.0)
            .fold(0.0, f64::max);
        assert!(stretch <= 0.1 + 1e-9, "frame {frame}: stretch {stretch}");
        if let Some(cloth) = &mut self.cloth {
            cloth.refit(p, 0.0).unwrap();
            let crossing = cloth.self_intersections();
            assert!(
                crossing.is_empty(),
                "frame {frame}: faces cross: {crossing:?}"
            );
        }
        if let (Some(h), Some(at)) = (&mut self.obstacle, obstacle_at) {
            h.refit(at, 0.0).unwrap();
            let nearest = nearest(h, p);
            assert!(
                nearest >= 0.5 * self.thickness,
                "frame {frame}: a vertex is {nearest} m from the obstacle"
            );
        }
    }
}

/// The sheet of `n`² falling 0.5 m onto a static sphere of radius 0.5 m for `frames` frames
/// of 1/`fps` s; `check` runs every frame.
fn drape(n: u32, fps: f64, frames: u32, settings: Settings, check: bool) -> (State, Simulator) {
    let garment = centred_sheet(n, 2.0);
    let ball = sphere(Point::new(0.0, -1.0, 0.0), 0.5, 12, 24);
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    set_obstacle(&mut sim, &ball);
    let mut checker = Checker::new(&garment, Some(&ball), &settings);
    for frame in 0..frames {
        sim.step(&mut state, 1.0 / fps).unwrap();
        if check {
            checker.check(frame, &sim, &state, Some(ball.positions()));
        }
    }
    (state, sim)
}

/// The sphere drape with `n`² vertices (odd `n` puts a vertex at the centre), 60 frames at
/// 24 fps, checked every frame.
fn sheet_drapes_over_a_sphere(n: u32, self_collision: bool) {
    let settings = Settings {
        self_collision,
        ..Settings::default()
    };
    let (state, _) = drape(n, 24.0, 60, settings, true);
    // Draped: the middle rests on top of the sphere (a corner of the central quad, the centre
    // vertex for odd n, within 1 cm of the thickness above it: which of them rests depends on
    // where the folds happen to cross the top), the corners hang well below its top.
    let centre = Point::new(0.0, -1.0, 0.0);
    let middle = [(n - 1) / 2, n / 2]
        .into_iter()
        .flat_map(|i| [(n - 1) / 2, n / 2].map(|j| state.positions[(i * n + j) as usize]))
        .map(|p| ((p - centre).norm() - 0.5 - settings.thickness).abs())
        .fold(f64::INFINITY, f64::min);
    assert!(
        middle < 0.01,
        "the middle is {middle} m off its resting height"
    );
    let corner = state.positions[0];
    assert!(corner.y < -0.9, "corner at {corner}");
}

#[test]
fn small_sheet_drapes_over_a_sphere_without_self_collision() {
    sheet_drapes_over_a_sphere(13, false);
}

#[test]
fn sheet_drapes_over_a_sphere_without_self_collision() {
    sheet_drapes_over_a_sphere(32, false);
}

#[test]
fn sheet_drapes_over_a_sphere_with_self_collision() {
    sheet_drapes_over_a_sphere(32, true);
}

/// The drape of `n`² with self-collision at 5 substeps a frame, at 24 and at 48 fps (substeps
/// of 1/120 and 1/240 s), and at 24 fps with 2 substeps (1/48 s): before contact (0.25 s)
/// the three are within 1 mm of each other. Backward Euler's damping, first order in the
/// step, put them 1.5 mm and 9 mm apart; BDF2's error is second order.
fn drape_does_not_depend_on_the_step(n: u32) {
    let settings = |substeps: f64| Settings {
        self_collision: true,
        max_substep: FRAME / substeps,
        integrator: Integrator::Bdf2,
        ..Settings::default()
    };
    let quarter_second =
        |fps: f64, substeps: f64| drape(n, fps, (fps / 4.0) as u32, settings(substeps), false).0;
    let at_24 = quarter_second(24.0, 5.0);
    for (other, what) in [
        (quarter_second(48.0, 2.5), "at 48 fps"),
        (quarter_second(24.0, 2.0), "at 2 substeps a frame"),
    ] {
        let apart = farthest(&at_24, &other);
        assert!(
            apart < 1e-3,
            "{n}²: {what}, {apart} m from 24 fps, 5 substeps"
        );
    }
}

#[test]
fn drape_does_not_depend_on_the_step_32() {
    drape_does_not_depend_on_the_step(32);
}

#[test]
#[ignore = "the 64² drape; CI runs it explicitly"]
fn drape_does_not_depend_on_the_step_64() {
    drape_does_not_depend_on_the_step(64);
}

#[test]
fn curtain_pinned_at_two_corners_keeps_its_invariants() {
    let n = 16;
    let garment = centred_sheet(n, 2.0);
    let settings = Settings {
        self_collision: true,
        ..Settings::default()
    };
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    sim.pin(&[0, n - 1], Motion::Fixed).unwrap();
    let mut checker = Checker::new(&garment, None, &settings);
    for frame in 0..36 {
        sim.step(&mut state, FRAME).unwrap();
        checker.check(frame, &sim, &state, None);
        let rest = sim.model().rest_positions();
        assert!((state.positions[0] - rest[0]).norm() <= 1e-12);
    }
    let fell = state.positions.iter().map(|p| -p.y).fold(0.0, f64::max);
    assert!(fell > 1.0, "the curtain did not fall ({fell} m)");
}

/// A 0.3 m sheet resting on a floor under gravity tilted by `slope` radians (the floor an
/// incline), no air drag, Coulomb friction `mu`: after `frames` frames, the mean velocity and
/// displacement of its vertices down the slope and their largest height above the floor.
fn slide_on_incline(slope: f64, mu: f64, frames: u32) -> (f64, f64, f64) {
    let settings = Settings {
        gravity: Vector3::new(slope.sin(), -slope.cos(), 0.0) * 9.81,
        friction: mu,
        ..Settings::default()
    };
    let lift = Vector3::new(0.0, settings.thickness, 0.0);
    let garment = moved(&centred_sheet(6, 0.3), lift);
    let lifted = garment.positions();
    let material = Material {
        drag: 0.0,
        ..Material::COTTON
    };
    let (mut sim, mut state) = simulator(&garment, &material, settings);
    let floor = block(Point::new(-5.0, -1.0, -5.0), Point::new(5.0, 0.0, 5.0));
    set_obstacle(&mut sim, &floor);
    for _ in 0..frames {
        sim.step(&mut state, FRAME).unwrap();
    }
    let count = state.positions.len() as f64;
    let velocity = state.velocities.iter().map(|v| v.x).sum::<f64>() / count;
    let moved = state
        .positions
        .iter()
        .zip(lifted)
        .map(|(p, q)| p.x - q.x)
        .sum::<f64>()
        / count;
    let height = state.positions.iter().map(|p| p.y).fold(0.0, f64::max);
    (velocity, moved, height)
}

/// A sheet laid on a floor: after its first substep, and after a later one, the normal forces
/// its contacts carry into the next substep (friction's N) add up to its weight. The first
/// substep is BDF2's trapezoidal start, whose contact impulses also cancel its explicit half:
/// over the half step alone they would weigh the sheet twice.
#[test]
fn the_contacts_carry_the_weight_of_a_sheet_at_rest() {
    let settings = Settings::default();
    let garment = moved(
        &centred_sheet(6, 0.3),
        Vector3::new(0.0, settings.thickness, 0.0),
    );
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    let floor = block(Point::new(-5.0, -1.0, -5.0), Point::new(5.0, 0.0, 5.0));
    set_obstacle(&mut sim, &floor);
    let weight = sim.model().masses().iter().sum::<f64>() * 9.81;
    for substeps in [1, 7] {
        for _ in 0..substeps {
            sim.step(&mut state, settings.max_substep).unwrap();
        }
        let carried: f64 = sim.contact_state().normal_force.iter().sum();
        assert!(
            (carried / weight - 1.0).abs() < 0.01,
            "after {substeps} substeps: {carried} N carried, {weight} N weight"
        );
    }
}

#[test]
fn friction_holds_a_sheet_on_a_gentle_incline_and_slows_it_on_a_steep_one() {
    // Coulomb: at rest while tan θ ≤ μ; else sliding at g (sin θ − μ cos θ). Half a second.
    let (frames, time) = (12, 12.0 * FRAME);
    let (velocity, moved, height) = slide_on_incline(20f64.to_radians(), 0.6, frames);
    assert!(
        velocity.abs() < 1e-3 && moved.abs() < 1e-3,
        "sticking sheet slid: {velocity} m/s, {moved} m"
    );
    assert!(height < 0.01, "the sheet left the incline ({height} m)");
    for mu in [0.0, 0.3] {
        let slope = 30f64.to_radians();
        let accel = 9.81 * (slope.sin() - mu * slope.cos());
        let (velocity, moved, height) = slide_on_incline(slope, mu, frames);
        // BDF2 started by a trapezoidal substep is exact under a constant acceleration.
        let (v, s) = (accel * time, 0.5 * accel * time * time);
        assert!(
            (velocity - v).abs() < 0.01 * v && (moved - s).abs() < 0.01 * s,
            "mu {mu}: {velocity} m/s after {moved} m, expected {v} m/s after {s} m"
        );
        assert!(
            height < 0.01,
            "mu {mu}: the sheet left the incline ({height} m)"
        );
    }
}

#[test]
fn sheet_folds_onto_itself_without_crossing() {
    // A 2 m × 1 m strip lying on a floor; its far edge is carried over a fold line at x = 0
    // and laid down 4 cm above the near half, so the middle must fold onto the lower layer.
    let (columns, rows) = (24, 8);
    let settings = Settings {
        self_collision: true,
        ..Settings::default()
    };
    let lift = Vector3::new(-1.0, settings.thickness, 0.0);
    let garment = moved(&sheet(columns, rows, 2.0, 1.0), lift);
    let floor = block(Point::new(-2.0, -0.5, -1.0), Point::new(2.0, 0.0, 2.0));
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    set_obstacle(&mut sim, &floor);
    let far_edge: Vec<u32> = (0..rows).map(|j| j * columns + columns - 1).collect();
    let axis_height = settings.thickness + 0.02;
    let fold = Motion::Script(Arc::new(move |t: f64| {
        let angle = std::f64::consts::PI * (t / 1.0).clamp(0.0, 1.0);
        let pivot = Vector3::new(0.0, axis_height, 0.0);
        let turn = UnitQuaternion::from_euler_angles(0.0, 0.0, angle);
        Isometry3::from_parts(Translation3::from(pivot - turn * pivot), turn)
    }));
    sim.pin(&far_edge, fold.clone()).unwrap();
    let mut checker = Checker::new(&garment, Some(&floor), &settings);
    for frame in 0..36 {
        sim.step(&mut state, FRAME).unwrap();
        checker.check(frame, &sim, &state, Some(floor.positions()));
    }
    // Folded: the far edge now lies over the near half, above the layer below it.
    let p = &state.positions;
    for &v in &far_edge {
        let q = p[v as usize];
        assert!(
            q.x < -0.9 && q.y > 2.0 * settings.thickness,
            "edge vertex at {q}"
        );
    }
}

#[test]
fn a_box_swept_through_the_sheet_in_one_frame_does_not_tunnel() {
    let n = 16;
    let garment = centred_sheet(n, 2.0);
    let settings = Settings::default();
    let (low, high) = (Point::new(-0.3, -0.8, -0.3), Point::new(0.3, -0.5, 0.3));
    let start = block(low, high);
    let rise = Vector3::new(0.0, 1.2, 0.0);
    let end: Vec<Point> = start.positions().iter().map(|p| p + rise).collect();
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    set_obstacle(&mut sim, &start);
    let mut checker = Checker::new(&garment, Some(&start), &settings);
    // One frame: the box passes from 0.5 m below the sheet to 0.4 m above it (29 m/s).
    sim.set_obstacle_motion(0.0, start.positions(), FRAME, &end)
        .unwrap();
    let mut pushed = 0;
    for frame in 0..12 {
        let report = sim.step(&mut state, FRAME).unwrap();
        pushed += report.impacts + report.contacts;
        let h = checker.obstacle.as_mut().unwrap();
        h.refit(&end, 0.0).unwrap();
        let nearest = nearest(h, &state.positions);
        assert!(
            nearest >= 0.5 * settings.thickness,
            "frame {frame}: {nearest} m"
        );
        assert!(
            state
                .positions
                .iter()
                .all(|p| p.iter().all(|c| c.is_finite()))
        );
    }
    assert!(pushed > 0);
    // The part of the sheet over the box was carried up with it, not left below.
    let middle = state.positions[(n / 2 * n + n / 2) as usize];
    assert!(middle.y > high.y + rise.y, "middle at {middle}");
}

#[test]
fn a_collision_surface_over_other_points_is_refused() {
    // Stencils over another garment's control points, and a hierarchy over another level's
    // refined points, are refused; the surface's own are taken.
    let garment = centred_sheet(5, 1.0);
    let settings = Settings {
        self_collision: true,
        ..Settings::default()
    };
    let (mut sim, _) = simulator(&garment, &Material::COTTON, settings);
    let refined_at = |level: u32| {
        let refiner = Refiner::new(&garment, level as usize);
        let stencils = refiner.stencils();
        let mut points = vec![Point::origin(); stencils.len()];
        stencils.apply(garment.positions(), &mut points);
        (stencils, refiner.refined_mesh(points, None))
    };
    let (stencils, refined) = refined_at(1);
    let (_, deeper) = refined_at(2);
    let other_garment = Refiner::new(&centred_sheet(4, 1.0), 1).stencils();
    let wrong = |result: Result<(), tailor_cloth::ClothError>| {
        matches!(result, Err(tailor_cloth::ClothError::WrongLength { .. }))
    };
    assert!(wrong(sim.set_collision_surface(other_garment, None)));
    assert!(wrong(sim.set_collision_surface(
        stencils.clone(),
        Some(&hierarchy(&deeper))
    )));
    sim.set_collision_surface(stencils, Some(&hierarchy(&refined)))
        .unwrap();
}

/// The closest distance of the sheet's level-2 Catmull-Clark surface to the ball after a
/// 13² drape of `frames` frames, with or without the simulator told about that surface.
fn drape_surface_clearance(frames: u32, with_surface: bool) -> (f64, f64) {
    let n = 13;
    let garment = centred_sheet(n, 2.0);
    let ball = sphere(Point::new(0.0, -1.0, 0.0), 0.5, 12, 24);
    let settings = Settings::default();
    let stencils = Refiner::new(&garment, 2).stencils();
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    set_obstacle(&mut sim, &ball);
    if with_surface {
        sim.set_collision_surface(stencils.clone(), None).unwrap();
    }
    let mut ball_hierarchy = hierarchy(&ball);
    ball_hierarchy.refit(ball.positions(), 0.0).unwrap();
    let mut refined = vec![Point::origin(); stencils.len()];
    let mut closest = f64::INFINITY;
    for _ in 0..frames {
        sim.step(&mut state, FRAME).unwrap();
        stencils.apply(&state.positions, &mut refined);
        closest = closest.min(nearest(&ball_hierarchy, &refined));
    }
    (closest, settings.thickness)
}

#[test]
fn the_subdivided_surface_keeps_the_thickness_when_the_simulator_knows_it() {
    // The sheet lands on the ball at about frame 8 and wraps it by frame 20.
    let (alone, thickness) = drape_surface_clearance(20, false);
    assert!(
        alone < 0.8 * thickness,
        "without the surface pass the refined surface should dip below the control points' \
         clearance (nearest {alone} m)"
    );
    let (with, thickness) = drape_surface_clearance(20, true);
    assert!(
        with >= thickness,
        "a refined point came within {with} m of the ball (thickness {thickness} m)"
    );
}

/// A cotton strip 2.5 cm wide with edges of `edge` m, clamped by its first two vertex rows
/// with 3 cm overhanging, after `frames` frames: the final state, the tip angle in degrees
/// (of the centreline's chord from the clamp to the tip, below the horizontal: over 90° it has
/// curled back over the clamp), the worst edge strain of any frame and the impacts.
fn clamped_strip(edge: f64, self_collision: bool, frames: u32) -> (State, f64, f64, u32) {
    let (length, width) = (0.03 + edge, 0.025);
    let columns = (length / edge).round() as u32 + 1;
    let rows = (width / edge).round() as u32 + 1;
    let garment = sheet(columns, rows, length, width);
    let settings = Settings {
        self_collision,
        ..Settings::default()
    };
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    let clamp: Vec<u32> = (0..rows)
        .flat_map(|j| [j * columns, j * columns + 1])
        .collect();
    sim.pin(&clamp, Motion::Fixed).unwrap();
    let (mut strain, mut impacts) = (0.0f64, 0);
    for _ in 0..frames {
        let report = sim.step(&mut state, FRAME).unwrap();
        strain = strain.max(report.max_strain);
        impacts += report.impacts;
    }
    let middle = rows / 2 * columns;
    let clamped = state.positions[(middle + 1) as usize];
    let tip = state.positions[(middle + columns - 1) as usize];
    let angle = (clamped.y - tip.y).atan2(tip.x - clamped.x).to_degrees();
    (state, angle, strain, impacts)
}

#[test]
fn a_finely_meshed_strip_droops_the_same_with_self_collision() {
    // Edges of a quarter and a half of the 5 mm thickness: in the rest shape every vertex lies
    // within the thickness of the faces up to four (two) rings around it. Nothing else comes
    // near, so self-collision must not change the droop: no repulsion, no impact.
    for (edge, frames) in [(0.00125, 24), (0.0025, 48)] {
        let (free, free_angle, free_strain, _) = clamped_strip(edge, false, frames);
        let (held, angle, strain, impacts) = clamped_strip(edge, true, frames);
        assert!(
            (30.0..80.0).contains(&free_angle),
            "edge {edge}: without self-collision the tip is at {free_angle}°"
        );
        let apart = farthest(&free, &held);
        assert!(
            apart <= 1e-9 && impacts == 0,
            "edge {edge}: self-collision moved the strip by {apart} m ({impacts} impacts), tip \
             at {angle}° against {free_angle}°"
        );
        assert!(
            strain <= 0.1 + 1e-9 && free_strain <= 0.1 + 1e-9,
            "edge {edge}: strain {strain}, {free_strain} without self-collision"
        );
    }
}

/// Two 3 cm strips of 4 cm quads crossing at right angles on a floor, the upper one let fall
/// onto the lower: where they cross, no vertex of either lies over the other's faces (the
/// vertices nearest the crossing sit 2 cm either side of its middle, the strips 3 cm wide),
/// so only their edges meet. Edge–edge repulsion holds the upper strip's edges 2.7 mm above
/// the lower's after a second (the lower pressed to half the thickness above the floor, as
/// the projection allows, the upper a little above the thickness); with vertex–face
/// repulsion alone the upper strip sank to the lower one's height, its edges 0.01 mm from
/// the lower's, where the impacts stopped them.
#[test]
fn crossing_strips_rest_a_thickness_apart_where_only_their_edges_meet() {
    let settings = Settings {
        self_collision: true,
        ..Settings::default()
    };
    let t = settings.thickness;
    let along = [-0.10, -0.06, -0.02, 0.02, 0.06, 0.10];
    let across = [-0.015, 0.015];
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    // The lower strip along x at the thickness above the floor, the upper along z 8 mm
    // higher; each a row of quads wound to face up.
    for (lower, height) in [(true, t), (false, t + 0.008)] {
        let first = positions.len() as u32;
        for &a in &along {
            for &c in &across {
                let (x, z) = if lower { (a, c) } else { (c, a) };
                positions.push(Point::new(x, height, z));
            }
        }
        for k in 0..along.len() as u32 - 1 {
            let v = first + 2 * k;
            faces.push(if lower {
                [v, v + 1, v + 3, v + 2]
            } else {
                [v, v + 2, v + 3, v + 1]
            });
        }
    }
    let garment = Mesh::from_polygons(positions, &faces).unwrap();
    let (mut sim, mut state) = simulator(&garment, &Material::COTTON, settings);
    let floor = block(Point::new(-1.0, -0.5, -1.0), Point::new(1.0, 0.0, 1.0));
    set_obstacle(&mut sim, &floor);
    let mut checker = Checker::new(&garment, Some(&floor), &settings);
    for frame in 0..24 {
        sim.step(&mut state, FRAME).unwrap();
        checker.check(frame, &sim, &state, Some(floor.positions()));
    }
    let p = &state.positions;
    let edges = sim.model().edges();
    let half = along.len() * across.len();
    let upper = |e: &[u32; 2]| e[0] as usize >= half;
    let gap = edges
        .iter()
        .filter(|e| !upper(e))
        .flat_map(|a| edges.iter().filter(|e| upper(e)).map(move |b| (a, b)))
        .map(|(a, b)| {
            let at = |e: &[u32; 2]| e.map(|v| p[v as usize]);
            segments_closest_points(at(a), at(b)).1
        })
        .fold(f64::INFINITY, f64::min);
    assert!(
        gap > 0.4 * t,
        "the strips' edges rest {:.2} mm apart, the thickness {:.1} mm",
        gap * 1e3,
        t * 1e3
    );
}
