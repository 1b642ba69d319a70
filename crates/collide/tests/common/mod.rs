//! Meshes for the tests and benchmarks: structured (sheets, a sphere with n-gon caps, a torus,
//! a sheet of n-gons with boundaries) and random (a triangle soup), plus motions.

#![allow(dead_code)]

use std::f64::consts::TAU;

use tailor_collide::Point;

/// A polygon mesh as CSR faces.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub positions: Vec<Point>,
    pub offsets: Vec<u32>,
    pub corners: Vec<u32>,
}

impl Mesh {
    fn new() -> Self {
        Self {
            positions: Vec::new(),
            offsets: vec![0],
            corners: Vec::new(),
        }
    }

    fn face(&mut self, corners: impl IntoIterator<Item = u32>) {
        self.corners.extend(corners);
        self.offsets.push(self.corners.len() as u32);
    }

    /// The same faces with positions mapped by `f`.
    pub fn mapped(&self, f: impl Fn(&Point) -> Point) -> Vec<Point> {
        self.positions.iter().map(f).collect()
    }

    pub fn face_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The corners of face `f`.
    pub fn face_corners(&self, f: u32) -> &[u32] {
        &self.corners[self.offsets[f as usize] as usize..self.offsets[f as usize + 1] as usize]
    }

    /// The same surface with every polygon split into its fan triangles, one face each.
    pub fn triangulated(&self) -> Mesh {
        let mut m = Mesh::new();
        m.positions.clone_from(&self.positions);
        for (t, _) in self.triangles() {
            m.face(t);
        }
        m
    }

    /// The fan triangles (as the hierarchy splits faces) with their face.
    pub fn triangles(&self) -> Vec<([u32; 3], u32)> {
        let mut out = Vec::new();
        for f in 0..self.face_count() as u32 {
            let c = self.face_corners(f);
            for w in c[1..].windows(2) {
                out.push(([c[0], w[0], w[1]], f));
            }
        }
        out
    }
}

/// An `n × n` grid of quads over `[0, 1]²`, lifted by `z(x, y)`.
pub fn sheet(n: u32, z: impl Fn(f64, f64) -> f64) -> Mesh {
    let mut m = Mesh::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            m.positions.push(Point::new(x, y, z(x, y)));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            m.face([v, v + 1, v + n + 2, v + n + 1]);
        }
    }
    m
}

/// A sheet folded back over itself round a hinge at x = 0.4..0.6 (a taco), whose upper half
/// sags through the lower one in the middle when `sag > 0.2`.
pub fn folded_sheet(n: u32, sag: f64) -> Mesh {
    let mut m = sheet(n, |_, _| 0.0);
    m.positions = m.mapped(|p| {
        let (x, y) = (p.x, p.y);
        let bump = sag
            * (std::f64::consts::PI * y).sin()
            * (std::f64::consts::PI * (1.0 - x) / 0.4).sin().max(0.0);
        if x <= 0.4 {
            Point::new(x, y, 0.0)
        } else if x <= 0.6 {
            let (s, c) = ((x - 0.4) / 0.2 * std::f64::consts::PI).sin_cos();
            Point::new(0.4 + 0.1 * s, y, 0.1 - 0.1 * c)
        } else {
            Point::new(1.0 - x, y, 0.2 - bump)
        }
    });
    m
}

/// A UV sphere of radius `r`: quads between `rings` latitude rings of `segments` vertices, and
/// one `segments`-gon cap at each pole. Outward-facing.
pub fn sphere(rings: u32, segments: u32, r: f64) -> Mesh {
    let mut m = Mesh::new();
    for j in 0..rings {
        let phi = std::f64::consts::PI * (j as f64 + 1.0) / (rings as f64 + 1.0);
        for i in 0..segments {
            let theta = TAU * i as f64 / segments as f64;
            m.positions.push(Point::new(
                r * phi.sin() * theta.cos(),
                r * phi.sin() * theta.sin(),
                r * phi.cos(),
            ));
        }
    }
    let at = |j: u32, i: u32| j * segments + i % segments;
    m.face((0..segments).map(|i| at(0, i)));
    for j in 0..rings - 1 {
        for i in 0..segments {
            m.face([at(j, i), at(j + 1, i), at(j + 1, i + 1), at(j, i + 1)]);
        }
    }
    m.face((0..segments).rev().map(|i| at(rings - 1, i)));
    m
}

