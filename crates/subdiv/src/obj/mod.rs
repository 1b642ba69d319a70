//! Control meshes as Wavefront OBJ with OpenSubdiv's `t` tags: [`read`]/[`parse`] and [`write()`].
//!
//! # Why a hand-written reader
//! `tobj` (used elsewhere for plain geometry) renumbers vertices when it merges the position,
//! texture and normal streams, and it drops `t` lines. A control mesh must keep the file's vertex
//! order (OpenSubdiv's refined vertex order, and every tag, is defined by it) and its creases,
//! corners and holes, so this module reads OBJ itself.
//!
//! # What is read
//! - `v x y z [w | r g b]`: position; a rational weight `w` or a vertex colour is ignored.
//! - `vt u [v [w]]`: texture coordinate (`v` defaults to 0, `w` is ignored). `vn x y z`: normals
//!   are range-checked when faces name them, otherwise ignored (the surface defines its normals).
//! - `f` with corners `v`, `v/vt`, `v//vn`, `v/vt/vn`; 1-based indices, or negative indices
//!   counting back from the last element defined so far. An index must name an element defined
//!   on an earlier line (the OBJ rule that makes relative indices meaningful).
//! - UVs: if faces carry `vt` indices, the mesh gets [`FaceVarying`](crate::FaceVarying) data
//!   whose values are the whole `vt` list, in file order, and whose indices are the corners' `vt`
//!   indices. Either every face names texture coordinates or none does; a face that disagrees
//!   with the first face (or a face whose corners disagree) is an error naming its line, since a
//!   face without UVs has no face-varying values to interpolate.
//! - `g a b ...` and `o a`: the faces that follow belong to every name on the line (`g` alone
//!   means `default`). [`Group`]s are listed in order of first appearance and only if they hold
//!   faces; faces before the first `g`/`o` belong to no group.
//! - `s`, `usemtl`, `mtllib`, `l`, `p`, and the display attributes `mg`, `maplib`, `usemap`,
//!   `lod`, `bevel`, `c_interp`, `d_interp`, `shadow_obj`, `trace_obj`, `ctech`, `stech` are
//!   accepted and ignored. Any other statement (free-form curves and surfaces: `vp`, `curv`,
//!   `surf`, ...) is an error rather than silently lost geometry. `#` starts a comment anywhere
//!   on a line; blank lines and CRLF line ends are fine.
//!
//! # OpenSubdiv tags
//! `t NAME i/f/s ARGS` carries `i` integers, then `f` floats, then `s` strings
//! (`regression/common/shape_utils.cpp`, `Shape::tag::parseTag`); the argument count must match.
//! Tags may appear anywhere in the file and are applied after all faces are read.
//! - `t crease 2N/1/0 a b c d ... s`: pairs (a,b), (c,d), ... (not a chain), all of sharpness s;
//!   `2N/N/0` gives pair k the k-th float. (OpenSubdiv's own regression reader indexes the
//!   floats by the pair's first integer position instead, a bug no shape exercises; we follow
//!   the documented format.) Both vertices are 0-based and must share an edge.
//! - `t corner N/1/0 v... s` or `N/N/0 v... s...`: vertex sharpness.
//! - `t hole N/0/0 f...`: 0-based hole faces.
//! - `t interpolateboundary 1/0/0 k`: 0 none, 1 edge-and-corner, 2 edge-only.
//! - `t facevaryinginterpolateboundary 1/0/0 k`: 0 none, 1 corners-only, 2 corners-plus1,
//!   3 corners-plus2, 4 boundaries, 5 all (`regression/common/far_utils.h`, `GetSdcOptions`).
//! - `t creasemethod 0/0/1 normal|chaikin`, `t smoothtriangles 0/0/1 catmark|smooth`.
//! - `t vertexedit|edgeedit|faceedit`: hierarchical edits, which OpenSubdiv 3 does not support,
//!   are checked for well-formed counts and ignored. Any other tag name is an error.
//!
//! A later tag for the same option, edge or vertex overrides an earlier one; without tags the
//! options are [`Options::default`](crate::Options::default). Sharpness is validated by
//! [`Mesh`]; negative sharpness is an error (OpenSubdiv silently clamps it to 0).
//!
//! # Errors
//! Every problem tied to a line is an [`ObjError::At`] naming the file, the 1-based line and a
//! [`Problem`]. [`MeshError`]s from [`Mesh`]'s validation (repeated vertices, creases that are not
//! edges, ...) are mapped back to the line of the face or tag that caused them; only an empty
//! mesh has no line. The reader never panics.
//!
//! A face with a repeated vertex is an error at its line by default. OpenSubdiv accepts such
//! degenerate faces (`f 4 3 5 5`, in four regression shapes: `catmark_nonman_edges`,
//! `catmark_nonman_quadpole{8,64,360}`) as non-manifold edges; [`read_with`] and [`parse_with`]
//! with [`Validation::allow_degenerate_faces`](crate::Validation) read them so (the conformance
//! harness does). The reader passes faces through unchanged.
//!
//! # Writing
//! [`write()`] prints positions, then `vt` when the mesh has UVs, `vn` when normals are given, at
//! a [`Precision`]: by default each coordinate is the shortest text that parses back to the
//! same `f32` (what renderers and OpenSubdiv keep; 7–9 significant digits), with
//! [`Precision::Full`] the shortest that parses back to the same `f64` bits (up to 17 digits,
//! about 40% more bytes). The text comes from the `ryu` crate (Adams, "Ryū: fast float-to-string
//! conversion", PLDI 2018), whose output is proven shortest and round-tripping and which is
//! several times as fast as `{}` formatting (the project's `docs/DESIGN.md` says why this crate);
//! integral values lose ryu's trailing `.0`, and magnitudes outside about 1e-5..1e16 take an
//! exponent (`1e-7`), never hundreds of digits. At full precision this is the text of Rust's `{}`
//! (or `{:e}` outside that range) but where the value lies exactly halfway between two shortest
//! texts, which ryu rounds to even and Rust away from zero. Then `f` lines,
//! one `t crease 2/1/0 a b s` per sharp edge, one `t corner 1/1/0 v s` per sharp vertex
//! (sharpness always at full precision), and a tag for each option that differs from
//! [`Options::default`](crate::Options::default). Hole faces are not written (their vertices
//! are), following the reference data's output convention, and neither are creases on edges
//! that only hole faces have, nor tags of sharpness 0 that reset nothing written before them
//! (refinement leaves many decayed creases at 0). Other tags are written as tagged, in order,
//! so reading the output of a mesh without holes or such no-op tags, written at full
//! precision, gives back an equal [`Mesh`]. Lines are formatted in parallel over chunks and
//! written in order: the bytes do not depend on the thread count.

