//! The committed assets are what the generator makes, and they are fit for simulation: the
//! mannequin is one closed, manifold, outward-facing quad mesh whose refined surface does not
//! cross itself; every frame of its sequence shares the rest topology; the garments carry the
//! documented groups and UVs and start clear of the refined rest body (no control point inside
//! it, none within 5 mm of it).
//!
//! The checks here are written independently of the generator (ray parity, closest points and
//! triangle crossings by brute force over plain arrays); only the byte comparison calls it.

#[path = "../examples/make_assets/generate/mod.rs"]
mod generate;

use std::fs;
use std::path::{Path, PathBuf};

use tailor_subdiv::obj::{ObjDocument, read};
use tailor_subdiv::topology::Level;
use tailor_subdiv::{Mesh, subdivide};

type Vec3 = [f64; 3];

const LAST_FRAME: usize = 120;

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
}

fn load(relative: &str) -> ObjDocument {
    read(&assets().join(relative)).unwrap_or_else(|e| panic!("{relative}: {e}"))
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn add_scaled(a: Vec3, b: Vec3, s: f64) -> Vec3 {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}

/// A triangle with its corner ids (to skip neighbours) and bounding box.
struct Tri {
    ids: [u32; 3],
    p: [Vec3; 3],
    lo: Vec3,
    hi: Vec3,
}

/// The refined rest body as triangles (each quad split along its 0–2 diagonal).
fn refined_rest_body() -> Vec<Tri> {
    let rest = load("mannequin/body_control.obj").mesh;
    let refined = subdivide(&rest, 2, false).0;
    let pos = |v: u32| refined.positions()[v as usize].coords.into();
    (0..refined.face_count())
        .flat_map(|f| {
            let fv = refined.face(f);
            (1..fv.len() - 1).map(move |k| [fv[0], fv[k], fv[k + 1]])
        })
        .map(|ids| {
            let p = ids.map(pos);
            let lo = [0, 1, 2].map(|a| p.iter().map(|q: &Vec3| q[a]).fold(f64::MAX, f64::min));
            let hi = [0, 1, 2].map(|a| p.iter().map(|q: &Vec3| q[a]).fold(f64::MIN, f64::max));
            Tri { ids, p, lo, hi }
        })
        .collect()
}

/// Where the segment `o + t d`, `t ∈ (0, t_max]`, crosses triangle `p`, if it does.
fn crossing(o: Vec3, d: Vec3, t_max: f64, [a, b, c]: &[Vec3; 3]) -> bool {
    let (e1, e2) = (sub(*b, *a), sub(*c, *a));
    let h = cross(d, e2);
    let det = dot(e1, h);
    if det.abs() < 1e-15 {
        return false;
    }
    let s = sub(o, *a);
    let u = dot(s, h) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    let t = dot(e2, q) / det;
    u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t <= t_max
}

/// Ray parity: an odd number of crossings on a ray in a generic direction means inside.
fn inside(p: Vec3, body: &[Tri]) -> bool {
    let d = [0.2672612419124244, 0.8017837257372732, 0.5345224838248488];
    body.iter()
        .filter(|t| crossing(p, d, f64::INFINITY, &t.p))
        .count()
        % 2
        == 1
}

/// The distance from `p` to triangle `[a, b, c]`: to its plane inside it, else to its edges.
fn triangle_distance(p: Vec3, [a, b, c]: &[Vec3; 3]) -> f64 {
    let n = cross(sub(*b, *a), sub(*c, *a));
    let nn = dot(n, n);
    let inside_edge = |x: Vec3, y: Vec3| dot(cross(sub(y, x), sub(p, x)), n) >= 0.0;
    if inside_edge(*a, *b) && inside_edge(*b, *c) && inside_edge(*c, *a) {
        return dot(sub(p, *a), n).abs() / nn.sqrt();
    }
    let segment = |x: Vec3, y: Vec3| {
        let e = sub(y, x);
        let t = (dot(sub(p, x), e) / dot(e, e)).clamp(0.0, 1.0);
        let r = sub(p, add_scaled(x, e, t));
        dot(r, r).sqrt()
    };
    segment(*a, *b).min(segment(*b, *c)).min(segment(*c, *a))
}

/// The distance from `p` to the nearest triangle, skipping those whose box is farther.
fn distance(p: Vec3, body: &[Tri]) -> f64 {
    let mut best = f64::INFINITY;
    for t in body {
        let gap = [0, 1, 2].map(|a| (t.lo[a] - p[a]).max(p[a] - t.hi[a]).max(0.0));
        if dot(gap, gap) < best * best {
            best = best.min(triangle_distance(p, &t.p));
        }
    }
    best
}

fn boundary_edges(level: &Level) -> usize {
    (0..level.edge_count())
        .filter(|&e| level.is_boundary_edge(e))
        .count()
}

fn assert_manifold(mesh: &Mesh, name: &str) -> Level {
    let level = Level::from_mesh(mesh);
    assert!(
        !level.edge_nonmanifold().contains(&true),
        "{name}: non-manifold edge"
    );
    assert!(
        !level.vertex_nonmanifold().contains(&true),
        "{name}: non-manifold vertex"
    );
    assert!(
        (0..mesh.face_count()).all(|f| mesh.face(f).len() == 4),
        "{name}: not all quads"
    );
    level
}

#[test]
fn committed_files_are_what_the_generator_makes() {
    let generated = generate::generate();
    println!("{}", generated.summary);
    for asset in &generated.assets {
        let committed = fs::read_to_string(assets().join(&asset.path))
            .unwrap_or_else(|e| panic!("{}: {e}", asset.path));
        assert!(
            committed == asset.text,
            "assets/{} differs from the generator's output: run `cargo run --release --example make_assets`",
            asset.path
        );
    }
    let expected = generated.assets.len();
    let on_disk: usize = ["mannequin", "garments"]
        .iter()
        .map(|dir| fs::read_dir(assets().join(dir)).unwrap().count())
        .sum();
    assert_eq!(on_disk, expected, "stray files under assets/");
}

#[test]
fn body_is_closed_manifold_and_outward() {
    let mesh = load("mannequin/body_control.obj").mesh;
    let level = assert_manifold(&mesh, "body");
    assert_eq!(boundary_edges(&level), 0, "body has holes");
    assert!((300..700).contains(&mesh.face_count()));
    let body = refined_rest_body();
    // Divergence theorem: positive when the faces point outward.
    let volume: f64 = body
        .iter()
        .map(|t| dot(t.p[0], cross(t.p[1], t.p[2])) / 6.0)
        .sum();
    assert!((0.04..0.1).contains(&volume), "volume {volume} m³");
    let lo = [0, 1, 2].map(|a| body.iter().map(|t| t.lo[a]).fold(f64::MAX, f64::min));
    let hi = [0, 1, 2].map(|a| body.iter().map(|t| t.hi[a]).fold(f64::MIN, f64::max));
    assert!(lo[1].abs() < 1e-5, "feet at y = {}", lo[1]);
    assert!((hi[1] - 1.75).abs() < 1e-5, "height {}", hi[1]);
    assert!(hi[2] > -lo[2], "the feet point to +Z");
}

#[test]
fn refined_rest_body_does_not_cross_itself() {
    let mut body = refined_rest_body();
    body.sort_by(|a, b| a.lo[0].total_cmp(&b.lo[0]));
    let edges_cross = |a: &Tri, b: &Tri| {
        (0..3).any(|k| {
            let (p, q) = (a.p[k], a.p[(k + 1) % 3]);
            crossing(p, sub(q, p), 1.0, &b.p)
        })
    };
    for (i, a) in body.iter().enumerate() {
        for b in body[i + 1..].iter().take_while(|b| b.lo[0] <= a.hi[0]) {
            let overlap = (1..3).all(|k| a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k]);
            let neighbours = a.ids.iter().any(|v| b.ids.contains(v));
            if overlap && !neighbours {
                assert!(
                    !edges_cross(a, b) && !edges_cross(b, a),
                    "refined body crosses itself near {:?}",
                    a.p[0]
                );
            }
        }
    }
}

