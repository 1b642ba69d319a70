//! OpenSubdiv's uniform refinement as both programs of this folder ask for it.

use opensubdiv_petite::far::{
    BoundaryInterpolation, TopologyDescriptor, TopologyRefiner, TopologyRefinerOptions,
    UniformRefinementOptions,
};

/// `Far::TopologyRefiner` of the mesh of `vertices` vertices and faces `sizes`/`corners`,
/// refined uniformly to `level` with tailor's default options (edge-only boundaries) and
/// OpenSubdiv's vertex order, the last level complete or minimal.
pub fn refine(
    vertices: usize,
    sizes: &[u32],
    corners: &[u32],
    level: usize,
    full_topology_in_last_level: bool,
) -> TopologyRefiner {
    let descriptor = TopologyDescriptor::new(vertices, sizes, corners).expect("valid mesh");
    let options = TopologyRefinerOptions {
        boundary_interpolation: Some(BoundaryInterpolation::EdgeOnly),
        face_varying_linear_interpolation: None,
        ..TopologyRefinerOptions::default()
    };
    let mut refiner = TopologyRefiner::new(descriptor, options).expect("OpenSubdiv topology");
    refiner.refine_uniform(UniformRefinementOptions {
        refinement_level: level,
        order_vertices_from_faces_first: false,
        full_topology_in_last_level,
    });
    refiner
}
