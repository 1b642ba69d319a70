//! Regular patches of a control mesh, and where their refined points go (built once per
//! topology, for [`crate::Evaluator`]).
//!
//! A control quad is *regular* when its four corners are interior, manifold, smooth vertices
//! of valence four with four quads around them and no sharp edge or vertex: then its nine
//! surrounding quads form a 4 × 4 grid of control points, and every refined point on the quad
//! (interior, edges and corners) is the uniform bicubic B-spline subdivision of that grid
//! (Stam 1998, §2; OpenSubdiv's `Far::PatchTable` builds the same `REGULAR` patches for limit
//! evaluation). Catmull-Clark's rules need nothing beyond the quad's corners' one-rings to
//! refine it: every point they touch is an edge or face point of those rings, or a vertex point
//! of the corners, and a zero sharpness stays zero under either crease method. Holes do not
//! change vertex masks, so they do not matter here.
//!
//! The refined points are numbered level by level in OpenSubdiv's order (vertex points, face
//! points, edge points), which this module reads as a list of [`Segment`]s: runs of
//! last-level vertices that hold one block per control vertex, face, face corner or edge, in
//! that component's order. A regular face writes its interior points, and the points of the
//! edges that first appear in it (level-0 edges are numbered by first appearance, so a run of
//! faces owns a run of edges), into its blocks: which grid point goes to which slot is read
//! off the refined topology of one regular face, then checked on every other. A face's blocks
//! in a segment are consecutive, and so are the edges it owns, so a face writes one run of
//! slots per segment ([`Slots`]). Vertex points are numbered like the control vertices, which
//! follow no face order; a run of faces takes the range of vertices from the lowest corner of
//! its faces on, and each of those vertices is written by the first of the run's regular faces
//! with that corner. So a run of faces writes disjoint, contiguous ranges of every segment,
//! which is what lets [`crate::Evaluator`] fill the output in parallel without sharing a slot.
//! Every point of a run's ranges that no regular face writes keeps its stencil row.

use rayon::prelude::*;

use crate::csr::{Csr, running_totals};
use crate::mesh::to_u32;
use crate::sparse::{SharedRows, SharedRowsBuilder};
use crate::topology::Level;

/// Levels with patches: at level 1 a quad owns three points, too few to beat their stencil
/// rows; above level 4 nobody refines a cloth mesh, and the kernels are specialised per level.
pub(crate) const LEVELS: std::ops::RangeInclusive<usize> = 2..=4;

/// The component a block of refined points belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Owner {
    /// One block per control vertex.
    Vertex,
    /// One block per control face.
    Face,
    /// One block per face corner (a face of `n` corners has `n` blocks, consecutive).
    Corner,
    /// One block per control edge.
    Edge,
}

/// A run of last-level vertices made of `unit` points per component of kind `owner`, in
/// component order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Segment {
    /// First last-level vertex of the run.
    pub start: usize,
    /// The components the blocks belong to.
    pub owner: Owner,
    /// Points per component.
    pub unit: usize,
}

impl Segment {
    /// The first vertex of component `index`'s block (for [`Owner::Corner`], `index` is the
    /// face's first corner).
    #[inline]
    pub fn block(&self, index: usize) -> usize {
        self.start + self.unit * index
    }
}

