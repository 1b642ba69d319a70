//! The garment against itself: proximity repulsion, then continuous impacts with impact zones
//! as the fail-safe (Bridson, Fedkiw & Anderson 2002, §7.1 and §7.4).
//!
//! Both act on velocities, the positions following as x = x₀ + h v, so the start of the
//! substep, free of intersections, stays the reference. An impulse along a unit normal n acts
//! on the four vertices of a vertex–triangle pair (weights 1, −w₀, −w₁, −w₂ with w the
//! barycentric coordinates) or an edge–edge pair (1 − s, s, −(1 − u), −u), each moving by its
//! weight over its mass, which changes the relative velocity of the two contact points by the
//! impulse times Σ αₖ² / mₖ ([`Substep::push_apart`]). The normal-cone culling of the collide
//! crate keeps both queries cheap where the cloth is smooth.
//!
//! **What repulsion leaves alone.** A mesh with edges shorter than the thickness has, in its
//! rest shape, vertices within the thickness of faces a few rings around them. Repelling those
//! pairs fights the elastic forces that hold the rest shape: a 2.5 cm cotton strip with
//! 2.5 mm edges, clamped with 3 cm overhanging, droops to a 46° tip angle in 2 s without
//! self-collision, and only to 18° with it (5 mm thickness), its edges strained 10.5%; with
//! 1.25 mm edges its tip rose above the clamp. So repulsion skips every vertex–face pair
//! within [`REST_MARGIN`] thicknesses of each other *in the rest shape* that the surface
//! joins without leaving that distance ([`Hierarchy::local_faces`], found once at the model's
//! rest positions), as PhysBAM, the library of Bridson et al., omits the point–face pairs
//! within 1.5 repulsion thicknesses of the collision-free start positions
//! (`TRIANGLE_REPULSIONS::Turn_Off_Repulsions_Based_On_Current_Proximity`).
//!
//! Why the rest-shape distance, rather than a count of rings or a geodesic bound: what fights
//! the rest shape is exactly a pair that the rest shape itself puts within the thickness,
//! whatever the edge lengths (rings ignore them), while a fold that brings a vertex near a
//! face farther away in the rest shape is a real contact and is still repelled: across a fold
//! whose layers lie a thickness apart the facing points are π/2 thicknesses apart on the
//! surface, beyond the margin, so only the pairs across the crease itself are left alone.
//! Requiring the surface to join the pair keeps two layers modelled closer than the thickness
//! (a turned-back hem) repelling each other away from their common crease. Why the half
//! thickness to spare: with 2.5 mm edges the faces two rings out sit at exactly the
//! thickness, and the slightest squashing or bending of the droop brings them, and the ones
//! beyond them diagonally (5.6 mm at rest), within it; skipping only the pairs within the
//! thickness, the strip with 1.25 mm edges drooped to 34.7° in 1 s instead of 43.7°. The
//! price is in creases tighter than the margin on such a mesh: the pairs across them are left
//! to the impacts, whose zones strain the cloth around them more than repulsion did.
//!
//! The continuous impacts skip only pairs sharing a vertex, as Bridson et al. and ARCSim do:
//! an impact is a contact at zero distance, which a pair apart in the rest shape reaches only
//! by the cloth passing through itself, whatever their rest distance, and the fail-safe is
//! what keeps that from happening. With nothing near but the rest shape's own neighbours,
//! self-collision changes no bit of the motion: the strip droops exactly as without it.
//!
//! **Edge–edge pairs repel too** (Bridson et al. §7.1 repel both kinds): two layers of a
//! coarse mesh crossing at an angle meet edge to edge with no vertex over a face, and with
//! vertex–face repulsion alone nothing kept them a thickness apart. Two 3 cm strips crossing
//! on a floor came to rest with the upper one at the lower one's height, their edges 0.01 mm
//! apart where the impacts stopped them every substep; a 64² sheet dropped upright onto a
//! floor and crumpled into a pile met 1,380 vertex–triangle and 6,652 edge–edge impacts in the
//! first round of one resting substep, and a frame there cost 2 s. An edge skips the edges
//! lying on the faces around its ends (those the table lists for an end, or using it;
//! [`Hierarchy::edge_proximity`]): on a mesh finer than the thickness those are the pairs the
//! rest shape holds near, on a coarse one the pairs a fold within a face or two brings
//! together, which the impacts are left to, as a vertex's own faces are. Touching pairs (zero
//! distance) have no side to push to and are left to the impacts too.

