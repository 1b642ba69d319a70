//! The [`Evaluator`] (B-spline patches on regular faces, stencil rows elsewhere) must give what
//! its stencil table gives, point for point in OpenSubdiv's order, within 1e-12 of the mesh's
//! size: on a big regular grid, next to creases (semi-sharp, fractional, infinite, Chaikin),
//! corners, boundaries, holes, n-gons, valence 3 and 5 vertices, and on every reference shape
//! the tests carry; for any per-vertex value type; whatever the thread count.

use std::path::Path;

use common::{at, grid_at, grid_faces};
use nalgebra::Vector2;
use tailor_subdiv::conformance::read_shape;
use tailor_subdiv::{Corner, Crease, CreaseMethod, Evaluator, Mesh, Point, Refiner};

mod common;

/// An `n` × `n` grid of quads, its points moved by a deterministic jitter so that no weight
/// meets a symmetric cancellation.
fn grid(n: usize) -> Mesh {
    grid_at(n, |i, j| {
        let h = ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0;
        Point::new(
            i as f64 + 0.3 * h,
            j as f64 - 0.2 * h,
            (i as f64 * 0.7).sin() + h,
        )
    })
}

/// A grid with irregular spots: two quads merged into a hexagon (valence 3 at the removed
/// edge's ends), a quad split into two triangles (valence 5 at the diagonal's ends), and a
/// pair of quads made pentagons by an extra vertex on their shared edge.
fn irregular_grid(n: usize) -> Mesh {
    let base = grid(n);
    let mut positions = base.positions().to_vec();
    let mut faces = grid_faces(n);
    let quad = |i: usize, j: usize| j * n + i;
    // Hexagon from quads (2, 2) and (3, 2).
    let (a, b) = (quad(2, 2), quad(3, 2));
    faces[a] = vec![
        at(n, 2, 2),
        at(n, 3, 2),
        at(n, 4, 2),
        at(n, 4, 3),
        at(n, 3, 3),
        at(n, 2, 3),
    ];
    // Triangles from quad (6, 5).
    let t = quad(6, 5);
    let q = faces[t].clone();
    faces[t] = vec![q[0], q[1], q[2]];
    faces.push(vec![q[0], q[2], q[3]]);
    // Quads (2, 7) and (3, 7) become pentagons through a new vertex on their shared edge.
    let mid = positions.len() as u32;
    let (p, r) = (at(n, 3, 7), at(n, 3, 8));
    positions.push(Point::from(
        (positions[p as usize].coords + positions[r as usize].coords) / 2.0,
    ));
    let pq = quad(2, 7);
    faces[pq] = vec![at(n, 2, 7), p, mid, r, at(n, 2, 8)];
    let right = quad(3, 7);
    faces[right] = vec![p, at(n, 4, 7), at(n, 4, 8), r, mid];
    faces.remove(b);
    Mesh::from_polygons(positions, &faces).unwrap()
}

/// Largest difference between the evaluator's points and the stencil table's, relative to the
/// control points' extent.
fn worst(mesh: &Mesh, levels: usize) -> (f64, Evaluator) {
    let refiner = Refiner::for_evaluation(mesh, levels);
    let evaluator = Evaluator::new(&refiner);
    let stencils = refiner.stencils();
    assert_eq!(evaluator.stencils(), &stencils);
    let control = mesh.positions();
    let mut expected = vec![Point::origin(); stencils.len()];
    stencils.apply(control, &mut expected);
    // Garbage in the output must be overwritten: every point is written.
    let mut got = vec![Point::new(f64::NAN, f64::NAN, f64::NAN); evaluator.len()];
    evaluator.apply(control, &mut got);
    let scale = control
        .iter()
        .map(|p| p.coords.amax())
        .fold(1.0_f64, f64::max);
    let diff = got
        .iter()
        .zip(&expected)
        .map(|(a, b)| (a - b).amax())
        .fold(
            0.0_f64,
            |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) },
        );
    (diff / scale, evaluator)
}

fn assert_matches(mesh: &Mesh, levels: usize, what: &str) -> Evaluator {
    let (err, evaluator) = worst(mesh, levels);
    assert!(
        err <= 1e-12,
        "{what} level {levels}: relative difference {err:e}"
    );
    evaluator
}

#[test]
fn regular_grid_is_all_patches_inside_and_matches() {
    let n = 24;
    for levels in 1..=4 {
        let e = assert_matches(&grid(n), levels, "grid");
        // Faces whose four corners are interior; level 1 keeps the stencil rows.
        let patches = if levels == 1 { 0 } else { (n - 2) * (n - 2) };
        assert_eq!(e.regular_faces(), patches, "level {levels}");
    }
}

#[test]
fn big_regular_grid_matches() {
    let e = assert_matches(&grid(150), 2, "150 x 150 grid");
    assert_eq!(e.regular_faces(), 148 * 148);
}