/// The segments of `levels` uniform refinements of a mesh with `counts` = (vertices, faces,
/// corners, edges), with the vertex count they add up to.
///
/// Level `k` appends face points (one per level-`k−1` face) and edge points (one per
/// level-`k−1` edge); level-`k` edges are the interior edges of level-`k−1` faces, then the
/// two halves of each level-`k−1` edge (`crate::refine`).
fn segments(levels: usize, counts: [usize; 4]) -> (Vec<Segment>, usize) {
    let mut kinds = vec![(Owner::Vertex, 1)];
    let mut edges = vec![(Owner::Edge, 1)];
    for k in 1..=levels {
        // A level-0 face of n corners has n·4^(k−2) level-(k−1) faces, each with 4 edges.
        kinds.push(if k == 1 {
            (Owner::Face, 1)
        } else {
            (Owner::Corner, 1 << (2 * (k - 2)))
        });
        kinds.extend_from_slice(&edges);
        let halves = edges.iter().map(|&(owner, unit)| (owner, 2 * unit));
        edges = std::iter::once((Owner::Corner, 1 << (2 * (k - 1))))
            .chain(halves)
            .collect();
    }
    let mut start = 0;
    let segments = kinds
        .into_iter()
        .map(|(owner, unit)| {
            let s = Segment { start, owner, unit };
            let count = match owner {
                Owner::Vertex => counts[0],
                Owner::Face => counts[1],
                Owner::Corner => counts[2],
                Owner::Edge => counts[3],
            };
            start += unit * count;
            s
        })
        .collect();
    (segments, start)
}

/// One point a regular face writes: `grid` (a position in its `S × S` grid of refined points,
/// row-major, or for an edge the distance in steps from the edge's first vertex) goes to
/// `offset` in its block of `segment`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Write {
    /// Index into the segment list.
    pub segment: u16,
    /// Offset within the component's block.
    pub offset: u32,
    /// Where the value comes from.
    pub grid: u16,
}

/// The grid points ([`grid_index`]) a patch writes into each segment after the first, in
/// slot order: row `pattern · segments + segment` (segment 0's rows are empty). A face or corner segment's row
/// is the same for every patch and kept at `pattern` 0; an edge segment's holds the blocks of
/// the patch's owned edges one after another, so it depends on [`Patch::pattern`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Slots {
    /// Row starts; one more than there are rows.
    offsets: Vec<u32>,
    /// Grid points.
    grid: Vec<u16>,
}

impl Slots {
    /// Row `i`.
    #[inline]
    fn row(&self, i: usize) -> &[u16] {
        &self.grid[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Memory held, in bytes.
    fn bytes(&self) -> usize {
        self.offsets.len() * 4 + self.grid.len() * 2
    }
}

/// Edge ownership and direction patterns ([`Patch::pattern`]).
const PATTERNS: usize = 256;

/// A regular control face: its 4 × 4 control points and where its blocks start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Patch {
    /// Control points, row-major: row `y` (across edge 0 is row 0), column `x` (across edge
    /// 3 is column 0); the face's corners are (1, 1), (2, 1), (2, 2), (1, 2).
    pub points: [u32; 16],
    /// The face.
    pub face: u32,
    /// Its first corner.
    pub corner: u32,
    /// The first edge it owns (the first edge that first appears in it).
    pub edge: u32,
    /// Bit `j`: edge `j` first appears in this face, so this face writes its points.
    pub owned: u8,
    /// Bit `j`: edge `j` runs from corner `j + 1` to corner `j` (against the face).
    pub flipped: u8,
    /// Bit `j`: this patch writes corner `j`'s vertex point (the first patch of its run with
    /// that corner, when the vertex is in the run's range).
    pub corners: u8,
    /// The first three control columns are the previous patch's last three (it is the
    /// neighbour across edge 3, the same way round, in the same run): the kernel reuses them.
    pub follows: bool,
}

/// Where a patch's corners are in [`Patch::points`].
pub(crate) const CORNER_POINTS: [usize; 4] = [5, 6, 10, 9];

impl Patch {
    /// Which edges the patch owns and which way they run, as a row group of [`Slots`].
    #[inline]
    pub fn pattern(&self) -> usize {
        usize::from(self.owned | self.flipped << 4)
    }
}

/// Where each vertex's, face's and edge's components start, for a run of faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Starts {
    /// First vertex: the lowest corner of the faces at or after the first face, so that a
    /// run's faces mostly find their corners in its range.
    pub vertex: u32,
    /// First face.
    pub face: u32,
    /// Its first corner.
    pub corner: u32,
    /// The first edge that first appears at or after it.
    pub edge: u32,
    /// First patch at or after it.
    pub patch: u32,
    /// First of its points in `irregular`.
    pub irregular: u32,
}

