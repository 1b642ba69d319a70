//! The face-varying topology of one level (OpenSubdiv's `Vtr::FVarLevel`), and how the base
//! level's is found from the face corners' value indices
//! (`FVarLevel::completeTopologyFromFaceValues`, `opensubdiv/vtr/fvarLevel.cpp`).
//!
//! Each vertex owns one or more *vertex values* ("siblings"): one per distinct value among its
//! face corners, numbered in order of first appearance walking its faces. Each vertex-face
//! incidence records the sibling its corner uses. An edge whose two faces disagree on the value
//! at either end is *discontinuous* (a seam); both its ends are then *mismatched*, as are
//! vertices the [`Mode`] sharpens. Every mismatched value is tagged:
//! - a *corner* (kept in place), when its span of faces is interrupted (by a seam or an
//!   infinitely sharp edge), is a single face with sharp corners, or the mode makes all the
//!   vertex's values sharp;
//! - a *crease* (the B-spline boundary rule along the span's two end edges), otherwise;
//! - *semi-sharp*, a corner that becomes a crease once the semi-sharp edges in its span (or the
//!   vertex's own sharpness) have decayed; *dependent-sharp* when it is semi-sharp only because
//!   the other of two values is (corners-plus modes).
//!
//! Crease values remember the first and last face of their span around the vertex, from which
//! the two crease end values are read.

use crate::csr::offsets_from_counts;
use crate::mesh::{FaceVarying, to_u32};
use crate::options::{BoundaryInterpolation, FVarLinear, Options};
use crate::rules::crease;
use crate::topology::Level;

/// How the face-varying interpolation option sharpens values (derived once from [`Options`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mode {
    /// `All`: everything bilinear.
    pub linear: bool,
    /// `All` or `Boundaries`: every face-varying boundary is a corner; no crease values.
    pub linear_boundaries: bool,
    /// `CornersPlus1` / `CornersPlus2`: one sharp value of two sharpens the other.
    pub dependent: bool,
    /// Anything but `None`: single-face spans are corners.
    pub corners_sharp: bool,
    /// Geometric boundary corners are smooth but face-varying ones sharp.
    pub smooth_corners_sharp: bool,
    /// `CornersPlus2`: a corner among two values sharpens both.
    pub sharpen_both: bool,
    /// Face-varying darts are sharpened.
    pub sharpen_darts: bool,
}

impl Mode {
    pub(crate) fn new(options: &Options) -> Self {
        let m = options.fvar_linear;
        let linear_boundaries = matches!(m, FVarLinear::All | FVarLinear::Boundaries);
        let corners_sharp = m != FVarLinear::None;
        let sharpen_both = m == FVarLinear::CornersPlus2;
        Self {
            linear: m == FVarLinear::All,
            linear_boundaries,
            dependent: matches!(m, FVarLinear::CornersPlus1 | FVarLinear::CornersPlus2),
            corners_sharp,
            smooth_corners_sharp: corners_sharp
                && options.boundary != BoundaryInterpolation::EdgeAndCorner,
            sharpen_both,
            sharpen_darts: sharpen_both || linear_boundaries,
        }
    }
}

/// Face-varying state of an edge.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct EdgeTag {
    /// The faces disagree on a value at one of the ends (a seam).
    pub mismatch: bool,
    /// Interpolated linearly (a seam or boundary under linear-boundary modes).
    pub linear: bool,
}

/// Face-varying state of a vertex value.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ValueTag {
    /// The value's topology differs from the vertex's; nothing else applies otherwise.
    pub mismatch: bool,
    /// A smooth boundary (crease); otherwise a corner.
    pub crease: bool,
    /// A corner until its semi-sharp features decay.
    pub semi_sharp: bool,
    /// Semi-sharp because the other value is.
    pub dep_sharp: bool,
}

impl ValueTag {
    pub(crate) const MISMATCH: Self = Self {
        mismatch: true,
        crease: false,
        semi_sharp: false,
        dep_sharp: false,
    };
    pub(crate) const CREASE: Self = Self {
        crease: true,
        ..Self::MISMATCH
    };

    /// Not a crease: kept in place (semi-sharp values included).
    pub(crate) fn is_corner(self) -> bool {
        !self.crease
    }

    /// A corner for good.
    pub(crate) fn is_inf_sharp(self) -> bool {
        !self.semi_sharp && !self.crease
    }
}

