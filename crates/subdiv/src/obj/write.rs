//! The OBJ writer: exact `f64`s, UVs, normals, faces without holes, tags and non-default options.

use std::collections::HashSet;
use std::fmt;
use std::io::{self, BufWriter, Write};

use nalgebra::Vector3;

use super::{BOUNDARY_CODES, CREASE_METHOD_NAMES, FVAR_CODES, TRIANGLE_RULE_NAMES};
use crate::mesh::Mesh;
use crate::options::Options;

/// Writes `mesh` as OBJ with OpenSubdiv tags, with one normal per vertex if `normals` is given.
///
/// Output is buffered internally. Hole faces are left out (their vertices are written), and so
/// are tags without effect; see the [module documentation](super) for the exact format.
///
/// # Errors
/// Any error of `out`; [`io::ErrorKind::InvalidInput`] if `normals` does not have one entry per
/// vertex.
pub fn write(
    mesh: &Mesh,
    normals: Option<&[Vector3<f64>]>,
    out: &mut impl Write,
) -> io::Result<()> {
    if let Some(n) = normals
        && n.len() != mesh.vertex_count()
    {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} normals for {} vertices", n.len(), mesh.vertex_count()),
        ));
    }
    let mut w = BufWriter::new(out);
    for p in mesh.positions() {
        writeln!(w, "v {} {} {}", Num(p.x), Num(p.y), Num(p.z))?;
    }
    let uvs = mesh.uvs();
    for uv in uvs.iter().flat_map(|uvs| &uvs.values) {
        writeln!(w, "vt {} {}", Num(uv.x), Num(uv.y))?;
    }
    for n in normals.unwrap_or_default() {
        writeln!(w, "vn {} {} {}", Num(n.x), Num(n.y), Num(n.z))?;
    }

    let mut hole = vec![false; mesh.face_count()];
    for &f in mesh.holes() {
        hole[f as usize] = true;
    }
    for f in (0..mesh.face_count()).filter(|&f| !hole[f]) {
        w.write_all(b"f")?;
        for c in mesh.face_range(f) {
            let v = u64::from(mesh.face_vertices()[c]) + 1;
            write!(w, " {v}")?;
            match (uvs, normals.is_some()) {
                (Some(uvs), true) => write!(w, "/{}/{v}", u64::from(uvs.indices[c]) + 1)?,
                (Some(uvs), false) => write!(w, "/{}", u64::from(uvs.indices[c]) + 1)?,
                (None, true) => write!(w, "//{v}")?,
                (None, false) => {}
            }
        }
        w.write_all(b"\n")?;
    }

    write_tags(mesh, &hole, &mut w)?;
    w.flush()
}

/// Creases and corners as tagged, minus those without effect, then the options that differ from the default.
fn write_tags(mesh: &Mesh, hole: &[bool], w: &mut impl Write) -> io::Result<()> {
    let edge = |[a, b]: [u32; 2]| (a.min(b), a.max(b));
    // Creases on edges that only hole faces have would name no edge once the holes are gone.
    let written_edges: Option<HashSet<(u32, u32)>> = hole.contains(&true).then(|| {
        (0..mesh.face_count())
            .filter(|&f| !hole[f])
            .flat_map(|f| {
                let fv = mesh.face(f);
                (0..fv.len()).map(move |j| edge([fv[j], fv[(j + 1) % fv.len()]]))
            })
            .collect()
    });
    // A zero sharpness only matters when it resets an entry written before it.
    let mut sharp_edges = HashSet::new();
    for c in mesh.creases() {
        let key = edge(c.vertices);
        let on_written_edge = written_edges.as_ref().is_none_or(|e| e.contains(&key));
        if on_written_edge && (c.sharpness > 0.0 || sharp_edges.contains(&key)) {
            sharp_edges.insert(key);
            let [a, b] = c.vertices;
            writeln!(w, "t crease 2/1/0 {a} {b} {}", Num(c.sharpness))?;
        }
    }
    let mut sharp_vertices = HashSet::new();
    for c in mesh.corners() {
        if c.sharpness > 0.0 || sharp_vertices.contains(&c.vertex) {
            sharp_vertices.insert(c.vertex);
            writeln!(w, "t corner 1/1/0 {} {}", c.vertex, Num(c.sharpness))?;
        }
    }

    let (o, default) = (mesh.options, Options::default());
    if o.boundary != default.boundary {
        write_code(w, "interpolateboundary 1/0/0", &BOUNDARY_CODES, o.boundary)?;
    }
    if o.crease_method != default.crease_method {
        write_code(
            w,
            "creasemethod 0/0/1",
            &CREASE_METHOD_NAMES,
            o.crease_method,
        )?;
    }
    if o.triangle_rule != default.triangle_rule {
        write_code(
            w,
            "smoothtriangles 0/0/1",
            &TRIANGLE_RULE_NAMES,
            o.triangle_rule,
        )?;
    }
    if o.fvar_linear != default.fvar_linear {
        write_code(
            w,
            "facevaryinginterpolateboundary 1/0/0",
            &FVAR_CODES,
            o.fvar_linear,
        )?;
    }
    Ok(())
}

/// Writes `t {tag} CODE` with the code of `value` in `table` (every table covers its option).
fn write_code<T: PartialEq, K: fmt::Display>(
    w: &mut impl Write,
    tag: &str,
    table: &[(T, K)],
    value: T,
) -> io::Result<()> {
    match table.iter().find(|(v, _)| *v == value) {
        Some((_, code)) => writeln!(w, "t {tag} {code}"),
        None => Ok(()),
    }
}

/// An `f64` printed so that it parses back to the same value: Rust's shortest round-trip digits,
/// in exponent form outside 1e-5..1e16 where plain `{}` would print hundreds of digits.
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}