mod chunk;
mod read;
mod write;

pub use read::{parse, parse_with, read, read_with};
pub use write::{Frames, write};

use crate::mesh::{Mesh, MeshError};
use crate::options::{BoundaryInterpolation, CreaseMethod, FVarLinear, TriangleRule, named_option};

/// How many digits [`write()`] gives positions, UVs and normals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Precision {
    /// The shortest text that parses back to the value rounded to `f32` (a value beyond
    /// `f32`'s range is written in full rather than as infinity).
    #[default]
    Single,
    /// The shortest text that parses back to the same `f64`.
    Full,
}

impl Precision {
    /// What a reader holds of `x` written at this precision: at [`Precision::Single`] the
    /// `f32` its text reads back as (`x` rounded to the nearest `f32`, as a renderer reading
    /// into `f32` holds it; `x` itself where that overflows, as it is written in full); at
    /// [`Precision::Full`] `x`. For checking a file before it is written. A reader into `f64`
    /// holds the text's shortest decimal, within half an `f32` step of this.
    #[must_use]
    pub fn round(self, x: f64) -> f64 {
        self.single(x).map_or(x, f64::from)
    }

    /// What a reader holds of `x` written at this precision when `x` is rounded towards the
    /// sign of `toward` rather than to the nearest: at [`Precision::Single`] the nearest
    /// `f32` on that side of `x` whose text, read into an `f64`, is on that side too (the
    /// shortest decimal can lie half a step either way of its `f32`), so at most two `f32`
    /// steps from `x`; `x`'s nearest when `toward` is zero. At [`Precision::Full`], `x`. For
    /// writing two features that are apart but nearer than an `f32` step so that they stay
    /// apart, as an `f32` reader and as an `f64` reader hold them.
    #[must_use]
    pub fn round_toward(self, x: f64, toward: f64) -> f64 {
        let Some(mut single) = self.single(x) else {
            return x;
        };
        if toward == 0.0 {
            return f64::from(single);
        }
        let mut buffer = ryu::Buffer::new();
        let on_side = |y: f64| (y - x) * toward >= 0.0;
        for _ in 0..3 {
            let value = f64::from(single);
            if on_side(value) && on_side(self.read_back(value, &mut buffer)) {
                break;
            }
            single = if toward > 0.0 {
                single.next_up()
            } else {
                single.next_down()
            };
        }
        f64::from(single)
    }

