//! The OBJ writer: coordinates as the shortest text that reads back as the same `f32` (or, at
//! [`Precision::Full`], `f64`), UVs, normals, faces without holes, tags and non-default options.
//!
//! Lines are formatted in parallel, a chunk of [`CHUNK_LINES`] lines per task, and written in
//! file order, so the bytes do not depend on the thread count; at most two batches of
//! [`BATCH_CHUNKS`] chunks are held as text at once, one being written while the next is
//! formatted.
//!
//! A sequence of frames of one mesh ([`Frames`], what `tailor simulate` writes) formats the
//! lines that do not change (UVs, groups, faces, tags) once and keeps them as text, so a frame
//! formats only its positions and normals: on the 64² drape, whose written surface has as many
//! faces and UVs as vertices, that is two thirds of the numbers.

use std::collections::HashSet;
use std::fmt;
use std::io::{self, BufWriter, Write};

use nalgebra::Vector3;
use rayon::prelude::*;

use super::{
    BOUNDARY_CODES, CREASE_METHOD_NAMES, FVAR_CODES, Group, Precision, TRIANGLE_RULE_NAMES,
};
use crate::mesh::{Mesh, Point};
use crate::options::Options;

/// Lines formatted by one task: enough that a task outweighs its scheduling (a 1.6 M-face
/// mesh makes about 200 tasks), few enough that two threads finish close together.
const CHUNK_LINES: usize = 16_384;

/// Chunks formatted before they are written: bounds the text held at once to about 60 MB
/// (two batches of 64 chunks of 16k lines of about 30 bytes), whatever the mesh's size.
const BATCH_CHUNKS: usize = 64;

/// Writes `mesh` as OBJ with OpenSubdiv tags, with one normal per vertex if `normals` is given,
/// positions, UVs and normals at `precision` (tags always at full precision).
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
    precision: Precision,
    out: &mut impl Write,
) -> io::Result<()> {
    if let Some(n) = normals {
        check_count(n.len(), "normals", mesh.vertex_count())?;
    }
    let mut w = BufWriter::new(out);
    write_positions(&mut w, mesh.positions(), precision)?;
    write_uvs(&mut w, mesh, precision)?;
    write_normals(&mut w, normals.unwrap_or_default(), precision)?;
    write_faces(&mut w, mesh, normals.is_some(), &[])?;
    w.flush()
}

/// The OBJ text of a mesh whose positions (and normals) change from frame to frame while its
/// faces, UVs, groups and tags stay: the lines that stay are formatted once, and each frame
/// formats only its positions and normals. A frame's bytes are those [`write()`] gives for the
/// mesh at that frame's positions, with a `g` line before each run of faces whose groups
/// differ from the face before's.
#[derive(Clone, Debug)]
pub struct Frames {
    precision: Precision,
    vertex_count: usize,
    normals: bool,
    /// The `vt` lines.
    uvs: Vec<u8>,
    /// The `g` and `f` lines and the tags.
    faces: Vec<u8>,
}

impl Frames {
    /// The frames of `mesh` with `groups`, with one normal per vertex when `normals`, the
    /// coordinates at `precision`.
    #[must_use]
    pub fn new(mesh: &Mesh, groups: &[Group], normals: bool, precision: Precision) -> Self {
        let (mut uvs, mut faces) = (Vec::new(), Vec::new());
        write_uvs(&mut uvs, mesh, precision).expect("writing to memory");
        write_faces(&mut faces, mesh, normals, groups).expect("writing to memory");
        Self {
            precision,
            vertex_count: mesh.vertex_count(),
            normals,
            uvs,
            faces,
        }
    }

    /// Writes the frame with `positions` and `normals`, buffered internally.
    ///
    /// # Errors
    /// Any error of `out`; [`io::ErrorKind::InvalidInput`] if `positions` or `normals` do not
    /// have one entry per vertex, or normals are given to frames made without them or missing
    /// from frames made with them.
    pub fn write(
        &self,
        positions: &[Point],
        normals: Option<&[Vector3<f64>]>,
        out: &mut impl Write,
    ) -> io::Result<()> {
        check_count(positions.len(), "positions", self.vertex_count)?;
        match (normals, self.normals) {
            (Some(n), true) => check_count(n.len(), "normals", self.vertex_count)?,
            (None, false) => {}
            (Some(_), false) => return Err(invalid("normals for frames made without".into())),
            (None, true) => return Err(invalid("no normals for frames made with them".into())),
        }
        let mut w = BufWriter::new(out);
        write_positions(&mut w, positions, self.precision)?;
        w.write_all(&self.uvs)?;
        write_normals(&mut w, normals.unwrap_or_default(), self.precision)?;
        w.write_all(&self.faces)?;
        w.flush()
    }
}

