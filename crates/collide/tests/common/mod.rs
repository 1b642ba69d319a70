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