    /// The precision a file's numbers were written at, from `numbers` as a reader into `f64`
    /// got them: [`Precision::Single`] when each is the shortest text of an `f32` read back
    /// (what [`write()`] writes at that precision; a reader into `f32`, such as a renderer,
    /// then holds [`Precision::round`] of each), else [`Precision::Full`]. A number written
    /// with more digits than an `f32` needs reads back as itself only by chance.
    pub fn of_text(numbers: impl IntoIterator<Item = f64>) -> Self {
        let mut buffer = ryu::Buffer::new();
        let single = numbers
            .into_iter()
            .all(|x| Self::Single.read_back(x, &mut buffer) == x);
        if single { Self::Single } else { Self::Full }
    }

    /// What a reader into `f64` holds of `x` written at this precision: its shortest text
    /// read back.
    fn read_back(self, x: f64, buffer: &mut ryu::Buffer) -> f64 {
        write::shortest(x, self, buffer).parse().unwrap_or(x)
    }

    /// `x` as the `f32` its text is written from, or `None` when it is written as an `f64`.
    fn single(self, x: f64) -> Option<f32> {
        let single = x as f32;
        (self == Self::Single && !(x.is_finite() && single.is_infinite())).then_some(single)
    }
}

named_option!(
    Precision,
    "precision",
    [(Precision::Single, "single"), (Precision::Full, "full")]
);

/// A control mesh read from OBJ, with the file's groups.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjDocument {
    /// The mesh, its tags and options.
    pub mesh: Mesh,
    /// The named groups (`g`/`o`) that hold faces, in order of first appearance.
    pub groups: Vec<Group>,
}

/// The faces listed under one `g` or `o` name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Group {
    /// The name as written.
    pub name: String,
    /// 0-based face indices in file order.
    pub faces: Vec<u32>,
}

/// Why an OBJ file could not be read as a control mesh.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    /// The file could not be read.
    #[error("{file}: {error}")]
    Io {
        /// The file name.
        file: String,
        /// What the system said.
        error: std::io::Error,
    },
    /// A line is wrong.
    #[error("{file}:{line}: {problem}")]
    At {
        /// The file name (`<stdin>` or as given to [`parse`]).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong with it.
        problem: Problem,
    },
    /// The mesh as a whole is invalid (it has no faces).
    #[error("{file}: {error}")]
    Mesh {
        /// The file name.
        file: String,
        /// What [`Mesh`] validation said.
        error: MeshError,
    },
}

impl ObjError {
    /// The 1-based line the error is about, if it is about one.
    #[must_use]
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::At { line, .. } => Some(*line),
            Self::Io { .. } | Self::Mesh { .. } => None,
        }
    }
}

/// At most this many characters of the input are quoted in an error: a bad token can be a
/// whole file's worth of bytes, and an error message is read by a person.
const QUOTED_CHARS: usize = 40;

/// `text` as an error quotes it: whole when short, else its first [`QUOTED_CHARS`] characters
/// and its length.
pub(super) fn excerpt(text: &str) -> String {
    match text.char_indices().nth(QUOTED_CHARS) {
        None => text.to_owned(),
        Some((end, _)) => format!("{}… ({} bytes)", &text[..end], text.len()),
    }
}