/// An [`io::ErrorKind::InvalidInput`] error saying `what`.
fn invalid(what: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, what)
}

/// Checks that there are as many entries (`count` of `what`) as `vertices`.
fn check_count(count: usize, what: &str, vertices: usize) -> io::Result<()> {
    if count == vertices {
        Ok(())
    } else {
        Err(invalid(format!("{count} {what} for {vertices} vertices")))
    }
}

/// The `v` lines of `positions`.
fn write_positions(
    w: &mut impl Write,
    positions: &[Point],
    precision: Precision,
) -> io::Result<()> {
    write_lines(w, positions.len(), |v, line| {
        let p = positions[v];
        push_numbers(line, b"v", &[p.x, p.y, p.z], precision);
    })
}

/// The `vt` lines of `mesh`'s UVs, if it has any.
fn write_uvs(w: &mut impl Write, mesh: &Mesh, precision: Precision) -> io::Result<()> {
    let uv_values = mesh.uvs().map_or(&[][..], |uvs| &uvs.values);
    write_lines(w, uv_values.len(), |k, line| {
        let uv = uv_values[k];
        push_numbers(line, b"vt", &[uv.x, uv.y], precision);
    })
}

/// The `vn` lines of `normals`.
fn write_normals(
    w: &mut impl Write,
    normals: &[Vector3<f64>],
    precision: Precision,
) -> io::Result<()> {
    write_lines(w, normals.len(), |v, line| {
        let n = normals[v];
        push_numbers(line, b"vn", &[n.x, n.y, n.z], precision);
    })
}

/// The `f` lines of `mesh`'s faces but its holes, naming a normal per vertex when
/// `with_normals`, with a `g` line before each run of faces whose `groups` differ from the
/// face before's (none before the first faces when they are in none), then the tags.
fn write_faces(
    w: &mut impl Write,
    mesh: &Mesh,
    with_normals: bool,
    groups: &[Group],
) -> io::Result<()> {
    let mut hole = vec![false; mesh.face_count()];
    for &f in mesh.holes() {
        hole[f as usize] = true;
    }
    let group_lines = group_lines(mesh.face_count(), &hole, groups);
    let (face_vertices, uvs) = (mesh.face_vertices(), mesh.uvs());
    write_lines(w, mesh.face_count(), |f, line| {
        if hole[f] {
            return;
        }
        if !group_lines.is_empty()
            && let Ok(k) = group_lines.binary_search_by_key(&f, |(g, _)| *g)
        {
            line.extend_from_slice(group_lines[k].1.as_bytes());
        }
        let mut integer = itoa::Buffer::new();
        let mut push = |line: &mut Vec<u8>, index: u32| {
            line.extend_from_slice(integer.format(u64::from(index) + 1).as_bytes());
        };
        line.push(b'f');
        for c in mesh.face_range(f) {
            let v = face_vertices[c];
            line.push(b' ');
            push(line, v);
            if let Some(uvs) = uvs {
                line.push(b'/');
                push(line, uvs.indices[c]);
            }
            if with_normals {
                line.extend_from_slice(if uvs.is_some() { b"/" } else { b"//" });
                push(line, v);
            }
        }
        line.push(b'\n');
    })?;

    write_tags(mesh, &hole, w)
}

/// The `g` line to write before each face that starts a run of faces in other `groups` than
/// the face before (a face in no group after grouped ones gets an empty `g` line); holes are
/// not written, so they neither start nor break a run.
fn group_lines(face_count: usize, hole: &[bool], groups: &[Group]) -> Vec<(usize, String)> {
    let mut names: Vec<Vec<&str>> = vec![Vec::new(); face_count];
    for g in groups {
        for &f in &g.faces {
            if let Some(names) = names.get_mut(f as usize) {
                names.push(&g.name);
            }
        }
    }
    let mut lines = Vec::new();
    let mut current: &[&str] = &[];
    for f in (0..face_count).filter(|&f| !hole[f]) {
        if names[f] != current {
            current = &names[f];
            lines.push((f, format!("g {}\n", current.join(" "))));
        }
    }
    lines
}

