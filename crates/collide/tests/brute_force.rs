//! Every hierarchy query gives exactly the brute-force answer (all vertex–triangle, all
//! triangle–triangle, all edge–edge pairs) on structured meshes (sheets, a folded sheet, a
//! sphere with n-gon caps, a torus, a sheet of n-gons with boundaries) and random triangle
//! soups, static and deforming, and the same answer with 1 and 2 threads.

mod common;

use common::{
    Coil, Fold, Mesh, Rng, collapsed, folded_sheet, ngon_sheet, sheet, soup, sphere, torus, wave,
};
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::Triangle;
use tailor_collide::{
    Closest, CollideError, DistanceBounds, Hierarchy, Impacts, LocalFaces, Neighbours, Point,
    edge_edge_impact, segments_closest_points, triangles_intersect, vertex_triangle_impact,
};

fn build(m: &Mesh) -> Hierarchy {
    Hierarchy::build(&m.positions, &m.offsets, &m.corners).unwrap()
}

fn g(p: &Point) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// Brute force: distance from `q` to every triangle of non-zero area (twice the area above
/// rounding of the longest edge squared), as `(distance, face, triangle)`.
fn all_distances(m: &Mesh, positions: &[Point], q: &Point) -> Vec<(f64, u32, u32)> {
    m.triangles()
        .iter()
        .enumerate()
        .filter_map(|(t, &(corners, f))| {
            let [a, b, c] = corners.map(|v| g(&positions[v as usize]));
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            if (b - a).cross(c - a).length() <= 4.0 * f64::EPSILON * longest {
                return None;
            }
            let (proj, _) =
                Triangle::new(a, b, c).project_local_point_and_get_location(g(q), false);
            Some(((g(q) - proj.point).length(), f, t as u32))
        })
        .collect()
}

/// Brute force: the nearest `(distance, face, triangle)` within `d` over faces not excluded.
fn nearest(
    all: &[(f64, u32, u32)],
    d: f64,
    excluded: impl Fn(u32) -> bool,
) -> Option<(f64, u32, u32)> {
    all.iter().filter(|x| x.0 <= d && !excluded(x.1)).fold(
        None,
        |best: Option<(f64, u32, u32)>, &x| match best {
            Some(b) if (b.0, b.1) <= (x.0, x.1) => Some(b),
            _ => Some(x),
        },
    )
}

/// Brute force: faces within `d`, sorted.
fn faces_near(all: &[(f64, u32, u32)], d: f64, excluded: impl Fn(u32) -> bool) -> Vec<u32> {
    let mut faces: Vec<u32> = all
        .iter()
        .filter(|x| x.0 <= d && !excluded(x.1))
        .map(|x| x.1)
        .collect();
    faces.dedup();
    faces
}

fn meshes() -> Vec<(&'static str, Mesh)> {
    vec![
        ("sphere", sphere(8, 12, 1.0)),
        ("torus", torus(16, 8, 1.0, 0.3)),
        (
            "ngons",
            ngon_sheet(5, 4, 3, |x, y| 0.2 * (3.0 * x).sin() * y),
        ),
        ("folded", folded_sheet(12, 0.3)),
        ("soup", soup(150, 0.3, 7)),
    ]
}

#[test]
fn closest_points_match_brute_force() {
    let mut rng = Rng::new(1);
    for (name, m) in meshes() {
        let h = build(&m);
        let queries: Vec<Point> = (0..60).map(|_| rng.point(1.5)).collect();
        for d in [0.1, 0.4, f64::INFINITY] {
            let got = h.closest_points(&queries, d).unwrap();
            let near = h.faces_within(&queries, d.min(0.4)).unwrap();
            for (i, q) in queries.iter().enumerate() {
                let all = all_distances(&m, &m.positions, q);
                let want = nearest(&all, d, |_| false);
                let got_key = got[i].map(|c| (c.distance, c.face, c.triangle));
                assert_eq!(got_key, want, "{name}: query {i} within {d}");
                let faces: Vec<u32> = near.of(i).iter().map(|c| c.face).collect();
                assert_eq!(
                    faces,
                    faces_near(&all, d.min(0.4), |_| false),
                    "{name}: query {i}"
                );
            }
        }
    }
}

/// Seeds for queries whose answers are `answers`, by turns the answer's own face, another of
/// the mesh's `faces` (most likely far from it) and none.
fn mixed_seeds(answers: &[Option<Closest>], faces: u32) -> Vec<Option<u32>> {
    answers
        .iter()
        .enumerate()
        .map(|(i, c)| match i % 3 {
            0 => c.map(|c| c.face),
            1 => Some((i as u32 * 7919) % faces),
            _ => None,
        })
        .collect()
}

/// A seed per query, whichever face it names (the true answer's, a far one, or none), leaves
/// every answer the same bits as the unseeded queries, which match brute force above.
#[test]
fn seeded_closest_points_are_the_unseeded_ones() {
    let mut rng = Rng::new(5);
    for (name, m) in meshes() {
        let h = build(&m);
        let faces = h.face_count() as u32;
        let queries: Vec<Point> = (0..60).map(|_| rng.point(1.5)).collect();
        for d in [0.1, 0.4, f64::INFINITY] {
            let want = h.closest_points(&queries, d).unwrap();
            let seeds = mixed_seeds(&want, faces);
            let mut got = Vec::new();
            h.closest_points_seeded_into(&queries, d, &seeds, &mut got)
                .unwrap();
            assert_eq!(got, want, "{name}: within {d}");
        }
    }
}

