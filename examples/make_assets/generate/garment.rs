//! Garments as quad control meshes shaped around the refined rest body.
//!
//! Each garment is a grid of rays: every control point looks outward from an axis inside the
//! body, finds where the ray last leaves the refined (level-2) rest surface, and sits a small
//! gap beyond it. Going down a garment the distance only grows (a running maximum, then a
//! flare), so the cloth hangs from the widest point above it instead of following the body in,
//! as fabric under gravity would. The generator then measures every control point's true
//! distance to the refined body and refuses to write a garment closer than [`MIN_CLEARANCE`].
//!
//! - The cape: 20 × 24 quads. Its top five rows fan out over the shoulders and the back of the
//!   neck on rays from the chest centre, elevation 55° down to 0°; the other rows hang from
//!   chest height to the knees on horizontal rays behind the body (±70° about the back).
//! - The skirt: 32 × 12 quads, a closed band from the waist to mid-thigh on horizontal rays all
//!   around; open at both ends.

use std::f64::consts::{PI, TAU};
use std::fmt::Write;

use super::geom::{P, Soup, V};
use super::round6;

/// The smallest distance allowed between a garment control point and the refined rest body.
pub const MIN_CLEARANCE: f64 = 0.005;
/// How far beyond the body surface a garment starts, along its ray.
const GAP: f64 = 0.015;
/// Rays only look this far for the body, so the arms never count.
const REACH: f64 = 0.3;

/// A quad garment with one UV per corner and a group list per face.
pub struct Garment {
    /// Control points.
    pub positions: Vec<P>,
    /// Texture coordinates.
    pub uvs: Vec<[f64; 2]>,
    /// Outward quads over `positions`.
    pub faces: Vec<[u32; 4]>,
    /// The same quads over `uvs`.
    pub uv_faces: Vec<[u32; 4]>,
    /// The groups of each face, space-separated as on an OBJ `g` line.
    pub groups: Vec<&'static str>,
    /// The smallest distance from a control point to the refined rest body.
    pub clearance: f64,
}

/// Where a ray last leaves the body within [`REACH`], or 0 when it meets nothing.
fn body_radius(body: &Soup, origin: P, dir: V) -> f64 {
    body.crossings(origin, dir, REACH)
        .last()
        .copied()
        .unwrap_or(0.0)
}

/// The cape, for a body whose chest centre is `chest` and knees are at height `knee`.
pub fn cape(body: &Soup, chest: P, knee: f64) -> Garment {
    const NU: usize = 20;
    const NV: usize = 24;
    const TOP: usize = 5;
    let top_elevation = 55f64.to_radians();
    let spread = 70f64.to_radians();
    let mut positions = Vec::new();
    let mut hanging = [0.0_f64; NU + 1];
    for r in 0..=NV {
        for (c, hang) in hanging.iter_mut().enumerate() {
            let phi = spread * (2.0 * c as f64 / NU as f64 - 1.0);
            let p = if r <= TOP {
                let beta = top_elevation * (1.0 - r as f64 / TOP as f64);
                let dir = V::new(beta.cos() * phi.sin(), beta.sin(), -beta.cos() * phi.cos());
                let reach = body_radius(body, chest, dir) + GAP;
                *hang = reach;
                chest + dir * reach
            } else {
                let t = (r - TOP) as f64 / (NV - TOP) as f64;
                let origin = P::new(0.0, chest.y + (knee - chest.y) * t, chest.z);
                let dir = V::new(phi.sin(), 0.0, -phi.cos());
                *hang = hang.max(body_radius(body, origin, dir) + GAP);
                origin + dir * (*hang + 0.10 * t * t)
            };
            positions.push(p);
        }
    }
    let groups = (0..NV)
        .flat_map(|r| {
            let g = match r {
                0 => "cape attach collar",
                1 | 2 => "cape collar",
                _ => "cape",
            };
            std::iter::repeat_n(g, NU)
        })
        .collect();
    let id = |r: usize, c: usize| (r * (NU + 1) + c) as u32;
    let faces: Vec<[u32; 4]> = (0..NV)
        .flat_map(|r| {
            (0..NU).map(move |c| [id(r, c), id(r, c + 1), id(r + 1, c + 1), id(r + 1, c)])
        })
        .collect();
    let uvs = (0..=NV)
        .flat_map(|r| (0..=NU).map(move |c| [c as f64 / NU as f64, 1.0 - r as f64 / NV as f64]))
        .collect();
    finish(body, positions, uvs, faces.clone(), faces, groups)
}

