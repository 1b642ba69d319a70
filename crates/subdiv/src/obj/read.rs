//! The OBJ reader: one pass over the lines, then [`Mesh`] validation with errors mapped back to
//! the line of the face or tag at fault.

use std::collections::HashMap;
use std::path::Path;

use super::{
    BOUNDARY_CODES, CREASE_METHOD_NAMES, FVAR_CODES, Group, ObjDocument, ObjError, Problem,
    TRIANGLE_RULE_NAMES,
};
use crate::mesh::{Corner, Crease, FaceVarying, Mesh, MeshError, Point, Uv, Validation};
use crate::options::Options;

/// Statements accepted and ignored.
const IGNORED: &[&str] = &[
    "s",
    "usemtl",
    "mtllib",
    "l",
    "p",
    "mg",
    "maplib",
    "usemap",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
];

/// Reads a control mesh from an OBJ file. Bytes that are not UTF-8 are replaced (they can only
/// occur in names and comments).
///
/// # Errors
/// [`ObjError::Io`] if the file cannot be read, otherwise as [`parse`].
pub fn read(path: &Path) -> Result<ObjDocument, ObjError> {
    read_with(path, Validation::default())
}

/// As [`read`], validating the mesh with `validation` (for instance to accept OpenSubdiv's
/// degenerate faces).
///
/// # Errors
/// As [`read`], less what `validation` allows.
pub fn read_with(path: &Path, validation: Validation) -> Result<ObjDocument, ObjError> {
    let file = path.display().to_string();
    match std::fs::read(path) {
        Ok(bytes) => parse_with(&String::from_utf8_lossy(&bytes), &file, validation),
        Err(error) => Err(ObjError::Io { file, error }),
    }
}

/// Parses a control mesh from OBJ text; `source` names it in error messages (a path, or
/// `<stdin>`).
///
/// # Errors
/// [`ObjError::At`] for a bad line (see [`Problem`]), [`ObjError::Mesh`] for a mesh without faces.
pub fn parse(text: &str, source: &str) -> Result<ObjDocument, ObjError> {
    parse_with(text, source, Validation::default())
}

/// As [`parse`], validating the mesh with `validation`.
///
/// # Errors
/// As [`parse`], less what `validation` allows.
pub fn parse_with(
    text: &str,
    source: &str,
    validation: Validation,
) -> Result<ObjDocument, ObjError> {
    let mut reader = Reader::new();
    let mut args = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let content = line.find('#').map_or(line, |hash| &line[..hash]);
        let mut tokens = content.split_ascii_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        args.clear();
        args.extend(tokens);
        reader
            .statement(index + 1, keyword, &args)
            .map_err(|problem| ObjError::At {
                file: source.to_owned(),
                line: index + 1,
                problem,
            })?;
    }
    reader.finish(source, validation)
}

/// Everything read so far, with the line of every face and tag entry for error messages.
struct Reader {
    positions: Vec<Point>,
    uv_values: Vec<Uv>,
    normal_count: usize,
    face_offsets: Vec<u32>,
    face_vertices: Vec<u32>,
    face_uvs: Vec<u32>,
    face_lines: Vec<usize>,
    /// The line of the first non-empty face and whether it has UVs; all faces must agree.
    first_face: Option<(usize, bool)>,
    groups: Vec<Group>,
    group_index: HashMap<String, usize>,
    current_groups: Vec<usize>,
    creases: Vec<Crease>,
    crease_lines: Vec<usize>,
    corners: Vec<Corner>,
    corner_lines: Vec<usize>,
    holes: Vec<u32>,
    hole_lines: Vec<usize>,
    options: Options,
}

impl Reader {
    fn new() -> Self {
        Self {
            positions: Vec::new(),
            uv_values: Vec::new(),
            normal_count: 0,
            face_offsets: vec![0],
            face_vertices: Vec::new(),
            face_uvs: Vec::new(),
            face_lines: Vec::new(),
            first_face: None,
            groups: Vec::new(),
            group_index: HashMap::new(),
            current_groups: Vec::new(),
            creases: Vec::new(),
            crease_lines: Vec::new(),
            corners: Vec::new(),
            corner_lines: Vec::new(),
            holes: Vec::new(),
            hole_lines: Vec::new(),
            options: Options::default(),
        }
    }

