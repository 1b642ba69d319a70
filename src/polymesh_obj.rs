//! Plain polygon OBJ files (simulation results, body frames) as flat position and CSR face
//! tables, read with `tobj`.
//!
//! Only what collision and the pipeline need is kept: `v` positions and `f` polygons of any
//! size. Texture coordinates and normals are ignored; `o`, `g`, `usemtl` and `mtllib` lines are
//! skipped so the whole file is one mesh whose faces share vertices across groups. tobj is asked
//! for separate indices (`single_index: false`) so positions are not split per corner; it numbers
//! them in order of first use by a face, which is the file's order for files whose faces visit
//! vertices in order (as tailor writes them), and the same for every frame of a sequence either
//! way. Vertex lines are checked here, so errors can name the file and line.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};
use nalgebra::Point3;

/// A polygon mesh: positions and CSR faces (`face_offsets`, `face_vertices`), the layout
/// `tailor_subdiv::Mesh` and `tailor_collide::Hierarchy` take.
#[derive(Clone, Debug, PartialEq)]
pub struct PolyMesh {
    /// Vertex positions.
    pub positions: Vec<Point3<f64>>,
    /// Face `f` uses `face_vertices[face_offsets[f]..face_offsets[f + 1]]`.
    pub face_offsets: Vec<u32>,
    /// Vertex indices of all faces, one after another.
    pub face_vertices: Vec<u32>,
}

/// Reads a polygon OBJ file.
///
/// # Errors
/// When the file cannot be read or parsed, has a vertex with a missing, unparsable or
/// non-finite coordinate, or has no faces; the message names the file, and the line when the
/// problem is on one.
pub fn read(path: &Path) -> Result<PolyMesh> {
    let text = fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    parse(&text).with_context(|| format!("reading {}", path.display()))
}

/// Parses the text of a polygon OBJ file (see [`read`]).
pub fn parse(text: &str) -> Result<PolyMesh> {
    let mut kept = String::with_capacity(text.len());
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("o" | "g" | "usemtl" | "mtllib") => continue,
            Some("v") => check_vertex(words).with_context(|| format!("line {}", number + 1))?,
            _ => {}
        }
        kept.push_str(line);
        kept.push('\n');
    }
    let options = tobj::LoadOptions {
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut kept.as_bytes(), &options, |_| {
        Err(tobj::LoadError::MaterialParseError)
    })
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut mesh = PolyMesh {
        positions: Vec::new(),
        face_offsets: vec![0],
        face_vertices: Vec::new(),
    };
    for model in models {
        let m = model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Point3::new(p[0], p[1], p[2])),
        );
        let arities = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities
        };
        let mut corners = m.indices.iter();
        for arity in arities {
            mesh.face_vertices
                .extend(corners.by_ref().take(arity as usize).map(|&i| base + i));
            mesh.face_offsets.push(mesh.face_vertices.len() as u32);
        }
    }
    if mesh.face_offsets.len() < 2 {
        bail!("no faces");
    }
    Ok(mesh)
}

/// Checks the coordinates of a `v` line: three (or four, with a weight) finite numbers.
fn check_vertex<'a>(words: impl Iterator<Item = &'a str>) -> Result<()> {
    let mut count = 0;
    for word in words {
        let value: f64 = word
            .parse()
            .with_context(|| format!("vertex coordinate {word:?} is not a number"))?;
        if !value.is_finite() {
            bail!("vertex coordinate {word} is not finite");
        }
        count += 1;
    }
    if count < 3 {
        bail!("a vertex needs three coordinates, found {count}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_polygons_across_groups() {
        let mesh = parse(
            "# two faces in two groups\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n\
             o a\nf 1/1 2/2 3/3 4/4\ng b\nf 2 5 3\n",
        )
        .unwrap();
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(mesh.positions[4], Point3::new(2.0, 0.0, 0.0));
        assert_eq!(mesh.face_offsets, vec![0, 4, 7]);
        assert_eq!(mesh.face_vertices, vec![0, 1, 2, 3, 1, 4, 2]);
    }

    #[test]
    fn errors_name_the_line() {
        let err = parse("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(
            format!("{err:#}"),
            "line 2: vertex coordinate nan is not finite"
        );
        let err = parse("v 0 0 0\nv 1 zero 0\n").unwrap_err();
        assert!(format!("{err:#}").starts_with("line 2: vertex coordinate \"zero\""));
        assert_eq!(format!("{:#}", parse("v 0 0 0\n").unwrap_err()), "no faces");
        assert!(parse("v 0 0 0\nf 1 2 3\n").is_err());
    }
}
