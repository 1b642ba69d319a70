//! Strain limiting: after each solve no edge is left stretched or squashed by more than a
//! fraction of its rest length.
//!
//! Provot, "Deformation Constraints in a Mass-Spring Model to Describe Rigid Cloth Behavior"
//! (Graphics Interface 1995): woven cloth barely stretches, but springs stiff enough to show
//! that make the system stiff and the steps small. Instead the springs keep a workable
//! stiffness and, after each step, every edge whose length is past its critical deformation
//! (10% in the paper) is brought back within it by moving its two ends along the edge, shared in
//! inverse proportion to their masses; an end whose position is prescribed (a pin, an
//! attachment) does not move, so the other end takes the whole correction. Provot corrects
//! stretched edges; edges squashed past the same fraction are lengthened here too, since
//! cloth buckles out of plane rather than compressing in it. An edge is brought [`SLACK`] of
//! the limit inside it rather than exactly to it, so that its neighbours' corrections do
//! not push it straight back out: brought exactly to the limit, the 64² drape's edges never
//! all settled and every substep ran all the sweeps; with the slack most end in under ten.
//!
//! The edges are visited in a fixed order (Gauss–Seidel, see [`StrainLimiter::limit`]),
//! sweep after sweep until none is past the limit or [`SWEEPS`] is reached; the result does
//! not depend on the thread count.
//! Each correction Δx of a vertex also changes its velocity by Δx / h, keeping the position
//! the one the velocity reaches over the substep. A vertex near the body has a [`Floor`] a
//! little above it: a correction that would take it below is shortened to end there (the
//! projection after would only push it back out and strain the edges again), and the edge's
//! other end takes what is left of the correction. After a
//! collision pass, [`StrainLimiter::limit_around`] runs the same sweeps with the vertices the
//! pass moved a hundred times heavier, so the cloth around them takes up the strain.

use tailor_subdiv::Point;
use tailor_subdiv::csr::Csr;

use crate::energy::Vec3;
use crate::model::Springs;
use crate::substep::{Floor, HELD_MASS, Substep};

/// Most Gauss–Seidel sweeps over the edges per substep (the impact of the 128² drape on the
/// sphere takes about 120; 64 left it 12% strained).
pub const SWEEPS: usize = 256;

/// An edge past the limit is brought this fraction of the limit inside it, so that the
/// corrections of its neighbours do not push it straight back out.
const SLACK: f64 = 0.05;

/// No source reaches this vertex through edges (or the search has not reached it yet).
const UNREACHED: u32 = u32::MAX;

/// An edge the order has not placed yet.
const UNPLACED: u32 = u32::MAX;

/// The strain limiter of one garment: its edges' vertex adjacency, built once, and the
/// per-substep order of the edges.
#[derive(Clone, Debug)]
pub(crate) struct StrainLimiter {
    /// The order of the edges' visits, from the fixed vertices, and after a collision pass
    /// also the ones it moved.
    order: EdgeOrder,
    /// The inverse masses of [`Self::limit_around`].
    weights: Vec<f64>,
    /// The places in `order` of the edges a sweep visits.
    pending: Pending,
    /// The positions the last call ended with, and its limit: an edge not pending then was
    /// within that limit at those positions.
    settled: Vec<Point>,
    settled_limit: f64,
    /// The edges pending at the start of a call, while the order is made again.
    carried: Vec<u32>,
}

impl StrainLimiter {
    pub fn new(springs: &Springs, vertex_count: usize) -> Self {
        let mut order = EdgeOrder::new(springs, vertex_count);
        order.restart(|_| false);
        Self {
            order,
            weights: Vec::with_capacity(vertex_count),
            pending: Pending::default(),
            settled: Vec::new(),
            settled_limit: 0.0,
            carried: Vec::new(),
        }
    }