/// Over a moving mesh and moving points, every point the bounds do not list for measuring is
/// farther than the distance asked about (brute force), except the points that did not move
/// over a mesh that did not move, which are never listed (their last answer holds); and the
/// bounds spare most of the measuring.
#[test]
fn distance_bounds_list_every_point_that_may_have_come_near() {
    let mut rng = Rng::new(11);
    for (name, m) in meshes() {
        let mut h = build(&m);
        let mut points: Vec<Point> = (0..200).map(|_| rng.point(1.5)).collect();
        let mut bounds = DistanceBounds::default();
        let (near, reach) = (0.1, 0.3);
        let (mut listed, mut asked) = (Vec::new(), 0);
        let mut t = 0.0;
        for step in 0..9 {
            // Steps 1, 4, 7: the mesh holds still; from step 1 on the odd points move only
            // every third step.
            let mesh_still = step % 3 == 1;
            let still = |i: usize| step % 3 != 0 && i % 2 == 1;
            if !mesh_still {
                t += 0.1;
            }
            let mesh = m.mapped(|p| {
                let w = wave(p, t);
                Point::new(w.x, w.y, p.z + w.z + 0.05 * t)
            });
            h.refit(&mesh, 0.0).unwrap();
            for (i, p) in points.iter_mut().enumerate() {
                if !still(i) {
                    *p += rng.point(0.01).coords;
                }
            }
            bounds.stale(&h, &points, near, &mut listed);
            asked += listed.len();
            for (i, p) in points.iter().enumerate() {
                let d = all_distances(&m, &mesh, p)
                    .iter()
                    .map(|x| x.0)
                    .fold(f64::INFINITY, f64::min);
                if bounds.past(i as u32, near) {
                    assert!(
                        d > near,
                        "{name}: step {step}, point {i} at {d} past {near}"
                    );
                }
                if listed.binary_search(&(i as u32)).is_ok() {
                    bounds.set(i as u32, d.min(reach));
                } else if !(still(i) && mesh_still) {
                    assert!(d > near, "{name}: step {step}, point {i} at {d} not listed");
                }
                if still(i) && mesh_still {
                    assert!(!listed.contains(&(i as u32)), "{name}: {i} did not move");
                }
            }
        }
        assert!(
            asked < 9 * points.len() / 2,
            "{name}: {asked} of {} measured",
            9 * points.len()
        );
    }
}

#[test]
fn closest_point_fields_are_consistent() {
    let m = sphere(6, 8, 1.0);
    let h = build(&m);
    let q = Point::new(0.3, 0.2, 1.4);
    let c = h.closest_points(&[q], f64::INFINITY).unwrap()[0].unwrap();
    let [a, b, d] = c.vertices.map(|v| m.positions[v as usize].coords);
    let w = c.barycentric;
    let from_weights = a * w[0] + b * w[1] + d * w[2];
    assert!((from_weights - c.point.coords).norm() < 1e-12);
    assert!(((q - c.point).norm() - c.distance).abs() < 1e-12);
    assert!((c.normal.norm() - 1.0).abs() < 1e-12 && c.normal.dot(&(q - c.point)) > 0.0);
    assert_eq!(h.triangle_faces()[c.triangle as usize], c.face);
}

#[test]
fn self_proximity_matches_brute_force() {
    for (name, m) in meshes() {
        let h = build(&m);
        for d in [0.02, 0.15] {
            let got = h.self_proximity(d, &LocalFaces::default()).unwrap();
            for (v, q) in m.positions.iter().enumerate() {
                let all = all_distances(&m, &m.positions, q);
                let face_has_v = |f: u32| m.face_corners(f).contains(&(v as u32));
                let faces: Vec<u32> = got.of(v).iter().map(|c| c.face).collect();
                assert_eq!(
                    faces,
                    faces_near(&all, d, face_has_v),
                    "{name}: vertex {v} within {d}"
                );
            }
        }
    }
}

#[test]
fn local_faces_are_the_sheet_around_a_vertex_not_the_layer_above() {
    // Flat: every face within the distance is around the vertex, and skipping them leaves
    // nothing near.
    let flat = sheet(12, |_, _| 0.0);
    let h = build(&flat);
    let d = 0.2;
    let local = h.local_faces(d).unwrap();
    let near = h.self_proximity(d, &LocalFaces::default()).unwrap();
    for v in 0..flat.positions.len() {
        let faces: Vec<u32> = near.of(v).iter().map(|c| c.face).collect();
        assert_eq!(local.of(v), &faces[..], "flat: vertex {v}");
    }
    assert!(local.pair_count() > 0);
    assert!(h.self_proximity(d, &local).unwrap().hits().is_empty());
    // The taco: its layers lie 0.2 apart and its crease starts at x = 0.4. A vertex of the
    // lower layer farther than the distance from the crease skips faces around it on its own
    // layer, none of the upper layer, and still finds the upper layer near.
    let taco = folded_sheet(20, 0.0);
    let h = build(&taco);
    let d = 0.25;
    let local = h.local_faces(d).unwrap();
    let near = h.self_proximity(d, &local).unwrap();
    let upper = |f: u32| {
        taco.face_corners(f)
            .iter()
            .all(|&c| taco.positions[c as usize].z == 0.2)
    };
    let mut checked = 0;
    for (v, p) in taco.positions.iter().enumerate() {
        if p.z == 0.0 && p.x < 0.1 {
            assert!(!local.of(v).is_empty(), "taco: vertex {v} skips nothing");
            assert!(
                !local.of(v).iter().any(|&f| upper(f)),
                "taco: vertex {v} skips the upper layer"
            );
            assert!(near.of(v).iter().any(|c| upper(c.face)), "taco: vertex {v}");
            checked += 1;
        }
    }
    assert!(checked > 0);
}