    fn statement(&mut self, line: usize, keyword: &str, args: &[&str]) -> Result<(), Problem> {
        match keyword {
            "v" => {
                let c = coordinates(args, "v", "3, 4 or 6 numbers", &[3, 4, 6])?;
                self.positions.push(Point::new(c[0], c[1], c[2]));
            }
            "vt" => {
                let c = coordinates(args, "vt", "1 to 3 numbers", &[1, 2, 3])?;
                self.uv_values.push(Uv::new(c[0], c[1]));
            }
            "vn" => {
                coordinates(args, "vn", "3 numbers", &[3])?;
                self.normal_count += 1;
            }
            "f" => self.face(line, args)?,
            "g" | "o" => self.set_groups(args),
            "t" => self.tag(line, args)?,
            _ if IGNORED.contains(&keyword) => {}
            _ => {
                return Err(Problem::UnknownStatement {
                    keyword: keyword.to_owned(),
                });
            }
        }
        Ok(())
    }

    fn face(&mut self, line: usize, corners: &[&str]) -> Result<(), Problem> {
        let mut has_uvs = None;
        for &token in corners {
            let malformed = || Problem::MalformedCorner {
                token: token.to_owned(),
            };
            let mut parts = token.split('/');
            let vertex = parts.next().unwrap_or_default();
            let (uv, normal) = (parts.next(), parts.next());
            if parts.next().is_some()
                || vertex.is_empty()
                || (uv == Some("") && normal.is_none())
                || normal == Some("")
            {
                return Err(malformed());
            }
            self.face_vertices
                .push(resolve(vertex, "vertex", self.positions.len())?);
            let uv = uv.filter(|t| !t.is_empty());
            if let Some(uv) = uv {
                self.face_uvs
                    .push(resolve(uv, "texture coordinate", self.uv_values.len())?);
            }
            if let Some(normal) = normal {
                resolve(normal, "normal", self.normal_count)?;
            }
            if *has_uvs.get_or_insert(uv.is_some()) != uv.is_some() {
                return Err(Problem::UvsOnSomeCorners);
            }
        }
        if let Some(has_uvs) = has_uvs {
            match self.first_face {
                None => self.first_face = Some((line, has_uvs)),
                Some((first_line, first)) if first != has_uvs => {
                    return Err(Problem::UvsOnSomeFaces {
                        has_uvs,
                        first_line,
                    });
                }
                Some(_) => {}
            }
        }
        let face = u32::try_from(self.face_lines.len()).map_err(|_| Problem::TooLarge)?;
        let end = u32::try_from(self.face_vertices.len()).map_err(|_| Problem::TooLarge)?;
        self.face_offsets.push(end);
        self.face_lines.push(line);
        for &g in &self.current_groups {
            self.groups[g].faces.push(face);
        }
        Ok(())
    }

    fn set_groups(&mut self, names: &[&str]) {
        self.current_groups.clear();
        let names = if names.is_empty() {
            &["default"][..]
        } else {
            names
        };
        for &name in names {
            let next = self.groups.len();
            let g = *self.group_index.entry(name.to_owned()).or_insert(next);
            if g == next {
                self.groups.push(Group {
                    name: name.to_owned(),
                    faces: Vec::new(),
                });
            }
            if !self.current_groups.contains(&g) {
                self.current_groups.push(g);
            }
        }
    }