#[test]
fn vertices_numbered_apart_from_the_faces_match() {
    // Scrambled vertex numbers and faces listed backwards: runs of faces no longer find their
    // corners in one range, so more vertex points keep their stencil rows.
    let n = 40;
    let base = grid(n);
    let count = base.positions().len();
    let renumber = |v: u32| (v as usize * 7919 % count) as u32;
    let mut positions = vec![Point::origin(); count];
    for (v, p) in base.positions().iter().enumerate() {
        positions[renumber(v as u32) as usize] = *p;
    }
    let faces: Vec<Vec<u32>> = grid_faces(n)
        .iter()
        .rev()
        .map(|f| f.iter().copied().map(renumber).collect())
        .collect();
    let mesh = Mesh::from_polygons(positions, &faces).unwrap();
    for levels in 2..=4 {
        let e = assert_matches(&mesh, levels, "scrambled grid");
        assert_eq!(e.regular_faces(), (n - 2) * (n - 2));
    }
}

#[test]
fn irregular_vertices_and_faces_match() {
    let mesh = irregular_grid(10);
    for levels in 2..=4 {
        let e = assert_matches(&mesh, levels, "irregular grid");
        assert!(e.regular_faces() > 20 && e.regular_faces() < 64);
    }
}

#[test]
fn creases_corners_and_holes_match() {
    let n = 12;
    let crease = |i0, j0, i1, j1, sharpness| Crease {
        vertices: [at(n, i0, j0), at(n, i1, j1)],
        sharpness,
    };
    let creases = vec![
        crease(3, 3, 4, 3, 1.0),
        crease(4, 3, 5, 3, 2.5),
        crease(5, 3, 6, 3, 0.3),
        crease(8, 8, 8, 9, 10.0),
        crease(8, 9, 8, 10, 10.0),
        crease(2, 9, 3, 9, 1.7),
    ];
    let corners = vec![
        Corner {
            vertex: at(n, 6, 6),
            sharpness: 1.5,
        },
        Corner {
            vertex: at(n, 9, 3),
            sharpness: 10.0,
        },
    ];
    let holes = vec![(5 * n + 9) as u32];
    let mesh = grid(n)
        .with_creases(creases)
        .unwrap()
        .with_corners(corners)
        .unwrap()
        .with_holes(holes)
        .unwrap();
    for method in [CreaseMethod::Uniform, CreaseMethod::Chaikin] {
        let mut mesh = mesh.clone();
        mesh.options.crease_method = method;
        for levels in 2..=4 {
            let e = assert_matches(&mesh, levels, &format!("{method:?} creases"));
            // Sharp features remove their faces from the patches; the rest stay.
            assert!(e.regular_faces() > 40 && e.regular_faces() < 100);
        }
    }
}

#[test]
fn reference_shapes_match() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/opensubdiv/shapes");
    let mut shapes = 0;
    let mut patches = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let mesh = read_shape(&path).unwrap();
        for levels in 1..=4 {
            patches += assert_matches(&mesh, levels, &path.display().to_string()).regular_faces();
        }
        shapes += 1;
    }
    assert!(shapes >= 20);
    // Tori and grids among them have regular faces.
    assert!(patches > 0);
}

#[test]
fn other_value_types_and_levels_fall_back_or_match() {
    let mesh = irregular_grid(8);
    let refiner = Refiner::for_evaluation(&mesh, 2);
    let evaluator = Evaluator::new(&refiner);
    let stencils = refiner.stencils();
    let uv: Vec<Vector2<f64>> = mesh.positions().iter().map(|p| p.xy().coords).collect();
    let mut a = vec![Vector2::zeros(); stencils.len()];
    let mut b = a.clone();
    stencils.apply(&uv, &mut a);
    evaluator.apply(&uv, &mut b);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).amax() < 1e-12);
    }
    let scalar: Vec<f64> = mesh.positions().iter().map(|p| p.z).collect();
    let mut a = vec![0.0; stencils.len()];
    let mut b = a.clone();
    stencils.apply(&scalar, &mut a);
    evaluator.apply(&scalar, &mut b);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-12);
    }
    // Levels 0, 1 and past the kernels are the stencil table itself.
    for levels in [0, 1, 5] {
        let refiner = Refiner::for_evaluation(&grid(4), levels);
        let e = Evaluator::new(&refiner);
        assert_eq!(e.regular_faces(), 0);
        let mut a = vec![Point::origin(); e.len()];
        let mut b = a.clone();
        e.apply(grid(4).positions(), &mut a);
        e.stencils().apply(grid(4).positions(), &mut b);
        assert_eq!(a, b);
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mesh = irregular_grid(30);
    let evaluator = Evaluator::new(&Refiner::for_evaluation(&mesh, 3));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut out = vec![Point::origin(); evaluator.len()];
        pool.install(|| evaluator.apply(mesh.positions(), &mut out));
        out
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}