#[test]
fn self_proximity_skips_exactly_the_local_faces_after_a_deformation() {
    // Tables made at rest, queried after the mesh moved: the answer is every face within the
    // distance that neither uses the vertex nor is listed for it, however the query leaves
    // the listed faces out (whole subtrees at a time on a fine sheet, whose lists are long).
    let bend = |p: &Point| {
        Point::new(
            p.x + 0.03 * (3.0 * p.y).sin(),
            p.y,
            p.z + 0.05 * (5.0 * p.x + 2.0 * p.y).cos(),
        )
    };
    // The sheet laid back over itself round a crease of radius 0.03: layers 0.06 apart.
    let fold = Fold {
        origin: Point::new(0.5, 0.5, 0.0),
        along: [0.0, 1.0],
        radius: 0.03,
        angle: std::f64::consts::PI,
        ripples: Vec::new(),
    };
    type Deform<'a> = &'a dyn Fn(&Point) -> Point;
    let cases: [(&str, Mesh, f64, f64, Deform); 3] = [
        ("fine sheet", sheet(30, |_, _| 0.0), 0.1, 0.07, &|p| {
            fold.apply(p)
        }),
        ("folded", folded_sheet(12, 0.3), 0.3, 0.25, &bend),
        ("torus", torus(16, 8, 1.0, 0.3), 0.25, 0.3, &bend),
    ];
    for (name, m, rest_distance, d, deform) in cases {
        let mut h = build(&m);
        let local = h.local_faces(rest_distance).unwrap();
        assert!(
            local.pair_count() > m.positions.len(),
            "{name}: lists too short"
        );
        let moved: Vec<Point> = m.positions.iter().map(deform).collect();
        h.refit(&moved, 0.0).unwrap();
        let got = h.self_proximity(d, &local).unwrap();
        let mut found = 0;
        for (v, q) in moved.iter().enumerate() {
            let all = all_distances(&m, &moved, q);
            let excluded = |f: u32| {
                m.face_corners(f).contains(&(v as u32)) || local.of(v).binary_search(&f).is_ok()
            };
            let faces: Vec<u32> = got.of(v).iter().map(|c| c.face).collect();
            assert_eq!(faces, faces_near(&all, d, excluded), "{name}: vertex {v}");
            found += faces.len();
        }
        assert!(found > 0, "{name}: nothing near");
    }
}

fn share_vertex(m: &Mesh, f: u32, g: u32) -> bool {
    m.face_corners(f)
        .iter()
        .any(|v| m.face_corners(g).contains(v))
}