    fn tag(&mut self, line: usize, args: &[&str]) -> Result<(), Problem> {
        let [name, counts, rest @ ..] = args else {
            return Err(Problem::TagHeader);
        };
        let mut parts = counts.split('/').map(|c| c.parse::<usize>().ok());
        let (Some(Some(ni)), Some(Some(nf)), Some(Some(ns)), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(Problem::TagHeader);
        };
        let declared = ni.saturating_add(nf).saturating_add(ns);
        if rest.len() != declared {
            return Err(Problem::TagArgumentCount {
                tag: (*name).to_owned(),
                declared,
                found: rest.len(),
            });
        }
        let ints = rest[..ni]
            .iter()
            .map(|t| integer(t))
            .collect::<Result<Vec<_>, _>>()?;
        let floats = rest[ni..ni + nf]
            .iter()
            .map(|t| number(t))
            .collect::<Result<Vec<_>, _>>()?;
        let strings = &rest[ni + nf..];
        let shape = |tag: &'static str, expected: &'static str, ok: bool| {
            if ok {
                Ok(())
            } else {
                Err(Problem::TagShape {
                    tag,
                    expected,
                    counts: (*counts).to_owned(),
                })
            }
        };
        match *name {
            "crease" => {
                let pairs = ni / 2;
                let ok = ni >= 2 && ni % 2 == 0 && ns == 0 && (nf == 1 || nf == pairs);
                shape("crease", "2N/1/0 or 2N/N/0", ok)?;
                for (k, pair) in ints.chunks_exact(2).enumerate() {
                    let a = tag_index("crease", "vertex", pair[0])?;
                    let b = tag_index("crease", "vertex", pair[1])?;
                    let sharpness = floats[if nf == 1 { 0 } else { k }];
                    self.creases.push(Crease {
                        vertices: [a, b],
                        sharpness,
                    });
                    self.crease_lines.push(line);
                }
            }
            "corner" => {
                shape(
                    "corner",
                    "N/1/0 or N/N/0",
                    ni >= 1 && ns == 0 && (nf == 1 || nf == ni),
                )?;
                for (k, &v) in ints.iter().enumerate() {
                    let vertex = tag_index("corner", "vertex", v)?;
                    let sharpness = floats[if nf == 1 { 0 } else { k }];
                    self.corners.push(Corner { vertex, sharpness });
                    self.corner_lines.push(line);
                }
            }
            "hole" => {
                shape("hole", "N/0/0", ni >= 1 && nf == 0 && ns == 0)?;
                for &f in &ints {
                    self.holes.push(tag_index("hole", "face", f)?);
                    self.hole_lines.push(line);
                }
            }
            "interpolateboundary" => {
                shape(
                    "interpolateboundary",
                    "1/0/0",
                    ni == 1 && nf == 0 && ns == 0,
                )?;
                self.options.boundary =
                    lookup("interpolateboundary", &BOUNDARY_CODES, &ints[0], "0 1 2")?;
            }
            "facevaryinginterpolateboundary" => {
                let tag = "facevaryinginterpolateboundary";
                shape(tag, "1/0/0", ni == 1 && nf == 0 && ns == 0)?;
                self.options.fvar_linear = lookup(tag, &FVAR_CODES, &ints[0], "0 1 2 3 4 5")?;
            }
            "creasemethod" => {
                shape("creasemethod", "0/0/1", ni == 0 && nf == 0 && ns == 1)?;
                self.options.crease_method = lookup(
                    "creasemethod",
                    &CREASE_METHOD_NAMES,
                    &strings[0],
                    "normal chaikin",
                )?;
            }
            "smoothtriangles" => {
                shape("smoothtriangles", "0/0/1", ni == 0 && nf == 0 && ns == 1)?;
                self.options.triangle_rule = lookup(
                    "smoothtriangles",
                    &TRIANGLE_RULE_NAMES,
                    &strings[0],
                    "catmark smooth",
                )?;
            }
            "vertexedit" | "edgeedit" | "faceedit" => {}
            _ => {
                return Err(Problem::UnknownTag {
                    name: (*name).to_owned(),
                });
            }
        }
        Ok(())
    }

    /// Builds and validates the mesh, mapping a [`MeshError`] to the line at fault.
    fn finish(mut self, source: &str, validation: Validation) -> Result<ObjDocument, ObjError> {
        let fail = |reader: &Self, error: MeshError| match reader.line_of(&error) {
            Some(line) => ObjError::At {
                file: source.to_owned(),
                line,
                problem: Problem::Mesh(error),
            },
            None => ObjError::Mesh {
                file: source.to_owned(),
                error,
            },
        };
        let positions = std::mem::take(&mut self.positions);
        let face_offsets = std::mem::take(&mut self.face_offsets);
        let face_vertices = std::mem::take(&mut self.face_vertices);
        let mut mesh = Mesh::from_flat_with(positions, face_offsets, face_vertices, validation)
            .map_err(|e| fail(&self, e))?;
        if let Some((_, true)) = self.first_face {
            let uvs = FaceVarying {
                values: std::mem::take(&mut self.uv_values),
                indices: std::mem::take(&mut self.face_uvs),
            };
            mesh = mesh.with_uvs(uvs).map_err(|e| fail(&self, e))?;
        }
        // `with_creases` builds the edge set; skip it when there is nothing to check.
        if !self.creases.is_empty() {
            mesh = mesh
                .with_creases(self.creases.clone())
                .map_err(|e| fail(&self, e))?;
        }
        mesh = mesh
            .with_corners(self.corners.clone())
            .map_err(|e| fail(&self, e))?;
        mesh = mesh
            .with_holes(self.holes.clone())
            .map_err(|e| fail(&self, e))?;
        mesh.options = self.options;
        self.groups.retain(|g| !g.faces.is_empty());
        Ok(ObjDocument {
            mesh,
            groups: self.groups,
        })
    }

