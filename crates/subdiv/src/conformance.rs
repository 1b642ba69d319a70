//! Conformance against OpenSubdiv's own output (`../shared/reference/opensubdiv`).
//!
//! The reference folder holds OpenSubdiv 3.6.0's Catmark regression shapes (`shapes/`) and what
//! OpenSubdiv made of them: uniformly refined control points (`refined/NAME_L{1,2,3}.obj`), limit
//! positions and normals at level 1 (`limit/NAME_L1.obj`) and face-varying UVs under each
//! interpolation mode (`facevarying/NAME_MODE_L{1,2,3}.obj`). Every comparison here is in
//! OpenSubdiv's vertex and face order, coordinate by coordinate, within [`TOLERANCE`].
//!
//! `catmark_lefthanded` is read with clockwise faces, as OpenSubdiv's regression harness does,
//! and shapes are read accepting degenerate faces (a repeated vertex), as OpenSubdiv does.

use std::fmt;
use std::fs;
use std::path::{Path, PathBuf};

use crate::evaluator::Evaluator;
use crate::mesh::{Mesh, Validation};
use crate::obj;
use crate::options::FVarLinear;
use crate::refiner::Refiner;

/// Largest accepted difference per coordinate, relative to the coordinate's magnitude when it
/// exceeds one.
pub const TOLERANCE: f64 = 1e-9;

/// An OpenSubdiv output file: vertices, optional UVs and normals, faces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reference {
    /// `v` lines.
    pub positions: Vec<[f64; 3]>,
    /// `vt` lines.
    pub uvs: Vec<[f64; 2]>,
    /// `vn` lines.
    pub normals: Vec<[f64; 3]>,
    /// `f` lines, 0-based vertex indices.
    pub faces: Vec<Vec<u32>>,
    /// `f` lines, 0-based UV indices (empty when the faces carry none).
    pub face_uvs: Vec<Vec<u32>>,
}

/// Reads an OpenSubdiv reference OBJ.
///
/// # Errors
/// I/O errors and malformed lines, as text.
pub fn read_reference(path: &Path) -> Result<Reference, String> {
    let text = fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut r = Reference::default();
    for (n, line) in text.lines().enumerate() {
        let bad = || format!("{}:{}: cannot read '{line}'", path.display(), n + 1);
        let mut it = line.split_whitespace();
        let nums = |it: std::str::SplitWhitespace<'_>| -> Result<Vec<f64>, String> {
            it.map(|t| t.parse::<f64>().map_err(|_| bad())).collect()
        };
        match it.next() {
            Some("v") => {
                let c = nums(it)?;
                r.positions.push([c[0], c[1], c[2]]);
            }
            Some("vt") => {
                let c = nums(it)?;
                r.uvs.push([c[0], c[1]]);
            }
            Some("vn") => {
                let c = nums(it)?;
                r.normals.push([c[0], c[1], c[2]]);
            }
            Some("f") => {
                let (mut fv, mut ft) = (Vec::new(), Vec::new());
                for corner in it {
                    let mut parts = corner.split('/');
                    let index = |p: Option<&str>| -> Result<Option<u32>, String> {
                        match p {
                            Some(s) if !s.is_empty() => {
                                s.parse::<u32>().map(|i| Some(i - 1)).map_err(|_| bad())
                            }
                            _ => Ok(None),
                        }
                    };
                    fv.push(index(parts.next())?.ok_or_else(bad)?);
                    if let Some(t) = index(parts.next())? {
                        ft.push(t);
                    }
                }
                r.faces.push(fv);
                if !ft.is_empty() {
                    r.face_uvs.push(ft);
                }
            }
            _ => {}
        }
    }
    Ok(r)
}

/// What one comparison found.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Reference file name.
    pub name: String,
    /// `None` when everything matched, else what did not.
    pub failure: Option<String>,
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.failure {
            None => write!(f, "pass  {}", self.name),
            Some(why) => write!(f, "FAIL  {}: {why}", self.name),
        }
    }
}

/// Largest accepted difference for limit UVs, which the reference computed in single
/// precision.
pub const SINGLE_TOLERANCE: f64 = 1e-6;

/// Compares vectors coordinate by coordinate within [`TOLERANCE`]; returns the first mismatch.
fn compare<const N: usize>(
    what: &str,
    ours: &[[f64; N]],
    theirs: &[[f64; N]],
) -> Result<(), String> {
    compare_within(what, ours, theirs, TOLERANCE)
}

/// Compares vectors coordinate by coordinate within `tolerance` (relative above magnitude 1).
fn compare_within<const N: usize>(
    what: &str,
    ours: &[[f64; N]],
    theirs: &[[f64; N]],
    tolerance: f64,
) -> Result<(), String> {
    if ours.len() != theirs.len() {
        return Err(format!(
            "{} {what} (reference {})",
            ours.len(),
            theirs.len()
        ));
    }
    for (i, (a, b)) in ours.iter().zip(theirs).enumerate() {
        for k in 0..N {
            let scale = a[k].abs().max(b[k].abs()).max(1.0);
            if (a[k] - b[k]).abs() > tolerance * scale || a[k].is_nan() != b[k].is_nan() {
                return Err(format!("{what} {i}: {a:?} vs reference {b:?}"));
            }
        }
    }
    Ok(())
}