impl Starts {
    /// The component index of segment kind `owner` at this start.
    #[inline]
    pub fn index(&self, owner: Owner) -> usize {
        match owner {
            Owner::Vertex => self.vertex as usize,
            Owner::Face => self.face as usize,
            Owner::Corner => self.corner as usize,
            Owner::Edge => self.edge as usize,
        }
    }
}

/// The regular patches of a mesh refined `levels` times and the layout of the refined points.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RegularPatches {
    /// Refinement level.
    pub levels: usize,
    /// The segments of the last level; the first is the control vertices' vertex points.
    pub segments: Vec<Segment>,
    /// The grid points a patch writes into each segment.
    pub slots: Slots,
    /// Regular faces, in face order.
    pub patches: Vec<Patch>,
    /// Runs of faces evaluated as one task; one more than there are runs.
    pub chunks: Vec<Starts>,
    /// Last-level vertices in face and edge blocks that no patch writes, run by run, in
    /// increasing order.
    pub irregular: Vec<u32>,
    /// Their stencil rows, in the same order: read in sequence, not picked out of the whole
    /// table a cache miss at a time.
    pub irregular_rows: SharedRows,
}

/// Faces per task: about 4096 refined points.
fn faces_per_chunk(levels: usize) -> usize {
    (4096 >> (2 * levels)).max(16)
}

impl RegularPatches {
    /// The regular patches of `base` refined `levels` times, `last_faces` being the last
    /// level's face → vertices and `stencils` the last level's stencil rows. `None` when there
    /// are none, or outside [`LEVELS`].
    pub fn new(
        base: &Level,
        levels: usize,
        last_faces: &Csr,
        stencils: &SharedRows,
    ) -> Option<Self> {
        if !LEVELS.contains(&levels) {
            return None;
        }
        let counts = [
            base.vertex_count,
            base.face_count(),
            base.face_verts.items.len(),
            base.edge_count(),
        ];
        let (segments, total) = segments(levels, counts);
        assert_eq!(total, stencils.rows(), "refined vertex count");
        let edge_start = edge_starts(base)?;
        let regular = regular_vertices(base);
        let grids = Grids {
            base,
            levels,
            last_faces,
        };
        // Offsets are read off the first candidate, then every candidate is checked against
        // them (and dropped if it differs, which would be a bug: tests count the patches).
        let candidates: Vec<(usize, [u32; 16])> = (0..base.face_count())
            .into_par_iter()
            .filter_map(|f| control_points(base, &regular, f).map(|p| (f, p)))
            .collect();
        let &(first, _) = candidates.first()?;
        let (face_writes, edge_writes) = grids.writes(first, &segments)?;
        let side = (1 << levels) + 1;
        let layout = Layout {
            base,
            segments: &segments,
            face_writes: &face_writes,
            edge_writes: &edge_writes,
            edge_start: &edge_start,
            side,
        };
        let mut patches: Vec<Patch> = candidates
            .into_par_iter()
            .filter_map(|(f, points)| {
                let grid = grids.grid(f)?;
                layout.patch(f, points, &grid)
            })
            .collect();
        for i in 1..patches.len() {
            let (before, after) = (patches[i - 1].points, patches[i].points);
            patches[i].follows = (0..16).all(|k| k % 4 == 3 || after[k] == before[k + 1]);
        }
        let slots = slots(&segments, &face_writes, &edge_writes, side);
        let mut this = Self {
            levels,
            segments,
            slots,
            patches,
            chunks: Vec::new(),
            irregular: Vec::new(),
            irregular_rows: SharedRows::default(),
        };
        this.chunks = this.chunk_starts(base, &edge_start);
        for run in &this.chunks {
            if let Some(p) = this.patches.get_mut(run.patch as usize) {
                p.follows = false;
            }
        }
        this.claim_corners();
        this.irregular = this.uncovered();
        let mut rows = SharedRowsBuilder::default();
        for &i in &this.irregular {
            let (cols, weights) = stencils.row(i as usize);
            rows.push_row(cols, weights);
        }
        this.irregular_rows = rows.finish();
        Some(this)
    }

