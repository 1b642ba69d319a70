//! Face-varying refinement against hand-derived values: bilinear everywhere in mode `All`,
//! identical to vertex refinement where there is no seam in mode `None`, the crease rule along
//! a seam, pinned corners in the corner modes. (Exactness to OpenSubdiv is checked by the
//! conformance run over `../shared/reference/opensubdiv/facevarying`.)

use tailor_subdiv::{Crease, FVarLinear, FaceVarying, Mesh, Refiner, Uv};

use common::flat_grid;

mod common;

const EPS: f64 = 1e-14;

/// UVs with a seam down the middle column of vertices of a 2 x 2 grid: faces on the right use
/// their own copies of the middle values, shifted by 10 in u. `top` is the UV of vertex 7.
fn seamed_2x2(top: Uv) -> FaceVarying {
    let mut values: Vec<Uv> = (0..9)
        .map(|v| Uv::new((v % 3) as f64, (v / 3) as f64))
        .collect();
    values[7] = top;
    // Right-hand copies of vertices 1, 4 and 7.
    for v in [1, 4, 7] {
        values.push(values[v] + Uv::new(10.0, 0.0));
    }
    let right = |v: u32| match v {
        1 => 9,
        4 => 10,
        7 => 11,
        v => v,
    };
    let mesh = flat_grid(2);
    let indices = (0..mesh.face_count())
        .flat_map(|f| {
            let right_face = f % 2 == 1;
            mesh.face(f)
                .iter()
                .map(move |&v| if right_face { right(v) } else { v })
                .collect::<Vec<_>>()
        })
        .collect();
    FaceVarying { values, indices }
}

fn with_uvs(mut mesh: Mesh, uvs: FaceVarying, mode: FVarLinear) -> Mesh {
    mesh.options.fvar_linear = mode;
    mesh.with_uvs(uvs).unwrap()
}

fn refine(mesh: &Mesh, levels: usize) -> (Refiner, FaceVarying) {
    let refiner = Refiner::new(mesh, levels);
    let uvs = refiner.refine_uvs(&mesh.uvs().unwrap().values).unwrap();
    (refiner, uvs)
}

fn close(a: Uv, b: Uv) -> bool {
    (a - b).norm() < EPS
}

#[test]
fn mode_all_is_bilinear_across_a_seam() {
    let mesh = with_uvs(flat_grid(2), seamed_2x2(Uv::new(1.3, 2.4)), FVarLinear::All);
    let (_, uvs) = refine(&mesh, 1);
    let base = mesh.uvs().unwrap();
    for f in 0..mesh.face_count() {
        let corner =
            |j: usize| base.values[base.indices[mesh.face_range(f).start + j % 4] as usize];
        let centroid = (0..4).map(corner).sum::<Uv>() / 4.0;
        for j in 0..4 {
            // Child j of a quad keeps the vertex point at index j.
            let child = &uvs.indices[4 * (mesh.face_range(f).start + j)..][..4];
            let at = |k: usize| uvs.values[child[(j + k) % 4] as usize];
            assert!(close(at(0), corner(j)), "face {f} child {j}: corner");
            assert!(
                close(at(1), (corner(j) + corner(j + 1)) / 2.0),
                "edge after"
            );
            assert!(close(at(2), centroid), "centroid");
            assert!(
                close(at(3), (corner(j + 3) + corner(j)) / 2.0),
                "edge before"
            );
        }
    }
}

#[test]
fn mode_none_without_seams_matches_vertex_refinement() {
    // A 3 x 3 grid with a crease and a semi-sharp crease, UVs one per vertex.
    let mesh = flat_grid(3)
        .with_creases(vec![
            Crease {
                vertices: [5, 6],
                sharpness: 10.0,
            },
            Crease {
                vertices: [9, 10],
                sharpness: 1.5,
            },
        ])
        .unwrap();
    let values: Vec<Uv> = mesh
        .positions()
        .iter()
        .map(|p| Uv::new(p.x * p.x + 0.3 * p.y, p.y - 0.1 * p.x * p.y))
        .collect();
    let indices = mesh.face_vertices().to_vec();
    let mesh = with_uvs(
        mesh,
        FaceVarying {
            values: values.clone(),
            indices,
        },
        FVarLinear::None,
    );
    let (refiner, uvs) = refine(&mesh, 3);
    let expected = refiner.refine(&values);
    assert_eq!(uvs.values.len(), expected.len());
    assert!(uvs.values.iter().zip(&expected).all(|(a, b)| close(*a, *b)));
    assert_eq!(uvs.indices, refiner.last().face_verts().items);
}

#[test]
fn a_seam_refines_each_side_as_a_crease() {
    let top = Uv::new(1.0, 2.5);
    let mesh = with_uvs(flat_grid(2), seamed_2x2(top), FVarLinear::None);
    let (refiner, uvs) = refine(&mesh, 1);
    let level = refiner.last();
    // The centre vertex (4) has two values, left then right, each on the crease rule
    // 3/4 V + 1/8 (top + bottom).
    let left = 0.75 * Uv::new(1.0, 1.0) + 0.125 * (top + Uv::new(1.0, 0.0));
    let right = left + Uv::new(10.0, 0.0);
    let at_centre: Vec<Uv> = (0..level.face_count())
        .flat_map(|f| {
            let r = level.face_verts().range(f);
            r.filter(|&c| level.face_verts().items[c] == 4)
                .map(|c| uvs.values[uvs.indices[c] as usize])
                .collect::<Vec<_>>()
        })
        .collect();
    assert_eq!(at_centre.len(), 4);
    assert!(at_centre.iter().all(|&u| close(u, left) || close(u, right)));
    assert!(
        at_centre.iter().any(|&u| close(u, left)) && at_centre.iter().any(|&u| close(u, right))
    );
    // The edge point of the seam edge (4, 7) is the midpoint on each side.
    let mid = (Uv::new(1.0, 1.0) + top) / 2.0;
    for side in [mid, mid + Uv::new(10.0, 0.0)] {
        assert_eq!(uvs.values.iter().filter(|&&u| close(u, side)).count(), 1);
    }
}

#[test]
fn corner_modes_pin_boundary_corners() {
    let values: Vec<Uv> = (0..9)
        .map(|v| Uv::new((v % 3) as f64 * 0.7, (v / 3) as f64 * 0.4))
        .collect();
    let base = flat_grid(2);
    let indices = base.face_vertices().to_vec();
    for (mode, pinned) in [(FVarLinear::None, false), (FVarLinear::CornersOnly, true)] {
        let mesh = with_uvs(
            base.clone(),
            FaceVarying {
                values: values.clone(),
                indices: indices.clone(),
            },
            mode,
        );
        let (_, uvs) = refine(&mesh, 1);
        // Vertex 0 is a corner of the grid; its child is child vertex 0, value 0.
        assert_eq!(close(uvs.values[0], values[0]), pinned, "{mode:?}");
    }
}
