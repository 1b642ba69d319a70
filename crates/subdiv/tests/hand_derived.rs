//! Refinement results derived by hand from the Catmull-Clark rules, and invariants any correct
//! implementation keeps: affine invariance (every stencil sums to one), stencils agreeing with
//! level-by-level refinement, results independent of the thread count, and the evaluation
//! refiner (minimal last level) giving exactly what the full one gives.

use nalgebra::Vector3;
use tailor_subdiv::{BoundaryInterpolation, Crease, Mesh, Point, Refiner, subdivide};

use common::flat_grid;

mod common;

fn cube() -> Mesh {
    let p = |x, y, z| Point::new(x, y, z);
    let positions = vec![
        p(-1.0, -1.0, 1.0),
        p(1.0, -1.0, 1.0),
        p(-1.0, 1.0, 1.0),
        p(1.0, 1.0, 1.0),
        p(-1.0, 1.0, -1.0),
        p(1.0, 1.0, -1.0),
        p(-1.0, -1.0, -1.0),
        p(1.0, -1.0, -1.0),
    ];
    let faces = [
        [0u32, 1, 3, 2],
        [2, 3, 5, 4],
        [4, 5, 7, 6],
        [6, 7, 1, 0],
        [1, 7, 5, 3],
        [6, 0, 2, 4],
    ];
    Mesh::from_polygons(positions, &faces).unwrap()
}

fn close(a: &Point, b: [f64; 3]) -> bool {
    (a - Point::new(b[0], b[1], b[2])).norm() < 1e-14
}

#[test]
fn cube_corner_moves_to_five_ninths() {
    // Valence 3: 1/3 V + 1/9 (sum of edge ends) + 1/9 (sum of face points) = 5/9 (1, 1, 1).
    let (refined, _) = subdivide(&cube(), 1, false);
    let p = refined.positions();
    assert!(close(&p[3], [5.0 / 9.0; 3]), "{:?}", p[3]);
    // Face point of the +z face, then the edge point of the edge (1,1,1)-(1,1,-1):
    // 1/4 of each end and 1/4 of each adjacent face point = (3/4, 3/4, 0).
    assert!(close(&p[8], [0.0, 0.0, 1.0]));
    let level = Refiner::new(&cube(), 1);
    let e = level.level(0).find_edge(3, 5).unwrap();
    assert!(
        close(&p[8 + 6 + e], [0.75, 0.75, 0.0]),
        "{:?}",
        p[8 + 6 + e]
    );
}

#[test]
fn sharp_crease_follows_the_cubic_b_spline_rule() {
    // An infinitely sharp crease across a flat grid, lifted in z at its middle vertex:
    // crease vertex point = 3/4 V + 1/8 (both crease neighbours), edge point = midpoint.
    let mut mesh = flat_grid(4);
    let mut p = mesh.positions().to_vec();
    p[12].z = 1.0; // centre of the 5x5 vertex grid
    mesh.set_positions(&p).unwrap();
    let crease = |a, b| Crease {
        vertices: [a, b],
        sharpness: 10.0,
    };
    let mesh = mesh
        .with_creases(vec![
            crease(10, 11),
            crease(11, 12),
            crease(12, 13),
            crease(13, 14),
        ])
        .unwrap();
    let (refined, _) = subdivide(&mesh, 1, false);
    assert!(close(&refined.positions()[12], [2.0, 2.0, 0.75]));
    assert!(close(&refined.positions()[11], [1.0, 2.0, 0.125]));
}

#[test]
fn half_sharp_edge_blends_crease_and_smooth_by_its_sharpness() {
    let mut mesh = flat_grid(2);
    let mut p = mesh.positions().to_vec();
    p[4].z = 1.0;
    mesh.set_positions(&p).unwrap();
    let smooth = subdivide(&mesh, 1, false).0;
    let sharp_mesh = mesh
        .clone()
        .with_creases(vec![Crease {
            vertices: [1, 4],
            sharpness: 0.5,
        }])
        .unwrap();
    let half = subdivide(&sharp_mesh, 1, false).0;
    let level = Refiner::new(&mesh, 1);
    let e = level.level(0).find_edge(1, 4).unwrap();
    let child = 9 + 4 + e;
    // Crease edge point is the midpoint (1, 0.5, 0.5); the result is halfway to it.
    let expect = (smooth.positions()[child].coords + Vector3::new(1.0, 0.5, 0.5)) / 2.0;
    assert!((half.positions()[child].coords - expect).norm() < 1e-14);
}

#[test]
fn flat_grid_limit_is_flat_with_upward_normals() {
    let (refined, limit) = subdivide(&flat_grid(3), 2, true);
    let limit = limit.unwrap();
    assert_eq!(limit.positions.len(), refined.vertex_count());
    for (p, n) in limit.positions.iter().zip(&limit.normals) {
        assert!(p.z.abs() < 1e-15);
        assert!((n - Vector3::z()).norm() < 1e-12, "{n:?}");
    }
}