    /// Where each run of faces starts (`irregular` left at zero until [`Self::uncovered`]).
    fn chunk_starts(&self, base: &Level, edge_start: &[u32]) -> Vec<Starts> {
        let faces = base.face_count();
        let per = faces_per_chunk(self.levels);
        // The lowest corner of faces f.., which never decreases with f.
        let mut lowest = vec![to_u32(base.vertex_count); faces + 1];
        for f in (0..faces).rev() {
            let corners = base.face_verts.row(f).iter().copied();
            lowest[f] = corners.fold(lowest[f + 1], u32::min);
        }
        let runs = faces.div_ceil(per);
        let mut patch = 0;
        (0..=runs)
            .map(|c| {
                let face = (c * per).min(faces);
                while patch < self.patches.len() && (self.patches[patch].face as usize) < face {
                    patch += 1;
                }
                Starts {
                    vertex: if c == 0 { 0 } else { lowest[face] },
                    face: to_u32(face),
                    corner: base.face_verts.offsets[face],
                    edge: edge_start[face],
                    patch: to_u32(patch),
                    irregular: 0,
                }
            })
            .collect()
    }

    /// Gives each vertex point in a run's range to the first of the run's patches with that
    /// vertex as a corner ([`Patch::corners`]).
    fn claim_corners(&mut self) {
        let mut claimed = Vec::new();
        for run in self.chunks.windows(2) {
            let (lo, hi) = (run[0], run[1]);
            claimed.clear();
            claimed.resize((hi.vertex - lo.vertex) as usize, false);
            for p in &mut self.patches[lo.patch as usize..hi.patch as usize] {
                for (j, &k) in CORNER_POINTS.iter().enumerate() {
                    let Some(v) = p.points[k].checked_sub(lo.vertex) else {
                        continue;
                    };
                    if let Some(slot) = claimed.get_mut(v as usize).filter(|c| !**c) {
                        *slot = true;
                        p.corners |= 1 << j;
                    }
                }
            }
        }
    }

    /// The points of a run's ranges that no patch writes, run by run; fills in
    /// `chunks[..].irregular`.
    fn uncovered(&mut self) -> Vec<u32> {
        let per_chunk: Vec<Vec<u32>> = (0..self.chunks.len() - 1)
            .into_par_iter()
            .map(|c| {
                let (lo, hi) = (self.chunks[c], self.chunks[c + 1]);
                let ranges: Vec<std::ops::Range<usize>> = self
                    .segments
                    .iter()
                    .map(|s| s.block(lo.index(s.owner))..s.block(hi.index(s.owner)))
                    .collect();
                let mut bases = Vec::with_capacity(ranges.len());
                let mut len = 0;
                for r in &ranges {
                    bases.push(len);
                    len += r.len();
                }
                let mut covered = vec![false; len];
                let mut cover = |at: usize| {
                    assert!(!covered[at], "a refined point written twice");
                    covered[at] = true;
                };
                for p in &self.patches[lo.patch as usize..hi.patch as usize] {
                    self.patch_runs(&lo, p, |segment, start, grid| {
                        let at = bases[segment] + start;
                        (at..at + grid.len()).for_each(&mut cover);
                    });
                    for (j, &k) in CORNER_POINTS.iter().enumerate() {
                        if p.corners & (1 << j) != 0 {
                            cover(bases[0] + (p.points[k] - lo.vertex) as usize);
                        }
                    }
                }
                ranges
                    .iter()
                    .zip(&bases)
                    .flat_map(|(r, &b)| {
                        let covered = &covered[b..b + r.len()];
                        r.clone()
                            .zip(covered)
                            .filter(|&(_, &c)| !c)
                            .map(|(i, _)| to_u32(i))
                    })
                    .collect()
            })
            .collect();
        let mut irregular = Vec::with_capacity(per_chunk.iter().map(Vec::len).sum());
        for (c, points) in per_chunk.iter().enumerate() {
            self.chunks[c].irregular = to_u32(irregular.len());
            irregular.extend_from_slice(points);
        }
        if let Some(last) = self.chunks.last_mut() {
            last.irregular = to_u32(irregular.len());
        }
        irregular
    }

