//! `tailor info`: what a control mesh is made of, before anyone simulates or renders it.
//!
//! Counts, the face-size and valence histograms, boundary and non-manifold components, creases,
//! corners, holes and the bounding box, computed from the same level-0 topology subdivision uses
//! (so "non-manifold" here means exactly what OpenSubdiv would sharpen).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use tailor_subdiv::topology::Level;

use crate::subdivide::read_mesh;

/// Arguments of `tailor info`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Control mesh (OBJ); `-` reads standard input.
    pub input: PathBuf,
}

/// Runs the command.
///
/// # Errors
/// Unreadable or invalid input.
pub fn run(args: &Args) -> Result<ExitCode> {
    let doc = read_mesh(&args.input)?;
    let mesh = &doc.mesh;
    let level = Level::from_mesh(mesh);
    println!("{}", args.input.display());
    println!("  vertices         {}", mesh.vertex_count());
    println!("  faces            {}", mesh.face_count());
    println!("  edges            {}", level.edge_count());
    let sizes = histogram((0..mesh.face_count()).map(|f| mesh.face(f).len()));
    println!("  face sizes       {}", format_histogram(&sizes));
    let valences = histogram((0..level.vertex_count).map(|v| level.vert_edges.range(v).len()));
    println!("  valences         {}", format_histogram(&valences));
    let boundary = (0..level.edge_count())
        .filter(|&e| level.is_boundary_edge(e))
        .count();
    let nm_edges = level.edge_nonmanifold.iter().filter(|&&n| n).count();
    let nm_verts = level.vertex_nonmanifold.iter().filter(|&&n| n).count();
    println!("  boundary edges   {boundary}");
    println!("  non-manifold     {nm_edges} edges, {nm_verts} vertices");
    println!(
        "  creases          {}",
        sharpness_summary(mesh.creases().iter().map(|c| c.sharpness))
    );
    println!(
        "  corners          {}",
        sharpness_summary(mesh.corners().iter().map(|c| c.sharpness))
    );
    println!("  holes            {}", mesh.holes().len());
    println!(
        "  uvs              {}",
        mesh.uvs().map_or(0, |u| u.values.len())
    );
    println!("  groups           {}", doc.groups.len());
    let (lo, hi) = bounds(mesh.positions());
    println!(
        "  bounding box     [{}, {}, {}] .. [{}, {}, {}]",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    println!(
        "  options          boundary {}, creases {}, triangles {}, uvs {}",
        mesh.options.boundary,
        mesh.options.crease_method,
        mesh.options.triangle_rule,
        mesh.options.fvar_linear
    );
    Ok(ExitCode::SUCCESS)
}

fn histogram(values: impl Iterator<Item = usize>) -> BTreeMap<usize, usize> {
    let mut h = BTreeMap::new();
    for v in values {
        *h.entry(v).or_insert(0) += 1;
    }
    h
}

fn format_histogram(h: &BTreeMap<usize, usize>) -> String {
    h.iter()
        .map(|(k, n)| format!("{k}:{n}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn sharpness_summary(values: impl Iterator<Item = f64>) -> String {
    let v: Vec<f64> = values.collect();
    if v.is_empty() {
        return "0".into();
    }
    let min = v.iter().copied().fold(f64::INFINITY, f64::min);
    let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    format!("{} (sharpness {min} to {max})", v.len())
}

fn bounds(points: &[tailor_subdiv::Point]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}