/// Brute force: every pair of faces sharing no vertex whose triangles meet.
fn brute_self_intersections(m: &Mesh, positions: &[Point]) -> Vec<[u32; 2]> {
    let tris = m.triangles();
    let corner = |t: [u32; 3]| t.map(|v| positions[v as usize]);
    let mut pairs = Vec::new();
    for (i, &(s, f)) in tris.iter().enumerate() {
        for &(t, g) in &tris[i + 1..] {
            if f != g && !share_vertex(m, f, g) && triangles_intersect(corner(s), corner(t)) {
                pairs.push([f.min(g), f.max(g)]);
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// A sheet crumpled enough to pass through itself.
fn crumpled(p: &Point) -> Point {
    Point::new(
        p.x,
        p.y + 0.3 * (5.0 * p.x).sin(),
        0.25 * (9.0 * p.x).cos() * (7.0 * p.y).sin(),
    )
}

#[test]
fn self_intersections_match_brute_force() {
    let mut cases = vec![];
    for (name, m) in meshes() {
        cases.push((name, m.positions.clone(), m.clone()));
        cases.push((name, m.mapped(crumpled), m));
    }
    let mut found_any = false;
    for (name, positions, m) in cases {
        let mut h = build(&m);
        h.refit(&positions, 0.0).unwrap();
        let want = brute_self_intersections(&m, &positions);
        found_any |= !want.is_empty();
        assert_eq!(h.self_intersections(), want, "{name}");
    }
    assert!(found_any, "the cases must include intersecting meshes");
}

#[test]
fn smooth_closed_and_open_surfaces_do_not_self_intersect() {
    for m in [
        sphere(10, 16, 1.0),
        torus(24, 12, 1.0, 0.3),
        folded_sheet(16, 0.1),
        common::sheet(20, |x, y| 0.1 * (4.0 * x).sin() * y),
    ] {
        assert!(build(&m).self_intersections().is_empty());
    }
    // The sagging fold does pass through itself.
    assert!(
        !build(&folded_sheet(16, 0.3))
            .self_intersections()
            .is_empty()
    );
}

fn unique_edges(m: &Mesh) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = m
        .triangles()
        .iter()
        .flat_map(|&([a, b, c], _)| [[a, b], [b, c], [c, a]])
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
}

type Key = (u32, u32, u64);
type EdgeKey = ([[u32; 2]; 2], u64);

/// Asserts two sorted lists are equal, naming only the differences.
fn assert_same<T: PartialEq + std::fmt::Debug>(got: &[T], want: &[T], what: &str) {
    let missing: Vec<&T> = want.iter().filter(|x| !got.contains(x)).collect();
    let extra: Vec<&T> = got.iter().filter(|x| !want.contains(x)).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "{what}: missing {missing:?}, extra {extra:?}"
    );
    assert_eq!(got, want, "{what}: order");
}

/// A vertex's straight path over the step.
type PathOf<'a> = &'a dyn Fn(u32) -> [Point; 2];

/// Brute force: every (vertex, triangle) impact, skipping triangles that use the vertex when
/// both come from one mesh.
fn brute_vertex_triangle(
    vertices: u32,
    vp: PathOf,
    triangles: &[([u32; 3], u32)],
    tp: PathOf,
    same: bool,
) -> Vec<Key> {
    let mut found = Vec::new();
    for (t, &(tri, _)) in triangles.iter().enumerate() {
        for v in 0..vertices {
            if !(same && tri.contains(&v))
                && let Some((time, _)) = vertex_triangle_impact(vp(v), tri.map(tp))
            {
                found.push((v, t as u32, time.to_bits()));
            }
        }
    }
    found.sort_unstable();
    found
}

/// Brute force: every edge–edge impact; within one mesh each unordered pair once, skipping
/// pairs that share a vertex.
fn brute_edge_edge(
    first: &[[u32; 2]],
    fp: PathOf,
    second: &[[u32; 2]],
    sp: PathOf,
    same: bool,
) -> Vec<EdgeKey> {
    let mut found = Vec::new();
    for (i, &a) in first.iter().enumerate() {
        let others = if same { &second[i + 1..] } else { second };
        for &b in others {
            if !(same && a.iter().any(|v| b.contains(v)))
                && let Some((time, _)) = edge_edge_impact(a.map(fp), b.map(sp))
            {
                found.push(([a, b], time.to_bits()));
            }
        }
    }
    found.sort_unstable();
    found
}

/// Brute force CCD of a mesh with itself.
fn brute_self_impacts(m: &Mesh, start: &[Point], end: &[Point]) -> (Vec<Key>, Vec<EdgeKey>) {
    let path = |v: u32| [start[v as usize], end[v as usize]];
    let edges = unique_edges(m);
    (
        brute_vertex_triangle(start.len() as u32, &path, &m.triangles(), &path, true),
        brute_edge_edge(&edges, &path, &edges, &path, true),
    )
}

fn self_impact_keys(h: &Hierarchy) -> (Vec<Key>, Vec<EdgeKey>) {
    let impacts = h.self_impacts();
    let vt = impacts
        .vertex_triangle
        .iter()
        .map(|i| (i.vertex, i.triangle, i.time.to_bits()))
        .collect();
    let ee = impacts
        .edge_edge
        .iter()
        .map(|i| (i.edges, i.time.to_bits()))
        .collect();
    (vt, ee)
}

#[test]
fn self_impacts_match_brute_force() {
    let mut rng = Rng::new(3);
    let cases: Vec<(&str, Mesh, Vec<Point>)> = {
        let fold = folded_sheet(8, 0.0);
        let fold_end = folded_sheet(8, 0.35).positions;
        let flat = common::sheet(8, |_, _| 0.0);
        let flat_end = flat.mapped(|p| wave(p, 1.0));
        let tor = torus(12, 6, 1.0, 0.3);
        let squash = tor.mapped(|p| Point::new(p.x, 0.1 * p.y, p.z));
        let sp = soup(60, 0.3, 11);
        let shaken: Vec<Point> = sp
            .positions
            .iter()
            .map(|p| p + rng.point(0.3).coords)
            .collect();
        let ng = ngon_sheet(4, 3, 3, |_, _| 0.0);
        let ng_end = ng.mapped(|p| Point::new(p.x, p.y, 0.3 * (std::f64::consts::PI * p.x).sin()));
        vec![
            ("fold closing", fold, fold_end),
            ("waving sheet", flat, flat_end),
            ("squashed torus", tor, squash),
            ("shaken soup", sp, shaken),
            ("bending ngons", ng, ng_end),
        ]
    };
    let mut found_any = false;
    for (name, m, end) in cases {
        let mut h = build(&m);
        h.refit_swept(&m.positions, &end, 0.0).unwrap();
        let want = brute_self_impacts(&m, &m.positions, &end);
        found_any |= !want.0.is_empty() && !want.1.is_empty();
        let got = self_impact_keys(&h);
        assert_same(&got.0, &want.0, name);
        assert_same(&got.1, &want.1, name);
    }
    assert!(found_any, "some case must have both kinds of impact");
}

/// Random folds of a quad sheet, nearly closed and closing further over the step, and random
/// coils (a ramp winding over itself, all its normals within a cone, pressed flatter over the
/// step), rippled about as high as the gap between their layers so that these pass through
/// each other in places: the normal cones clear the flat and gently curved patches the
/// coarsening makes, never a patch that touches itself, so the continuous and static
/// self-collision queries find exactly what brute force finds.
#[test]
fn random_folds_and_coils_match_brute_force() {
    let mut rng = Rng::new(17);
    let flat = common::sheet(12, |_, _| 0.0);
    let (mut impacts, mut crossings) = ([0; 2], [0; 2]);
    for case in 0..16 {
        let (name, start, end) = if case % 2 == 0 {
            let fold = Fold::random(&mut rng);
            let later = fold.later(0.1 + 0.3 * rng.unit(), 0.5 * rng.unit());
            let name = format!("case {case}: {fold:?}");
            (
                name,
                flat.mapped(|p| fold.apply(p)),
                flat.mapped(|p| later.apply(p)),
            )
        } else {
            let coil = Coil::random(&mut rng);
            let later = coil.later(0.5 + 0.4 * rng.unit(), 0.5 * rng.unit());
            let name = format!("case {case}: {coil:?}");
            (
                name,
                flat.mapped(|p| coil.apply(p)),
                flat.mapped(|p| later.apply(p)),
            )
        };
        let mut h = build(&flat);
        h.refit_swept(&start, &end, 0.0).unwrap();
        let want = brute_self_impacts(&flat, &start, &end);
        impacts[case % 2] += want.0.len() + want.1.len();
        let got = self_impact_keys(&h);
        assert_same(&got.0, &want.0, &name);
        assert_same(&got.1, &want.1, &name);
        h.refit(&end, 0.0).unwrap();
        let want = brute_self_intersections(&flat, &end);
        crossings[case % 2] += want.len();
        assert_eq!(h.self_intersections(), want, "{name}");
    }
    assert!(
        impacts.iter().chain(&crossings).all(|&n| n > 0),
        "folds and coils must touch themselves: impacts {impacts:?}, crossings {crossings:?}"
    );
}

/// The rounds after a query: some vertices' end positions move (none, a few, a patch, all),
/// and asking again for what moved gives the same lists as the whole query, which brute force
/// confirms.
#[test]
fn self_impacts_asked_again_for_what_moved_match_the_whole_query() {
    let mut rng = Rng::new(29);
    let flat = common::sheet(12, |_, _| 0.0);
    let n = flat.positions.len();
    let mut changed = 0;
    for case in 0..12 {
        let fold = Fold::random(&mut rng);
        let later = fold.later(0.1 + 0.3 * rng.unit(), 0.5 * rng.unit());
        let start = flat.mapped(|p| fold.apply(p));
        let end = flat.mapped(|p| later.apply(p));
        let mut h = build(&flat);
        h.refit_swept(&start, &end, 0.0).unwrap();
        let mut impacts = h.self_impacts();
        let share = [0.0, 0.02, 0.2, 1.0][case % 4];
        let moved: Vec<bool> = (0..n).map(|_| rng.unit() < share).collect();
        let again: Vec<Point> = end
            .iter()
            .zip(&moved)
            .map(|(p, &m)| if m { p + rng.point(0.1).coords } else { *p })
            .collect();
        h.refit_swept(&start, &again, 0.0).unwrap();
        let whole = h.self_impacts();
        changed += usize::from(whole != impacts);
        h.self_impacts_again(&moved, &mut impacts);
        assert_eq!(impacts, whole, "case {case}: {fold:?}, {share} moved");
        let want = brute_self_impacts(&flat, &start, &again);
        let got = self_impact_keys(&h);
        assert_same(&got.0, &want.0, &format!("case {case}"));
        assert_same(&got.1, &want.1, &format!("case {case}"));
    }
    assert!(
        changed >= 6,
        "the moves must change the answers: {changed} of the 9 that move did"
    );
}

#[test]
fn impacts_between_meshes_match_brute_force() {
    let body = sphere(6, 10, 0.5);
    let cloth = common::sheet(6, |_, _| 0.7);
    let drop = cloth.mapped(|p| Point::new(p.x - 0.5, p.y - 0.5, -0.2 + 0.3 * p.x));
    let lifted = cloth.mapped(|p| Point::new(p.x - 0.5, p.y - 0.5, p.z));
    let body_end = body.mapped(|p| p + tailor_collide::Vector::new(0.05, 0.0, 0.1));
    let mut hc = build(&cloth);
    hc.refit_swept(&lifted, &drop, 0.0).unwrap();
    let mut hb = build(&body);
    hb.refit_swept(&body.positions, &body_end, 0.0).unwrap();
    let impacts = hc.impacts_with(&hb);

    let cloth_path = |v: u32| [lifted[v as usize], drop[v as usize]];
    let body_path = |v: u32| [body.positions[v as usize], body_end[v as usize]];
    let want_vt = brute_vertex_triangle(
        cloth.positions.len() as u32,
        &cloth_path,
        &body.triangles(),
        &body_path,
        false,
    );
    let want_tv = brute_vertex_triangle(
        body.positions.len() as u32,
        &body_path,
        &cloth.triangles(),
        &cloth_path,
        false,
    );
    let want_ee = brute_edge_edge(
        &unique_edges(&cloth),
        &cloth_path,
        &unique_edges(&body),
        &body_path,
        false,
    );
    let keys = |list: &[tailor_collide::VertexTriangleImpact]| -> Vec<Key> {
        list.iter()
            .map(|i| (i.vertex, i.triangle, i.time.to_bits()))
            .collect()
    };
    assert!(!want_vt.is_empty() && !want_tv.is_empty() && !want_ee.is_empty());
    assert_same(&keys(&impacts.vertex_triangle), &want_vt, "cloth vertices");
    assert_same(&keys(&impacts.triangle_vertex), &want_tv, "body vertices");
    let ee: Vec<_> = impacts
        .edge_edge
        .iter()
        .map(|i| (i.edges, i.time.to_bits()))
        .collect();
    assert_same(&ee, &want_ee, "edges");
}

/// Generalised winding number (Jacobson et al. 2013): the sum of signed solid angles / 4π.
fn winding_number(m: &Mesh, q: &Point) -> f64 {
    m.triangles()
        .iter()
        .map(|&(t, _)| {
            let [a, b, c] = t.map(|v| m.positions[v as usize] - q);
            let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
            let det = a.dot(&b.cross(&c));
            let div = la * lb * lc + a.dot(&b) * lc + b.dot(&c) * la + c.dot(&a) * lb;
            2.0 * det.atan2(div)
        })
        .sum::<f64>()
        / (4.0 * std::f64::consts::PI)
}

#[test]
fn signed_distance_sign_matches_winding_number() {
    let mut rng = Rng::new(5);
    for m in [sphere(8, 12, 1.0), torus(16, 8, 1.0, 0.4)] {
        let h = build(&m);
        let queries: Vec<Point> = (0..200).map(|_| rng.point(1.5)).collect();
        let signed = h.signed_distances(&queries).unwrap();
        let closest = h.closest_points(&queries, f64::INFINITY).unwrap();
        for ((q, s), c) in queries.iter().zip(signed).zip(closest) {
            assert_eq!(s.abs(), c.unwrap().distance);
            let inside = winding_number(&m, q) > 0.5;
            assert_eq!(s < 0.0, inside, "{q}");
        }
    }
}

/// Signed distances seeded with any faces (each answer's own, a far one, none) are the
/// unseeded ones to the bit, which the test above checks against the winding number, and
/// each answer names the face of its closest point.
#[test]
fn seeded_signed_distances_are_the_unseeded_ones() {
    let mut rng = Rng::new(6);
    for m in [sphere(8, 12, 1.0), torus(16, 8, 1.0, 0.4)] {
        let h = build(&m);
        let faces = h.face_count() as u32;
        let queries: Vec<Point> = (0..200).map(|_| rng.point(1.5)).collect();
        let want = h.signed_distances(&queries).unwrap();
        let closest = h.closest_points(&queries, f64::INFINITY).unwrap();
        let seeds = mixed_seeds(&closest, faces);
        let got = h.signed_distances_seeded(&queries, &seeds).unwrap();
        for (i, ((d, face), c)) in got.iter().zip(&closest).enumerate() {
            assert_eq!(d.to_bits(), want[i].to_bits(), "query {i}");
            assert_eq!(*face, c.map(|c| c.face), "query {i}");
        }
    }
}

#[test]
fn answers_do_not_depend_on_thread_count() {
    let m = folded_sheet(70, 0.1);
    let start = m.positions.clone();
    let end = folded_sheet(70, 0.35).positions;
    let mut rng = Rng::new(9);
    let queries: Vec<Point> = (0..300).map(|_| rng.point(1.0)).collect();
    // A ball the closing fold sweeps through.
    let mut ball = sphere(8, 12, 0.15);
    ball.positions = ball.mapped(|p| Point::new(p.x + 0.2, p.y + 0.5, p.z));
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut h = build(&m);
            h.refit_swept(&start, &end, 0.01).unwrap();
            let impacts = h.self_impacts();
            let mut body = build(&ball);
            body.refit_swept(&ball.positions, &ball.positions, 0.0)
                .unwrap();
            let body_hits = h.vertex_impacts_with(&body);
            h.refit(&end, 0.0).unwrap();
            (
                (h.depth(), h.closest_points(&queries, 0.2).unwrap()),
                h.self_proximity(0.02, &LocalFaces::default()).unwrap(),
                h.self_intersections(),
                impacts,
                body_hits,
                h.edge_proximity(0.02, &LocalFaces::default()).unwrap(),
            )
        })
    };
    let one = run(1);
    assert!(!one.2.is_empty() && !one.3.vertex_triangle.is_empty());
    assert!(!one.4.is_empty() && !one.5.is_empty());
    assert_eq!(one, run(2));
}