/// The face-varying topology of one level.
#[derive(Clone, Debug, Default)]
pub(crate) struct FVarLevel {
    /// Value index of every face corner, parallel to `Level::face_verts.items`.
    pub face_values: Vec<u32>,
    /// One tag per edge.
    pub edge_tags: Vec<EdgeTag>,
    /// Vertex `v`'s values are slots `offsets[v]..offsets[v + 1]`.
    pub offsets: Vec<u32>,
    /// Sibling used by each vertex-face incidence, parallel to `Level::vert_faces.items`.
    pub face_siblings: Vec<u16>,
    /// Value index of each slot: the identity except at level 0, where slots point into the
    /// user's value table.
    pub slot_values: Vec<u32>,
    /// One tag per slot.
    pub tags: Vec<ValueTag>,
    /// First and last face (positions around the vertex) of each crease slot's span.
    pub crease_ends: Vec<[u16; 2]>,
    /// Number of values of the level.
    pub value_count: usize,
}

/// What one value's span of faces around a vertex contains (`FVarLevel::ValueSpan`).
#[derive(Clone, Copy, Debug, Default)]
struct Span {
    size: u16,
    start: u16,
    discts: u16,
    semi_sharp: u16,
    inf_sharp: u16,
}

/// Boundary vertex: one of its edges has fewer than two faces (`Level::VTag::_boundary`).
pub(crate) fn is_boundary_vertex(l: &Level, v: usize) -> bool {
    l.vert_edges
        .row(v)
        .iter()
        .any(|&e| l.is_boundary_edge(e as usize))
}

/// Has a semi-sharp incident edge (`Level::VTag::_semiSharpEdges`).
pub(crate) fn has_semi_sharp_edges(l: &Level, v: usize) -> bool {
    l.vert_edges
        .row(v)
        .iter()
        .any(|&e| crease::is_semi_sharp(l.edge_sharpness[e as usize]))
}

fn next_corner(n: usize, c: usize) -> usize {
    if c + 1 == n { 0 } else { c + 1 }
}

fn prev_corner(n: usize, c: usize) -> usize {
    if c == 0 { n - 1 } else { c - 1 }
}

impl FVarLevel {
    /// The slot range of vertex `v`.
    pub(crate) fn slots(&self, v: usize) -> std::ops::Range<usize> {
        self.offsets[v] as usize..self.offsets[v + 1] as usize
    }

    /// Number of values of vertex `v`.
    pub(crate) fn count(&self, v: usize) -> usize {
        self.slots(v).len()
    }

    /// The value of the first slot of `v`.
    pub(crate) fn first_value(&self, v: usize) -> u32 {
        self.slot_values[self.offsets[v] as usize]
    }