/// Writes `count` lines, line `i` appended to its chunk's text by `line(i, text)`: a batch of
/// chunks is formatted in parallel while this thread writes the batch before it, in order.
/// The two batches' buffers are reused, so a large mesh does not map fresh memory for each.
fn write_lines(
    w: &mut impl Write,
    count: usize,
    line: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    write_lines_in(w, count, [CHUNK_LINES, BATCH_CHUNKS], line)
}

/// As [`write_lines`], with `chunk_lines` lines to a chunk and `batch_chunks` chunks to a batch.
fn write_lines_in(
    w: &mut impl Write,
    count: usize,
    [chunk_lines, batch_chunks]: [usize; 2],
    line: impl Fn(usize, &mut Vec<u8>) + Sync,
) -> io::Result<()> {
    let chunks: Vec<_> = (0..count)
        .step_by(chunk_lines)
        .map(|start| start..(start + chunk_lines).min(count))
        .collect();
    let (mut formatted, mut spare): (Vec<Vec<u8>>, Vec<Vec<u8>>) = (Vec::new(), Vec::new());
    for batch in chunks.chunks(batch_chunks) {
        spare.resize_with(batch.len(), Vec::new);
        let mut written = Ok(());
        rayon::in_place_scope(|scope| {
            let (spare, line) = (&mut spare, &line);
            scope.spawn(move |_| {
                batch.par_iter().zip(spare).for_each(|(lines, text)| {
                    text.clear();
                    for i in lines.clone() {
                        line(i, text);
                    }
                });
            });
            written = formatted.iter().try_for_each(|text| w.write_all(text));
        });
        written?;
        std::mem::swap(&mut formatted, &mut spare);
    }
    formatted.iter().try_for_each(|text| w.write_all(text))
}

/// Appends `keyword`, each value after a space at `precision`, and a line end.
fn push_numbers(line: &mut Vec<u8>, keyword: &[u8], values: &[f64], precision: Precision) {
    let mut buffer = ryu::Buffer::new();
    line.extend_from_slice(keyword);
    for &x in values {
        line.push(b' ');
        line.extend_from_slice(shortest(x, precision, &mut buffer).as_bytes());
    }
    line.push(b'\n');
}