    /// Brings every edge of `springs` within `limit` (a fraction, e.g. 0.1) of its rest
    /// length, moving the end positions and velocities of the substep `m` (a vertex of zero
    /// inverse mass does not move). Returns the number of corrections.
    ///
    /// The first sweep visits the edges outwards from the fixed vertices and moves only the
    /// end further from them (Guendelman, Bridson & Fedkiw's shock propagation, SIGGRAPH
    /// 2003): cloth hanging from pins or attachments is pulled back in one sweep instead of a
    /// correction diffusing one edge per sweep. Later sweeps alternate backwards and
    /// forwards with the mass-weighted split.
    pub fn limit(
        &mut self,
        springs: &Springs,
        limit: f64,
        m: &mut Substep,
        floors: &[Floor],
    ) -> u32 {
        self.sweep(springs, limit, m, floors, None)
    }

    /// The sweeps of [`Self::limit`], the first outwards from the fixed vertices and the ones
    /// `moved` flags, if any.
    ///
    /// A sweep visits only the edges [`Pending`] holds: an edge a visit finds within the
    /// limit leaves it, and every edge at a vertex that moves comes back, so a skipped edge
    /// is one whose ends have not moved since it was found within the limit, which its visit
    /// would find again. The positions the last call ended with are kept, and a call starts
    /// with the edges still pending and those at the vertices that have moved since, in the
    /// new order when the sources changed (every call after a collision pass: the edges are
    /// carried over by edge, not visited all again). The corrections, their order and so the
    /// bytes are those of visiting every edge; most sweeps touch a few hundred edges of
    /// thousands. On the 64² drape at one substep the limiter runs about 400 times, most of
    /// them after a collision pass, so the order is made only as far as the sweeps reach
    /// ([`EdgeOrder`]): made whole, a breadth-first pass over the mesh of about 0.1 ms, it
    /// was most of what the limiter spent.
    fn sweep(
        &mut self,
        springs: &Springs,
        limit: f64,
        m: &mut Substep,
        floors: &[Floor],
        moved: Option<&[bool]>,
    ) -> u32 {
        let Substep {
            h,
            x,
            v,
            inverse_mass,
            ..
        } = m;
        let h = *h;
        let comparable = self.settled.len() == x.len() && self.settled_limit == limit;
        let source = |v: usize| inverse_mass[v] == 0.0 || moved.is_some_and(|moved| moved[v]);
        let reordered = !self.order.starts_from(source);
        // The edges still pending from the last call, by edge: the new order moves their places.
        let mut carried = std::mem::take(&mut self.carried);
        carried.clear();
        if reordered {
            if comparable {
                carried.extend(self.pending.places().map(|k| self.order.edge(k)));
            }
            self.order.restart(source);
        }
        let Self {
            order,
            pending,
            settled,
            settled_limit,
            ..
        } = self;
        let edges = springs.verts.len();
        if !comparable {
            order.finish();
            pending.fill(edges);
        } else {
            if reordered {
                pending.clear(edges);
                for &e in &carried {
                    pending.insert(order.place(e));
                }
            }
            for (v, (now, then)) in x.iter().zip(settled.iter()).enumerate() {
                if now != then {
                    order.insert_around(v, pending);
                }
            }
        }
        self.carried = carried;
        let inner = limit * (1.0 - SLACK);
        let mut corrections = 0;
        for sweep in 0..SWEEPS {
            let forward = sweep % 2 == 0;
            let mut changed = false;
            // The next place to look from; what a visit brings back ahead of it is visited in
            // this sweep, what it brings back behind in the next.
            let mut cursor = if forward {
                Some(0)
            } else {
                edges.checked_sub(1)
            };
            loop {
                let found = cursor.and_then(|c| {
                    if forward {
                        pending.first_from(c)
                    } else {
                        pending.last_to(c)
                    }
                });
                let Some(k) = found else { break };
                cursor = if forward {
                    Some(k + 1)
                } else {
                    k.checked_sub(1)
                };
                let e = order.edge(k) as usize;
                let ([a, b], rest) = (springs.verts[e], springs.rest[e]);
                let (a, b) = (a as usize, b as usize);
                let (mut wa, mut wb) = (inverse_mass[a], inverse_mass[b]);
                let (depth_a, depth_b) = (order.depth[a], order.depth[b]);
                if sweep == 0 && depth_a != depth_b {
                    // Shock propagation: the end nearer the sources holds.
                    if depth_a < depth_b {
                        wa = 0.0;
                    } else {
                        wb = 0.0;
                    }
                }
                // An edge neither end of which may move now stays to be visited again.
                if wa + wb == 0.0 {
                    continue;
                }
                let d = x[b] - x[a];
                let length = d.norm();
                let (short, long) = ((1.0 - limit) * rest, (1.0 + limit) * rest);
                if (short..=long).contains(&length) {
                    pending.remove(k);
                    continue;
                }
                if length == 0.0 {
                    continue;
                }
                let goal = length.clamp((1.0 - inner) * rest, (1.0 + inner) * rest);
                // Moving a by +s·wa·d and b by −s·wb·d changes the length by −s (wa + wb) length.
                let s = (length - goal) / (length * (wa + wb));
                let (share_a, share_b) = (d * (s * wa), d * (-s * wb));
                let mut da = floors[a].clamp(x[a], share_a);
                let mut db = floors[b].clamp(x[b], share_b);
                // An end its floor stopped holds, and the other takes what is left of the
                // correction: else an end held heavier after a collision pass takes it a
                // ten-thousandth a sweep, and the edge stays past the limit.
                let (stopped_a, stopped_b) = (da != share_a, db != share_b);
                if stopped_a != stopped_b && (if stopped_a { wb } else { wa }) > 0.0 {
                    let d = (x[b] + db) - (x[a] + da);
                    let length = d.norm();
                    if length > 0.0 {
                        let rest_of = d * ((length - goal) / length);
                        if stopped_a {
                            db += floors[b].clamp(x[b] + db, -rest_of);
                        } else {
                            da += floors[a].clamp(x[a] + da, rest_of);
                        }
                    }
                }
                x[a] += da;
                v[a] += da / h;
                x[b] += db;
                v[b] += db / h;
                // The edge itself comes back with its ends: a floor may have kept it past
                // the limit.
                for (end, delta) in [(a, da), (b, db)] {
                    if delta != Vec3::zeros() {
                        order.insert_around(end, pending);
                    }
                }
                changed = true;
                corrections += 1;
            }
            if !changed {
                break;
            }
        }
        settled.clear();
        settled.extend_from_slice(x);
        *settled_limit = limit;
        corrections
    }