/// Reads a shape as OpenSubdiv's regression harness does.
///
/// # Errors
/// The shape cannot be read.
pub fn read_shape(path: &Path) -> Result<Mesh, String> {
    let validation = Validation {
        allow_degenerate_faces: true,
    };
    let doc = obj::read_with(path, validation).map_err(|e| e.to_string())?;
    let left_handed = path.file_stem().is_some_and(|s| s == "catmark_lefthanded");
    Ok(if left_handed {
        doc.mesh.with_reversed_faces()
    } else {
        doc.mesh
    })
}

/// Per-corner items (vertex or UV indices, parallel to the mesh's face vertices) of every face
/// that is not a hole, face by face.
fn faces_without_holes(mesh: &Mesh, corners: &[u32]) -> Vec<Vec<u32>> {
    let holes: std::collections::HashSet<u32> = mesh.holes().iter().copied().collect();
    (0..mesh.face_count())
        .filter(|&f| !holes.contains(&crate::mesh::to_u32(f)))
        .map(|f| corners[mesh.face_range(f)].to_vec())
        .collect()
}

/// Compares refined UVs, value by value and face corner by face corner (`f v/vt`).
fn check_uvs(mesh: &Mesh, reference: &Reference) -> Result<(), String> {
    let uvs = mesh
        .uvs()
        .ok_or("the reference has UVs, the shape has none")?;
    let ours: Vec<[f64; 2]> = uvs.values.iter().map(|t| [t.x, t.y]).collect();
    compare("uvs", &ours, &reference.uvs)?;
    if faces_without_holes(mesh, &uvs.indices) != reference.face_uvs {
        return Err("face UV indices differ".into());
    }
    Ok(())
}

/// Checks the refined control points and faces of `shape` at `level` against `reference`.
/// # Errors
/// The first mismatch, described.
pub fn check_refined(shape: &Mesh, level: usize, reference: &Reference) -> Result<(), String> {
    // The evaluation refiner, whose last level is completed only for `refined_mesh`, so both
    // ways of building the last level are checked (limits use `Refiner::new`).
    let refiner = Refiner::for_evaluation(shape, level);
    let points = refiner.refine(shape.positions());
    let ours: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    compare("vertices", &ours, &reference.positions)?;
    let uvs = match shape.uvs() {
        Some(uvs) if !reference.uvs.is_empty() => refiner.refine_uvs(&uvs.values),
        _ => None,
    };
    let mesh = refiner.refined_mesh(points, uvs);
    if faces_without_holes(&mesh, mesh.face_vertices()) != reference.faces {
        return Err("faces differ".into());
    }
    if !reference.uvs.is_empty() {
        check_uvs(&mesh, reference)?;
    }
    // The stencil table, then the evaluator built on it (regular faces as B-spline patches).
    let evaluator = Evaluator::new(&refiner);
    let mut out = vec![crate::mesh::Point::origin(); evaluator.len()];
    evaluator.stencils().apply(shape.positions(), &mut out);
    let ours: Vec<[f64; 3]> = out.iter().map(|p| [p.x, p.y, p.z]).collect();
    compare("stencil vertices", &ours, &reference.positions)?;
    evaluator.apply(shape.positions(), &mut out);
    let ours: Vec<[f64; 3]> = out.iter().map(|p| [p.x, p.y, p.z]).collect();
    compare("evaluator vertices", &ours, &reference.positions)
}

/// Checks limit positions and (where the reference has them) normals at level 1.
/// # Errors
/// The first mismatch, described.
pub fn check_limit(shape: &Mesh, reference: &Reference) -> Result<(), String> {
    let refiner = Refiner::new(shape, 1);
    let points: Vec<_> = refiner
        .refine(shape.positions())
        .iter()
        .map(|p| p.coords)
        .collect();
    let (pos, normals) = refiner.limit_masks().evaluate(&points);
    let ours: Vec<[f64; 3]> = pos.iter().map(|p| [p.x, p.y, p.z]).collect();
    compare("limit positions", &ours, &reference.positions)?;
    if !reference.normals.is_empty() {
        let ours: Vec<[f64; 3]> = normals.iter().map(|n| [n.x, n.y, n.z]).collect();
        compare("limit normals", &ours, &reference.normals)?;
    }
    if let (Some(uvs), false) = (shape.uvs(), reference.uvs.is_empty()) {
        let limit = refiner
            .refine_uvs(&uvs.values)
            .and_then(|refined| refiner.limit_uvs(&refined))
            .ok_or("no UVs refined")?;
        let ours: Vec<[f64; 2]> = limit.values.iter().map(|t| [t.x, t.y]).collect();
        compare_within("limit uvs", &ours, &reference.uvs, SINGLE_TOLERANCE)?;
    }
    Ok(())
}

