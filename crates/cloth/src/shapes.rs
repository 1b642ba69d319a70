//! Simple garments and obstacles for tests, benchmarks and demos, and the shadow a garment casts.

use tailor_subdiv::{Mesh, Point};

use crate::energy::Vec3;

/// A flat rectangular sheet of `columns × rows` vertices (at least 2 × 2) in the plane y = 0,
/// spanning `[0, width] × [0, depth]` in x and z, made of quads facing +y. Vertex `i + columns·j`
/// sits at x = i·width/(columns − 1), z = j·depth/(rows − 1).
///
/// # Panics
/// If `columns` or `rows` is below 2.
#[must_use]
pub fn sheet(columns: u32, rows: u32, width: f64, depth: f64) -> Mesh {
    assert!(
        columns >= 2 && rows >= 2,
        "a sheet needs at least 2 × 2 vertices"
    );
    let (dx, dz) = (width / f64::from(columns - 1), depth / f64::from(rows - 1));
    let positions = (0..rows)
        .flat_map(|j| {
            (0..columns).map(move |i| Point::new(f64::from(i) * dx, 0.0, f64::from(j) * dz))
        })
        .collect();
    let mut faces = Vec::with_capacity(((columns - 1) * (rows - 1)) as usize);
    for j in 0..rows - 1 {
        for i in 0..columns - 1 {
            let a = i + columns * j;
            faces.push([a, a + columns, a + columns + 1, a + 1]);
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a sheet is a valid mesh")
}

/// A square [`sheet`] of `n × n` vertices and side `side`, flat at y = 0 and centred over the
/// origin in x and z: the garment of the sphere drape (`examples/drape.rs`).
///
/// # Panics
/// If `n` is below 2.
#[must_use]
pub fn centred_sheet(n: u32, side: f64) -> Mesh {
    let mut mesh = sheet(n, n, side, side);
    let half = Vec3::new(0.5 * side, 0.0, 0.5 * side);
    let centred: Vec<Point> = mesh.positions().iter().map(|p| p - half).collect();
    mesh.set_positions(&centred).expect("same vertex count");
    mesh
}

/// A flat disc of `radius` in the plane y = 0, centred at the origin, meshed as an O-grid of
/// quads facing +y: a core square of half-side `radius`/2 cut into `n × n` cells, then `rings`
/// rings of 4n quads each, blending the square's boundary into the circle, whose hem has 4n
/// edges of about 2π radius/(4n). The core's vertex (i, j) is `i + (n + 1)·j`; ring k's vertices
/// follow, 4n a ring. `rings` ≈ n/π makes the rings' cells about as deep as the hem's are long.
///
/// # Panics
/// If `n` or `rings` is zero.
#[must_use]
pub fn disc(radius: f64, n: u32, rings: u32) -> Mesh {
    assert!(n >= 1 && rings >= 1, "a disc needs a core and a ring");
    let half = 0.5 * radius;
    let core = |i: u32| -half + 2.0 * half * f64::from(i) / f64::from(n);
    let mut positions: Vec<Point> = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| Point::new(core(i), 0.0, core(j))))
        .collect();
    // The core's boundary, counter-clockwise from the corner (−half, −half) at −3π/4; each of
    // its points blends towards the point of the circle at the same fraction of the turn.
    let square: Vec<u32> = (0..n)
        .chain((0..n).map(|j| n + (n + 1) * j))
        .chain((0..n).map(|i| (n - i) + (n + 1) * n))
        .chain((0..n).map(|j| (n + 1) * (n - j)))
        .collect();
    let around = square.len() as u32;
    for k in 1..=rings {
        let t = f64::from(k) / f64::from(rings);
        for (p, &s) in square.iter().enumerate() {
            let angle =
                -0.75 * std::f64::consts::PI + std::f64::consts::TAU * p as f64 / f64::from(around);
            let circle = Point::new(radius * angle.cos(), 0.0, radius * angle.sin());
            positions.push(positions[s as usize] + (circle - positions[s as usize]) * t);
        }
    }
    let mut faces: Vec<Vec<u32>> = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = i + (n + 1) * j;
            faces.push(vec![a, a + n + 1, a + n + 2, a + 1]);
        }
    }
    let ring = |k: u32, p: u32| {
        if k == 0 {
            square[(p % around) as usize]
        } else {
            (n + 1) * (n + 1) + (k - 1) * around + p % around
        }
    };
    for k in 1..=rings {
        for p in 0..around {
            let mut face = vec![
                ring(k - 1, p),
                ring(k - 1, p + 1),
                ring(k, p + 1),
                ring(k, p),
            ];
            let at = |q: u32| positions[q as usize];
            let normal = (at(face[1]) - at(face[0])).cross(&(at(face[2]) - at(face[0])));
            if normal.y < 0.0 {
                face.reverse();
            }
            faces.push(face);
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a disc is a valid mesh")
}

/// A closed cylinder about the vertical axis through `base` (the centre of its bottom), of
/// `radius` and `height`, its side cut into `segments` quads and its caps into triangle fans
/// round a centre vertex; faces wind counter-clockwise seen from outside, as an obstacle needs.
///
/// # Panics
/// If `segments` is below 3.
#[must_use]
pub fn cylinder(base: Point, radius: f64, height: f64, segments: u32) -> Mesh {
    assert!(segments >= 3, "a cylinder needs 3 segments");
    let up = Vec3::y() * height;
    let mut positions = vec![base, base + up];
    for level in [0.0, 1.0] {
        for i in 0..segments {
            let angle = std::f64::consts::TAU * f64::from(i) / f64::from(segments);
            let rim = Vec3::new(radius * angle.cos(), 0.0, radius * angle.sin());
            positions.push(base + rim + up * level);
        }
    }
    let bottom = |i: u32| 2 + i % segments;
    let top = |i: u32| 2 + segments + i % segments;
    let mut faces = Vec::new();
    for i in 0..segments {
        faces.push(vec![bottom(i), bottom(i + 1), top(i + 1), top(i)]);
        faces.push(vec![0, bottom(i + 1), bottom(i)]);
        faces.push(vec![1, top(i), top(i + 1)]);
    }
    outward(positions, faces, base + 0.5 * up)
}

/// The area of the shadow `positions` of `mesh`'s faces cast on the plane y = 0 (their
/// projection along y, overlaps counted once): the faces, split into triangle fans, are
/// rasterised on a grid of square cells of side `cell`, and the cells whose centres they cover
/// are counted. The error is of the order of the outline's length times `cell`.
#[must_use]
pub fn projected_area(mesh: &Mesh, positions: &[Point], cell: f64) -> f64 {
    let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in positions {
        for (k, c) in [p.x, p.z].into_iter().enumerate() {
            low[k] = low[k].min(c);
            high[k] = high[k].max(c);
        }
    }
    let cells = |k: usize| ((high[k] - low[k]) / cell).ceil() as usize + 1;
    let (columns, rows) = (cells(0), cells(1));
    let mut covered = vec![false; columns * rows];
    let flat = |v: u32| {
        let p = positions[v as usize];
        [(p.x - low[0]) / cell - 0.5, (p.z - low[1]) / cell - 0.5]
    };
    for f in 0..mesh.face_count() {
        let face = mesh.face(f);
        for k in 1..face.len() - 1 {
            let t = [face[0], face[k], face[k + 1]].map(flat);
            let span = |axis: usize, count: usize| {
                let lo = t.iter().map(|p| p[axis]).fold(f64::INFINITY, f64::min);
                let hi = t.iter().map(|p| p[axis]).fold(f64::NEG_INFINITY, f64::max);
                (lo.ceil().max(0.0) as usize)..=(hi.floor().min(count as f64 - 1.0) as usize)
            };
            let edge = |a: [f64; 2], b: [f64; 2], q: [f64; 2]| {
                (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])
            };
            let orientation = edge(t[0], t[1], t[2]);
            if orientation == 0.0 {
                continue;
            }
            for row in span(1, rows) {
                for column in span(0, columns) {
                    let q = [column as f64, row as f64];
                    let inside =
                        (0..3).all(|e| edge(t[e], t[(e + 1) % 3], q) * orientation.signum() >= 0.0);
                    if inside {
                        covered[column + columns * row] = true;
                    }
                }
            }
        }
    }
    covered.iter().filter(|&&c| c).count() as f64 * cell * cell
}

