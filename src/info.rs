//! `tailor info`: what a control mesh is made of, before anyone simulates or renders it.
//!
//! Counts, the face-size and valence histograms, boundary and non-manifold components, creases,
//! corners, holes and the bounding box, computed from the same level-0 topology subdivision uses
//! (so "non-manifold" here means exactly what OpenSubdiv would sharpen).

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use tailor_subdiv::topology::Level;

use crate::output;
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
/// Unreadable or invalid input, standard output that cannot be written.
pub fn run(args: &Args) -> Result<ExitCode> {
    let doc = read_mesh(&args.input)?;
    let mesh = &doc.mesh;
    let level = Level::from_mesh(mesh);
    let mut out = String::new();
    writeln!(out, "{}", args.input.display())?;
    writeln!(out, "  vertices         {}", mesh.vertex_count())?;
    writeln!(out, "  faces            {}", mesh.face_count())?;
    writeln!(out, "  edges            {}", level.edge_count())?;
    let sizes = histogram((0..mesh.face_count()).map(|f| mesh.face(f).len()));
    writeln!(out, "  face sizes       {}", format_histogram(&sizes))?;
    let valences = histogram((0..level.vertex_count()).map(|v| level.vert_edges().range(v).len()));
    writeln!(out, "  valences         {}", format_histogram(&valences))?;
    let boundary = (0..level.edge_count())
        .filter(|&e| level.is_boundary_edge(e))
        .count();
    let nm_edges = level.edge_nonmanifold().iter().filter(|&&n| n).count();
    let nm_verts = level.vertex_nonmanifold().iter().filter(|&&n| n).count();
    writeln!(out, "  boundary edges   {boundary}")?;
    writeln!(
        out,
        "  non-manifold     {nm_edges} edges, {nm_verts} vertices"
    )?;
    writeln!(
        out,
        "  creases          {}",
        sharpness_summary(mesh.creases().iter().map(|c| c.sharpness))
    )?;
    writeln!(
        out,
        "  corners          {}",
        sharpness_summary(mesh.corners().iter().map(|c| c.sharpness))
    )?;
    writeln!(out, "  holes            {}", mesh.holes().len())?;
    writeln!(
        out,
        "  uvs              {}",
        mesh.uvs().map_or(0, |u| u.values.len())
    )?;
    writeln!(out, "  groups           {}", doc.groups.len())?;
    let (lo, hi) = bounds(mesh.positions());
    let [lo, hi] = [lo, hi].map(|corner| readable(corner, lo.iter().chain(&hi)));
    writeln!(out, "  bounding box     [{lo}] .. [{hi}]")?;
    writeln!(
        out,
        "  options          boundary {}, creases {}, triangles {}, fvar-linear {}",
        mesh.options.boundary,
        mesh.options.crease_method,
        mesh.options.triangle_rule,
        mesh.options.fvar_linear
    )?;
    output::print(&out)?;
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

/// The coordinates of `corner` with six significant digits of the largest of `all` (the same
/// number of decimals for every coordinate, so the columns line up), not the 17 digits that
/// round-trip an `f64`.
fn readable<'a>(corner: [f64; 3], all: impl Iterator<Item = &'a f64>) -> String {
    let largest = all
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let whole_digits = if largest >= 1.0 {
        largest.log10().floor() as i32 + 1
    } else {
        1
    };
    let decimals = (6 - whole_digits).clamp(0, 12) as usize;
    corner
        .map(|x| {
            let text = format!("{x:.decimals$}");
            // "-0.00000" is zero.
            if text
                .trim_start_matches('-')
                .trim_matches(|c| c == '0' || c == '.')
                .is_empty()
            {
                text.trim_start_matches('-').to_owned()
            } else {
                text
            }
        })
        .join(", ")
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