fn bumpy_creased_cube() -> Mesh {
    let mut mesh = cube();
    let p: Vec<Point> = mesh
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| p + Vector3::new(0.1 * i as f64, 0.0, -0.05 * i as f64))
        .collect();
    mesh.set_positions(&p).unwrap();
    mesh.with_creases(vec![
        Crease {
            vertices: [0, 1],
            sharpness: 1.7,
        },
        Crease {
            vertices: [1, 3],
            sharpness: 0.3,
        },
    ])
    .unwrap()
}

#[test]
fn stencils_sum_to_one_and_agree_with_level_by_level_refinement() {
    let mesh = bumpy_creased_cube();
    let refiner = Refiner::new(&mesh, 3);
    let direct = refiner.refine(mesh.positions());
    let stencils = refiner.stencils();
    let mut via = vec![Point::origin(); stencils.len()];
    stencils.apply(mesh.positions(), &mut via);
    for (a, b) in direct.iter().zip(&via) {
        assert!((a - b).norm() < 1e-13);
    }
    for i in 0..stencils.len() {
        let (_, w) = stencils.rows.row(i);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-13, "row {i}");
    }
}

#[test]
fn evaluation_refiner_gives_the_full_refiners_results() {
    let mesh = bumpy_creased_cube();
    for levels in 1..=3 {
        let (full, eval) = (
            Refiner::new(&mesh, levels),
            Refiner::for_evaluation(&mesh, levels),
        );
        let points = full.refine(mesh.positions());
        assert_eq!(points, eval.refine(mesh.positions()));
        assert_eq!(full.stencils(), eval.stencils());
        // The last level, completed on demand, is the one built up front.
        let (a, b) = (full.last(), eval.last());
        assert!(a == b, "the completed last level differs");
        assert_eq!(
            full.refined_mesh(points.clone(), None),
            eval.refined_mesh(points, None)
        );
    }
}

/// The refined mesh `subdivide` writes, read off the minimal last level (creases from the
/// level above it), is the one the complete last level gives: on every reference shape
/// (boundaries, creases, corners, holes, non-manifold vertices), with each boundary mode.
#[test]
fn refined_meshes_from_the_minimal_last_level_are_the_full_ones() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/opensubdiv/shapes");
    let validation = tailor_subdiv::Validation {
        allow_degenerate_faces: true,
    };
    let mut creased = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let mut mesh = tailor_subdiv::obj::read_with(&path, validation)
            .unwrap()
            .mesh;
        for boundary in [
            BoundaryInterpolation::None,
            BoundaryInterpolation::EdgeOnly,
            BoundaryInterpolation::EdgeAndCorner,
        ] {
            mesh.options.boundary = boundary;
            for levels in 1..=2 {
                let (full, eval) = (
                    Refiner::new(&mesh, levels),
                    Refiner::for_evaluation(&mesh, levels),
                );
                let points = full.refine(mesh.positions());
                let (a, b) = (
                    full.refined_mesh(points.clone(), None),
                    eval.refined_mesh(points, None),
                );
                assert_eq!(a, b, "{} at level {levels}, {boundary:?}", path.display());
                creased += usize::from(!a.creases().is_empty());
            }
        }
    }
    assert!(creased > 20, "only {creased} refined meshes with creases");
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mesh = bumpy_creased_cube();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let refiner = Refiner::new(&mesh, 4);
            (refiner.refine(mesh.positions()), refiner.stencils())
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn scalar_fields_refine_like_coordinates() {
    // Any per-vertex attribute (a stiffness map, say) follows the same rules as positions.
    let mesh = bumpy_creased_cube();
    let refiner = Refiner::new(&mesh, 2);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p.y).collect();
    let refined_field = refiner.refine(&field);
    for (f, p) in refined_field.iter().zip(refiner.refine(mesh.positions())) {
        assert_eq!(*f, p.y);
    }
}

#[test]
fn limit_stencils_agree_with_limit_masks() {
    let mesh = bumpy_creased_cube();
    let refiner = Refiner::new(&mesh, 2);
    let refined: Vec<Vector3<f64>> = refiner
        .refine(mesh.positions())
        .iter()
        .map(|p| p.coords)
        .collect();
    let (pos, normals) = refiner.limit_masks().evaluate(&refined);
    let [sp, s1, s2] = refiner.limit_stencils();
    let control: Vec<Vector3<f64>> = mesh.positions().iter().map(|p| p.coords).collect();
    let eval = |s: &tailor_subdiv::StencilTable| {
        let mut out = vec![Vector3::zeros(); s.len()];
        s.apply(&control, &mut out);
        out
    };
    let (p2, t1, t2) = (eval(&sp), eval(&s1), eval(&s2));
    for i in 0..pos.len() {
        assert!((pos[i] - p2[i]).norm() < 1e-13);
        let n = tailor_subdiv::limit::normal(&t1[i], &t2[i]);
        assert!((normals[i] - n).norm() < 1e-9, "vertex {i}");
    }
}