use tailor_collide::{
    CollideError, EdgeProximity, Hierarchy, Impacts, LocalFaces, Neighbours, same_bits,
};
use tailor_subdiv::Point;

use crate::energy::Vec3;
use crate::substep::Substep;

/// Rounds of impact-zone merging before giving up (each merges at least two zones).
pub(super) const ZONE_ROUNDS: usize = 64;

/// Within how many thicknesses of each other in the rest shape a vertex and a face joined by
/// the surface do not repel (PhysBAM's default factor; see the module docs).
const REST_MARGIN: f64 = 1.5;

/// Fraction of the thickness two colliding points are set to separate by.
pub(super) const SEPARATION: f64 = 0.1;

/// The answers of the self-collision queries, kept from substep to substep so that each query
/// refills them instead of allocating, and the pairs repulsion leaves alone.
#[derive(Clone, Debug, Default)]
pub(super) struct Buffers {
    /// The faces around each vertex in the rest shape that repulsion skips.
    local: LocalFaces,
    near: Neighbours,
    edges_near: Vec<EdgeProximity>,
    impacts: SelfImpacts,
    /// The vertices an impulse round changed.
    touched: Vec<bool>,
}

impl Buffers {
    /// Empty buffers, and the faces around each vertex within [`REST_MARGIN`] times
    /// `thickness` at the `rest` positions (see the module docs), which repulsion skips.
    pub(super) fn new(
        cloth: &mut Hierarchy,
        rest: &[Point],
        thickness: f64,
    ) -> Result<Self, CollideError> {
        cloth.refit(rest, 0.0)?;
        Ok(Self {
            local: cloth.local_faces(REST_MARGIN * thickness)?,
            ..Self::default()
        })
    }
}

/// A mesh's continuous self impacts with the straight paths they answer, so that the next
/// query on the same starts asks again only of the vertices whose ends moved since
/// ([`Hierarchy::self_impacts_again`], the same lists as asking of the whole mesh): the rounds
/// of impulses and impact zones after the first query move a few vertices each. On the 128²
/// drape a substep took eleven rounds of a few impacts each, every one a query of the whole
/// mesh. When no other pass has refit the mesh since (its [`Hierarchy::refit_count`]), the
/// vertices found moved are the only ends its refit takes ([`Hierarchy::refit_swept_ends`]),
/// rather than the refit comparing every start and end once more.
#[derive(Clone, Debug, Default)]
pub(super) struct SelfImpacts {
    pub impacts: Impacts,
    start: Vec<Point>,
    end: Vec<Point>,
    moved: Vec<bool>,
    /// The vertices `moved` flags, in order.
    listed: Vec<u32>,
    /// The mesh's refit count after this query's own refit.
    fit: Option<u64>,
}

impl SelfImpacts {
    /// Refits `mesh` swept from `x0` to `x` and finds its self impacts; whether there is any.
    pub fn query(
        &mut self,
        mesh: &mut Hierarchy,
        x0: &[Point],
        x: &[Point],
    ) -> Result<bool, CollideError> {
        let answered = self.start.len() == x0.len()
            && self.end.len() == x.len()
            && self.start.iter().zip(x0).all(|(p, q)| same_bits(p, q));
        if answered {
            self.moved.clear();
            self.listed.clear();
            for (v, (p, q)) in x.iter().zip(&self.end).enumerate() {
                let moved = !same_bits(p, q);
                self.moved.push(moved);
                if moved {
                    self.listed.push(v as u32);
                }
            }
            if self.fit == Some(mesh.refit_count()) {
                if !self.listed.is_empty() {
                    mesh.refit_swept_ends(x, &self.listed)?;
                }
            } else {
                mesh.refit_swept(x0, x, 0.0)?;
            }
            if !self.listed.is_empty() {
                mesh.self_impacts_again(&self.moved, &mut self.impacts);
                for &v in &self.listed {
                    self.end[v as usize] = x[v as usize];
                }
            }
        } else {
            mesh.refit_swept(x0, x, 0.0)?;
            mesh.self_impacts_into(&mut self.impacts);
            self.start.clear();
            self.start.extend_from_slice(x0);
            self.end.clear();
            self.end.extend_from_slice(x);
        }
        self.fit = Some(mesh.refit_count());
        Ok(!(self.impacts.vertex_triangle.is_empty() && self.impacts.edge_edge.is_empty()))
    }
}