    /// The run of slots patch `p` (of the run of faces starting at `lo`) writes in each
    /// segment after the first: `run(segment, start in the run's range of that segment,
    /// grid point of each slot)`. Segment 0, the vertex points, is written corner by corner
    /// ([`Patch::corners`]).
    #[inline]
    pub fn patch_runs(&self, lo: &Starts, p: &Patch, mut run: impl FnMut(usize, usize, &[u16])) {
        let n = self.segments.len();
        for (s, seg) in self.segments.iter().enumerate().skip(1) {
            let (component, row) = match seg.owner {
                Owner::Face => (p.face - lo.face, s),
                Owner::Corner => (p.corner - lo.corner, s),
                Owner::Edge => (p.edge - lo.edge, p.pattern() * n + s),
                Owner::Vertex => unreachable!("only segment 0 holds vertex points"),
            };
            run(s, seg.unit * component as usize, self.slots.row(row));
        }
    }

    /// Memory held, in bytes.
    pub fn bytes(&self) -> usize {
        self.patches.len() * size_of::<Patch>()
            + self.chunks.len() * size_of::<Starts>()
            + self.irregular.len() * 4
            + self.irregular_rows.bytes()
            + self.slots.bytes()
    }
}

/// The grid position (row-major, side `s`) of the point `t` steps along edge `j` from
/// corner `j`.
#[inline]
pub(crate) fn edge_grid(s: usize, j: usize, t: usize) -> usize {
    let (x, y) = match j {
        0 => (t, 0),
        1 => (s - 1, t),
        2 => (s - 1 - t, s - 1),
        _ => (0, s - 1 - t),
    };
    y * s + x
}

/// Where the layout stores grid point `row_major` (`y · s + x`): column-major, `x · s + y`,
/// because the kernel computes the grid by lines of constant `x`.
fn grid_index(s: usize, row_major: usize) -> u16 {
    let (x, y) = (row_major % s, row_major / s);
    u16::try_from(x * s + y).expect("small grid")
}

/// The slot table of a level whose grids have side `s`, from the writes of one face's
/// blocks and one edge's blocks (which cover each block's slots exactly once: [`Grids::writes`]
/// checks it). A Segment's row lists its writes' grid points by offset; an edge segment's,
/// for each pattern, those of edge 0, 1, 2, 3 in turn where owned, along the edge or (flipped)
/// against it.
fn slots(segments: &[Segment], face_writes: &[Write], edge_writes: &[Write], s: usize) -> Slots {
    let mut sorted = [face_writes, edge_writes].concat();
    sorted.sort_unstable_by_key(|w| (w.segment, w.offset));
    let writes = |segment: usize| {
        let at = |w: &Write| usize::from(w.segment).cmp(&segment);
        let first = sorted.partition_point(|w| at(w).is_lt());
        let end = sorted.partition_point(|w| at(w).is_le());
        &sorted[first..end]
    };
    let mut table = Slots {
        offsets: vec![0],
        grid: Vec::new(),
    };
    for pattern in 0..PATTERNS {
        for (i, seg) in segments.iter().enumerate() {
            if seg.owner == Owner::Edge {
                for j in (0..4).filter(|&j| pattern & (1 << j) != 0) {
                    let flipped = pattern & (16 << j) != 0;
                    table.grid.extend(writes(i).iter().map(|w| {
                        let t = w.grid as usize;
                        let t = if flipped { s - 1 - t } else { t };
                        grid_index(s, edge_grid(s, j, t))
                    }));
                }
            } else if pattern == 0 && seg.owner != Owner::Vertex {
                let grid = writes(i).iter().map(|w| grid_index(s, w.grid as usize));
                table.grid.extend(grid);
            }
            table.offsets.push(to_u32(table.grid.len()));
        }
    }
    table
}

