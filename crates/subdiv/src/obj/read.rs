//! The OBJ reader: chunks of lines parsed in parallel ([`super::chunk`]), joined in file order,
//! any chunk the parallel pass could not take read again line by line; then [`Mesh`]
//! validation with errors mapped back to the line of the face or tag at fault.
//!
//! The line-by-line reading is the definition: a chunk joined whole changes the reader exactly
//! as reading its lines one by one would, and every chunk that might not (an error, a relative
//! index, an index past what the lines before define) is read line by line after the chunks
//! before it. So the mesh, or the error and its line, never depend on the chunking or the
//! thread count.

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use rayon::prelude::*;

use super::chunk::Chunk;
use super::{
    BOUNDARY_CODES, CREASE_METHOD_NAMES, FVAR_CODES, Group, ObjDocument, ObjError, Problem,
    TRIANGLE_RULE_NAMES, excerpt,
};
use crate::mesh::{Corner, Crease, FaceVarying, Mesh, MeshError, Point, Uv, Validation};
use crate::options::Options;

/// Bytes of text one parallel task parses (ended at the next line end): a 5 MB control mesh
/// makes 20 tasks, enough to keep two threads busy to the end.
const CHUNK_BYTES: usize = 1 << 18;

/// Statements accepted and ignored.
pub(super) const IGNORED: &[&str] = &[
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
    // A UTF-8 byte-order mark, which some Windows tools write, is not a statement.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    parse_in_chunks(text, source, validation, CHUNK_BYTES)
}

/// As [`parse_with`], parsing chunks of about `chunk_bytes` bytes in parallel.
fn parse_in_chunks(
    text: &str,
    source: &str,
    validation: Validation,
    chunk_bytes: usize,
) -> Result<ObjDocument, ObjError> {
    let pieces = split_lines(text, chunk_bytes);
    let chunks: Vec<Chunk> = pieces.par_iter().map(|piece| Chunk::parse(piece)).collect();
    let mut reader = Reader::new();
    let mut lines_before = 0;
    for (piece, chunk) in pieces.iter().zip(chunks) {
        if !reader.join(&chunk, lines_before, source)? {
            reader.read_lines(piece, lines_before, source)?;
        }
        lines_before += chunk.lines;
    }
    reader.finish(source, validation)
}

/// `text` cut into pieces of whole lines, each `size` bytes or a little more (up to the end
/// of the line it would cut).
fn split_lines(text: &str, size: usize) -> Vec<&str> {
    let mut pieces = Vec::new();
    let mut rest = text;
    while !rest.is_empty() {
        let cut = match rest.as_bytes().get(size..) {
            Some(tail) => tail
                .iter()
                .position(|&b| b == b'\n')
                .map_or(rest.len(), |k| size + k + 1),
            None => rest.len(),
        };
        let (piece, tail) = rest.split_at(cut);
        pieces.push(piece);
        rest = tail;
    }
    pieces
}