/// Repulsion's pairs at the substep's start `x0`: every vertex within `thickness` of a face,
/// and every edge within it of another, except the pairs the rest shape holds that near (the
/// faces around each vertex that `buffers` lists; see the module docs), into `buffers` for
/// [`repel`]. They depend on the start alone, so the simulator finds them beside the solve.
pub(super) fn find_near(
    cloth: &mut Hierarchy,
    thickness: f64,
    x0: &[Point],
    buffers: &mut Buffers,
) -> Result<(), CollideError> {
    let Buffers {
        local,
        near,
        edges_near,
        ..
    } = buffers;
    cloth.refit(x0, 0.0)?;
    cloth.self_proximity_into(thickness, local, near)?;
    cloth.edge_proximity_into(thickness, local, edges_near)
}

/// Repulsion on the pairs [`find_near`] found at the start of this substep: each stops
/// approaching and separates by a tenth of the overlap per substep; `moved` flags the
/// vertices whose velocities it changed.
pub(super) fn repel(
    cloth: &Hierarchy,
    thickness: f64,
    m: &mut Substep,
    buffers: &Buffers,
    moved: &mut [bool],
) {
    moved.fill(false);
    let Buffers {
        near, edges_near, ..
    } = buffers;
    let x0 = m.x0;
    let mut push = |vertices: [u32; 4], alpha: [f64; 4], normal: Vec3, distance: f64| {
        let target = SEPARATION * (thickness - distance) / m.h;
        if m.push_apart(&vertices, &alpha, normal, target) {
            for k in vertices {
                moved[k as usize] = true;
            }
        }
    };
    let triangles = cloth.triangles();
    for (p, point) in x0.iter().enumerate() {
        for c in near.of(p) {
            let [a, b, d] = triangles[c.triangle as usize];
            let normal = if c.distance > 0.0 {
                (point - c.point) / c.distance
            } else {
                c.normal
            };
            let w = c.barycentric;
            push(
                [p as u32, a, b, d],
                [1.0, -w[0], -w[1], -w[2]],
                normal,
                c.distance,
            );
        }
    }
    // An edge–edge pair pushes the first edge away from the second: along the direction from
    // the second's closest point to the first's. Touching pairs have no such direction (the
    // edges' plane normal does not say which side each is on) and are left to the impacts.
    let edges = cloth.edges();
    for e in edges_near.iter().filter(|e| e.distance > 0.0) {
        let ([a, b], [c, d]) = (edges[e.edges[0] as usize], edges[e.edges[1] as usize]);
        let [s, u] = e.parameters;
        push(
            [a, b, c, d],
            [1.0 - s, s, u - 1.0, -u],
            -e.direction,
            e.distance,
        );
    }
    // Only after a change: strain limiting leaves x and x₀ + h v apart by rounding, and
    // repulsion that finds nothing to do leaves the substep's bits alone.
    if moved.contains(&true) {
        m.sync_positions();
    }
}

/// One contact of the continuous query as four weighted vertices and a unit normal at the
/// time of contact.
pub(super) struct Pair {
    pub vertices: [u32; 4],
    pub alpha: [f64; 4],
    /// The time of contact, a fraction of the substep.
    pub time: f64,
    /// Vertex–triangle (else edge–edge).
    pub triangle: bool,
}

impl Pair {
    /// The impacts of `mesh`'s last query.
    pub fn list(mesh: &Hierarchy, impacts: &Impacts) -> impl Iterator<Item = Self> {
        let triangles = mesh.triangles();
        let vt = impacts.vertex_triangle.iter().map(|i| {
            let [a, b, c] = triangles[i.triangle as usize];
            let w = i.barycentric;
            Self {
                vertices: [i.vertex, a, b, c],
                alpha: [1.0, -w[0], -w[1], -w[2]],
                time: i.time,
                triangle: true,
            }
        });
        let ee = impacts.edge_edge.iter().map(|i| {
            let ([a, b], [c, d]) = (i.edges[0], i.edges[1]);
            let [s, u] = i.parameters;
            Self {
                vertices: [a, b, c, d],
                alpha: [1.0 - s, s, u - 1.0, -u],
                time: i.time,
                triangle: false,
            }
        });
        vt.chain(ee)
    }

    /// Σ αₖ pₖ over positions `p`.
    fn combine(&self, p: &[Point]) -> Vec3 {
        self.vertices
            .iter()
            .zip(&self.alpha)
            .map(|(&k, &a)| p[k as usize].coords * a)
            .sum()
    }