/// The drape coefficient of a circular fabric draped over a circular pedestal of radius
/// `pedestal` (BS 5058, ISO 9073-9, after Cusick 1968): the share of the annulus of the flat
/// fabric outside the pedestal that the draped fabric's shadow still covers,
/// (A_shadow − A_pedestal)/(A_flat − A_pedestal), with the shadows of `fabric` at rest and at
/// `positions` measured by [`projected_area`] on cells of 1/400 of the pedestal
/// radius. 1 for a stiff fabric that stays flat, towards 0 for one that hangs straight down.
#[must_use]
pub fn drape_coefficient(fabric: &Mesh, positions: &[Point], pedestal: f64) -> f64 {
    let cell = pedestal / 400.0;
    let base = std::f64::consts::PI * pedestal * pedestal;
    let flat = projected_area(fabric, fabric.positions(), cell);
    (projected_area(fabric, positions, cell) - base) / (flat - base)
}

/// A closed polygon sphere of `rings` latitude bands (at least 2) and `segments` longitude
/// bands (at least 3): quads, with triangle fans at the poles (on the y axis). Faces wind
/// counter-clockwise seen from outside, as an obstacle needs.
///
/// # Panics
/// If `rings < 2` or `segments < 3`.
#[must_use]
pub fn sphere(center: Point, radius: f64, rings: u32, segments: u32) -> Mesh {
    assert!(
        rings >= 2 && segments >= 3,
        "a sphere needs 2 rings and 3 segments"
    );
    let mut positions = vec![center + Vec3::y() * radius];
    for j in 1..rings {
        let polar = std::f64::consts::PI * f64::from(j) / f64::from(rings);
        for i in 0..segments {
            let azimuth = std::f64::consts::TAU * f64::from(i) / f64::from(segments);
            let direction = Vec3::new(
                polar.sin() * azimuth.cos(),
                polar.cos(),
                polar.sin() * azimuth.sin(),
            );
            positions.push(center + direction * radius);
        }
    }
    positions.push(center - Vec3::y() * radius);
    let bottom = positions.len() as u32 - 1;
    let ring = |j: u32, i: u32| 1 + (j - 1) * segments + i % segments;
    let mut faces = Vec::new();
    for i in 0..segments {
        faces.push(vec![0, ring(1, i), ring(1, i + 1)]);
        for j in 1..rings - 1 {
            faces.push(vec![
                ring(j, i),
                ring(j + 1, i),
                ring(j + 1, i + 1),
                ring(j, i + 1),
            ]);
        }
        faces.push(vec![ring(rings - 1, i), bottom, ring(rings - 1, i + 1)]);
    }
    outward(positions, faces, center)
}