/// For each face, the first edge that first appears in it or later (level-0 edges are
/// numbered by first appearance walking the faces); `None` if the numbering is otherwise.
fn edge_starts(base: &Level) -> Option<Vec<u32>> {
    let mut starts = vec![0u32; base.face_count() + 1];
    let mut last = 0;
    for e in 0..base.edge_count() {
        let first = *base.edge_faces.row(e).iter().min()? as usize;
        if first < last {
            return None;
        }
        last = first;
        starts[first + 1] += 1;
    }
    running_totals(&mut starts);
    Some(starts)
}

/// Interior, manifold, smooth vertices of valence four whose four faces are quads and whose
/// edges and self are not sharp: the vertices around which Catmull-Clark is the B-spline rule.
fn regular_vertices(base: &Level) -> Vec<bool> {
    (0..base.vertex_count)
        .into_par_iter()
        .map(|v| {
            let faces = base.vert_faces.row(v);
            let edges = base.vert_edges.row(v);
            faces.len() == 4
                && edges.len() == 4
                && !base.vertex_nonmanifold[v]
                && base.vertex_sharpness[v] == 0.0
                && faces
                    .iter()
                    .all(|&f| base.face_verts.range(f as usize).len() == 4)
                && edges.iter().all(|&e| {
                    let e = e as usize;
                    base.edge_sharpness[e] == 0.0
                        && !base.edge_nonmanifold[e]
                        && base.edge_faces.range(e).len() == 2
                })
        })
        .collect()
}

/// The face across edge `j` of face `f`, and that edge's place in it.
fn across(base: &Level, f: usize, j: usize) -> Option<(usize, usize)> {
    let e = base.face_edges[base.face_verts.offsets[f] as usize + j] as usize;
    let range = base.edge_faces.range(e);
    if range.len() != 2 {
        return None;
    }
    range
        .map(|i| {
            let g = base.edge_faces.items[i] as usize;
            (g, usize::from(base.edge_face_local[i]))
        })
        .find(|&(g, _)| g != f)
}

/// The 4 × 4 control points of face `f` if it is a regular quad, row-major as in
/// [`Patch::points`].
fn control_points(base: &Level, regular: &[bool], f: usize) -> Option<[u32; 16]> {
    let fv = base.face_verts.row(f);
    if fv.len() != 4 || !fv.iter().all(|&v| regular[v as usize]) {
        return None;
    }
    if (0..4).any(|i| fv[(i + 1)..].contains(&fv[i])) {
        return None;
    }
    // Corner j sits at CORNER[j]; edge j runs along DIR[j]; its far side is OUT[j].
    const CORNER: [(i32, i32); 4] = [(1, 1), (2, 1), (2, 2), (1, 2)];
    const DIR: [(i32, i32); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];
    const OUT: [(i32, i32); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];
    let mut points = [u32::MAX; 16];
    let mut put = |(x, y): (i32, i32), v: u32| points[(y * 4 + x) as usize] = v;
    let add = |a: (i32, i32), b: (i32, i32)| (a.0 + b.0, a.1 + b.1);
    let sub = |a: (i32, i32), b: (i32, i32)| (a.0 - b.0, a.1 - b.1);
    for j in 0..4 {
        put(CORNER[j], fv[j]);
        // Across edge j (corner j → j+1), the neighbour runs j+1 → j, then on to the points
        // beyond corner j and corner j+1.
        let (g, m) = across(base, f, j)?;
        let gv = base.face_verts.row(g);
        if gv.len() != 4 {
            return None;
        }
        put(add(CORNER[j], OUT[j]), gv[(m + 2) % 4]);
        put(add(CORNER[(j + 1) % 4], OUT[j]), gv[(m + 3) % 4]);
        // Across the neighbour's next edge (corner j → beyond it) lies the diagonal quad.
        let (h, q) = across(base, g, (m + 1) % 4)?;
        let hv = base.face_verts.row(h);
        if hv.len() != 4 {
            return None;
        }
        put(sub(add(CORNER[j], OUT[j]), DIR[j]), hv[(q + 3) % 4]);
    }
    Some(points)
}