/// The shortest text that parses back to `x` at `precision` (`x as f32` at
/// [`Precision::Single`], unless that overflows to infinity: such a value is written in full).
///
/// ryu prints integral values with a trailing `.0` (`1.0`, `-0.0`), which is left out as
/// Rust's `Display` does; magnitudes outside its decimal range (1e-5..1e16 for `f64`,
/// 1e-6..1e13 for `f32`) are written with an exponent (`1e-7`, `2.5e20`), never as hundreds of
/// digits.
pub(super) fn shortest(x: f64, precision: Precision, buffer: &mut ryu::Buffer) -> &str {
    let text = match precision.single(x) {
        Some(single) => buffer.format(single),
        None => buffer.format(x),
    };
    text.strip_suffix(".0").unwrap_or(text)
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

/// An `f64` printed in full: the shortest text that parses back to the same bits.
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(shortest(self.0, Precision::Full, &mut ryu::Buffer::new()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit patterns from a fixed-seed generator (Knuth's MMIX LCG), the high bits first.
    fn bits(n: usize) -> impl Iterator<Item = u64> {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        (0..n).map(move |_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state
        })
    }

    /// Significant digits of a number's text.
    fn digits(text: &str) -> usize {
        let mantissa = text.split('e').next().unwrap_or_default();
        let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
        digits.trim_matches('0').len().max(1)
    }

    /// Lines formatted in chunks and batches of any size, on any number of threads, come out
    /// in order: the text of formatting them one after another.
    #[test]
    fn lines_come_out_in_order_whatever_the_chunks_and_threads() {
        let line = |i: usize, text: &mut Vec<u8>| {
            push_numbers(
                text,
                b"v",
                &[i as f64 / 7.0, -(i as f64)],
                Precision::Single,
            );
        };
        for count in [0, 1, 10, 97] {
            let mut expected = Vec::new();
            (0..count).for_each(|i| line(i, &mut expected));
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                for sizes in [[1, 1], [1, 3], [3, 2], [7, 5], [100, 1]] {
                    let mut out = Vec::new();
                    pool.install(|| write_lines_in(&mut out, count, sizes, line))
                        .unwrap();
                    assert!(
                        out == expected,
                        "{count} lines, {threads} threads, {sizes:?}"
                    );
                }
            }
        }
    }

    fn single(x: f64) -> String {
        shortest(x, Precision::Single, &mut ryu::Buffer::new()).to_owned()
    }

    fn full(x: f64) -> String {
        shortest(x, Precision::Full, &mut ryu::Buffer::new()).to_owned()
    }

    #[test]
    fn single_precision_text_reads_back_as_the_same_f32() {
        let edges = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            1.0 / 3.0,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::EPSILON,
            1e-6,
            1e-6_f32.next_down(),
            1e13,
            1e13_f32.next_down(),
            16_777_217.0,
        ];
        let random = bits(200_000).map(|b| f32::from_bits((b >> 32) as u32));
        let unit = bits(200_000).map(|b| ((b >> 40) as f32) / (1u32 << 24) as f32 * 2.0 - 1.0);
        for x in edges.into_iter().chain(random).chain(unit) {
            if !x.is_finite() {
                continue;
            }
            let text = single(f64::from(x));
            let back: f32 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x:e} wrote {text}");
            // Through an f64 reader (tailor's, tobj's) and rounded, the same bits too.
            let wide: f64 = text.parse().unwrap();
            assert_eq!((wide as f32).to_bits(), x.to_bits(), "{x:e} wrote {text}");
            // As few significant digits as Rust's own shortest round-trip text.
            assert_eq!(
                digits(&text),
                digits(&format!("{x:e}")),
                "{x:e} wrote {text}"
            );
            assert!(text.len() <= 16, "{x:e} wrote {text}");
        }
        assert_eq!(single(0.1 + 0.2), "0.3");
        assert_eq!(single(-0.0), "-0");
        assert_eq!(single(2.0), "2");
        assert_eq!(single(1e-7), "1e-7");
        assert_eq!(single(0.123_456_789_012), "0.12345679");
    }

    #[test]
    fn single_precision_keeps_what_f32_cannot_hold() {
        for x in [1e39, -3e300, f64::MAX] {
            assert_eq!(single(x).parse::<f64>().unwrap(), x);
        }
        // Below f32's range a value rounds to zero, as an f32 reader would make it.
        assert_eq!(single(1e-300), "0");
    }

    #[test]
    fn round_gives_what_a_reader_of_the_text_holds() {
        let edges = [
            0.1,
            -1.0 / 3.0,
            1e39,
            -3e300,
            1e-300,
            16_777_217.0,
            f64::MAX,
        ];
        let random = bits(100_000).map(f64::from_bits);
        let unit = bits(100_000).map(|b| (b >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0);
        for x in edges
            .into_iter()
            .chain(random)
            .chain(unit)
            .filter(|x| x.is_finite())
        {
            for precision in [Precision::Single, Precision::Full] {
                let text = shortest(x, precision, &mut ryu::Buffer::new()).to_owned();
                let wide: f64 = text.parse().unwrap();
                let narrow: f32 = text.parse().unwrap();
                let back = match precision {
                    Precision::Single if narrow.is_finite() => f64::from(narrow),
                    _ => wide,
                };
                let rounded = precision.round(x);
                assert_eq!(rounded.to_bits(), back.to_bits(), "{x:e} at {precision:?}");
                // An f64 reader is within half an f32 step of it (the subnormals' below f32's
                // normal range).
                let step = (f64::from(f32::EPSILON) * rounded.abs())
                    .max(f64::from(f32::from_bits(1)))
                    / 2.0;
                assert!((wide - rounded).abs() <= step, "{x:e} at {precision:?}");
            }
        }
    }

    #[test]
    fn round_toward_takes_the_nearest_f32_read_on_the_side_asked() {
        let unit = bits(100_000).map(|b| (b >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0);
        let mut buffer = ryu::Buffer::new();
        let mut read =
            |y: f64| -> f64 { shortest(y, Precision::Single, &mut buffer).parse().unwrap() };
        let mut stepped = 0;
        for x in unit.chain([0.0, 1.0, 0.1, -0.1, 1e-30]) {
            let nearest = Precision::Single.round(x);
            assert_eq!(Precision::Single.round_toward(x, 0.0), nearest);
            for toward in [1.0, -1.0] {
                let r = Precision::Single.round_toward(x, toward);
                // An f32 on the side asked, read back from its text on that side too ...
                assert_eq!(f64::from(r as f32), r);
                assert!((r - x) * toward >= 0.0, "{x:e} toward {toward}: {r:e}");
                assert!(
                    (read(r) - x) * toward >= 0.0,
                    "{x:e} toward {toward}: {r:e}"
                );
                // ... and the nearest such: the f32 before it is not.
                let before = f64::from(if toward > 0.0 {
                    (r as f32).next_down()
                } else {
                    (r as f32).next_up()
                });
                let fits = (before - x) * toward >= 0.0 && (read(before) - x) * toward >= 0.0;
                assert!(!fits, "{x:e} toward {toward}: {before:e} is nearer");
                stepped += usize::from(r != nearest && (nearest - x) * toward >= 0.0);
            }
            assert_eq!(Precision::Full.round_toward(x, 1.0), x);
        }
        // The text read into an f64 sometimes lands on the wrong side of the nearest.
        assert!(stepped > 1000, "{stepped}");
    }

    #[test]
    fn the_precision_of_a_text_is_told_from_its_numbers() {
        let unit: Vec<f64> = bits(10_000)
            .map(|b| (b >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0)
            .collect();
        let read = |precision: Precision| -> Vec<f64> {
            let mut buffer = ryu::Buffer::new();
            unit.iter()
                .map(|&x| shortest(x, precision, &mut buffer).parse().unwrap())
                .collect()
        };
        assert_eq!(
            Precision::of_text(read(Precision::Single)),
            Precision::Single
        );
        assert_eq!(Precision::of_text(read(Precision::Full)), Precision::Full);
        // One number with more digits than an f32 needs makes the text full.
        let mut mixed = read(Precision::Single);
        mixed[5000] = 0.1 + 1e-12;
        assert_eq!(Precision::of_text(mixed), Precision::Full);
        // Short decimals are f32 text too: an f32 reader holds their nearest f32.
        assert_eq!(Precision::of_text([0.5, -2.0, 0.1]), Precision::Single);
    }

    /// The text of `{}`, or `{:e}` outside 1e-5..1e16 (where `{}` writes hundreds of digits).
    fn display(x: f64) -> String {
        let a = x.abs();
        if a == 0.0 || (1e-5..1e16).contains(&a) {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    }

    /// Full precision writes the text of `{}` (`{:e}` outside 1e-5..1e16), but for a value
    /// exactly halfway between two shortest texts (a tie, such as ...781.25 at 1.7e15 where
    /// the spacing of `f64`s is 0.25), where ryu rounds the last digit to even and Rust away
    /// from zero: both read back as the value.
    /// Whether decimal texts `a` and `b` of `x`, as long as each other and different only in
    /// their last digit, are the two roundings of an exact value that ends in 5 just after it.
    fn is_tie(x: f64, a: &str, b: &str) -> bool {
        let Some((_, fraction)) = a.split_once('.') else {
            return false;
        };
        let decimals = fraction.len();
        let exact = format!("{x:.*}", decimals + 40);
        let after = &exact[exact.len() - 40..];
        let differ = a.bytes().zip(b.bytes()).filter(|(p, q)| p != q).count();
        a.len() == b.len()
            && differ == 1
            && a.as_bytes()[a.len() - 1] != b.as_bytes()[b.len() - 1]
            && after.starts_with('5')
            && after[1..].bytes().all(|d| d == b'0')
    }

    #[test]
    fn full_precision_is_rust_display_but_for_ties() {
        let edges = [
            0.0,
            -0.0,
            1.0,
            0.1 + 0.2,
            1e-5,
            1e-5_f64.next_down(),
            1e16,
            1e16_f64.next_down(),
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            123_456_789.0,
        ];
        let random = bits(200_000).map(f64::from_bits);
        let unit = bits(200_000).map(|b| (b >> 11) as f64 / (1u64 << 53) as f64 * 200.0 - 100.0);
        for x in edges.into_iter().chain(random).chain(unit) {
            if x.is_finite() {
                let (text, rust) = (full(x), display(x));
                assert_eq!(
                    text.parse::<f64>().unwrap().to_bits(),
                    x.to_bits(),
                    "{rust}"
                );
                assert!(
                    text == rust || is_tie(x, &text, &rust),
                    "{text} against {rust}"
                );
            }
        }
    }
}
