//! Plain polygon OBJ files (simulation results, body frames) as flat position and CSR face
//! tables, read by the same strict reader as every other command (`tailor_subdiv::obj`): an
//! error names the file and the line (a UTF-8 byte-order mark is read past, a face of one or
//! two corners or an index to a vertex not yet defined is an error, as for `subdivide` and
//! `info`). Vertices keep the file's order. Texture coordinates, normals and groups are read
//! and dropped: collision and pictures need positions and faces only.
//!
//! `tobj` read these files before, renumbering vertices in order of first use and reporting
//! most problems without a line; it stays as the oracle of this module's test, which reads
//! what tailor writes with both and compares.

use std::path::Path;

use anyhow::Result;
use nalgebra::Point3;
use tailor_subdiv::obj;

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

impl From<obj::ObjDocument> for PolyMesh {
    fn from(doc: obj::ObjDocument) -> Self {
        let mesh = doc.mesh;
        Self {
            positions: mesh.positions().to_vec(),
            face_offsets: mesh.face_offsets().to_vec(),
            face_vertices: mesh.face_vertices().to_vec(),
        }
    }
}

/// Reads a polygon OBJ file.
///
/// # Errors
/// As `tailor_subdiv::obj::read`: the message names the file, and the line when the problem is
/// on one.
pub fn read(path: &Path) -> Result<PolyMesh> {
    Ok(obj::read(path)?.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses OBJ text as [`read`] reads a file; `source` names it in errors.
    fn parse(text: &str, source: &str) -> Result<PolyMesh> {
        Ok(obj::parse(text, source)?.into())
    }

    #[test]
    fn reads_polygons_across_groups() {
        let mesh = parse(
            "# two faces in two groups\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n\
             o a\nf 1 2 3 4\ng b\nf 2 5 3\n",
            "t.obj",
        )
        .unwrap();
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(mesh.positions[4], Point3::new(2.0, 0.0, 0.0));
        assert_eq!(mesh.face_offsets, vec![0, 4, 7]);
        assert_eq!(mesh.face_vertices, vec![0, 1, 2, 3, 1, 4, 2]);
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let message = |text: &str| format!("{:#}", parse(text, "t.obj").unwrap_err());
        assert!(message("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").starts_with("t.obj:2: "));
        assert!(message("v 0 0 0\nv 1 zero 0\n").starts_with("t.obj:2: "));
        // What tobj let through: faces of one or two corners, forward references.
        assert!(message("v 0 0 0\nv 1 0 0\nf 1 2\n").starts_with("t.obj:3: "));
        assert!(message("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n").starts_with("t.obj:3: "));
        assert!(message("v 0 0 0\n").starts_with("t.obj: "));
        // A byte-order mark is not an error.
        assert!(parse("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj").is_ok());
    }

    #[test]
    fn reads_what_tailor_writes_as_tobj_does() {
        // A refined cube with UVs written by the OBJ writer: tobj (positions as f64, one index
        // stream per attribute) and this reader agree on every position and face.
        let cube = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/crates/subdiv/tests/data/opensubdiv/shapes/catmark_cube.obj"
        ))
        .unwrap();
        let control = obj::parse(&cube, "cube").unwrap().mesh;
        let refiner = tailor_subdiv::Refiner::new(&control, 2);
        let refined = refiner.refined_mesh(refiner.refine(control.positions()), None);
        let mut text = Vec::new();
        obj::write(&refined, None, obj::Precision::Full, &mut text).unwrap();
        let ours = parse(std::str::from_utf8(&text).unwrap(), "refined").unwrap();
        let options = tobj::LoadOptions {
            single_index: false,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj_buf(&mut text.as_slice(), &options, |_| {
            Err(tobj::LoadError::MaterialParseError)
        })
        .unwrap();
        let theirs = &models[0].mesh;
        let position = |i: u32| {
            let p = &theirs.positions[3 * i as usize..3 * i as usize + 3];
            Point3::new(p[0], p[1], p[2])
        };
        // tobj numbers vertices in order of first use; the corners must be the same points.
        assert_eq!(ours.face_vertices.len(), theirs.indices.len());
        for (&a, &b) in ours.face_vertices.iter().zip(&theirs.indices) {
            assert_eq!(ours.positions[a as usize], position(b));
        }
        let offsets: Vec<u32> = std::iter::once(0)
            .chain(theirs.face_arities.iter().scan(0, |end, &n| {
                *end += n;
                Some(*end)
            }))
            .collect();
        assert_eq!(ours.face_offsets, offsets);
    }
}