/// Reads a regular face's refined points off the last level's faces.
struct Grids<'a> {
    base: &'a Level,
    levels: usize,
    last_faces: &'a Csr,
}

impl Grids<'_> {
    /// The last-level vertex at each point of face `f`'s `S × S` grid (row-major, corner 0 at
    /// the origin, edge 0 along the first row). The `4^levels` last-level faces of a level-0
    /// quad are consecutive, child `j` of a quad sits at its corner `j` with the same
    /// orientation (`crate::refine`), so a face's index spells its cell in base 4.
    fn grid(&self, f: usize) -> Option<Vec<u32>> {
        const OFFSET: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];
        let n = self.levels;
        let s = (1 << n) + 1;
        let first = (self.base.face_verts.offsets[f] as usize) << (2 * (n - 1));
        let mut grid = vec![u32::MAX; s * s];
        for leaf in 0..1usize << (2 * n) {
            let (mut x, mut y) = (0, 0);
            for k in 0..n {
                let digit = (leaf >> (2 * (n - 1 - k))) & 3;
                x += OFFSET[digit].0 << (n - 1 - k);
                y += OFFSET[digit].1 << (n - 1 - k);
            }
            let verts = self.last_faces.row(first + leaf);
            for (c, &(dx, dy)) in OFFSET.iter().enumerate() {
                let slot = &mut grid[(y + dy) * s + x + dx];
                if *slot != u32::MAX && *slot != verts[c] {
                    return None;
                }
                *slot = verts[c];
            }
        }
        Some(grid)
    }

    /// The face and edge writes, read off regular face `f`.
    fn writes(&self, f: usize, segments: &[Segment]) -> Option<(Vec<Write>, Vec<Write>)> {
        let grid = self.grid(f)?;
        let base = self.base;
        let s = (1 << self.levels) + 1;
        let corner = base.face_verts.offsets[f] as usize;
        let find = |vertex: u32| {
            let i = segments.partition_point(|seg| seg.start <= vertex as usize) - 1;
            let seg = &segments[i];
            (i, seg, vertex as usize - seg.start)
        };
        let mut face_writes = Vec::new();
        for y in 1..s - 1 {
            for x in 1..s - 1 {
                let (i, seg, at) = find(grid[y * s + x]);
                let index = match seg.owner {
                    Owner::Face => f,
                    Owner::Corner => corner,
                    Owner::Vertex | Owner::Edge => return None,
                };
                let offset = at.checked_sub(seg.unit * index)?;
                let len = if seg.owner == Owner::Face { 1 } else { 4 };
                if offset >= seg.unit * len {
                    return None;
                }
                face_writes.push(write(i, offset, y * s + x));
            }
        }
        let e = base.face_edges[corner] as usize;
        let forward = base.edge_verts[e][0] == base.face_verts.items[corner];
        let mut edge_writes = Vec::new();
        for t in 1..s - 1 {
            let (i, seg, at) = find(grid[edge_grid(s, 0, t)]);
            if seg.owner != Owner::Edge {
                return None;
            }
            let offset = at.checked_sub(seg.unit * e)?;
            if offset >= seg.unit {
                return None;
            }
            edge_writes.push(write(i, offset, if forward { t } else { s - 1 - t }));
        }
        // Every slot of a quad's blocks and of an edge's blocks, once.
        let slots = |owners: &[Owner], len: usize| -> usize {
            segments
                .iter()
                .filter(|seg| owners.contains(&seg.owner))
                .map(|seg| seg.unit * if seg.owner == Owner::Corner { len } else { 1 })
                .sum()
        };
        let distinct = |w: &[Write]| {
            let mut keys: Vec<(u16, u32)> = w.iter().map(|w| (w.segment, w.offset)).collect();
            keys.sort_unstable();
            keys.dedup();
            keys.len() == w.len()
        };
        let complete = slots(&[Owner::Face, Owner::Corner], 4) == face_writes.len()
            && slots(&[Owner::Edge], 1) == edge_writes.len()
            && distinct(&face_writes)
            && distinct(&edge_writes);
        complete.then_some((face_writes, edge_writes))
    }
}

