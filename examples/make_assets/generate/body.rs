//! The mannequin's Catmull-Clark control mesh, box-modelled.
//!
//! The torso is the surface of an 8 × 6 × 4 lattice box (columns across, levels up, rows deep),
//! each level mapped to a rounded cross-section of its own half-width and half-depth (hips,
//! waist, chest, sloping shoulders). Limbs are tubes of 8-vertex rings grown out of 2 × 2
//! patches of that surface, the way a modeller extrudes faces: the patch's four quads are
//! removed, their boundary loop (8 vertices) becomes the tube's first ring, and each further
//! ring is an ellipse in a frame carried along the tube by parallel transport (so tubes that
//! bend, like the ankle into the foot, do not twist). A tube ends in four quads around a centre
//! vertex. The result is one closed, consistently oriented, all-quad manifold: legs from the
//! bottom, arms from the sides, neck and head from the top.
//!
//! Coordinates here are a design space in metres (Y up, facing +Z, the character's left at +X);
//! [`super`] scales them so the refined body stands 1.75 m tall on y = 0.

use std::f64::consts::FRAC_PI_4;

use super::geom::{P, V};

/// Lattice cells across (X), up (Y) and deep (Z).
const N: [usize; 3] = [8, 6, 4];
/// Per level (bottom to top): height, half-width, half-depth, centre z.
const LEVELS: [[f64; 4]; 7] = [
    [0.80, 0.165, 0.095, 0.0],
    [0.90, 0.180, 0.110, -0.005],
    [1.02, 0.145, 0.095, 0.0],
    [1.14, 0.155, 0.100, 0.005],
    [1.26, 0.170, 0.110, 0.010],
    [1.36, 0.185, 0.100, 0.0],
    [1.45, 0.175, 0.080, -0.010],
];
/// Column positions in [-1, 1] at the bottom (room for the legs) and top (room for the neck).
const SX_BOTTOM: [f64; 9] = [-1.0, -0.88, -0.55, -0.15, 0.0, 0.15, 0.55, 0.88, 1.0];
const SX_TOP: [f64; 9] = [-1.0, -0.8, -0.55, -0.3, 0.0, 0.3, 0.55, 0.8, 1.0];
/// Row positions in [-1, 1].
const SZ: [f64; 5] = [-1.0, -0.6, 0.0, 0.6, 1.0];
/// How far cross-sections round from a rectangle toward an ellipse.
const ROUNDING: f64 = 0.5;
/// How far the shoulders drop from the neck to the arm.
const SHOULDER_SLOPE: f64 = 0.05;

/// The character's left (+X) or right (-X).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// +X.
    Left,
    /// -X.
    Right,
}

impl Side {
    /// Both sides, left first.
    pub const BOTH: [Self; 2] = [Self::Left, Self::Right];

    /// +1 for left, -1 for right.
    pub fn sign(self) -> f64 {
        match self {
            Self::Left => 1.0,
            Self::Right => -1.0,
        }
    }
}

/// The body part a control vertex was built for; it decides which bones may move it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// The lattice box.
    Torso,
    /// The neck and head tube.
    Head,
    /// An arm tube.
    Arm(Side),
    /// A leg tube (with its foot).
    Leg(Side),
}

/// The shoulder joint, arm direction (A-pose, 30° below horizontal) of one side, design space.
pub fn arm_frame(side: Side) -> (P, V) {
    let s = side.sign();
    let (sin, cos) = 30f64.to_radians().sin_cos();
    (P::new(0.165 * s, 1.37, 0.0), V::new(cos * s, -sin, 0.0))
}

/// The x of a leg's axis, design space.
pub fn leg_x(side: Side) -> f64 {
    0.095 * side.sign()
}

/// A closed all-quad control mesh with the part of each vertex.
pub struct Body {
    /// Control points, design space.
    pub positions: Vec<P>,
    /// Outward-oriented quads.
    pub faces: Vec<[u32; 4]>,
    /// The part of each control point.
    pub parts: Vec<Part>,
}

/// One cross-section of a tube: centre, direction of travel, radii along the frame's u and v.
struct Ring {
    center: P,
    tangent: V,
    radii: [f64; 2],
}

fn ring(center: [f64; 3], tangent: [f64; 3], ru: f64, rv: f64) -> Ring {
    Ring {
        center: P::from(center),
        tangent: V::from(tangent).normalize(),
        radii: [ru, rv],
    }
}

/// A 2 × 2 patch of the lattice surface where a tube starts: the fixed axis and its value, the
/// first cell along each remaining axis (in increasing axis order).
struct Patch {
    axis: usize,
    value: usize,
    first: [usize; 2],
}

