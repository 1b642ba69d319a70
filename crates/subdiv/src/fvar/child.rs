//! The face-varying topology of a child level, inherited from its parent
//! (OpenSubdiv's `Vtr::FVarRefinement::applyRefinement`, `opensubdiv/vtr/fvarRefinement.cpp`).
//!
//! No analysis is repeated: child values follow the parent's.
//! - A vertex point has one value per parent value when the parent vertex is mismatched, else
//!   one; its siblings, tags and crease ends are copied.
//! - A face point has a single matching value.
//! - An edge point has one value per incident face when the parent edge is a seam, else one;
//!   its values are creases (corners under linear-boundary modes) along the two child faces of
//!   each parent face when the parent edge was a seam or linear boundary.
//!
//! Child values are numbered like child vertices (vertex points, face points, edge points), each
//! vertex's values consecutively. Semi-sharp values whose sharpness has decayed become creases
//! (`reclassifySemisharpValues`).

use super::level::{EdgeTag, FVarLevel, Mode, ValueTag, has_semi_sharp_edges};
use crate::csr::offsets_from_counts;
use crate::mesh::to_u32;
use crate::refine::Refinement;
use crate::rules::crease;
use crate::topology::Level;

impl FVarLevel {
    /// The child of `self` (on level `p`) through `step`.
    pub(crate) fn refine(&self, p: &Level, step: &Refinement, mode: &Mode) -> Self {
        let c = &step.child;
        let (nv, nf, ne) = (p.vertex_count, p.face_count(), p.edge_count());
        let matched = |v: usize| !self.tags[self.offsets[v] as usize].mismatch;
        let edge_values = |e: usize| {
            if self.edge_tags[e].mismatch {
                p.edge_faces.range(e).len().max(1)
            } else {
                1
            }
        };
        let counts = (0..nv)
            .map(|v| if matched(v) { 1 } else { self.count(v) })
            .chain(std::iter::repeat_n(1, nf))
            .chain((0..ne).map(edge_values))
            .map(to_u32);
        let offsets = offsets_from_counts(counts);
        let slots = *offsets.last().expect("offsets") as usize;
        let mut child = Self {
            face_values: Vec::new(),
            edge_tags: vec![EdgeTag::default(); p.face_verts.items.len()],
            face_siblings: vec![0; c.vert_faces.items.len()],
            slot_values: (0..to_u32(slots)).collect(),
            tags: vec![ValueTag::default(); slots],
            crease_ends: vec![[0, 0]; slots],
            value_count: slots,
            offsets,
        };
        child
            .edge_tags
            .extend(self.edge_tags.iter().flat_map(|&t| [t, t]));
        let split = if mode.linear_boundaries {
            ValueTag::MISMATCH
        } else {
            ValueTag::CREASE
        };
        // Vertex points: siblings, tags and crease ends of the parent values.
        for v in 0..nv {
            let cs = child.slots(v);
            let ps = self.offsets[v] as usize;
            if cs.len() > 1 {
                let (pr, cr) = (p.vert_faces.range(v), c.vert_faces.range(v));
                child.face_siblings[cr].copy_from_slice(&self.face_siblings[pr]);
            }
            for (k, slot) in cs.enumerate() {
                let tag = self.tags[ps + k];
                child.tags[slot] = tag;
                if !tag.is_inf_sharp() {
                    child.crease_ends[slot] = self.crease_ends[ps + k];
                }
            }
        }
        // Edge points on seams: one value per parent face, each over its two child faces.
        let layout = step.layout;
        for e in 0..ne {
            let cv = layout.edges + e;
            let cs = child.slots(cv);
            let tag = self.edge_tags[e];
            if cs.len() > 1 {
                for (k, i) in c.vert_faces.range(cv).enumerate() {
                    child.face_siblings[i] = (k / 2) as u16;
                }
            }
            if tag.mismatch || tag.linear {
                for (k, slot) in cs.enumerate() {
                    child.tags[slot] = split;
                    if !split.is_inf_sharp() {
                        child.crease_ends[slot] = [(2 * k) as u16, (2 * k + 1) as u16];
                    }
                }
            }
        }
        if !mode.linear_boundaries {
            child.reclassify_semi_sharp(p, c, mode);
        }
        child.face_values_from_siblings(c);
        child
    }

    /// Turns semi-sharp values of vertex points into creases once no semi-sharp feature is
    /// left in their span (`FVarRefinement::reclassifySemisharpValues`).
    fn reclassify_semi_sharp(&mut self, p: &Level, c: &Level, mode: &Mode) {
        let to_crease = |tag: &mut ValueTag| *tag = ValueTag::CREASE;
        for v in 0..p.vertex_count {
            let slots = self.slots(v);
            if !self.tags[slots.start].mismatch {
                continue;
            }
            if !crease::is_semi_sharp(p.vertex_sharpness[v]) && !has_semi_sharp_edges(p, v) {
                continue;
            }
            if crease::is_sharp(c.vertex_sharpness[v]) {
                continue;
            }
            if !has_semi_sharp_edges(c, v) {
                for tag in &mut self.tags[slots] {
                    if tag.semi_sharp {
                        to_crease(tag);
                    }
                }
                continue;
            }
            let edges = c.vert_edges.row(v);
            for slot in slots.clone() {
                let tag = self.tags[slot];
                if tag.semi_sharp && !tag.dep_sharp {
                    let still = self
                        .span_interior_edges(slot, edges.len())
                        .any(|i| crease::is_semi_sharp(c.edge_sharpness[edges[i] as usize]));
                    if !still {
                        to_crease(&mut self.tags[slot]);
                    }
                }
            }
            if slots.len() == 2 && mode.dependent {
                let (a, b) = (slots.start, slots.start + 1);
                if self.tags[a].dep_sharp && !self.tags[b].semi_sharp {
                    self.tags[a].dep_sharp = false;
                } else if self.tags[b].dep_sharp && !self.tags[a].semi_sharp {
                    self.tags[b].dep_sharp = false;
                }
            }
        }
    }

    /// The weight of the corner rule for a semi-sharp value decaying to a crease: the
    /// fractional weight of the sharpness inside its span (`FVarRefinement::getFractionalWeight`).
    pub(crate) fn fractional_weight(
        &self,
        p: &Level,
        c: &Level,
        method: crate::options::CreaseMethod,
        v: usize,
        sibling: usize,
    ) -> f32 {
        let (pe, ce) = (p.vert_edges.row(v), c.vert_edges.row(v));
        let slot = self.offsets[v] as usize + sibling;
        let (parent, child): (Vec<f32>, Vec<f32>) = self
            .span_interior_edges(slot, pe.len())
            .map(|i| {
                (
                    p.edge_sharpness[pe[i] as usize],
                    c.edge_sharpness[ce[i] as usize],
                )
            })
            .unzip();
        crease::fractional_weight_at_vertex(
            method,
            p.vertex_sharpness[v],
            c.vertex_sharpness[v],
            &parent,
            &child,
        )
    }
}