#[test]
fn every_frame_has_the_rest_topology() {
    let rest = load("mannequin/body_control.obj").mesh;
    let first = load("mannequin/body_0000.obj").mesh;
    assert_eq!(
        first.positions(),
        rest.positions(),
        "frame 0 is the rest pose"
    );
    let mut moved = 0.0_f64;
    for frame in 0..=LAST_FRAME {
        let mesh = load(&format!("mannequin/body_{frame:04}.obj")).mesh;
        assert_eq!(mesh.face_offsets(), rest.face_offsets(), "frame {frame}");
        assert_eq!(mesh.face_vertices(), rest.face_vertices(), "frame {frame}");
        for (p, q) in mesh.positions().iter().zip(rest.positions()) {
            moved = moved.max((p - q).norm());
        }
    }
    assert!(moved > 0.3, "the mannequin barely moves ({moved} m)");
    assert!(
        !assets()
            .join(format!("mannequin/body_{:04}.obj", LAST_FRAME + 1))
            .exists()
    );
}

/// Checks a garment's groups (by name, each a set of faces), UVs and openness.
fn check_garment(name: &str, groups: &[&str]) -> ObjDocument {
    let doc = load(&format!("garments/{name}.obj"));
    let mesh = &doc.mesh;
    let level = assert_manifold(mesh, name);
    assert!(boundary_edges(&level) > 0, "{name} should be open");
    let names: Vec<&str> = doc.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, groups, "{name} groups");
    let all = &doc.groups.iter().find(|g| g.name == name).unwrap().faces;
    assert_eq!(
        all.len(),
        mesh.face_count(),
        "{name}: group {name} holds every face"
    );
    let attach = &doc
        .groups
        .iter()
        .find(|g| g.name == "attach")
        .unwrap()
        .faces;
    assert!(!attach.is_empty() && attach.len() < mesh.face_count() / 4);
    let uvs = mesh.uvs().unwrap_or_else(|| panic!("{name} has no UVs"));
    assert!(
        uvs.values
            .iter()
            .all(|uv| (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y))
    );
    doc
}