#[test]
fn hierarchy_is_balanced_on_connected_and_scattered_meshes() {
    for (m, faces) in [
        (common::sheet(64, |_, _| 0.0), 4096.0f64),
        (soup(3000, 0.01, 2), 3000.0),
    ] {
        let h = build(&m);
        let log = faces.log2().ceil() as usize;
        assert!(
            h.depth() >= log && h.depth() <= log + log / 2,
            "depth {} for {faces} faces",
            h.depth()
        );
    }
}

#[test]
fn bad_input_is_an_error_and_degenerate_triangles_are_counted() {
    let m = sphere(4, 6, 1.0);
    let mut p = m.positions.clone();
    p[3].z = f64::NAN;
    assert_eq!(
        Hierarchy::build(&p, &m.offsets, &m.corners).unwrap_err(),
        CollideError::NonFinitePosition { vertex: 3 }
    );
    assert_eq!(
        Hierarchy::build(&m.positions, &[0], &[]).unwrap_err(),
        CollideError::Empty
    );
    let h = build(&m);
    assert_eq!(
        h.closest_points(&[Point::new(0.0, f64::INFINITY, 0.0)], 1.0)
            .unwrap_err(),
        CollideError::NonFiniteQuery { point: 0 }
    );
    assert!(matches!(
        h.self_proximity(f64::NAN, &LocalFaces::default()),
        Err(CollideError::BadDistance { .. })
    ));

    // Collapse triangle 4 of a soup onto a segment and triangle 7 onto a point: both are
    // counted, and neither is ever reported.
    let s = soup(10, 0.3, 4);
    let q = collapsed(&s);
    let mut h = build(&s);
    h.refit(&q, 0.0).unwrap();
    assert_eq!(h.degenerate_triangles(), 2);
    for v in [13, 21] {
        let hit = h.closest_points(&[q[v]], f64::INFINITY).unwrap()[0].unwrap();
        assert!(hit.face != 4 && hit.face != 7);
    }
    assert!(
        h.self_intersections()
            .iter()
            .all(|p| !p.contains(&4) && !p.contains(&7))
    );
}

