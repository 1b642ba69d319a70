//! The asset generator: everything in `assets/` that is made rather than written by hand.
//!
//! [`generate`] builds the mannequin's control mesh ([`body`]), scales it so its level-2
//! Catmull-Clark surface stands [`HEIGHT`] tall with its lowest point on y = 0, skins it to a
//! skeleton and poses it for every frame ([`skeleton`]), and shapes the garments around the
//! refined rest body ([`garment`]). It uses no randomness, no hash-map order and no threads, and
//! rounds every written coordinate to 6 decimals (what it writes is what the later steps
//! measure), so the same source gives the same bytes on every run; `tests/assets.rs` checks that
//! against the committed files.

mod body;
mod garment;
mod geom;
mod skeleton;

use std::fmt::Write;

use tailor_subdiv::{Mesh, subdivide};

use geom::{P, Soup};

/// Standing height of the refined body, metres.
pub const HEIGHT: f64 = 1.75;
/// Frames per second of the body sequence.
pub const FPS: usize = 24;

/// One generated file.
pub struct Asset {
    /// Path relative to `assets/`.
    pub path: String,
    /// Contents.
    pub text: String,
}

/// The generated files and a human-readable account of them.
pub struct Generated {
    /// Files, in a fixed order.
    pub assets: Vec<Asset>,
    /// Counts, bounds, volume and clearances.
    pub summary: String,
}

/// `x` rounded to 6 decimals (as printed), without negative zero.
fn round6(x: f64) -> f64 {
    (x * 1e6).round() / 1e6 + 0.0
}

/// Builds every asset.
///
/// # Panics
/// If the generated geometry breaks one of its own checks (a garment too close to the body).
#[must_use]
pub fn generate() -> Generated {
    let built = body::build();
    let design = Mesh::from_polygons(built.positions.clone(), &built.faces).expect("valid body");
    let (lo, hi) = bounds(subdivide(&design, 2, false).0.positions());
    let scale = HEIGHT / (hi.y - lo.y);
    let to_final = |p: P| P::new(p.x * scale, (p.y - lo.y) * scale, p.z * scale);

    let rest: Vec<P> = built
        .positions
        .iter()
        .map(|&p| to_final(p).map(round6))
        .collect();
    let mut mesh = design;
    mesh.set_positions(&rest).expect("same vertex count");
    let refined = subdivide(&mesh, 2, false).0;
    let soup = Soup::from_faces(
        refined.positions(),
        (0..refined.face_count()).map(|f| refined.face(f)),
    );

    let mut summary = String::new();
    let (lo, hi) = bounds(refined.positions());
    writeln!(
        summary,
        "body: {} control vertices, {} quads; level-2 surface {} quads, \
         bounds [{:.3}, {:.3}, {:.3}] .. [{:.3}, {:.3}, {:.3}] m, volume {:.4} m³",
        rest.len(),
        built.faces.len(),
        refined.face_count(),
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        geom::volume(&soup)
    )
    .expect("write to string");

    let mut assets = vec![Asset {
        path: "mannequin/body_control.obj".into(),
        text: body_obj(&mut mesh, &rest, "mannequin control mesh, rest pose"),
    }];
    let skeleton = skeleton::Skeleton::new(to_final);
    let weights: Vec<_> = rest
        .iter()
        .zip(&built.parts)
        .map(|(&p, &part)| skeleton.weights(p, part))
        .collect();
    for frame in 0..=skeleton::LAST_FRAME {
        let posed = skeleton::skin(&rest, &weights, &skeleton.pose(frame));
        assets.push(Asset {
            path: format!("mannequin/body_{frame:04}.obj"),
            text: body_obj(
                &mut mesh,
                &posed,
                &format!(
                    "mannequin frame {frame} of 0..={} at {FPS} fps",
                    skeleton::LAST_FRAME
                ),
            ),
        });
    }

    let knee = to_final(P::new(0.0, 0.47, 0.0)).y;
    let garments = [
        (
            "cape",
            garment::cape(&soup, to_final(P::new(0.0, 1.30, 0.0)), knee),
        ),
        (
            "skirt",
            garment::skirt(
                &soup,
                P::origin(),
                to_final(P::new(0.0, 1.02, 0.0)).y,
                to_final(P::new(0.0, 0.60, 0.0)).y,
            ),
        ),
    ];
    for (name, g) in &garments {
        writeln!(
            summary,
            "{name}: {} control vertices, {} quads, {} uvs; nearest the refined body {:.1} mm",
            g.positions.len(),
            g.faces.len(),
            g.uvs.len(),
            g.clearance * 1e3
        )
        .expect("write to string");
        assets.push(Asset {
            path: format!("garments/{name}.obj"),
            text: g.obj(&format!(
                "{name} control mesh, made by examples/make_assets"
            )),
        });
    }
    Generated { assets, summary }
}

/// The body with `positions` (rounded) as OBJ, after a comment line.
fn body_obj(mesh: &mut Mesh, positions: &[P], header: &str) -> String {
    let rounded: Vec<P> = positions.iter().map(|p| p.map(round6)).collect();
    mesh.set_positions(&rounded).expect("same vertex count");
    let mut out = format!("# {header}, made by examples/make_assets\n").into_bytes();
    tailor_subdiv::obj::write(mesh, None, tailor_subdiv::obj::Precision::Full, &mut out)
        .expect("write to memory");
    String::from_utf8(out).expect("OBJ is ASCII")
}

/// Componentwise minimum and maximum.
fn bounds(points: &[P]) -> (P, P) {
    points.iter().fold(
        (P::from([f64::INFINITY; 3]), P::from([f64::NEG_INFINITY; 3])),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    )
}