    /// The base level from the user's per-corner value indices.
    pub(crate) fn base(l: &Level, uvs: &FaceVarying, mode: &Mode) -> Self {
        let nv = l.vertex_count;
        let mut fl = Self {
            face_values: uvs.indices.clone(),
            edge_tags: vec![EdgeTag::default(); l.edge_count()],
            face_siblings: vec![0; l.vert_faces.items.len()],
            value_count: uvs.values.len(),
            ..Self::default()
        };
        let mut mismatch = vec![false; nv];
        let mut counts = Vec::with_capacity(nv);
        let mut values = Vec::new();
        let mut unique = Vec::new();
        for v in 0..nv {
            fl.corner_values(l, v, &mut values);
            let manifold = !l.vertex_nonmanifold[v];
            let boundary = is_boundary_vertex(l, v);
            let edges = l.vert_edges.row(v);
            let mut seam = |fl: &mut Self, e: u32| {
                let [a, b] = l.edge_verts[e as usize];
                mismatch[a as usize] = true;
                mismatch[b as usize] = true;
                let tag = &mut fl.edge_tags[e as usize];
                tag.mismatch = true;
                tag.linear = mode.linear_boundaries;
            };
            if manifold {
                // Edge i lies between faces i - 1 and i.
                for i in usize::from(boundary)..values.len() {
                    if values[i] != values[prev_corner(values.len(), i)] {
                        seam(&mut fl, edges[i]);
                    }
                }
            } else if !values.is_empty() {
                for (i, &e) in edges.iter().enumerate() {
                    if fl.edge_discontinuous_at(l, e as usize, l.end_in_edge(to_u32(v), edges, i)) {
                        seam(&mut fl, e);
                    }
                }
            }
            if boundary && !mismatch[v] {
                if mode.linear_boundaries && !values.is_empty() {
                    mismatch[v] = true;
                    for (i, &e) in edges.iter().enumerate() {
                        let outer = if manifold {
                            i == 0 || i + 1 == edges.len()
                        } else {
                            l.is_boundary_edge(e as usize)
                        };
                        if outer {
                            fl.edge_tags[e as usize].linear = true;
                        }
                    }
                } else if values.len() == 1 && mode.smooth_corners_sharp {
                    mismatch[v] = true;
                }
            }
            let count = assign_siblings(
                &values,
                &mut unique,
                &mut fl.face_siblings[l.vert_faces.range(v)],
            );
            if !manifold && !mismatch[v] {
                mismatch[v] = count > 1;
            }
            counts.push(to_u32(count));
        }
        fl.offsets = offsets_from_counts(counts);
        let slots = *fl.offsets.last().expect("offsets") as usize;
        fl.slot_values = vec![0; slots];
        fl.tags = vec![ValueTag::default(); slots];
        fl.crease_ends = vec![[0, 0]; slots];
        let mut spans = Vec::new();
        for (v, &mismatched) in mismatch.iter().enumerate() {
            let faces = l.vert_faces.range(v);
            let slot0 = fl.offsets[v] as usize;
            let corner = |i: usize| {
                l.face_verts.offsets[l.vert_faces.items[i] as usize] as usize
                    + l.vert_face_local[i] as usize
            };
            if !faces.is_empty() {
                fl.slot_values[slot0] = fl.face_values[corner(faces.start)];
            }
            if !mismatched {
                continue;
            }
            let mut next = 1;
            for i in faces.clone().skip(1) {
                if usize::from(fl.face_siblings[i]) == next && next < fl.count(v) {
                    fl.slot_values[slot0 + next] = fl.face_values[corner(i)];
                    next += 1;
                }
            }
            fl.tag_values(l, v, mode, &mut spans);
        }
        fl
    }

    /// The value index of each face corner at `v`, in the vertex's face order.
    fn corner_values(&self, l: &Level, v: usize, out: &mut Vec<u32>) {
        out.clear();
        out.extend(l.vert_faces.range(v).map(|i| {
            let f = l.vert_faces.items[i] as usize;
            self.face_values[l.face_verts.offsets[f] as usize + l.vert_face_local[i] as usize]
        }));
    }

    /// Whether the faces of edge `e` disagree on the value at its end `end` (0 or 1) (non-manifold
    /// case). The corner is found from the edge's place in each face, not by searching the face
    /// for the vertex, which a degenerate face holds twice.
    fn edge_discontinuous_at(&self, l: &Level, e: usize, end: usize) -> bool {
        let faces = l.edge_faces.range(e);
        if faces.len() < 2 {
            return false;
        }
        let first_vertex = l.edge_verts[e][0];
        let value_in = |k: usize| {
            let r = l.face_verts.range(l.edge_faces.items[k] as usize);
            let c = l.edge_face_local[k] as usize;
            let reversed = usize::from(l.face_verts.items[r.start + c] != first_vertex);
            let corner = if end == reversed {
                c
            } else {
                next_corner(r.len(), c)
            };
            self.face_values[r.start + corner]
        };
        let first = value_in(faces.start);
        faces.skip(1).any(|k| value_in(k) != first)
    }

    /// Tags the values of a mismatched vertex of the base level (second half of
    /// `completeTopologyFromFaceValues`).
    fn tag_values(&mut self, l: &Level, v: usize, mode: &Mode, spans: &mut Vec<Span>) {
        let n = self.count(v);
        let slot0 = self.offsets[v] as usize;
        let vertex_sharp = l.vertex_sharpness[v];
        let boundary = is_boundary_vertex(l, v);
        let mut all_sharp = mode.linear_boundaries
            || crease::is_infinite(vertex_sharp)
            || l.vertex_nonmanifold[v]
            || (mode.dependent && n > 2)
            || (mode.sharpen_darts && n == 1 && !boundary);
        self.gather_spans(l, v, spans);
        let mut dependent = false;
        if !all_sharp && mode.dependent && n == 2 {
            let (a, b) = (spans[0], spans[1]);
            all_sharp = a.inf_sharp > 0 || b.inf_sharp > 0 || a.discts > 0 || b.discts > 0;
            if mode.sharpen_both {
                all_sharp |= a.size == 1 || b.size == 1;
            }
            dependent = (a.semi_sharp > 0) != (b.semi_sharp > 0);
        }
        let nfaces = l.vert_faces.range(v).len();
        for (i, span) in spans.iter().enumerate() {
            let slot = slot0 + i;
            self.tags[slot] = ValueTag::MISMATCH;
            if span.discts > 0 {
                continue;
            }
            let inf_sharp =
                all_sharp || span.inf_sharp > 0 || (span.size == 1 && mode.corners_sharp);
            if inf_sharp {
                continue;
            }
            let tag = &mut self.tags[slot];
            if span.semi_sharp > 0 || crease::is_semi_sharp(vertex_sharp) {
                tag.semi_sharp = true;
            } else if dependent {
                tag.semi_sharp = true;
                tag.dep_sharp = true;
            } else {
                tag.crease = true;
            }
            if !mode.linear_boundaries {
                let last = (span.start + span.size).wrapping_sub(1);
                // Value 0 may wrap around the vertex: its end is then before its start.
                let end = if i == 0 && span.start != 0 {
                    last.wrapping_sub(nfaces as u16)
                } else {
                    last
                };
                self.crease_ends[slot] = [span.start, end];
            }
        }
    }