    /// [`Self::limit`] after a collision pass: the vertices `moved` flags count [`HELD_MASS`]
    /// times heavier and the first sweep goes outwards from them as from fixed vertices, so
    /// the cloth around them takes up the strain the pass left, in few sweeps, rather than
    /// undoing what it did.
    pub fn limit_around(
        &mut self,
        springs: &Springs,
        limit: f64,
        m: &mut Substep,
        floors: &[Floor],
        moved: &[bool],
    ) -> u32 {
        let mut weights = std::mem::take(&mut self.weights);
        weights.clear();
        weights.extend(
            m.inverse_mass
                .iter()
                .zip(moved)
                .map(|(&w, &moved)| if moved { w / HELD_MASS } else { w }),
        );
        let corrections = self.sweep(
            springs,
            limit,
            &mut m.weighted(&weights),
            floors,
            Some(moved),
        );
        self.weights = weights;
        corrections
    }
}

/// The order of the sweeps' visits: the edges by the breadth-first depth of their nearer
/// end from the source vertices, those of one depth by index, the edges no source reaches
/// last (by index).
///
/// Made as far as the sweeps need it: a depth's edges get their places when a sweep first
/// asks for one of them (or of a deeper edge), the search expanding one depth at a time.
/// After a collision pass the sources are the few vertices it moved and the sweeps rarely
/// reach beyond a few rings of edges around them, where a whole order would search the whole
/// mesh at each of the hundreds of calls a run makes. The places given are those of the
/// whole order, since every edge of a depth is placed before any deeper one; a vertex the
/// search has not reached yet is one depth past every placed edge, which compares with an
/// end of a placed edge as its depth would.
#[derive(Clone, Debug)]
struct EdgeOrder {
    /// Edges at each vertex.
    incident: Csr,
    /// The other end of each edge of `incident`, entry for entry.
    across: Vec<u32>,
    /// Each vertex's depth, [`UNREACHED`] where the search has not reached it.
    depth: Vec<u32>,
    /// The search's queue: the sources, then the vertices of each depth in turn.
    queue: Vec<u32>,
    /// Where the vertices of the next depth to place start in `queue`; every vertex before
    /// it has been expanded, so `queue` holds every vertex of that depth after it.
    next: usize,
    /// The depth whose edges are placed next.
    level: u32,
    /// The placed edges in order.
    order: Vec<u32>,
    /// Each edge's place, [`UNPLACED`] until it has one.
    place: Vec<u32>,
    /// Every edge is placed.
    complete: bool,
    /// The edges of one depth, while they are placed.
    scratch: Vec<u32>,
}