#[test]
fn closest_points_break_ties_and_skip_zero_area_like_brute_force() {
    // Queries straight above the vertices and edge midpoints of a flat grid of quads, in mesh
    // order: every answer is a tie between faces (the lowest wins) or between the two
    // triangles of a quad (the lower wins), and each query starts from its predecessor's face.
    let grid = common::sheet(12, |_, _| 0.0);
    let mut queries: Vec<Point> = grid.mapped(|p| Point::new(p.x, p.y, 0.05));
    queries.extend(grid.mapped(|p| Point::new(p.x + 0.5 / 12.0, p.y, 0.02)));
    // A soup whose triangles 4 and 7 collapse to a segment and a point, queried at and around
    // them: the nearest triangle is often a zero-area one, which must be skipped.
    let s = soup(40, 0.3, 4);
    let collapsed = collapsed(&s);
    let mut rng = Rng::new(12);
    let near: Vec<Point> = [12, 13, 14, 21]
        .iter()
        .flat_map(|&v| [collapsed[v]; 8])
        .map(|p| p + rng.point(0.02).coords)
        .collect();
    for (name, m, positions, queries) in [
        ("grid", &grid, grid.positions.clone(), queries),
        ("collapsed soup", &s, collapsed, near),
    ] {
        let mut h = build(m);
        h.refit(&positions, 0.0).unwrap();
        for d in [0.03, f64::INFINITY] {
            let got = h.closest_points(&queries, d).unwrap();
            for (i, q) in queries.iter().enumerate() {
                let want = nearest(&all_distances(m, &positions, q), d, |_| false);
                let got_key = got[i].map(|c| (c.distance, c.face, c.triangle));
                assert_eq!(got_key, want, "{name}: query {i} within {d}");
            }
        }
    }
}