    /// The span of faces of each value around `v` (`FVarLevel::gatherValueSpans`).
    fn gather_spans(&self, l: &Level, v: usize, spans: &mut Vec<Span>) {
        let edges = l.vert_edges.row(v);
        let nfaces = l.vert_faces.range(v).len();
        let siblings = &self.face_siblings[l.vert_faces.range(v)];
        let boundary = edges.len() > nfaces;
        spans.clear();
        spans.resize(self.count(v), Span::default());
        // Counts what interrupts or sharpens a span at edge `e`.
        let classify = |span: &mut Span, e: u32| {
            let s = l.edge_sharpness[e as usize];
            if self.edge_tags[e as usize].mismatch {
                span.discts += 1;
            } else if crease::is_infinite(s) {
                span.inf_sharp += 1;
            } else if crease::is_semi_sharp(s) {
                span.semi_sharp += 1;
            }
        };
        if l.vertex_nonmanifold[v] {
            for s in spans.iter_mut() {
                s.discts = 1;
            }
        } else if spans.len() == 1 && !boundary {
            // A single value: a dart if one seam ends here, disjoint if more.
            let span = &mut spans[0];
            let mut seen_seam = false;
            for (i, &e) in edges.iter().enumerate() {
                if self.edge_tags[e as usize].mismatch {
                    if seen_seam {
                        span.discts = 1;
                        break;
                    }
                    seen_seam = true;
                    span.start = i as u16;
                } else {
                    classify(span, e);
                }
            }
            span.size = nfaces as u16;
        } else {
            spans[0].size = 1;
            let wraps = !boundary && siblings[nfaces - 1] == 0;
            if wraps {
                classify(&mut spans[0], edges[0]);
            }
            for i in 1..nfaces {
                let s = usize::from(siblings[i]);
                if siblings[i] == siblings[i - 1] {
                    classify(&mut spans[s], edges[i]);
                } else {
                    if spans[s].size > 0 {
                        spans[s].discts += 1;
                    }
                    spans[s].start = i as u16;
                }
                spans[s].size += 1;
            }
            if wraps {
                spans[0].discts = spans[0].discts.wrapping_sub(1);
            }
        }
    }

    /// The values at the two ends of edge `e` as seen from its `i`-th face
    /// (`FVarLevel::getEdgeFaceValues`).
    pub(crate) fn edge_face_values(&self, l: &Level, e: usize, i: usize) -> [u32; 2] {
        let [a, b] = l.edge_verts[e];
        if self.count(a as usize) + self.count(b as usize) <= 2 {
            return [self.first_value(a as usize), self.first_value(b as usize)];
        }
        let k = l.edge_faces.offsets[e] as usize + i;
        let (f, c) = (
            l.edge_faces.items[k] as usize,
            l.edge_face_local[k] as usize,
        );
        let r = l.face_verts.range(f);
        let n = r.len();
        let pair = [
            self.face_values[r.start + c],
            self.face_values[r.start + next_corner(n, c)],
        ];
        if l.face_verts.items[r.start + c] == a {
            pair
        } else {
            [pair[1], pair[0]]
        }
    }