    /// The contact normal at the time of impact of the motion from `x0` to `x`, pointing the
    /// way the first feature was relative to the second at the start, and the features' gap
    /// along it at the start; `None` when the normal is undefined.
    pub fn normal_and_gap(&self, x0: &[Point], x: &[Point]) -> Option<(Vec3, f64)> {
        let at = |k: u32| {
            let k = k as usize;
            x0[k] + (x[k] - x0[k]) * self.time
        };
        let [a, b, c, d] = self.vertices.map(at);
        let n = if self.triangle {
            (c - b).cross(&(d - b))
        } else {
            (b - a).cross(&(d - c))
        };
        let start = self.combine(x0);
        let n = if n.norm() > 0.0 { n } else { start };
        let n = n.try_normalize(0.0)?;
        let n = if start.dot(&n) < 0.0 { -n } else { n };
        Some((n, start.dot(&n)))
    }
}

/// One round of continuous self-collision: an impulse at every impact of the straight-line
/// motion, then positions again from velocities. `None` when there was no impact; else how
/// many impacts it handled and the vertices whose velocities it changed. A round stops two
/// features approaching at once, which strains the edges around them: the response relaxes
/// strain around the changed vertices before the next round, whose query checks that
/// relaxing crossed nothing, and after a few rounds leaves the rest to [`impact_zones`].
pub(super) fn impulse_round<'a>(
    cloth: &mut Hierarchy,
    thickness: f64,
    m: &mut Substep,
    buffers: &'a mut Buffers,
) -> Result<Option<(u32, &'a [bool])>, CollideError> {
    let Buffers {
        impacts, touched, ..
    } = buffers;
    touched.resize(m.v.len(), false);
    if !impacts.query(cloth, m.x0, m.x)? {
        return Ok(None);
    }
    touched.fill(false);
    let mut handled = 0;
    for pair in Pair::list(cloth, &impacts.impacts) {
        let Some((normal, gap)) = pair.normal_and_gap(m.x0, m.x) else {
            continue;
        };
        let target = (SEPARATION * thickness - gap) / m.h;
        if m.push_apart(&pair.vertices, &pair.alpha, normal, target) {
            for &k in &pair.vertices {
                touched[k as usize] = true;
            }
        }
        handled += 1;
    }
    m.sync_positions();
    Ok(Some((handled, touched)))
}

/// Merges the vertices of every remaining impact into zones that move together ([`Zones`]),
/// until no impact is left.
pub(super) fn impact_zones(
    cloth: &mut Hierarchy,
    m: &mut Substep,
    buffers: &mut Buffers,
) -> Result<u32, CollideError> {
    let impacts = &mut buffers.impacts;
    let mut zones = Zones::new(m.v.len());
    for _ in 0..ZONE_ROUNDS {
        impacts.query(cloth, m.x0, m.x)?;
        let before = zones.merged;
        for pair in Pair::list(cloth, &impacts.impacts) {
            zones.merge_all(&pair.vertices);
        }
        if zones.merged == before {
            break;
        }
        zones.move_together(m);
    }
    Ok(zones.merged)
}

/// Impact zones (Bridson et al. §7.4): sets of vertices, merged as impacts join them, that
/// move with one velocity, the mean of their movable vertices' (momentum kept), or, when a
/// zone holds vertices whose motion is prescribed (pins, attachments), the mean of theirs.
/// A zone translates rigidly, so two of its features cannot meet during the substep if they
/// did not touch at its start; the zones here translate rather than rotate.
pub(super) struct Zones {
    parent: Vec<u32>,
    /// How many merges were made.
    pub merged: u32,
    momentum: Vec<(Vec3, f64)>,
    held: Vec<(Vec3, u32)>,
}