/// A closed box (six quads) between corners `low` and `high`, faces winding counter-clockwise
/// seen from outside.
#[must_use]
pub fn block(low: Point, high: Point) -> Mesh {
    let corner = |k: u32| {
        let pick = |bit: u32, lo: f64, hi: f64| if k & bit == 0 { lo } else { hi };
        Point::new(
            pick(1, low.x, high.x),
            pick(2, low.y, high.y),
            pick(4, low.z, high.z),
        )
    };
    let positions = (0..8).map(corner).collect();
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ]
    .map(Vec::from)
    .to_vec();
    outward(positions, faces, nalgebra::center(&low, &high))
}

/// The mesh of a shape star-shaped around `center`, each face turned to wind
/// counter-clockwise seen from outside.
fn outward(positions: Vec<Point>, mut faces: Vec<Vec<u32>>, center: Point) -> Mesh {
    for face in &mut faces {
        let p = |k: usize| positions[face[k] as usize];
        let normal = (p(1) - p(0)).cross(&(p(2) - p(0)));
        if normal.dot(&(p(0) - center)) < 0.0 {
            face.reverse();
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a closed shape is a valid mesh")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_faces_point_up() {
        let mesh = sheet(3, 2, 2.0, 1.0);
        assert_eq!(mesh.vertex_count(), 6);
        assert_eq!(mesh.face_count(), 2);
        let p = mesh.positions();
        let f = mesh.face(1);
        let n = (p[f[1] as usize] - p[f[0] as usize]).cross(&(p[f[2] as usize] - p[f[1] as usize]));
        assert!(n.y > 0.0);
        assert_eq!(p[5], Point::new(2.0, 0.0, 1.0));
    }

    #[test]
    fn obstacles_are_closed_and_face_outwards() {
        for mesh in [
            cylinder(Point::new(0.0, -0.5, 1.0), 0.3, 0.5, 12),
            sphere(Point::new(1.0, 2.0, 3.0), 0.5, 6, 8),
            block(Point::new(-1.0, 0.0, 0.0), Point::new(1.0, 0.5, 2.0)),
        ] {
            let h = tailor_collide::Hierarchy::build(
                mesh.positions(),
                mesh.face_offsets(),
                mesh.face_vertices(),
            )
            .unwrap();
            assert!(h.is_closed());
            let far = Point::new(10.0, 10.0, 10.0);
            let centroid = Point::from(
                mesh.positions().iter().map(|p| p.coords).sum::<Vec3>()
                    / mesh.vertex_count() as f64,
            );
            let d = h.signed_distances(&[far, centroid]).unwrap();
            assert!(d[0] > 0.0 && d[1] < 0.0, "{d:?}");
        }
    }

    #[test]
    fn a_disc_is_an_o_grid_facing_up_whose_shadow_is_its_area() {
        let (radius, n, rings) = (0.15, 8, 3);
        let mesh = disc(radius, n, rings);
        assert_eq!(
            mesh.vertex_count() as u32,
            (n + 1) * (n + 1) + rings * 4 * n
        );
        assert_eq!(mesh.face_count() as u32, n * n + rings * 4 * n);
        let p = mesh.positions();
        for f in 0..mesh.face_count() {
            let c = mesh.face(f);
            let normal =
                (p[c[1] as usize] - p[c[0] as usize]).cross(&(p[c[2] as usize] - p[c[1] as usize]));
            assert!(normal.y > 0.0, "face {f} faces down");
        }
        // The hem lies on the circle.
        let hem = &p[p.len() - 4 * n as usize..];
        assert!(hem.iter().all(|q| (q.coords.norm() - radius).abs() < 1e-12));
        // The shadow of the flat disc is the area of its 32-gon, to a cell's width of outline.
        let polygon = 0.5
            * f64::from(4 * n)
            * radius
            * radius
            * (std::f64::consts::TAU / f64::from(4 * n)).sin();
        let cell = 1e-3;
        let shadow = projected_area(&mesh, p, cell);
        let outline = std::f64::consts::TAU * radius * cell;
        assert!((shadow - polygon).abs() < outline, "{shadow} vs {polygon}");
        // Folded in half over the x axis, it casts half the shadow.
        let folded: Vec<Point> = p
            .iter()
            .map(|q| {
                if q.z < 0.0 {
                    Point::new(q.x, 0.01, -q.z)
                } else {
                    *q
                }
            })
            .collect();
        let half = projected_area(&mesh, &folded, cell);
        assert!(
            (half - 0.5 * polygon).abs() < outline,
            "{half} vs {}",
            0.5 * polygon
        );
    }
}