/// What is wrong with one line of an OBJ file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// A token that should be a number is not one.
    #[error("malformed number '{token}'")]
    MalformedNumber {
        /// The token.
        token: String,
    },
    /// A coordinate is NaN or infinite.
    #[error("coordinate '{token}' is not finite")]
    NonFinite {
        /// The token.
        token: String,
    },
    /// A statement has the wrong number of values.
    #[error("'{statement}' expects {expected}, found {found}")]
    Arity {
        /// The statement keyword.
        statement: &'static str,
        /// What it accepts.
        expected: &'static str,
        /// How many values the line has.
        found: usize,
    },
    /// A face corner is not `v`, `v/vt`, `v//vn` or `v/vt/vn`.
    #[error("malformed face corner '{token}' (expected v, v/vt, v//vn or v/vt/vn)")]
    MalformedCorner {
        /// The token.
        token: String,
    },
    /// An index is 0; OBJ indices start at 1 (or count back from -1).
    #[error("{kind} index 0 is invalid: OBJ indices start at 1")]
    IndexZero {
        /// `vertex`, `texture coordinate` or `normal`.
        kind: &'static str,
    },
    /// An index names an element that is not defined before this line.
    #[error("{kind} index {index} is out of range: {count} defined so far")]
    IndexOutOfRange {
        /// `vertex`, `texture coordinate` or `normal`.
        kind: &'static str,
        /// The index as written.
        index: i64,
        /// How many are defined before the line.
        count: usize,
    },
    /// Some corners of a face name texture coordinates and others do not.
    #[error("some corners of this face have texture coordinates and others do not")]
    UvsOnSomeCorners,
    /// This face and an earlier one disagree on having texture coordinates.
    #[error(
        "this face {} texture coordinates but the face on line {first_line} {}",
        if *has_uvs { "has" } else { "has no" },
        if *has_uvs { "has none" } else { "has them" }
    )]
    UvsOnSomeFaces {
        /// Whether this face has them.
        has_uvs: bool,
        /// The line of the first face, which decided.
        first_line: usize,
    },
    /// The statement keyword is not one this reader knows.
    #[error("unsupported statement '{keyword}'")]
    UnknownStatement {
        /// The keyword.
        keyword: String,
    },
    /// A `t` line lacks a name or its `ints/floats/strings` counts.
    #[error("malformed tag: expected 't NAME ints/floats/strings ARGS...'")]
    TagHeader,
    /// A tag has more or fewer arguments than its counts declare.
    #[error("tag '{tag}' declares {declared} arguments but has {found}")]
    TagArgumentCount {
        /// The tag name.
        tag: String,
        /// The sum of the declared counts.
        declared: usize,
        /// How many follow.
        found: usize,
    },
    /// A known tag with argument counts it does not accept.
    #[error("tag '{tag}' expects {expected} arguments, got {counts}")]
    TagShape {
        /// The tag name.
        tag: &'static str,
        /// The accepted `ints/floats/strings` forms.
        expected: &'static str,
        /// The counts given.
        counts: String,
    },
    /// A tag names a negative or impossibly large vertex or face.
    #[error("{tag} tag names {kind} {index}, which does not exist")]
    TagIndex {
        /// The tag name.
        tag: &'static str,
        /// `vertex` or `face`.
        kind: &'static str,
        /// The index as written.
        index: i64,
    },
    /// An option tag with a value outside its list.
    #[error("tag '{tag}' has unknown value '{value}' (expected one of: {expected})")]
    UnknownTagValue {
        /// The tag name.
        tag: &'static str,
        /// The value given.
        value: String,
        /// The accepted values.
        expected: &'static str,
    },
    /// A tag name this reader does not know.
    #[error("unknown tag '{name}'")]
    UnknownTag {
        /// The name.
        name: String,
    },
    /// More face corners or faces than `u32` indices allow.
    #[error("the mesh is too large for 32-bit indices")]
    TooLarge,
    /// [`Mesh`] validation failed because of this line's face or tag.
    #[error("{0}")]
    Mesh(MeshError),
}

/// `t interpolateboundary` codes (`GetSdcOptions` in OpenSubdiv's `far_utils.h`).
const BOUNDARY_CODES: [(BoundaryInterpolation, i64); 3] = [
    (BoundaryInterpolation::None, 0),
    (BoundaryInterpolation::EdgeAndCorner, 1),
    (BoundaryInterpolation::EdgeOnly, 2),
];

/// `t facevaryinginterpolateboundary` codes (`GetSdcOptions` in OpenSubdiv's `far_utils.h`).
const FVAR_CODES: [(FVarLinear, i64); 6] = [
    (FVarLinear::None, 0),
    (FVarLinear::CornersOnly, 1),
    (FVarLinear::CornersPlus1, 2),
    (FVarLinear::CornersPlus2, 3),
    (FVarLinear::Boundaries, 4),
    (FVarLinear::All, 5),
];

/// `t creasemethod` spellings.
const CREASE_METHOD_NAMES: [(CreaseMethod, &str); 2] = [
    (CreaseMethod::Uniform, "normal"),
    (CreaseMethod::Chaikin, "chaikin"),
];

/// `t smoothtriangles` spellings.
const TRIANGLE_RULE_NAMES: [(TriangleRule, &str); 2] = [
    (TriangleRule::Catmark, "catmark"),
    (TriangleRule::Smooth, "smooth"),
];