impl EdgeOrder {
    fn new(springs: &Springs, vertex_count: usize) -> Self {
        let ends = springs.verts.iter().enumerate();
        let incident = Csr::group_by(
            vertex_count,
            ends.flat_map(|(e, &[a, b])| [(a, e as u32), (b, e as u32)]),
        );
        let across = (0..vertex_count)
            .flat_map(|v| {
                incident.row(v).iter().map(move |&e| {
                    let [a, b] = springs.verts[e as usize];
                    if a as usize == v { b } else { a }
                })
            })
            .collect();
        Self {
            incident,
            across,
            depth: vec![UNREACHED; vertex_count],
            queue: Vec::with_capacity(vertex_count),
            next: 0,
            level: 0,
            order: Vec::with_capacity(springs.verts.len()),
            place: vec![UNPLACED; springs.verts.len()],
            complete: false,
            scratch: Vec::new(),
        }
    }

    /// Starts the order again from the vertices `source` flags; nothing is placed.
    fn restart(&mut self, source: impl Fn(usize) -> bool) {
        self.depth.fill(UNREACHED);
        self.queue.clear();
        for v in 0..self.depth.len() {
            if source(v) {
                self.depth[v] = 0;
                self.queue.push(v as u32);
            }
        }
        self.next = 0;
        self.level = 0;
        self.order.clear();
        self.place.fill(UNPLACED);
        self.complete = false;
    }

    /// Whether the order starts from exactly the vertices `source` flags (its depth 0).
    fn starts_from(&self, source: impl Fn(usize) -> bool) -> bool {
        (0..self.depth.len()).all(|v| (self.depth[v] == 0) == source(v))
    }

    /// The edge at place `k` (placed).
    fn edge(&self, k: usize) -> u32 {
        self.order[k]
    }

    /// Edge `e`'s place, placing as many depths as it takes.
    fn place(&mut self, e: u32) -> usize {
        while self.place[e as usize] == UNPLACED {
            self.place_next();
        }
        self.place[e as usize] as usize
    }

    /// Adds the places of the edges at vertex `v` to `pending`.
    fn insert_around(&mut self, v: usize, pending: &mut Pending) {
        for i in self.incident.range(v) {
            let e = self.incident.items[i];
            pending.insert(self.place(e));
        }
    }

    /// Places every edge.
    fn finish(&mut self) {
        while !self.complete {
            self.place_next();
        }
    }