#[test]
fn vertex_impacts_with_a_body_match_brute_force() {
    let body = sphere(6, 10, 0.5);
    let body_end = body.mapped(|p| p + tailor_collide::Vector::new(0.05, 0.0, 0.1));
    let cloth = common::sheet(6, |_, _| 0.7);
    let lifted = cloth.mapped(|p| Point::new(p.x - 0.5, p.y - 0.5, p.z));
    let dropped = cloth.mapped(|p| Point::new(p.x - 0.5, p.y - 0.5, -0.2 + 0.3 * p.x));
    let scraps = soup(80, 0.2, 21);
    let mut rng = Rng::new(22);
    let thrown: Vec<Point> = scraps
        .positions
        .iter()
        .map(|p| p * 0.6 + rng.point(0.4).coords)
        .collect();
    for (name, m, start, end) in [
        ("falling sheet", &cloth, lifted, dropped),
        ("thrown soup", &scraps, scraps.positions.clone(), thrown),
    ] {
        let mut hc = build(m);
        hc.refit_swept(&start, &end, 0.0).unwrap();
        let mut hb = build(&body);
        hb.refit_swept(&body.positions, &body_end, 0.0).unwrap();
        let got: Vec<Key> = hc
            .vertex_impacts_with(&hb)
            .iter()
            .map(|i| (i.vertex, i.triangle, i.time.to_bits()))
            .collect();
        let path = |v: u32| [start[v as usize], end[v as usize]];
        let body_path = |v: u32| [body.positions[v as usize], body_end[v as usize]];
        let want = brute_vertex_triangle(
            start.len() as u32,
            &path,
            &body.triangles(),
            &body_path,
            false,
        );
        assert!(!want.is_empty(), "{name}: the case must hit the body");
        assert_same(&got, &want, name);
        assert_eq!(
            hc.vertex_impacts_with(&hb),
            hc.impacts_with(&hb).vertex_triangle,
            "{name}"
        );
    }
}

/// Brute force: every pair of edges sharing no vertex within `d`, neither lying on a face
/// that uses an end of the other or that `skip` lists for that end, as (edges, distance bits,
/// parameter bits).
fn brute_edge_proximity(
    m: &Mesh,
    positions: &[Point],
    d: f64,
    skip: &LocalFaces,
) -> Vec<(u32, u32, u64, [u64; 2])> {
    let edges = unique_edges(m);
    let at = |e: [u32; 2]| e.map(|v| positions[v as usize]);
    let faces = m.offsets.len() - 1;
    let around = |edge: [u32; 2], other: [u32; 2]| {
        edge.iter().any(|&v| {
            (0..faces as u32).any(|f| {
                let corners = m.face_corners(f);
                let near_end = corners.contains(&v) || skip.of(v as usize).contains(&f);
                near_end && other.iter().all(|w| corners.contains(w))
            })
        })
    };
    let mut found = Vec::new();
    for (i, &a) in edges.iter().enumerate() {
        for (j, &b) in edges.iter().enumerate().skip(i + 1) {
            if a.iter().any(|v| b.contains(v)) || around(a, b) || around(b, a) {
                continue;
            }
            let (t, distance) = segments_closest_points(at(a), at(b));
            if distance <= d {
                found.push((i as u32, j as u32, distance.to_bits(), t.map(f64::to_bits)));
            }
        }
    }
    found
}

#[test]
fn edge_proximity_matches_brute_force() {
    let mut found_any = false;
    // Beside the usual meshes, 42-gons, each owning more than 64 edges (sides and fan
    // diagonals), past what a face pair's bit set of edges holds.
    let wide = ngon_sheet(3, 2, 20, |x, y| 0.2 * (3.0 * x).sin() * y);
    for (name, m) in meshes().into_iter().chain([("wide ngons", wide)]) {
        assert_eq!(build(&m).edges(), unique_edges(&m).as_slice(), "{name}");
        let mut h = build(&m);
        let tables = [LocalFaces::default(), h.local_faces(0.1).unwrap()];
        for (positions, skip) in [m.positions.clone(), m.mapped(crumpled)]
            .into_iter()
            .flat_map(|p| tables.iter().map(move |t| (p.clone(), t)))
        {
            h.refit(&positions, 0.0).unwrap();
            for d in [0.02, 0.15] {
                let near = h.edge_proximity(d, skip).unwrap();
                let got: Vec<_> = near
                    .iter()
                    .map(|p| {
                        let [i, j] = p.edges;
                        (i, j, p.distance.to_bits(), p.parameters.map(f64::to_bits))
                    })
                    .collect();
                let want = brute_edge_proximity(&m, &positions, d, skip);
                found_any |= !want.is_empty();
                assert_same(&got, &want, name);
                for p in &near {
                    let [a, b] = p.edges.map(|e| h.edges()[e as usize]);
                    let on = |e: [u32; 2], t: f64| {
                        positions[e[0] as usize]
                            + (positions[e[1] as usize] - positions[e[0] as usize]) * t
                    };
                    let gap = on(b, p.parameters[1]) - on(a, p.parameters[0]);
                    if p.distance > 0.0 {
                        assert!((gap - p.direction * p.distance).norm() < 1e-12, "{name}");
                    }
                }
            }
        }
    }
    assert!(found_any);
}