/// The skirt, from height `waist` to height `hem`, around the vertical axis through `axis`.
pub fn skirt(body: &Soup, axis: P, waist: f64, hem: f64) -> Garment {
    const NA: usize = 32;
    const ND: usize = 12;
    let mut positions = Vec::new();
    let mut hanging = [0.0_f64; NA];
    for r in 0..=ND {
        let t = r as f64 / ND as f64;
        let origin = P::new(axis.x, waist + (hem - waist) * t, axis.z);
        for (c, hang) in hanging.iter_mut().enumerate() {
            let phi = TAU * c as f64 / NA as f64 - PI;
            let dir = V::new(phi.sin(), 0.0, phi.cos());
            *hang = hang.max(body_radius(body, origin, dir) + GAP);
            positions.push(origin + dir * (*hang + 0.06 * t * t));
        }
    }
    let id = |r: usize, c: usize| (r * NA + c % NA) as u32;
    let uv_id = |r: usize, c: usize| (r * (NA + 1) + c) as u32;
    let quad = |f: &dyn Fn(usize, usize) -> u32, r: usize, c: usize| {
        [f(r, c), f(r + 1, c), f(r + 1, c + 1), f(r, c + 1)]
    };
    let faces = (0..ND).flat_map(|r| (0..NA).map(move |c| (r, c)));
    let uvs = (0..=ND)
        .flat_map(|r| (0..=NA).map(move |c| [c as f64 / NA as f64, 1.0 - r as f64 / ND as f64]))
        .collect();
    let groups = (0..ND * NA)
        .map(|f| if f < NA { "skirt attach" } else { "skirt" })
        .collect();
    finish(
        body,
        positions,
        uvs,
        faces.clone().map(|(r, c)| quad(&id, r, c)).collect(),
        faces.map(|(r, c)| quad(&uv_id, r, c)).collect(),
        groups,
    )
}

/// Rounds to the written precision and checks the clearance of every control point.
fn finish(
    body: &Soup,
    positions: Vec<P>,
    uvs: Vec<[f64; 2]>,
    faces: Vec<[u32; 4]>,
    uv_faces: Vec<[u32; 4]>,
    groups: Vec<&'static str>,
) -> Garment {
    let positions: Vec<P> = positions.into_iter().map(|p| p.map(round6)).collect();
    let mut clearance = f64::INFINITY;
    for (i, p) in positions.iter().enumerate() {
        let d = body.distance(*p);
        assert!(
            d >= MIN_CLEARANCE,
            "garment vertex {i} at {p} is {d} m from the body"
        );
        clearance = clearance.min(d);
    }
    Garment {
        positions,
        uvs,
        faces,
        uv_faces,
        groups,
        clearance,
    }
}

impl Garment {
    /// The garment as OBJ text: `v`, `vt`, then faces `v/vt` under `g` lines.
    pub fn obj(&self, header: &str) -> String {
        let mut s = format!("# {header}\n");
        for p in &self.positions {
            writeln!(s, "v {} {} {}", p.x, p.y, p.z).expect("write to string");
        }
        for [u, v] in &self.uvs {
            writeln!(s, "vt {} {}", round6(*u), round6(*v)).expect("write to string");
        }
        let mut current = "";
        for ((f, t), g) in self.faces.iter().zip(&self.uv_faces).zip(&self.groups) {
            if *g != current {
                writeln!(s, "g {g}").expect("write to string");
                current = g;
            }
            s.push('f');
            for (v, vt) in f.iter().zip(t) {
                write!(s, " {}/{}", v + 1, vt + 1).expect("write to string");
            }
            s.push('\n');
        }
        s
    }
}