/// The keyword of an OBJ line, its arguments left in `args`; `None` for a blank or comment line.
pub(super) fn split_statement<'a>(line: &'a str, args: &mut Vec<&'a str>) -> Option<&'a str> {
    let content = line.find('#').map_or(line, |hash| &line[..hash]);
    let mut tokens = content.split_ascii_whitespace();
    let keyword = tokens.next()?;
    args.clear();
    args.extend(tokens);
    Some(keyword)
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

    /// Reads the lines of `text`, the first of which is line `lines_before + 1` of the file.
    fn read_lines(
        &mut self,
        text: &str,
        lines_before: usize,
        source: &str,
    ) -> Result<(), ObjError> {
        let mut args = Vec::new();
        for (index, line) in text.lines().enumerate() {
            self.read_line(lines_before + index + 1, line, &mut args, source)?;
        }
        Ok(())
    }

    /// Reads `text`, line `line` of the file.
    fn read_line<'a>(
        &mut self,
        line: usize,
        text: &'a str,
        args: &mut Vec<&'a str>,
        source: &str,
    ) -> Result<(), ObjError> {
        let Some(keyword) = split_statement(text, args) else {
            return Ok(());
        };
        self.statement(line, keyword, args)
            .map_err(|problem| ObjError::At {
                file: source.to_owned(),
                line,
                problem,
            })
    }

    /// Adds what `chunk` parsed, its first line being line `lines_before + 1`, exactly as
    /// reading its lines would; `false`, having added nothing, when that cannot be promised
    /// and the chunk must be read line by line: it is not clean, one of its indices reaches
    /// past what the lines before it define, its faces disagree with earlier ones on texture
    /// coordinates, or the tables would outgrow `u32` indices.
    ///
    /// # Errors
    /// A `g`, `o` or `t` line of the chunk that is wrong (the chunk's first error, since
    /// every other line of it is clean).
    fn join(&mut self, chunk: &Chunk, lines_before: usize, source: &str) -> Result<bool, ObjError> {
        let defined = [
            self.positions.len(),
            self.uv_values.len(),
            self.normal_count,
        ];
        let disagrees = matches!(
            (self.first_face, chunk.first_face),
            (Some((_, earlier)), Some((_, this))) if earlier != this
        );
        let fits = |a: usize, b: usize| u32::try_from(a + b).is_ok();
        if !chunk.clean
            || disagrees
            || chunk.needed.iter().zip(defined).any(|(&n, d)| n > d)
            || !fits(self.face_vertices.len(), chunk.face_vertices.len())
            || !fits(self.face_lines.len(), chunk.face_lines.len())
        {
            return Ok(false);
        }
        let line_of = |local: usize| lines_before + local + 1;
        if self.first_face.is_none() {
            self.first_face = chunk.first_face.map(|(local, uvs)| (line_of(local), uvs));
        }
        self.positions.extend_from_slice(&chunk.positions);
        self.uv_values.extend_from_slice(&chunk.uv_values);
        self.normal_count += chunk.normal_count;
        // Both tables fit `u32` indices: checked above.
        let base = self.face_vertices.len() as u32;
        self.face_offsets
            .extend(chunk.face_ends.iter().map(|&end| base + end));
        self.face_vertices.extend_from_slice(&chunk.face_vertices);
        self.face_uvs.extend_from_slice(&chunk.face_uvs);
        let first = self.face_lines.len();
        self.face_lines
            .extend(chunk.face_lines.iter().map(|&local| line_of(local)));
        let mut args = Vec::new();
        let mut done = 0;
        for event in &chunk.kept {
            self.join_groups(first + done..first + event.faces_before);
            done = event.faces_before;
            self.read_line(line_of(event.line), event.text, &mut args, source)?;
        }
        self.join_groups(first + done..self.face_lines.len());
        Ok(true)
    }

    /// Puts faces `faces` (which fit `u32` indices) into the current groups.
    fn join_groups(&mut self, faces: Range<usize>) {
        for &g in &self.current_groups {
            self.groups[g]
                .faces
                .extend(faces.start as u32..faces.end as u32);
        }
    }

    fn statement(&mut self, line: usize, keyword: &str, args: &[&str]) -> Result<(), Problem> {
        match keyword {
            "v" => self.positions.push(vertex(args)?),
            "vt" => self.uv_values.push(texture_coordinate(args)?),
            "vn" => {
                normal(args)?;
                self.normal_count += 1;
            }
            "f" => self.face(line, args)?,
            "g" | "o" => self.set_groups(args),
            "t" => self.tag(line, args)?,
            _ if IGNORED.contains(&keyword) => {}
            _ => {
                return Err(Problem::UnknownStatement {
                    keyword: excerpt(keyword),
                });
            }
        }
        Ok(())
    }

    fn face(&mut self, line: usize, corners: &[&str]) -> Result<(), Problem> {
        let mut has_uvs = None;
        for &token in corners {
            let (vertex, uv, normal) = corner_parts(token)?;
            self.face_vertices
                .push(resolve(vertex, "vertex", self.positions.len())?);
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
                    name: excerpt(name),
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
                tag: excerpt(name),
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
                    counts: excerpt(counts),
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
                    name: excerpt(name),
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
        mesh = mesh
            .with_creases(self.creases.clone())
            .map_err(|e| fail(&self, e))?;
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

/// The position of a `v` line (a weight or a colour after it is checked and ignored).
pub(super) fn vertex(args: &[&str]) -> Result<Point, Problem> {
    let c = coordinates(args, "v", "3, 4 or 6 numbers", &[3, 4, 6])?;
    Ok(Point::new(c[0], c[1], c[2]))
}

/// The texture coordinate of a `vt` line (`v` 0 when absent, `w` ignored).
pub(super) fn texture_coordinate(args: &[&str]) -> Result<Uv, Problem> {
    let c = coordinates(args, "vt", "1 to 3 numbers", &[1, 2, 3])?;
    Ok(Uv::new(c[0], c[1]))
}

/// Checks a `vn` line (normals are only counted).
pub(super) fn normal(args: &[&str]) -> Result<(), Problem> {
    coordinates(args, "vn", "3 numbers", &[3]).map(drop)
}

/// The vertex, texture coordinate and normal index tokens of a face corner (`v`, `v/vt`,
/// `v//vn`, `v/vt/vn`).
pub(super) fn corner_parts(token: &str) -> Result<(&str, Option<&str>, Option<&str>), Problem> {
    let mut parts = token.split('/');
    let vertex = parts.next().unwrap_or_default();
    let (uv, normal) = (parts.next(), parts.next());
    if parts.next().is_some()
        || vertex.is_empty()
        || (uv == Some("") && normal.is_none())
        || normal == Some("")
    {
        return Err(Problem::MalformedCorner {
            token: excerpt(token),
        });
    }
    Ok((vertex, uv.filter(|t| !t.is_empty()), normal))
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
                token: excerpt(token),
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
        token: excerpt(token),
    })
}