    /// The line of the face or tag entry a validation error is about. [`Mesh`] reports the first
    /// failing entry of a list, so the first entry matching the error is that entry.
    fn line_of(&self, error: &MeshError) -> Option<usize> {
        let first = |lines: &[usize], i: Option<usize>| i.and_then(|i| lines.get(i).copied());
        let bad = |s: f64| s.is_nan() || s < 0.0;
        match *error {
            MeshError::TooFewVertices { face, .. }
            | MeshError::TooManyVertices { face, .. }
            | MeshError::RepeatedVertex { face, .. }
            | MeshError::VertexOutOfRange { face, .. }
            | MeshError::UvOutOfRange { face, .. } => self.face_lines.get(face).copied(),
            MeshError::TagVertexOutOfRange {
                tag: "crease",
                vertex,
                ..
            } => first(
                &self.crease_lines,
                self.creases
                    .iter()
                    .position(|c| c.vertices.contains(&vertex)),
            ),
            MeshError::TagVertexOutOfRange { vertex, .. } => first(
                &self.corner_lines,
                self.corners.iter().position(|c| c.vertex == vertex),
            ),
            MeshError::BadSharpness { tag: "crease", .. } => first(
                &self.crease_lines,
                self.creases.iter().position(|c| bad(c.sharpness)),
            ),
            MeshError::BadSharpness { .. } => first(
                &self.corner_lines,
                self.corners.iter().position(|c| bad(c.sharpness)),
            ),
            MeshError::CreaseNotAnEdge(a, b) => first(
                &self.crease_lines,
                self.creases.iter().position(|c| c.vertices == [a, b]),
            ),
            MeshError::HoleOutOfRange { face, .. } => {
                first(&self.hole_lines, self.holes.iter().position(|&h| h == face))
            }
            MeshError::Empty
            | MeshError::NonFinitePosition { .. }
            | MeshError::NonFiniteUv { .. }
            | MeshError::UvCountMismatch { .. } => None,
        }
    }
}

/// Parses the numbers of a `v`, `vt` or `vn` line; missing trailing values are 0.
fn coordinates(
    args: &[&str],
    statement: &'static str,
    expected: &'static str,
    allowed: &[usize],
) -> Result<[f64; 3], Problem> {
    if !allowed.contains(&args.len()) {
        return Err(Problem::Arity {
            statement,
            expected,
            found: args.len(),
        });
    }
    let mut c = [0.0; 3];
    for (k, token) in args.iter().enumerate() {
        let x = number(token)?;
        if !x.is_finite() {
            return Err(Problem::NonFinite {
                token: (*token).to_owned(),
            });
        }
        if let Some(slot) = c.get_mut(k) {
            *slot = x;
        }
    }
    Ok(c)
}

fn number(token: &str) -> Result<f64, Problem> {
    token.parse().map_err(|_| Problem::MalformedNumber {
        token: token.to_owned(),
    })
}

fn integer(token: &str) -> Result<i64, Problem> {
    token.parse().map_err(|_| Problem::MalformedNumber {
        token: token.to_owned(),
    })
}

/// Turns a 1-based or negative (relative) OBJ index into a 0-based one among `count` elements.
fn resolve(token: &str, kind: &'static str, count: usize) -> Result<u32, Problem> {
    let index = integer(token)?;
    let count_i64 = i64::try_from(count).unwrap_or(i64::MAX);
    let resolved = match index {
        0 => return Err(Problem::IndexZero { kind }),
        1.. => index - 1,
        _ => count_i64 + index,
    };
    if (0..count_i64).contains(&resolved) {
        u32::try_from(resolved).map_err(|_| Problem::TooLarge)
    } else {
        Err(Problem::IndexOutOfRange { kind, index, count })
    }
}

/// A tag's 0-based vertex or face index; existence is checked by [`Mesh`].
fn tag_index(tag: &'static str, kind: &'static str, index: i64) -> Result<u32, Problem> {
    u32::try_from(index).map_err(|_| Problem::TagIndex { tag, kind, index })
}

/// The option value spelled `key` in `table`.
fn lookup<T: Copy, K: PartialEq + std::fmt::Display>(
    tag: &'static str,
    table: &[(T, K)],
    key: &K,
    expected: &'static str,
) -> Result<T, Problem> {
    table
        .iter()
        .find(|(_, k)| k == key)
        .map(|(v, _)| *v)
        .ok_or_else(|| Problem::UnknownTagValue {
            tag,
            value: key.to_string(),
            expected,
        })
}