/// Builds the mannequin.
pub fn build() -> Body {
    let mut body = Body {
        positions: Vec::new(),
        faces: Vec::new(),
        parts: Vec::new(),
    };
    let ids = lattice_vertices(&mut body);
    let patches = [
        (
            Part::Leg(Side::Right),
            Patch {
                axis: 1,
                value: 0,
                first: [1, 1],
            },
        ),
        (
            Part::Leg(Side::Left),
            Patch {
                axis: 1,
                value: 0,
                first: [5, 1],
            },
        ),
        (
            Part::Head,
            Patch {
                axis: 1,
                value: N[1],
                first: [3, 1],
            },
        ),
        (
            Part::Arm(Side::Right),
            Patch {
                axis: 0,
                value: 0,
                first: [4, 1],
            },
        ),
        (
            Part::Arm(Side::Left),
            Patch {
                axis: 0,
                value: N[0],
                first: [4, 1],
            },
        ),
    ];
    let patch_quads = lattice_faces(&mut body, &ids, &patches.each_ref().map(|(_, p)| p));
    for ((part, _), quads) in patches.iter().zip(&patch_quads) {
        let (t0, u0, rings, cap) = tube(*part);
        grow_tube(&mut body, *part, boundary_loop(quads), t0, u0, &rings, cap);
    }
    drop_unused(body)
}

/// Removes the vertices no face uses (the centres of the patches), keeping the order of the rest.
fn drop_unused(body: Body) -> Body {
    let mut used = vec![false; body.positions.len()];
    for &v in body.faces.as_flattened() {
        used[v as usize] = true;
    }
    let mut new_id = vec![u32::MAX; used.len()];
    let mut kept = Body {
        positions: Vec::new(),
        faces: Vec::new(),
        parts: Vec::new(),
    };
    for (v, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        new_id[v] = kept.positions.len() as u32;
        kept.positions.push(body.positions[v]);
        kept.parts.push(body.parts[v]);
    }
    kept.faces = body
        .faces
        .iter()
        .map(|f| f.map(|v| new_id[v as usize]))
        .collect();
    kept
}

/// The lattice point (i, j, k) mapped to the torso.
fn torso_point(idx: [usize; 3]) -> P {
    let [i, j, k] = idx;
    let [y, w, d, zc] = LEVELS[j];
    let t = j as f64 / N[1] as f64;
    let sx = SX_BOTTOM[i] + (SX_TOP[i] - SX_BOTTOM[i]) * t;
    let sz = SZ[k];
    let round = |s: f64| 1.0 - ROUNDING + ROUNDING * (1.0 - s * s / 2.0).sqrt();
    let slope = if j == N[1] {
        SHOULDER_SLOPE * sx * sx
    } else {
        0.0
    };
    P::new(w * sx * round(sz), y - slope, zc + d * sz * round(sx))
}

/// Adds the lattice points on the box's surface; returns their ids by (i, j, k), `u32::MAX` inside.
fn lattice_vertices(body: &mut Body) -> Vec<u32> {
    let mut ids = vec![u32::MAX; (N[0] + 1) * (N[1] + 1) * (N[2] + 1)];
    for j in 0..=N[1] {
        for k in 0..=N[2] {
            for i in 0..=N[0] {
                let idx = [i, j, k];
                if (0..3).any(|a| idx[a] == 0 || idx[a] == N[a]) {
                    ids[lattice_index(idx)] = body.positions.len() as u32;
                    body.positions.push(torso_point(idx));
                    body.parts.push(Part::Torso);
                }
            }
        }
    }
    ids
}

fn lattice_index([i, j, k]: [usize; 3]) -> usize {
    (j * (N[2] + 1) + k) * (N[0] + 1) + i
}

/// Adds the box's outward quads except those of `patches`, which are returned per patch.
fn lattice_faces(body: &mut Body, ids: &[u32], patches: &[&Patch]) -> Vec<Vec<[u32; 4]>> {
    let mut removed = vec![Vec::new(); patches.len()];
    for axis in 0..3 {
        let (b, c) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        for value in [0, N[axis]] {
            for p in 0..N[b] {
                for q in 0..N[c] {
                    let corner = |dp: usize, dq: usize| {
                        let mut idx = [0; 3];
                        idx[axis] = value;
                        idx[b] = p + dp;
                        idx[c] = q + dq;
                        idx
                    };
                    let mut quad = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                    // e_b × e_c is +e_axis for (b, c) cyclic after axis; outward is ±e_axis.
                    let cyclic = (axis + 1) % 3 == b;
                    if cyclic != (value == N[axis]) {
                        quad.reverse();
                    }
                    let face = quad.map(|idx| ids[lattice_index(idx)]);
                    let hit = patches.iter().position(|pa| {
                        pa.axis == axis
                            && pa.value == value
                            && (pa.first[0]..pa.first[0] + 2).contains(&p)
                            && (pa.first[1]..pa.first[1] + 2).contains(&q)
                    });
                    match hit {
                        Some(h) => removed[h].push(face),
                        None => body.faces.push(face),
                    }
                }
            }
        }
    }
    removed
}