    /// The value at the far end of the `i`-th edge of `v`, as seen from `v`'s (single)
    /// value (`FVarLevel::getVertexEdgeValues`).
    pub(crate) fn vertex_edge_value(&self, l: &Level, v: usize, i: usize) -> u32 {
        let e = l.vert_edges.row(v)[i];
        let other = l.other_end(e, to_u32(v)) as usize;
        if self.count(other) == 1 {
            return self.first_value(other);
        }
        let value_at = |k: usize, step: fn(usize, usize) -> usize| {
            let f = l.vert_faces.items[k] as usize;
            let r = l.face_verts.range(f);
            self.face_values[r.start + step(r.len(), l.vert_face_local[k] as usize)]
        };
        let faces = l.vert_faces.range(v);
        if !l.vertex_nonmanifold[v] {
            if is_boundary_vertex(l, v) && i + 1 == l.vert_edges.range(v).len() {
                value_at(faces.start + i - 1, prev_corner)
            } else {
                value_at(faces.start + i, next_corner)
            }
        } else {
            let k = l.edge_faces.offsets[e as usize] as usize;
            let (f, c) = (
                l.edge_faces.items[k] as usize,
                l.edge_face_local[k] as usize,
            );
            let r = l.face_verts.range(f);
            if l.face_verts.items[r.start + c] as usize == other {
                self.face_values[r.start + c]
            } else {
                self.face_values[r.start + next_corner(r.len(), c)]
            }
        }
    }

    /// The two end values of the crease of sibling `s` of `v`
    /// (`FVarLevel::getVertexCreaseEndValues`).
    pub(crate) fn crease_end_values(&self, l: &Level, v: usize, s: usize) -> [u32; 2] {
        let [start, end] = self.crease_ends[self.offsets[v] as usize + s];
        let faces = l.vert_faces.range(v);
        let value_at = |k: usize, step: fn(usize, usize) -> usize| {
            let i = faces.start + k;
            let r = l.face_verts.range(l.vert_faces.items[i] as usize);
            self.face_values[r.start + step(r.len(), l.vert_face_local[i] as usize)]
        };
        [
            value_at(usize::from(start), next_corner),
            value_at(usize::from(end), prev_corner),
        ]
    }

    /// The positions, around `v`, of the edges inside the crease span of slot `slot`: those
    /// after its first face up to its last, wrapping around.
    pub(crate) fn span_interior_edges(
        &self,
        slot: usize,
        valence: usize,
    ) -> impl Iterator<Item = usize> {
        let [start, end] = self.crease_ends[slot].map(usize::from);
        let (wrap, upto) = if end > start {
            (0..0, start + 1..end + 1)
        } else if start > end {
            (start + 1..valence, 0..end + 1)
        } else {
            (0..0, 0..0)
        };
        wrap.chain(upto)
    }

    /// Rebuilds `face_values` from the vertex-face siblings
    /// (`FVarLevel::initializeFaceValuesFromVertexFaceSiblings`).
    pub(crate) fn face_values_from_siblings(&mut self, l: &Level) {
        self.face_values = l
            .face_verts
            .items
            .iter()
            .map(|&v| self.offsets[v as usize])
            .collect();
        for v in 0..l.vertex_count {
            if self.count(v) > 1 {
                for i in l.vert_faces.range(v) {
                    let f = l.vert_faces.items[i] as usize;
                    let corner = l.face_verts.offsets[f] as usize + l.vert_face_local[i] as usize;
                    self.face_values[corner] += u32::from(self.face_siblings[i]);
                }
            }
        }
    }
}

/// Numbers the distinct values around a vertex in order of first appearance and writes each
/// face's sibling; returns the count. Reproduces OpenSubdiv's shortcut for the second value,
/// which can count a value twice when the values alternate (a, b, a, b).
fn assign_siblings(values: &[u32], unique: &mut Vec<u32>, siblings: &mut [u16]) -> usize {
    unique.clear();
    let Some(&first) = values.first() else {
        return 1;
    };
    unique.push(first);
    let mut current = 0u16;
    let mut out = vec![0u16; values.len()];
    for i in 1..values.len() {
        if values[i] != values[i - 1] {
            let found = match unique.len() {
                1 => None,
                2 if unique[0] != values[i] => None,
                _ => unique.iter().position(|&u| u == values[i]),
            };
            current = match found {
                Some(k) => k as u16,
                None => {
                    unique.push(values[i]);
                    (unique.len() - 1) as u16
                }
            };
        }
        out[i] = current;
    }
    if unique.len() > 1 {
        siblings.copy_from_slice(&out);
    }
    unique.len()
}