/// A torus of quads, `n` around the tube's centre line and `k` around the tube.
pub fn torus(n: u32, k: u32, big: f64, small: f64) -> Mesh {
    let mut m = Mesh::new();
    for i in 0..n {
        let u = TAU * i as f64 / n as f64;
        for j in 0..k {
            let v = TAU * j as f64 / k as f64;
            let rho = big + small * v.cos();
            m.positions
                .push(Point::new(rho * u.cos(), rho * u.sin(), small * v.sin()));
        }
    }
    let at = |i: u32, j: u32| (i % n) * k + j % k;
    for i in 0..n {
        for j in 0..k {
            m.face([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    m
}

/// A `cols × rows` sheet of `(2k + 2)`-gons: each cell's bottom and top edges are split into
/// `k` segments, shared with the cells below and above; its sides are single edges.
pub fn ngon_sheet(cols: u32, rows: u32, k: u32, z: impl Fn(f64, f64) -> f64) -> Mesh {
    let mut m = Mesh::new();
    let width = cols * k + 1;
    for j in 0..=rows {
        for i in 0..width {
            let (x, y) = (i as f64 / (width - 1) as f64, j as f64 / rows as f64);
            m.positions.push(Point::new(x, y, z(x, y)));
        }
    }
    for j in 0..rows {
        for c in 0..cols {
            let bottom = (0..=k).map(|s| j * width + c * k + s);
            let top = (0..=k).rev().map(|s| (j + 1) * width + c * k + s);
            m.face(bottom.chain(top));
        }
    }
    m
}

/// A tube of quads along x, `n` rings of `k` vertices, radius `r`, length 1, bent by `bend`
/// (0 straight, 1 a half circle), as an arm or a sleeve bends.
pub fn bent_tube(n: u32, k: u32, r: f64, bend: f64) -> Mesh {
    let mut m = Mesh::new();
    for i in 0..n {
        let s = i as f64 / (n - 1) as f64;
        let angle = bend * std::f64::consts::PI * s;
        let (centre, along) = if bend == 0.0 {
            (Point::new(s, 0.0, 0.0), [1.0, 0.0])
        } else {
            let radius = 1.0 / (bend * std::f64::consts::PI);
            (
                Point::new(radius * angle.sin(), radius * (1.0 - angle.cos()), 0.0),
                [angle.cos(), angle.sin()],
            )
        };
        for j in 0..k {
            let (sv, cv) = (TAU * j as f64 / k as f64).sin_cos();
            // Ring in the plane spanned by the bend normal and z.
            let normal = [-along[1], along[0]];
            m.positions.push(Point::new(
                centre.x + r * cv * normal[0],
                centre.y + r * cv * normal[1],
                r * sv,
            ));
        }
    }
    for i in 0..n - 1 {
        for j in 0..k {
            let at = |i: u32, j: u32| i * k + j % k;
            m.face([at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    m
}

/// A small deterministic generator (xorshift) so tests need no dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point uniform in the cube `[-s, s]³`.
    pub fn point(&mut self, s: f64) -> Point {
        Point::new(
            s * (2.0 * self.unit() - 1.0),
            s * (2.0 * self.unit() - 1.0),
            s * (2.0 * self.unit() - 1.0),
        )
    }
}

/// `count` random triangles of size about `size` in the cube `[-1, 1]³`, none sharing vertices.
pub fn soup(count: u32, size: f64, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed);
    let mut m = Mesh::new();
    for t in 0..count {
        let centre = rng.point(1.0);
        for _ in 0..3 {
            m.positions.push(centre + rng.point(size).coords);
        }
        m.face([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    m
}

/// The positions of a `soup` of at least 8 triangles with triangle 4 collapsed onto a
/// segment (its second vertex at the midpoint of the other two) and triangle 7 onto a point.
pub fn collapsed(soup: &Mesh) -> Vec<Point> {
    let mut p = soup.positions.clone();
    p[13] = p[12] + (p[14] - p[12]) * 0.5;
    p[22] = p[21];
    p[23] = p[21];
    p
}

/// A travelling wave over a sheet in the plane z = 0, at time `t`.
pub fn wave(p: &Point, t: f64) -> Point {
    Point::new(
        p.x,
        p.y,
        0.1 * (6.0 * p.x + 3.0 * t).sin() * (4.0 * p.y + t).cos(),
    )
}

/// A random fold of a sheet lying in the plane z = 0: the part beyond a line through `origin`
/// along `along` (a unit vector of the plane) wraps round a cylinder of radius `radius` by the
/// angle `angle` (π lays it back over the rest, 2·`radius` above), and every point is then
/// pushed along the folded surface's normal by `ripple` sine waves `(amplitude, wave vector,
/// phase)`, wrinkling both layers.
#[derive(Clone, Debug)]
pub struct Fold {
    pub origin: Point,
    pub along: [f64; 2],
    pub radius: f64,
    pub angle: f64,
    pub ripples: Vec<(f64, [f64; 2], f64)>,
}

impl Fold {
    /// A fold of the unit square nearly closed (2.6–3.1 rad) round a line through its middle
    /// part, with ripples about as high as the gap between the layers.
    pub fn random(rng: &mut Rng) -> Self {
        let turn = std::f64::consts::TAU * rng.unit();
        let radius = 0.03 + 0.07 * rng.unit();
        let ripples = random_ripples(rng, radius);
        Self {
            origin: Point::new(0.3 + 0.4 * rng.unit(), 0.3 + 0.4 * rng.unit(), 0.0),
            along: [turn.cos(), turn.sin()],
            radius,
            angle: 2.6 + 0.5 * rng.unit(),
            ripples,
        }
    }

    /// The same fold a step later: closed further by `close` radians, the ripples drifted by
    /// `drift` radians of phase.
    pub fn later(&self, close: f64, drift: f64) -> Self {
        let mut next = self.clone();
        next.angle += close;
        for r in &mut next.ripples {
            r.2 += drift;
        }
        next
    }

    /// Where the point `p` of the flat sheet goes.
    pub fn apply(&self, p: &Point) -> Point {
        let [dx, dy] = self.along;
        let (rx, ry) = (p.x - self.origin.x, p.y - self.origin.y);
        // Across the fold line and along it.
        let (s, t) = (rx * -dy + ry * dx, rx * dx + ry * dy);
        let r = self.radius;
        let (mut u, mut z, a) = if s <= 0.0 {
            (s, 0.0, 0.0)
        } else if s <= r * self.angle {
            let a = s / r;
            (r * a.sin(), r - r * a.cos(), a)
        } else {
            let a = self.angle;
            let rest = s - r * a;
            (
                r * a.sin() + rest * a.cos(),
                r - r * a.cos() + rest * a.sin(),
                a,
            )
        };
        let lift = ripple(&self.ripples, p);
        u -= lift * a.sin();
        z += lift * a.cos();
        Point::new(
            self.origin.x + u * -dy + t * dx,
            self.origin.y + u * dx + t * dy,
            z,
        )
    }
}

/// A ripple `(amplitude, wave vector, phase)`.
pub type Ripple = (f64, [f64; 2], f64);

/// Two ripples of wave numbers 4–14 in random directions, `0.3..1.5 × height` high.
fn random_ripples(rng: &mut Rng, height: f64) -> Vec<Ripple> {
    (0..2)
        .map(|_| {
            let k = 4.0 + 10.0 * rng.unit();
            let dir = std::f64::consts::TAU * rng.unit();
            let amplitude = height * (0.3 + 1.2 * rng.unit());
            (amplitude, [k * dir.cos(), k * dir.sin()], 6.0 * rng.unit())
        })
        .collect()
}

/// The sum of `ripples` at the point `p` of the flat sheet.
fn ripple(ripples: &[Ripple], p: &Point) -> f64 {
    ripples
        .iter()
        .map(|&(h, [kx, ky], phase)| h * (kx * p.x + ky * p.y + phase).sin())
        .sum()
}

/// A random coil of the unit square: a ramp winding `turns` times round the z axis between
/// radii 0.5 and 1, rising `pitch` a radian, rippled as high as half the gap between its
/// turns. Its normals all lean less than 90° from the z axis, so only its contour shows that
/// it passes over itself.
#[derive(Clone, Debug)]
pub struct Coil {
    pub turns: f64,
    pub pitch: f64,
    pub ripples: Vec<Ripple>,
}

impl Coil {
    /// 1.1–1.6 turns, 1–3 cm a radian.
    pub fn random(rng: &mut Rng) -> Self {
        let pitch = 0.01 + 0.02 * rng.unit();
        let mut ripples = random_ripples(rng, pitch * std::f64::consts::PI);
        // Gentle enough for the normals to stay in a cone round the z axis.
        for r in &mut ripples {
            r.1 = r.1.map(|k| k / 3.0);
        }
        Self {
            turns: 1.1 + 0.5 * rng.unit(),
            pitch,
            ripples,
        }
    }

    /// The same coil a step later, pressed flatter by the factor `squash`, the ripples
    /// drifted by `drift` radians of phase.
    pub fn later(&self, squash: f64, drift: f64) -> Self {
        let mut next = self.clone();
        next.pitch *= squash;
        for r in &mut next.ripples {
            r.2 += drift;
        }
        next
    }

    /// Where the point `p` of the flat sheet goes.
    pub fn apply(&self, p: &Point) -> Point {
        let a = std::f64::consts::TAU * self.turns * p.x;
        let rho = 0.5 + 0.5 * p.y;
        Point::new(
            rho * a.cos(),
            rho * a.sin(),
            self.pitch * a + ripple(&self.ripples, p),
        )
    }
}