impl Zones {
    /// Every one of `n` vertices its own zone.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            merged: 0,
            momentum: Vec::new(),
            held: Vec::new(),
        }
    }

    fn root(&mut self, mut k: u32) -> u32 {
        while self.parent[k as usize] != k {
            let up = self.parent[self.parent[k as usize] as usize];
            self.parent[k as usize] = up;
            k = up;
        }
        k
    }

    /// Puts `vertices` in one zone.
    pub fn merge_all(&mut self, vertices: &[u32]) {
        let Some((&first, rest)) = vertices.split_first() else {
            return;
        };
        let mut first = self.root(first);
        for &k in rest {
            let other = self.root(k);
            if other != first {
                let (lo, hi) = (first.min(other), first.max(other));
                self.parent[hi as usize] = lo;
                first = lo;
                self.merged += 1;
            }
        }
    }

    /// Gives every vertex its zone's velocity, and positions from velocities.
    pub fn move_together(&mut self, m: &mut Substep) {
        let n = m.v.len();
        self.momentum.clear();
        self.momentum.resize(n, (Vec3::zeros(), 0.0));
        self.held.clear();
        self.held.resize(n, (Vec3::zeros(), 0));
        for k in 0..n {
            let r = self.root(k as u32) as usize;
            let inverse = m.inverse_mass[k];
            if inverse > 0.0 {
                self.momentum[r].0 += m.v[k] / inverse;
                self.momentum[r].1 += 1.0 / inverse;
            } else {
                self.held[r].0 += m.v[k];
                self.held[r].1 += 1;
            }
        }
        for k in 0..n {
            if m.inverse_mass[k] > 0.0 {
                let r = self.root(k as u32) as usize;
                let (p, mass) = self.momentum[r];
                let (v, count) = self.held[r];
                m.v[k] = if count > 0 {
                    v / f64::from(count)
                } else {
                    p / mass
                };
            }
        }
        m.sync_positions();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two 4 × 4 sheets of unit quads, the second 1 above the first, as one mesh.
    fn two_sheets() -> (Vec<Point>, Vec<u32>, Vec<u32>) {
        let (mut positions, mut offsets, mut corners) = (Vec::new(), vec![0], Vec::new());
        for layer in 0..2u32 {
            let base = positions.len() as u32;
            for j in 0..5 {
                for i in 0..5 {
                    let wobble = 0.01 * f64::from((i * 7 + j * 3) % 5);
                    positions.push(Point::new(
                        f64::from(i),
                        f64::from(j),
                        f64::from(layer) + wobble,
                    ));
                }
            }
            for j in 0..4 {
                for i in 0..4 {
                    let v = base + j * 5 + i;
                    corners.extend([v, v + 1, v + 6, v + 5]);
                    offsets.push(corners.len() as u32);
                }
            }
        }
        (positions, offsets, corners)
    }

    /// Queries asked again, after the mesh was refit by others in between (statically, or
    /// swept to other ends) or not, answer as a query of a new mesh does.
    #[test]
    fn queries_asked_again_answer_as_a_new_query_whoever_refit_the_mesh() {
        let (x0, offsets, corners) = two_sheets();
        let mut mesh = Hierarchy::build(&x0, &offsets, &corners).unwrap();
        let mut kept = SelfImpacts::default();
        let fresh = |x: &[Point]| {
            let mut mesh = Hierarchy::build(&x0, &offsets, &corners).unwrap();
            let mut query = SelfImpacts::default();
            query.query(&mut mesh, &x0, x).unwrap();
            query.impacts
        };
        let moved = |x: &[Point], vertices: &[usize], dz: f64| {
            let mut x = x.to_vec();
            for &v in vertices {
                x[v].z += dz;
            }
            x
        };
        // The upper sheet falls through the lower one.
        let upper: Vec<usize> = (25..50).collect();
        let x1 = moved(&x0, &upper, -2.0);
        assert!(kept.query(&mut mesh, &x0, &x1).unwrap());
        assert!(kept.impacts == fresh(&x1), "the answers at x1");
        // A few of its vertices stay above.
        let x2 = moved(&x1, &[31, 32, 37], 2.0);
        kept.query(&mut mesh, &x0, &x2).unwrap();
        assert!(kept.impacts == fresh(&x2), "the answers at x2");
        // Another pass refits the mesh at the start, then one more vertex stays.
        mesh.refit(&x0, 0.0).unwrap();
        let x3 = moved(&x2, &[38], 2.0);
        kept.query(&mut mesh, &x0, &x3).unwrap();
        assert!(kept.impacts == fresh(&x3), "the answers at x3");
        // Another pass refits it swept to other ends; the same ends asked again, then one
        // vertex more.
        mesh.refit_swept(&x0, &x0, 0.0).unwrap();
        kept.query(&mut mesh, &x0, &x3).unwrap();
        assert!(kept.impacts == fresh(&x3), "the answers at x3");
        let x4 = moved(&x3, &[43], 2.0);
        kept.query(&mut mesh, &x0, &x4).unwrap();
        assert!(kept.impacts == fresh(&x4), "the answers at x4");
        assert_ne!(
            fresh(&x4),
            fresh(&x3),
            "the last vertex's move changes the answers"
        );
    }
}