    /// Places the edges of the next depth (those with an end there and none nearer), by
    /// index, and queues the vertices one deeper; when no vertex is that deep, the edges no
    /// source reaches, by index.
    fn place_next(&mut self) {
        debug_assert!(!self.complete, "every edge is placed");
        let (start, end) = (self.next, self.queue.len());
        if start == end {
            for (e, place) in self.place.iter_mut().enumerate() {
                if *place == UNPLACED {
                    *place = self.order.len() as u32;
                    self.order.push(e as u32);
                }
            }
            self.complete = true;
            return;
        }
        let level = self.level;
        self.scratch.clear();
        for &v in &self.queue[start..end] {
            let range = self.incident.range(v as usize);
            let (edges, others) = (&self.incident.items[range.clone()], &self.across[range]);
            for (&e, &other) in edges.iter().zip(others) {
                // UNREACHED is deeper than any depth: an end not reached yet is one deeper.
                if self.depth[other as usize] >= level {
                    self.scratch.push(e);
                }
            }
        }
        // An edge with both ends at this depth was found from each.
        self.scratch.sort_unstable();
        self.scratch.dedup();
        for &e in &self.scratch {
            self.place[e as usize] = self.order.len() as u32;
            self.order.push(e);
        }
        for k in start..end {
            let v = self.queue[k] as usize;
            for &other in &self.across[self.incident.range(v)] {
                let d = &mut self.depth[other as usize];
                if *d == UNREACHED {
                    *d = level + 1;
                    self.queue.push(other);
                }
            }
        }
        self.next = end;
        self.level = level + 1;
    }
}

/// A set of places `0..n` in the edge order, as bits, walked forwards or backwards while it
/// changes.
#[derive(Clone, Debug, Default)]
struct Pending {
    words: Vec<u64>,
}

impl Pending {
    /// No place of `0..n`.
    fn clear(&mut self, n: usize) {
        self.words.clear();
        self.words.resize(n.div_ceil(64), 0);
    }