/// The boundary of oriented quads as a vertex loop running the way the quads do.
fn boundary_loop(quads: &[[u32; 4]]) -> Vec<u32> {
    let edges: Vec<(u32, u32)> = quads
        .iter()
        .flat_map(|q| (0..4).map(move |i| (q[i], q[(i + 1) % 4])))
        .collect();
    let outer: Vec<(u32, u32)> = edges
        .iter()
        .copied()
        .filter(|&(a, b)| !edges.contains(&(b, a)))
        .collect();
    let mut chain = vec![outer[0].0];
    while chain.len() < outer.len() {
        let last = chain[chain.len() - 1];
        let next = outer.iter().find(|e| e.0 == last).expect("closed loop").1;
        chain.push(next);
    }
    chain
}

/// The start tangent, start u axis, rings and cap centre of the tube of `part`.
fn tube(part: Part) -> (V, V, Vec<Ring>, P) {
    match part {
        Part::Leg(side) => {
            let x = leg_x(side);
            let down = [0.0, -1.0, 0.0];
            let rings = vec![
                ring([x, 0.72, 0.0], down, 0.078, 0.082),
                ring([x, 0.60, 0.0], down, 0.066, 0.072),
                ring([x, 0.47, 0.005], down, 0.050, 0.055),
                ring([x, 0.34, -0.01], down, 0.052, 0.060),
                ring([x, 0.12, 0.0], down, 0.034, 0.040),
                ring([x, 0.05, 0.04], [0.0, -1.0, 1.0], 0.040, 0.055),
                ring([x, 0.035, 0.13], [0.0, 0.0, 1.0], 0.042, 0.030),
            ];
            (-V::y(), V::x(), rings, P::new(x, 0.03, 0.20))
        }
        Part::Head => {
            let up = [0.0, 1.0, 0.0];
            let rings = vec![
                ring([0.0, 1.51, -0.015], up, 0.050, 0.052),
                ring([0.0, 1.58, 0.0], up, 0.072, 0.085),
                ring([0.0, 1.66, 0.0], up, 0.080, 0.095),
                ring([0.0, 1.73, -0.005], up, 0.068, 0.080),
            ];
            (V::y(), V::x(), rings, P::new(0.0, 1.77, -0.005))
        }
        Part::Arm(side) => {
            let (j, d) = arm_frame(side);
            let out = V::x() * side.sign();
            let at = |s: f64| (j + d * s).coords.into();
            let along = d.into();
            let rings = vec![
                ring(at(0.07), (out + d).into(), 0.060, 0.058),
                ring(at(0.17), along, 0.048, 0.048),
                ring(at(0.29), along, 0.038, 0.040),
                ring(at(0.40), along, 0.040, 0.036),
                ring(at(0.53), along, 0.020, 0.028),
                ring(at(0.63), along, 0.016, 0.044),
            ];
            (out, V::y(), rings, j + d * 0.74)
        }
        Part::Torso => unreachable!("the torso is the lattice, not a tube"),
    }
}

/// Grows a tube from `loop0` (oriented like the removed patch) through `rings` to a cap.
fn grow_tube(body: &mut Body, part: Part, loop0: Vec<u32>, t0: V, u0: V, rings: &[Ring], cap: P) {
    let n = loop0.len();
    let centre = loop0
        .iter()
        .map(|&v| body.positions[v as usize].coords)
        .sum::<V>()
        / n as f64;
    let mut u = (u0 - t0 * u0.dot(&t0)).normalize();
    let v = t0.cross(&u);
    let angle = |p: &P| {
        let r = p.coords - centre;
        r.dot(&v).atan2(r.dot(&u))
    };
    // Start at the vertex nearest +u; turn the way the loop turns around the tube.
    let start = (0..n)
        .min_by(|&a, &b| {
            let (pa, pb) = (
                &body.positions[loop0[a] as usize],
                &body.positions[loop0[b] as usize],
            );
            angle(pa).abs().total_cmp(&angle(pb).abs())
        })
        .expect("non-empty loop");
    let mut prev: Vec<u32> = (0..n).map(|k| loop0[(start + k) % n]).collect();
    let step = angle(&body.positions[prev[1] as usize]) - angle(&body.positions[prev[0] as usize]);
    let turn = step.sin().signum();
    for r in rings {
        u = (u - r.tangent * u.dot(&r.tangent)).normalize();
        let v = r.tangent.cross(&u);
        let first = body.positions.len() as u32;
        for k in 0..n {
            let (s, c) = (turn * FRAC_PI_4 * k as f64).sin_cos();
            body.positions
                .push(r.center + u * (r.radii[0] * c) + v * (r.radii[1] * s));
            body.parts.push(part);
        }
        let next: Vec<u32> = (0..n as u32).map(|k| first + k).collect();
        for k in 0..n {
            let k1 = (k + 1) % n;
            body.faces.push([prev[k], prev[k1], next[k1], next[k]]);
        }
        prev = next;
    }
    let c = body.positions.len() as u32;
    body.positions.push(cap);
    body.parts.push(part);
    for q in 0..n / 2 {
        let [a, b, d] = [2 * q, 2 * q + 1, (2 * q + 2) % n].map(|k| prev[k]);
        body.faces.push([a, b, d, c]);
    }
}
