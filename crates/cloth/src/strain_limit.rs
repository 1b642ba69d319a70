//! Strain limiting: after each solve no edge is left stretched or squashed by more than a
//! fraction of its rest length.
//!
//! Provot, "Deformation Constraints in a Mass-Spring Model to Describe Rigid Cloth Behavior"
//! (Graphics Interface 1995): woven cloth barely stretches, but springs stiff enough to show
//! that make the system stiff and the steps small. Instead the springs keep a workable
//! stiffness and, after each step, every edge whose length is past its critical deformation
//! (10% in the paper) is brought back to it by moving its two ends along the edge, shared in
//! inverse proportion to their masses; an end whose position is prescribed (a pin, an
//! attachment) does not move, so the other end takes the whole correction. Provot corrects
//! stretched edges; edges squashed past the same fraction are lengthened here too, since
//! cloth buckles out of plane rather than compressing in it.
//!
//! The edges are visited in a fixed order (Gauss–Seidel, see [`StrainLimiter::limit`]),
//! sweep after sweep until none is past the limit or [`SWEEPS`] is reached; the result does
//! not depend on the thread count.
//! Each correction Δx of a vertex also changes its velocity by Δx / h, keeping the position
//! the one the velocity reaches over the substep.

use crate::collision::Motion as Substep;
use crate::model::Springs;

/// Most Gauss–Seidel sweeps over the edges per substep.
pub const SWEEPS: usize = 16;

/// No fixed vertex reaches this vertex through edges.
const UNREACHED: u32 = u32::MAX;

/// The strain limiter of one garment: its edges' vertex adjacency, built once, and the
/// per-substep order of the edges.
#[derive(Clone, Debug)]
pub(crate) struct StrainLimiter {
    /// Edges at each vertex, CSR.
    offsets: Vec<u32>,
    incident: Vec<u32>,
    /// Edges by breadth-first depth from the fixed vertices, then the unreached ones.
    order: Vec<u32>,
    depth: Vec<u32>,
    /// Which vertices were fixed when `order` was made.
    fixed: Vec<bool>,
}

impl StrainLimiter {
    pub fn new(springs: &Springs, vertex_count: usize) -> Self {
        let mut offsets = vec![0u32; vertex_count + 1];
        for &[a, b] in &springs.verts {
            offsets[a as usize + 1] += 1;
            offsets[b as usize + 1] += 1;
        }
        for i in 0..vertex_count {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut incident = vec![0u32; offsets[vertex_count] as usize];
        for (e, &[a, b]) in springs.verts.iter().enumerate() {
            for v in [a, b] {
                incident[fill[v as usize] as usize] = e as u32;
                fill[v as usize] += 1;
            }
        }
        Self {
            offsets,
            incident,
            order: (0..springs.verts.len() as u32).collect(),
            depth: vec![UNREACHED; vertex_count],
            fixed: vec![false; vertex_count],
        }
    }

    /// Orders the edges outwards from the vertices with zero inverse mass (breadth first, a
    /// fixed order), when that set changed since the last call.
    fn order_from_fixed(&mut self, springs: &Springs, inverse_mass: &[f64]) {
        let same = self
            .fixed
            .iter()
            .zip(inverse_mass)
            .all(|(&f, &w)| f == (w == 0.0));
        if same && self.order.len() == springs.verts.len() {
            return;
        }
        for (f, &w) in self.fixed.iter_mut().zip(inverse_mass) {
            *f = w == 0.0;
        }
        self.depth.fill(UNREACHED);
        let mut queue: Vec<u32> = (0..inverse_mass.len() as u32)
            .filter(|&v| self.fixed[v as usize])
            .collect();
        for &v in &queue {
            self.depth[v as usize] = 0;
        }
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head] as usize;
            head += 1;
            let row = self.offsets[v] as usize..self.offsets[v + 1] as usize;
            for &e in &self.incident[row] {
                let [a, b] = springs.verts[e as usize];
                let other = if a as usize == v { b } else { a } as usize;
                if self.depth[other] == UNREACHED {
                    self.depth[other] = self.depth[v] + 1;
                    queue.push(other as u32);
                }
            }
        }
        let depth = &self.depth;
        let key = |e: &u32| {
            let [a, b] = springs.verts[*e as usize];
            depth[a as usize].min(depth[b as usize])
        };
        self.order = (0..springs.verts.len() as u32).collect();
        self.order.sort_by_key(key);
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
    pub fn limit(&mut self, springs: &Springs, limit: f64, m: &mut Substep) -> u32 {
        let Substep {
            h,
            x,
            v,
            inverse_mass,
            ..
        } = m;
        let h = *h;
        self.order_from_fixed(springs, inverse_mass);
        let edges = self.order.len();
        let mut corrections = 0;
        for sweep in 0..SWEEPS {
            let mut changed = false;
            for k in 0..edges {
                let e = self.order[if sweep % 2 == 0 { k } else { edges - 1 - k }] as usize;
                let ([a, b], rest) = (springs.verts[e], springs.rest[e]);
                let (a, b) = (a as usize, b as usize);
                let (mut wa, mut wb) = (inverse_mass[a], inverse_mass[b]);
                if sweep == 0 && self.depth[a] != self.depth[b] {
                    // Shock propagation: the end nearer the fixed vertices holds.
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
                let goal = length.clamp((1.0 - limit) * rest, (1.0 + limit) * rest);
                if goal == length || length == 0.0 {
                    continue;
                }
                // Moving a by +s·wa·d and b by −s·wb·d changes the length by −s (wa + wb) length.
                let s = (length - goal) / (length * (wa + wb));
                let da = d * (s * wa);
                let db = d * (-s * wb);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Vec3;
    use tailor_subdiv::Point;

    /// Runs the limiter at 10% on a substep of 0.01 s ending at `x` with zero velocities;
    /// returns the corrections and the velocities.
    fn limit(springs: &Springs, inverse_mass: &[f64], x: &mut [Point]) -> (u32, Vec<Vec3>) {
        let x0 = x.to_vec();
        let mut v = vec![Vec3::zeros(); x.len()];
        let mut m = Substep {
            h: 0.01,
            x0: &x0,
            x,
            v: &mut v,
            inverse_mass,
        };
        let n = StrainLimiter::new(springs, inverse_mass.len()).limit(springs, 0.1, &mut m);
        (n, v)
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
        assert!(((x[1] - x[0]).norm() - 1.1).abs() < 1e-12);
        // 0.4 of shortening, a quarter at the heavy end, three quarters at the light one.
        assert!((x[0].x - 0.1).abs() < 1e-12);
        assert!((x[1].x - 1.2).abs() < 1e-12);
        assert!((v[0].x - 0.1 / h).abs() < 1e-9 && (v[1].x + 0.3 / h).abs() < 1e-9);
    }

    #[test]
    fn a_squashed_edge_is_lengthened_and_a_fixed_end_stays() {
        let (springs, mut x) = chain(&[0.5]);
        limit(&springs, &[0.0, 1.0], &mut x);
        assert_eq!(x[0], Point::origin());
        assert!((x[1].x - 0.9).abs() < 1e-12);
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