    /// The places in the set, in order.
    fn places(&self) -> impl Iterator<Item = usize> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let k = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    w * 64 + k
                })
            })
        })
    }

    /// Every place `0..n`.
    fn fill(&mut self, n: usize) {
        self.words.clear();
        self.words.resize(n.div_ceil(64), u64::MAX);
        if !n.is_multiple_of(64) {
            let last = self.words.len() - 1;
            self.words[last] = (1 << (n % 64)) - 1;
        }
    }

    fn insert(&mut self, k: usize) {
        self.words[k / 64] |= 1 << (k % 64);
    }

    fn remove(&mut self, k: usize) {
        self.words[k / 64] &= !(1 << (k % 64));
    }

    /// The first place at or after `k`.
    fn first_from(&self, k: usize) -> Option<usize> {
        let mut w = k / 64;
        let mut bits = *self.words.get(w)? & (u64::MAX << (k % 64));
        loop {
            if bits != 0 {
                return Some(w * 64 + bits.trailing_zeros() as usize);
            }
            w += 1;
            bits = *self.words.get(w)?;
        }
    }

    /// The last place at or before `k`.
    fn last_to(&self, k: usize) -> Option<usize> {
        let mut w = k / 64;
        let mut bits = self.words[w] & (u64::MAX >> (63 - k % 64));
        loop {
            if bits != 0 {
                return Some(w * 64 + 63 - bits.leading_zeros() as usize);
            }
            w = w.checked_sub(1)?;
            bits = self.words[w];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs the limiter at 10% on a substep of 0.01 s ending at `x` with zero velocities,
    /// with `floors` (none if empty), after a collision pass that `moved` the
    /// vertices it flags (none if empty); returns the corrections and the velocities.
    fn run(
        springs: &Springs,
        inverse_mass: &[f64],
        x: &mut [Point],
        floors: &[Floor],
        moved: &[bool],
    ) -> (u32, Vec<Vec3>) {
        let x0 = x.to_vec();
        let n = inverse_mass.len();
        let mut v = vec![Vec3::zeros(); n];
        let mut m = Substep {
            h: 0.01,
            x0: &x0,
            x,
            v: &mut v,
            inverse_mass,
        };
        let free = vec![Floor::NONE; n];
        let floors = if floors.is_empty() { &free } else { floors };
        let mut limiter = StrainLimiter::new(springs, n);
        let corrections = if moved.is_empty() {
            limiter.limit(springs, 0.1, &mut m, floors)
        } else {
            limiter.limit_around(springs, 0.1, &mut m, floors, moved)
        };
        (corrections, v)
    }

    /// [`run`] with no contacts and no collision pass.
    fn limit(springs: &Springs, inverse_mass: &[f64], x: &mut [Point]) -> (u32, Vec<Vec3>) {
        run(springs, inverse_mass, x, &[], &[])
    }

    fn chain(lengths: &[f64]) -> (Springs, Vec<Point>) {
        let mut springs = Springs::default();
        let mut x = vec![Point::origin()];
        for (i, &l) in lengths.iter().enumerate() {
            springs.verts.push([i as u32, i as u32 + 1]);
            springs.rest.push(1.0);
            x.push(x[i] + Vec3::new(l, 0.0, 0.0));
        }
        (springs, x)
    }

    /// A 10 × 10 grid of unit cells with one diagonal each, every vertex displaced by up to
    /// a quarter of a cell (a fixed pseudo-random sequence): most edges past 10%.
    fn jumbled_grid() -> (Springs, Vec<Point>) {
        let side = 10;
        let at = |i: u32, j: u32| Point::new(f64::from(i), f64::from(j), 0.0);
        let mut springs = Springs::default();
        for j in 0..side {
            for i in 0..side {
                let v = j * side + i;
                let mut link = |w: u32, rest: f64| {
                    springs.verts.push([v, w]);
                    springs.rest.push(rest);
                };
                if i + 1 < side {
                    link(v + 1, 1.0);
                }
                if j + 1 < side {
                    link(v + side, 1.0);
                }
                if i + 1 < side && j + 1 < side {
                    link(v + side + 1, 2f64.sqrt());
                }
            }
        }
        let mut seed = 12345_u64;
        let mut jitter = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let x = (0..side * side)
            .map(|v| at(v % side, v / side) + Vec3::new(jitter(), jitter(), jitter()) * 0.5)
            .collect();
        (springs, x)
    }

    #[test]
    fn a_limiter_kept_from_call_to_call_gives_the_bytes_of_a_new_one() {
        // The kept limiter skips the edges it found within the limit whose ends have not
        // moved since, in the edges' new order when that changed; a new one visits every
        // edge. Between the calls vertices move, the vertices a collision pass moved change
        // and masses change (both reorder the edges), and the limit changes.
        let (springs, mut kept_x) = jumbled_grid();
        let n = kept_x.len();
        let mut fresh_x = kept_x.clone();
        let (mut kept_v, mut fresh_v) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        let mut inverse_mass = vec![1.0; n];
        inverse_mass[0] = 0.0;
        let mut floors = vec![Floor::NONE; n];
        floors[55] = Floor {
            normal: Vec3::z(),
            offset: kept_x[55].z - 0.01,
        };
        let mut kept = StrainLimiter::new(&springs, n);
        let nudge = |x: &mut [Point], v: usize, k: f64| x[v] += Vec3::new(0.3 * k, -0.2, 0.1);
        let mut moved = vec![false; n];
        let mut limit = 0.1;
        for call in 0..12 {
            // Calls 1, 5 and 8 keep the order; the others make it again (calls 2, 3, 4, 9,
            // 10 and 11 from other moved vertices), carrying the edges still pending.
            match call {
                2 => {
                    for v in [12, 13, 47, 90] {
                        moved[v] = true;
                    }
                }
                3 | 9 | 10 | 11 => moved[5 * call + 20] = true,
                4 => moved.fill(false),
                6 => inverse_mass[99] = 0.0,
                7 => limit = 0.05,
                _ => {}
            }
            if call != 5 {
                for v in [3 * call + 7, 50 + call, 81 - call] {
                    nudge(&mut kept_x, v, call as f64);
                    nudge(&mut fresh_x, v, call as f64);
                }
            }
            let x0 = kept_x.clone();
            let [kept_corrections, fresh_corrections] = [
                (&mut kept_x, &mut kept_v, &mut kept),
                (
                    &mut fresh_x,
                    &mut fresh_v,
                    &mut StrainLimiter::new(&springs, n),
                ),
            ]
            .map(|(x, v, limiter)| {
                let mut m = Substep {
                    h: 0.01,
                    x0: &x0,
                    x,
                    v,
                    inverse_mass: &inverse_mass,
                };
                limiter.limit_around(&springs, limit, &mut m, &floors, &moved)
            });
            assert!(
                fresh_corrections > 0 || call == 5,
                "call {call}: nothing to correct"
            );
            assert_eq!(
                kept_corrections, fresh_corrections,
                "call {call}: corrections"
            );
            assert_eq!(kept_x, fresh_x, "call {call}: positions");
            assert_eq!(kept_v, fresh_v, "call {call}: velocities");
        }
    }

    /// The whole order by its definition: depths by a breadth-first search from the sources,
    /// the edges sorted by the depth of their nearer end (the unreached last), then by index.
    fn whole_order(springs: &Springs, n: usize, sources: &[usize]) -> (Vec<u32>, Vec<usize>) {
        let mut depth = vec![UNREACHED; n];
        let mut queue: std::collections::VecDeque<usize> = sources.iter().copied().collect();
        for &v in sources {
            depth[v] = 0;
        }
        while let Some(v) = queue.pop_front() {
            for &[a, b] in &springs.verts {
                let (a, b) = (a as usize, b as usize);
                for (from, to) in [(a, b), (b, a)] {
                    if from == v && depth[to] == UNREACHED {
                        depth[to] = depth[v] + 1;
                        queue.push_back(to);
                    }
                }
            }
        }
        let mut edges: Vec<usize> = (0..springs.verts.len()).collect();
        edges.sort_by_key(|&e| {
            let [a, b] = springs.verts[e];
            (depth[a as usize].min(depth[b as usize]), e)
        });
        let mut place = vec![0; edges.len()];
        for (k, &e) in edges.iter().enumerate() {
            place[e] = k;
        }
        (depth, place)
    }

    #[test]
    fn edges_are_placed_where_the_whole_order_puts_them() {
        // The jumbled grid and a separate edge no source on the grid reaches.
        let (mut springs, _) = jumbled_grid();
        springs.verts.push([100, 101]);
        springs.rest.push(1.0);
        let n = 102;
        let edges = springs.verts.len();
        let mut order = EdgeOrder::new(&springs, n);
        for sources in [
            vec![],
            vec![0],
            vec![45],
            vec![12, 13, 47, 90],
            vec![100],
            vec![7, 101],
        ] {
            let (depth, whole) = whole_order(&springs, n, &sources);
            // Asked in a scrambled order, from near the sources outwards and back.
            order.restart(|v| sources.contains(&v));
            let asked = (0..edges).map(|i| (i * 97 + 31) % edges);
            for e in asked.clone().take(edges / 3) {
                assert_eq!(
                    order.place(e as u32),
                    whole[e],
                    "sources {sources:?}, edge {e}"
                );
                assert_eq!(order.edge(whole[e]), e as u32);
                // The ends of a placed edge compare as their depths do.
                let [a, b] = springs.verts[e].map(|v| v as usize);
                assert_eq!(
                    order.depth[a].cmp(&order.depth[b]),
                    depth[a].cmp(&depth[b]),
                    "sources {sources:?}, edge {e}"
                );
            }
            order.finish();
            for e in asked {
                assert_eq!(
                    order.place(e as u32),
                    whole[e],
                    "sources {sources:?}, edge {e}"
                );
            }
        }
    }

    #[test]
    fn a_stretched_edge_is_shortened_to_the_limit_sharing_by_inverse_mass() {
        let (springs, mut x) = chain(&[1.5]);
        let (n, v) = limit(&springs, &[1.0, 3.0], &mut x);
        let h = 0.01;
        assert_eq!(n, 1);
        // Past 10%, so brought to 9.5% (SLACK inside the limit): 0.405 of shortening, a
        // quarter at the heavy end, three quarters at the light one.
        assert!(((x[1] - x[0]).norm() - 1.095).abs() < 1e-12);
        assert!((x[0].x - 0.10125).abs() < 1e-12);
        assert!((x[1].x - 1.19625).abs() < 1e-12);
        assert!((v[0].x - 0.10125 / h).abs() < 1e-9 && (v[1].x + 0.30375 / h).abs() < 1e-9);
    }

    #[test]
    fn a_squashed_edge_is_lengthened_and_a_fixed_end_stays() {
        let (springs, mut x) = chain(&[0.5]);
        limit(&springs, &[0.0, 1.0], &mut x);
        assert_eq!(x[0], Point::origin());
        assert!((x[1].x - 0.905).abs() < 1e-12);
    }

    #[test]
    fn a_vertex_near_the_body_stops_at_its_floor() {
        // Squashed to half: lengthening to 0.905 would move b 0.2025 along +x, towards the
        // body behind its floor x ≤ 0.6 (normal −x); b stops there, and a takes what is left
        // of the correction at once: one correction brings the edge to 0.905.
        let (springs, mut x) = chain(&[0.5]);
        let floor = Floor {
            normal: -Vec3::x(),
            offset: -0.6,
        };
        let (n, v) = run(&springs, &[1.0, 1.0], &mut x, &[Floor::NONE, floor], &[]);
        assert_eq!(n, 1);
        assert!((x[1].x - 0.6).abs() < 1e-12, "{x:?}");
        assert!((x[0].x + 0.305).abs() < 1e-12, "{x:?}");
        assert!(x[0].x < 0.0 && v[0].x < 0.0 && v[1].x > 0.0);
        // The same with a ten thousand times heavier (a contact held after a collision
        // pass): it still takes all that b cannot. Sharing by mass alone, it moved a
        // ten-thousandth of what was left each sweep, and after every sweep the edge was
        // still 39% short.
        let (springs, mut x) = chain(&[0.5]);
        run(&springs, &[1e-4, 1.0], &mut x, &[Floor::NONE, floor], &[]);
        let length = (x[1] - x[0]).norm();
        assert!((length - 0.905).abs() < 1e-12, "{x:?}");
    }

    #[test]
    fn after_a_collision_pass_the_cloth_around_the_moved_vertices_gives_way() {
        // A chain of three, both edges 50% long, vertex 0 moved by a collision pass: the
        // first sweep goes outwards from it, so it stays and the others take the correction.
        let (springs, mut x) = chain(&[1.5, 1.5]);
        run(&springs, &[1.0; 3], &mut x, &[], &[true, false, false]);
        assert_eq!(x[0], Point::origin());
        assert!(
            (x[1].x - 1.095).abs() < 1e-12 && (x[2].x - 2.19).abs() < 1e-12,
            "{x:?}"
        );
        // Without the pass the same chain shares the correction from both ends.
        let (springs, mut x) = chain(&[1.5, 1.5]);
        limit(&springs, &[1.0; 3], &mut x);
        assert!(x[0].x > 0.0, "{x:?}");
    }

    #[test]
    fn edges_within_the_limit_are_untouched() {
        let (springs, mut x) = chain(&[1.05, 0.95, 1.0]);
        let before = x.clone();
        let (n, _) = limit(&springs, &[1.0; 4], &mut x);
        assert_eq!((n, x), (0, before));
    }

    #[test]
    fn sweeps_bring_a_chain_pulled_at_one_end_within_the_limit() {
        // A chain of ten unit edges pinned at 0, each 12% long after a step and the free end
        // yanked a further 30%: corrections must travel the whole chain.
        let mut lengths = vec![1.12; 9];
        lengths.push(1.4);
        let (springs, mut x) = chain(&lengths);
        let mut inverse = vec![1.0; 11];
        inverse[0] = 0.0;
        limit(&springs, &inverse, &mut x);
        let worst = (0..10)
            .map(|i| ((x[i + 1] - x[i]).norm() - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 0.1 + 1e-3, "worst strain {worst}");
        assert_eq!(x[0], Point::origin());
    }
}