#[test]
fn garments_have_their_groups_and_uvs() {
    let cape = check_garment("cape", &["cape", "attach", "collar"]);
    let group = |name: &str| &cape.groups.iter().find(|g| g.name == name).unwrap().faces;
    assert!(group("attach").iter().all(|f| group("collar").contains(f)));
    // The attached faces are the top row: their vertices are the highest of the cape.
    let mesh = &cape.mesh;
    let top = group("attach")
        .iter()
        .flat_map(|&f| mesh.face(f as usize))
        .map(|&v| mesh.positions()[v as usize].y)
        .fold(f64::MAX, f64::min);
    let below = (0..mesh.face_count())
        .filter(|f| !group("collar").contains(&(*f as u32)))
        .flat_map(|f| mesh.face(f))
        .map(|&v| mesh.positions()[v as usize].y)
        .fold(f64::MIN, f64::max);
    assert!(top > below, "the collar sits above the rest of the cape");
    check_garment("skirt", &["skirt", "attach"]);
}

#[test]
fn garments_clear_the_rest_body() {
    let body = refined_rest_body();
    for name in ["cape", "skirt"] {
        let mesh = load(&format!("garments/{name}.obj")).mesh;
        for (i, p) in mesh.positions().iter().enumerate() {
            let p: Vec3 = p.coords.into();
            assert!(!inside(p, &body), "{name} vertex {i} is inside the body");
            let d = distance(p, &body);
            assert!(d >= 0.005, "{name} vertex {i} is {d} m from the body");
        }
        // Faces point away from the body: along their normal, the body recedes.
        let outward = (0..mesh.face_count())
            .filter(|&f| {
                let fv = mesh.face(f);
                let q = |k: usize| -> Vec3 { mesh.positions()[fv[k] as usize].coords.into() };
                let n = cross(sub(q(2), q(0)), sub(q(3), q(1)));
                let c = add_scaled(q(0), sub(q(2), q(0)), 0.5);
                let s = 0.005 / dot(n, n).sqrt();
                distance(add_scaled(c, n, s), &body) > distance(add_scaled(c, n, -s), &body)
            })
            .count();
        assert_eq!(outward, mesh.face_count(), "{name} faces point outward");
    }
}