/// The reference files of `dir` (`refined/`, `limit/` and `facevarying/`), sorted.
#[must_use]
pub fn reference_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["refined", "limit", "facevarying"]
        .iter()
        .filter_map(|sub| fs::read_dir(dir.join(sub)).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    files.sort();
    files
}

/// Runs every comparison the reference folder supports and returns one outcome per file.
#[must_use]
pub fn run(dir: &Path) -> Vec<Outcome> {
    reference_files(dir)
        .into_iter()
        .map(|file| {
            let name = file
                .strip_prefix(dir)
                .unwrap_or(&file)
                .display()
                .to_string();
            let failure = check_file(dir, &file).err();
            Outcome { name, failure }
        })
        .collect()
}

/// What a reference file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Uniformly refined control points and faces (`refined/`).
    Refined,
    /// Limit positions and normals of the level-1 points (`limit/`).
    Limit,
    /// Refined points with UVs under one face-varying mode (`facevarying/`).
    FaceVarying,
}

/// How OpenSubdiv made a reference file: from which shape, at which level, with which options.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The control mesh, in `shapes/`.
    pub shape: PathBuf,
    /// What the file holds.
    pub kind: Kind,
    /// The refinement level.
    pub level: usize,
    /// The face-varying mode, for [`Kind::FaceVarying`].
    pub fvar_linear: Option<FVarLinear>,
    /// The shape's faces are clockwise (`catmark_lefthanded`).
    pub left_handed: bool,
}

/// The case of reference file `file` in folder `dir`, from its folder and name.
///
/// # Errors
/// A file name that names no level, or a face-varying file that names no mode.
pub fn case(dir: &Path, file: &Path) -> Result<Case, String> {
    let kind = match file
        .parent()
        .and_then(Path::file_name)
        .and_then(|k| k.to_str())
    {
        Some("refined") => Kind::Refined,
        Some("limit") => Kind::Limit,
        _ => Kind::FaceVarying,
    };
    let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let (shape_name, mode, level) = split_name(stem).ok_or("unrecognised file name")?;
    let (shape_name, fvar_linear) = if kind == Kind::FaceVarying {
        let mode = mode.ok_or("no face-varying mode in the file name")?;
        (shape_name, Some(mode))
    } else {
        (stem.rsplit_once("_L").map_or(stem, |s| s.0), None)
    };
    Ok(Case {
        shape: dir.join("shapes").join(format!("{shape_name}.obj")),
        kind,
        level,
        fvar_linear,
        left_handed: shape_name == "catmark_lefthanded",
    })
}

/// Compares an OBJ another program wrote for `case` (read with [`read_reference`]) with
/// OpenSubdiv's `reference`: positions, normals and UVs coordinate by coordinate (limit UVs
/// within [`SINGLE_TOLERANCE`]), faces and their UV indices exactly.
///
/// # Errors
/// The first mismatch, described.
pub fn check_written(
    case: &Case,
    written: &Reference,
    reference: &Reference,
) -> Result<(), String> {
    compare("vertices", &written.positions, &reference.positions)?;
    if !reference.normals.is_empty() {
        compare("normals", &written.normals, &reference.normals)?;
    }
    if case.kind != Kind::Limit && written.faces != reference.faces {
        return Err("faces differ".into());
    }
    if !reference.uvs.is_empty() {
        let tolerance = if case.kind == Kind::Limit {
            SINGLE_TOLERANCE
        } else {
            TOLERANCE
        };
        compare_within("uvs", &written.uvs, &reference.uvs, tolerance)?;
        if case.kind != Kind::Limit && written.face_uvs != reference.face_uvs {
            return Err("face UV indices differ".into());
        }
    }
    Ok(())
}

/// Parses `NAME_L3` or `NAME_MODE_L3` into the shape name, the mode and the level.
fn split_name(stem: &str) -> Option<(&str, Option<FVarLinear>, usize)> {
    let (rest, level) = stem.rsplit_once("_L")?;
    let level = level.parse().ok()?;
    for (mode, name) in [
        (FVarLinear::None, "none"),
        (FVarLinear::CornersOnly, "cornersonly"),
        (FVarLinear::CornersPlus1, "cornersplus1"),
        (FVarLinear::CornersPlus2, "cornersplus2"),
        (FVarLinear::Boundaries, "boundaries"),
        (FVarLinear::All, "all"),
    ] {
        if let Some(shape) = rest.strip_suffix(name).and_then(|s| s.strip_suffix('_')) {
            return Some((shape, Some(mode), level));
        }
    }
    Some((rest, None, level))
}

fn check_file(dir: &Path, file: &Path) -> Result<(), String> {
    let case = case(dir, file)?;
    let mut shape = read_shape(&case.shape)?;
    let reference = read_reference(file)?;
    match case.kind {
        Kind::Refined => check_refined(&shape, case.level, &reference),
        Kind::Limit => check_limit(&shape, &reference),
        Kind::FaceVarying => {
            // The mode comes from the file name; the reference must carry UVs.
            if reference.uvs.is_empty() {
                return Err("no vt lines in the reference".into());
            }
            shape.options.fvar_linear = case.fvar_linear.unwrap_or_default();
            check_refined(&shape, case.level, &reference)
        }
    }
}