fn write(segment: usize, offset: usize, grid: usize) -> Write {
    Write {
        segment: u16::try_from(segment).expect("few segments"),
        offset: to_u32(offset),
        grid: u16::try_from(grid).expect("small grid"),
    }
}

/// Checks a candidate face's refined topology against the writes and makes its patch.
struct Layout<'a> {
    base: &'a Level,
    segments: &'a [Segment],
    face_writes: &'a [Write],
    edge_writes: &'a [Write],
    edge_start: &'a [u32],
    side: usize,
}

impl Layout<'_> {
    fn patch(&self, f: usize, points: [u32; 16], grid: &[u32]) -> Option<Patch> {
        let base = self.base;
        let s = self.side;
        let range = base.face_verts.range(f);
        let (fv, fe) = (
            &base.face_verts.items[range.clone()],
            &base.face_edges[range],
        );
        let corner = base.face_verts.offsets[f] as usize;
        let index = |seg: &Segment| match seg.owner {
            Owner::Face => f,
            _ => corner,
        };
        let faces_ok = self.face_writes.iter().all(|w| {
            let seg = &self.segments[w.segment as usize];
            grid[w.grid as usize] as usize == seg.block(index(seg)) + w.offset as usize
        });
        let corners_ok = (0..4).all(|j| grid[edge_grid(s, j, 0)] == fv[j]);
        let (mut owned, mut flipped, mut rank) = (0u8, 0u8, 0);
        for j in 0..4 {
            let e = fe[j] as usize;
            let forward = base.edge_verts[e][0] == fv[j];
            flipped |= u8::from(!forward) << j;
            let edges_ok = self.edge_writes.iter().all(|w| {
                let seg = &self.segments[w.segment as usize];
                let t = w.grid as usize;
                let t = if forward { t } else { s - 1 - t };
                grid[edge_grid(s, j, t)] as usize == seg.block(e) + w.offset as usize
            });
            if !edges_ok {
                return None;
            }
            if base.edge_faces.row(e).iter().min() == Some(&to_u32(f)) {
                if e != self.edge_start[f] as usize + rank {
                    return None;
                }
                owned |= 1 << j;
                rank += 1;
            }
        }
        (faces_ok && corners_ok).then_some(Patch {
            points,
            face: to_u32(f),
            corner: to_u32(corner),
            edge: self.edge_start[f],
            owned,
            flipped,
            corners: 0,
            follows: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_of_two_levels() {
        // 9 vertices, 4 quads (16 corners), 12 edges: a 2 x 2 grid.
        let (segs, total) = segments(2, [9, 4, 16, 12]);
        let kinds: Vec<(Owner, usize)> = segs.iter().map(|s| (s.owner, s.unit)).collect();
        assert_eq!(
            kinds,
            vec![
                (Owner::Vertex, 1),
                (Owner::Face, 1),
                (Owner::Edge, 1),
                (Owner::Corner, 1),
                (Owner::Corner, 1),
                (Owner::Edge, 2),
            ]
        );
        // 5 x 5 per quad side: 81 vertices at level 2 of a 2 x 2 grid.
        assert_eq!(total, 81);
    }

    #[test]
    fn edge_grid_walks_the_boundary_counter_clockwise() {
        let s = 3;
        let walk: Vec<usize> = (0..4)
            .flat_map(|j| (0..2).map(move |t| edge_grid(s, j, t)))
            .collect();
        assert_eq!(walk, vec![0, 1, 2, 5, 8, 7, 6, 3]);
    }
}
