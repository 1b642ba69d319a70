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

use tailor_subdiv::csr::{Csr, group_into};

use crate::model::Springs;
use crate::substep::{Floor, HELD_MASS, Substep};

/// Most Gauss–Seidel sweeps over the edges per substep (the impact of the 128² drape on the
/// sphere takes about 120; 64 left it 12% strained).
pub const SWEEPS: usize = 256;

/// An edge past the limit is brought this fraction of the limit inside it, so that the
/// corrections of its neighbours do not push it straight back out.
const SLACK: f64 = 0.05;

/// No source reaches this vertex through edges.
const UNREACHED: u32 = u32::MAX;

/// The strain limiter of one garment: its edges' vertex adjacency, built once, and the
/// per-substep order of the edges.
#[derive(Clone, Debug)]
pub(crate) struct StrainLimiter {
    /// Edges at each vertex.
    incident: Csr,
    /// Edges by breadth-first depth from the sources, then the unreached ones.
    order: Vec<u32>,
    depth: Vec<u32>,
    /// The vertices `order` starts from: fixed ones, and after a collision pass the ones it
    /// moved.
    sources: Vec<bool>,
    /// The inverse masses of [`Self::limit_around`].
    weights: Vec<f64>,
    /// The breadth-first queue of [`Self::order_from`], and the row starts of its grouping
    /// of the edges by depth.
    queue: Vec<u32>,
    starts: Vec<u32>,
}

impl StrainLimiter {
    pub fn new(springs: &Springs, vertex_count: usize) -> Self {
        let ends = springs.verts.iter().enumerate();
        let incident = ends.flat_map(|(e, &[a, b])| [(a, e as u32), (b, e as u32)]);
        Self {
            incident: Csr::group_by(vertex_count, incident),
            order: (0..springs.verts.len() as u32).collect(),
            depth: vec![UNREACHED; vertex_count],
            sources: vec![false; vertex_count],
            weights: Vec::with_capacity(vertex_count),
            queue: Vec::with_capacity(vertex_count),
            starts: Vec::with_capacity(vertex_count + 3),
        }
    }

    /// Orders the edges outwards from the vertices `source` flags (breadth first, a fixed
    /// order), when that set changed since the last call.
    fn order_from(&mut self, springs: &Springs, source: impl Fn(usize) -> bool) {
        let n = self.depth.len();
        let same = (0..n).all(|v| self.sources[v] == source(v));
        if same && self.order.len() == springs.verts.len() {
            return;
        }
        for (v, f) in self.sources.iter_mut().enumerate() {
            *f = source(v);
        }
        self.depth.fill(UNREACHED);
        let queue = &mut self.queue;
        queue.clear();
        queue.extend((0..n as u32).filter(|&v| self.sources[v as usize]));
        for &v in queue.iter() {
            self.depth[v as usize] = 0;
        }
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head] as usize;
            head += 1;
            for &e in self.incident.row(v) {
                let [a, b] = springs.verts[e as usize];
                let other = if a as usize == v { b } else { a } as usize;
                if self.depth[other] == UNREACHED {
                    self.depth[other] = self.depth[v] + 1;
                    queue.push(other as u32);
                }
            }
        }
        // Edges by the depth of their nearer end, stably (the unreached last, at depth n).
        let depth = &self.depth;
        let by_depth = springs.verts.iter().enumerate().map(|(e, &[a, b])| {
            let d = depth[a as usize].min(depth[b as usize]);
            (if d == UNREACHED { n as u32 } else { d }, e as u32)
        });
        group_into(n + 1, by_depth, &mut self.starts, &mut self.order);
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
        if let Some(moved) = moved {
            self.order_from(springs, |v| inverse_mass[v] == 0.0 || moved[v]);
        } else {
            self.order_from(springs, |v| inverse_mass[v] == 0.0);
        }
        let edges = self.order.len();
        let inner = limit * (1.0 - SLACK);
        let mut corrections = 0;
        for sweep in 0..SWEEPS {
            let mut changed = false;
            for k in 0..edges {
                let e = self.order[if sweep % 2 == 0 { k } else { edges - 1 - k }] as usize;
                let ([a, b], rest) = (springs.verts[e], springs.rest[e]);
                let (a, b) = (a as usize, b as usize);
                let (mut wa, mut wb) = (inverse_mass[a], inverse_mass[b]);
                if sweep == 0 && self.depth[a] != self.depth[b] {
                    // Shock propagation: the end nearer the sources holds.
                    if self.depth[a] < self.depth[b] {
                        wa = 0.0;
                    } else {
                        wb = 0.0;
                    }
                }
                if wa + wb == 0.0 {
                    continue;
                }
                let d = x[b] - x[a];
                let length = d.norm();
                let (short, long) = ((1.0 - limit) * rest, (1.0 + limit) * rest);
                if (short..=long).contains(&length) || length == 0.0 {
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
                changed = true;
                corrections += 1;
            }
            if !changed {
                break;
            }
        }
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

#[cfg(test)]
mod tests {
    use tailor_subdiv::Point;

    use super::*;
    use crate::energy::Vec3;

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