#[test]
fn into_variants_reuse_their_buffers() {
    let m = folded_sheet(16, 0.0);
    let end = folded_sheet(16, 0.35).positions;
    let mut body = build(&sphere(6, 8, 0.2));
    body.refit_swept(
        &sphere(6, 8, 0.2).positions,
        &sphere(6, 8, 0.2).positions,
        0.0,
    )
    .unwrap();
    let mut h = build(&m);
    let mut rng = Rng::new(31);
    let queries: Vec<Point> = (0..50).map(|_| rng.point(1.0)).collect();
    let (mut closest, mut within, mut near) =
        (Vec::new(), Neighbours::default(), Neighbours::default());
    let (mut impacts, mut body_impacts, mut vertex_hits, mut edges) = (
        Impacts::default(),
        Impacts::default(),
        Vec::new(),
        Vec::new(),
    );
    // Two steps with different answers through the same buffers.
    for (from, to) in [(&m.positions, &end), (&end, &m.positions)] {
        h.refit_swept(from, to, 0.0).unwrap();
        h.self_impacts_into(&mut impacts);
        assert_eq!(impacts, h.self_impacts());
        h.impacts_with_into(&body, &mut body_impacts);
        assert_eq!(body_impacts, h.impacts_with(&body));
        h.vertex_impacts_with_into(&body, &mut vertex_hits);
        assert_eq!(vertex_hits, h.vertex_impacts_with(&body));
        h.refit(to, 0.0).unwrap();
        h.closest_points_into(&queries, 0.3, &mut closest).unwrap();
        assert_eq!(closest, h.closest_points(&queries, 0.3).unwrap());
        h.faces_within_into(&queries, 0.1, &mut within).unwrap();
        assert_eq!(within, h.faces_within(&queries, 0.1).unwrap());
        h.self_proximity_into(0.05, &LocalFaces::default(), &mut near)
            .unwrap();
        assert_eq!(
            near,
            h.self_proximity(0.05, &LocalFaces::default()).unwrap()
        );
        // The layers lie 0.2 apart at the end of the second step.
        h.edge_proximity_into(0.25, &LocalFaces::default(), &mut edges)
            .unwrap();
        assert_eq!(
            edges,
            h.edge_proximity(0.25, &LocalFaces::default()).unwrap()
        );
    }
    assert!(!impacts.vertex_triangle.is_empty() && !edges.is_empty());
    // A bad argument is an error that leaves the buffer as it was.
    let before = edges.clone();
    assert!(
        h.edge_proximity_into(-1.0, &LocalFaces::default(), &mut edges)
            .is_err()
    );
    assert_eq!(edges, before);
}

#[test]
fn memory_is_linear_in_faces() {
    let per_face = |n: u32| {
        let m = common::sheet(n, |x, y| 0.1 * (6.0 * x).sin() * y).triangulated();
        build(&m).memory_bytes() as f64 / m.face_count() as f64
    };
    let (small, large) = (per_face(20), per_face(80));
    assert!(
        small > 100.0 && large < 1000.0,
        "{small} {large} bytes per face"
    );
    assert!(
        (large / small - 1.0).abs() < 0.15,
        "{small} vs {large} bytes per face"
    );
}

#[test]
fn runs_of_queries_resting_on_and_hanging_off_a_body_match_brute_force() {
    // Runs of queries as a cloth draped over a body asks them: bands resting on the sphere
    // (0 to 2% of its radius off it, some exactly on a vertex), then bands far from it (inside
    // and outside its box), so that the face answering one query is often out of reach of the
    // next and the root's box alone rejects many. At radii from a millimetre to a kilometre the
    // outward-rounded single-precision boxes and the pruning slack meet rounding at every
    // scale; the limits run from a hair's breadth to infinity.
    let mut rng = Rng::new(23);
    for r in [1e-3, 1.0, 1e3] {
        let m = sphere(12, 16, 1.0);
        let positions = m.mapped(|p| Point::from(p.coords * r));
        let h = Hierarchy::build(&positions, &m.offsets, &m.corners).unwrap();
        let mut queries = Vec::new();
        for band in 0..12 {
            for _ in 0..25 {
                let dir = rng.point(1.0).coords.normalize();
                let lift = match band % 3 {
                    0 => 0.02 * rng.unit(),
                    1 => 0.1 + 2.0 * rng.unit(),
                    _ => 1e-9 * (rng.unit() - 0.5),
                };
                queries.push(Point::from(dir * r * (1.0 + lift)));
            }
            queries.push(positions[band * 7]);
        }
        for d in [1e-9, 0.004, 0.02, 0.5, f64::INFINITY].map(|d| d * r) {
            let got = h.closest_points(&queries, d).unwrap();
            for (i, q) in queries.iter().enumerate() {
                let want = nearest(&all_distances(&m, &positions, q), d, |_| false);
                let got_key = got[i].map(|c| (c.distance, c.face, c.triangle));
                assert_eq!(got_key, want, "radius {r}: query {i} within {d}");
            }
        }
    }
}
