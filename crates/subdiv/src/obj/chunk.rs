//! The reader's parallel pass: one chunk of whole lines parsed without the lines before it.
//!
//! What does not depend on earlier lines is parsed here: the numbers of `v`, `vt` and `vn`
//! lines, and faces whose indices are all absolute (positive), with how many elements of each
//! kind the lines before the chunk must define for every index to name an element of an
//! earlier line ([`Chunk::needed`]). `g`, `o` and `t` lines are kept, to be read in order when
//! the chunk is joined. Anything else — a line with an error, a relative or zero index, an
//! unknown statement, faces that disagree on texture coordinates — leaves the chunk not
//! [`clean`](Chunk::clean), and the reader reads it again line by line with the rules and
//! messages of [`super::read`].

use super::read::{
    IGNORED, corner_parts, integer, normal, split_statement, texture_coordinate, vertex,
};
use crate::mesh::{Point, Uv};

/// What one chunk's lines hold, lines counted from the chunk's first (0).
pub(super) struct Chunk<'a> {
    /// Lines in the chunk (as [`str::lines`] counts them).
    pub lines: usize,
    /// Whether every line was parsed; if not, the rest of this record is incomplete.
    pub clean: bool,
    /// `v` positions.
    pub positions: Vec<Point>,
    /// `vt` values.
    pub uv_values: Vec<Uv>,
    /// `vn` lines.
    pub normal_count: usize,
    /// Where each face's corners end in `face_vertices`, counted from the chunk's first corner.
    pub face_ends: Vec<u32>,
    /// 0-based vertex of every corner.
    pub face_vertices: Vec<u32>,
    /// 0-based texture coordinate of every corner, when the faces have them.
    pub face_uvs: Vec<u32>,
    /// The line of each face.
    pub face_lines: Vec<usize>,
    /// The line of the first face with corners and whether it has texture coordinates (every
    /// face of a clean chunk agrees with it).
    pub first_face: Option<(usize, bool)>,
    /// Vertices, texture coordinates and normals that the lines before the chunk must define.
    pub needed: [usize; 3],
    /// `g`, `o` and `t` lines, to be read in order.
    pub kept: Vec<Kept<'a>>,
}

/// A line kept for the reader: its text, its line and the chunk's faces before it.
pub(super) struct Kept<'a> {
    /// Faces of the chunk before the line.
    pub faces_before: usize,
    /// The line, counted from the chunk's first (0).
    pub line: usize,
    /// Its text.
    pub text: &'a str,
}

impl<'a> Chunk<'a> {
    /// Parses `text`, whole lines.
    pub fn parse(text: &'a str) -> Self {
        let ends = text.bytes().filter(|&b| b == b'\n').count();
        let mut chunk = Self {
            lines: ends + usize::from(!text.is_empty() && !text.ends_with('\n')),
            clean: true,
            positions: Vec::new(),
            uv_values: Vec::new(),
            normal_count: 0,
            face_ends: Vec::new(),
            face_vertices: Vec::new(),
            face_uvs: Vec::new(),
            face_lines: Vec::new(),
            first_face: None,
            needed: [0; 3],
            kept: Vec::new(),
        };
        let mut args = Vec::new();
        for (line, content) in text.lines().enumerate() {
            let Some(keyword) = split_statement(content, &mut args) else {
                continue;
            };
            let parsed = match keyword {
                "v" => vertex(&args).map(|p| chunk.positions.push(p)).is_ok(),
                "vt" => texture_coordinate(&args)
                    .map(|uv| chunk.uv_values.push(uv))
                    .is_ok(),
                "vn" => {
                    chunk.normal_count += 1;
                    normal(&args).is_ok()
                }
                "f" => chunk.face(line, &args).is_some(),
                "g" | "o" | "t" => {
                    chunk.kept.push(Kept {
                        faces_before: chunk.face_lines.len(),
                        line,
                        text: content,
                    });
                    true
                }
                _ => IGNORED.contains(&keyword),
            };
            if !parsed {
                chunk.clean = false;
                break;
            }
        }
        chunk
    }

    /// Adds the face on `line` with corners `corners`; `None` when the reader must read it.
    fn face(&mut self, line: usize, corners: &[&str]) -> Option<()> {
        let mut has_uvs = None;
        for &token in corners {
            let (v, uv, normal) = corner_parts(token).ok()?;
            let v = self.absolute(v, 0)?;
            self.face_vertices.push(v);
            if let Some(uv) = uv {
                let uv = self.absolute(uv, 1)?;
                self.face_uvs.push(uv);
            }
            if let Some(normal) = normal {
                self.absolute(normal, 2)?;
            }
            if *has_uvs.get_or_insert(uv.is_some()) != uv.is_some() {
                return None;
            }
        }
        if let Some(has_uvs) = has_uvs {
            match self.first_face {
                None => self.first_face = Some((line, has_uvs)),
                Some((_, first)) if first != has_uvs => return None,
                Some(_) => {}
            }
        }
        self.face_ends
            .push(u32::try_from(self.face_vertices.len()).ok()?);
        self.face_lines.push(line);
        Some(())
    }

    /// The 0-based index of the element of kind `kind` (vertex, texture coordinate, normal)
    /// that absolute index `token` names, noting how many the lines before the chunk must
    /// define for it to name an earlier line; `None` for a relative or zero index.
    fn absolute(&mut self, token: &str, kind: usize) -> Option<u32> {
        let index = usize::try_from(integer(token).ok()?).ok()?;
        let zero_based = u32::try_from(index.checked_sub(1)?).ok()?;
        let defined = [
            self.positions.len(),
            self.uv_values.len(),
            self.normal_count,
        ][kind];
        self.needed[kind] = self.needed[kind].max(index.saturating_sub(defined));
        Some(zero_based)
    }
}