pub(super) fn integer(token: &str) -> Result<i64, Problem> {
    token.parse().map_err(|_| Problem::MalformedNumber {
        token: excerpt(token),
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
            value: excerpt(&key.to_string()),
            expected,
        })
}

#[cfg(test)]
mod tests {
    //! Reading in parallel chunks is reading line by line: the same document, or the same error
    //! at the same line, for every chunk size (down to a chunk per byte, which puts every
    //! line in a chunk of its own).

    use super::*;

    /// The definition: every line read in order by one reader.
    fn line_by_line(text: &str, validation: Validation) -> Result<ObjDocument, ObjError> {
        let mut reader = Reader::new();
        reader.read_lines(text, 0, "t.obj")?;
        reader.finish("t.obj", validation)
    }

    /// Asserts that `text` reads the same in chunks of every size as line by line; returns
    /// the error message, if any.
    fn same_in_chunks(text: &str) -> Option<String> {
        let validation = Validation::default();
        let expected = line_by_line(text, validation).map_err(|e| e.to_string());
        for size in [1, 2, 5, 16, 64, 1000, CHUNK_BYTES] {
            let chunked = parse_in_chunks(text, "t.obj", validation, size);
            assert_eq!(
                chunked.map_err(|e| e.to_string()),
                expected,
                "chunks of {size} bytes: {text:?}"
            );
        }
        expected.err()
    }

    /// A 3 × 2 grid of quads with UVs, groups, a tag and ignored statements.
    const GRID: &str = "# grid\nmtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\n\
        v 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 1 0\nv 0 2 0\nv 1 2 0\nv 2 2 0\nv 3 2 0\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng left both\ns 1\n\
        f 1/1/1 2/2/1 6/3/1 5/4/1\nf 5/1 6/2 10/3 9/4\no right\nusemtl red\n\
        f 2/1 3/2 7/3 6/4\r\nf 6/1 7/2 11/3 10/4\ng both\nf 3/1 4/2 8/3 7/4\n\
        f 7/1 8/2 12/3 11/4   # last face\nt crease 2/1/0 1 2 1.5\nt interpolateboundary 1/0/0 1\n";

    #[test]
    fn chunks_read_as_lines_do() {
        assert_eq!(same_in_chunks(GRID), None);
        let doc = parse(GRID, "t.obj").unwrap();
        assert_eq!(doc.mesh.face_count(), 6);
        assert_eq!(doc.groups.len(), 3);
        assert_eq!(doc.groups[1].faces, vec![0, 1, 4, 5], "both");
        // Relative indices, vertices after faces, and faces before any vertex is defined.
        let relative = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf 1 3 -1\n";
        assert_eq!(same_in_chunks(relative), None);
        let shapes = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/opensubdiv/shapes");
        for entry in std::fs::read_dir(shapes).unwrap() {
            let text = std::fs::read_to_string(entry.unwrap().path()).unwrap();
            same_in_chunks(&text);
        }
    }

    #[test]
    fn errors_name_the_line_in_any_chunk() {
        // Each edit makes line 26 (the third face) or a line after it wrong, with the faces
        // before it read and the error found when its chunk is joined, not when parsed.
        let cases = [
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 70/3 6/4",
                "t.obj:26: vertex index 70",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 -13/3 6/4",
                "t.obj:26: vertex index -13",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 0/3 6/4",
                "t.obj:26: vertex index 0",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 7/9 6/4",
                "t.obj:26: texture coordinate index 9",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2 3 7 6",
                "t.obj:26: this face has no texture",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3 7/3 6/4",
                "t.obj:26: some corners",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 7/3 6/4/1/2",
                "t.obj:26: malformed face corner",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 7/3 7/4",
                "t.obj:26: face 2 uses vertex 6 more than once",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "f 2/1 3/2 7/3 6/4/2",
                "t.obj:26: normal index 2",
            ),
            (
                "f 2/1 3/2 7/3 6/4",
                "curv 0 1 2",
                "t.obj:26: unsupported statement",
            ),
            ("g both", "vp 1", "t.obj:28: unsupported statement"),
            ("f 7/1 8/2", "f 7/1 8/x", "t.obj:30: malformed number 'x'"),
            ("t crease 2/1/0 1 2", "t crease 2/1/0 1 7", "t.obj:31: "),
            (
                "t interpolateboundary 1/0/0 1",
                "t bogus 0/0/0",
                "t.obj:32: unknown tag",
            ),
            (
                "vn 0 0 1",
                "vn 0 nan 1",
                "t.obj:19: coordinate 'nan' is not finite",
            ),
        ];
        for (from, to, expected) in cases {
            assert!(GRID.contains(from), "{from}");
            let text = GRID.replacen(from, to, 1);
            let error = same_in_chunks(&text).unwrap_or_default();
            assert!(error.starts_with(expected), "{to}: {error}");
        }
    }
}
