//! Whether a shot met its quality. A run that stretches the cloth past its strain limit, or
//! leaves it in the body or through itself, still writes every frame; without a judgement at
//! the end it would finish exactly like a good one, and a pipeline would publish it. So the
//! figures already kept for every frame ([`FrameStats`]) are judged, and each kind of failure
//! is reported once, with its frames as compact ranges ("12-19, 33"), its worst value and
//! where on the garment it happened, since a frame number alone leaves the artist searching
//! the whole garment for what to fix:
//!
//! - strain: the frame ends with an edge more than [`STRAIN_TOLERANCE`] past the scene's
//!   `strain_limit`. Not judged when the limit is 0 (limiting off: any strain is allowed).
//!   Each failing frame's spot is its worst edge.
//! - penetration and self-intersection: `tailor check`'s test, run on every frame's written
//!   surface, finds anything at all. The test finds them on the refined surface, which the
//!   artist does not edit, so each failing frame's spot is mapped back to the control mesh
//!   ([`Surface`]): the deepest penetrating vertex to the control vertex it follows most, the
//!   first crossing face pair to the control faces they lie in.
//!
//! All three then name their spots alike: the garment group holding each failing frame's
//! spot (the smallest such group, the most specific name), or, for spots in no group, their
//! vertices.
//!
//! The caller prints [`Failure`]s as warnings, puts [`json`] in `summary.json`, and decides
//! the exit status (`--strict`).

use std::fmt;

use serde_json::{Map, Value, json};
use tailor_subdiv::obj::ObjDocument;

use super::surface::Surface;
use crate::checkpoint::FrameStats;

/// How far past `strain_limit` an edge may end a frame before the frame fails: one
/// percentage point of strain, absolute (a 10% limit fails above 11%, a 2% limit above 3%).
/// The limiter brings edges inside the limit, but within a substep the collision passes
/// have the last word and may leave an edge a hair past it; that is not a failure.
pub const STRAIN_TOLERANCE: f64 = 0.01;

/// Most ungrouped vertices named in a warning; `summary.json` lists them all.
const VERTICES_SHOWN: usize = 8;

/// What failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// An edge ended a frame past the strain limit (the scene's `strain_limit`).
    Strain {
        /// The scene's limit, a fraction of rest length.
        limit: f64,
    },
    /// Cloth vertices inside the body or closer to it than the thickness.
    Penetration,
    /// Face pairs of the cloth crossing.
    SelfIntersection,
}

impl Kind {
    /// The key in `summary.json`'s `failures`.
    fn key(self) -> &'static str {
        match self {
            Self::Strain { .. } => "strain",
            Self::Penetration => "penetration",
            Self::SelfIntersection => "self_intersection",
        }
    }
}

/// Where on the garment's control mesh a frame failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spot {
    /// The most strained edge, by its vertices.
    Edge([u32; 2]),
    /// The control vertex the deepest penetrating refined vertex follows most.
    Vertex(u32),
    /// The control faces of the first crossing refined face pair (the same face twice when
    /// both lie in one).
    Faces([u32; 2]),
}

impl Spot {
    /// The vertex sets that name the spot: each lies in a group when a face of the group
    /// holds all of it (an edge's ends, a vertex, each face's corners).
    fn parts<'a>(&'a self, garment: &'a ObjDocument) -> Vec<&'a [u32]> {
        match self {
            Self::Edge(edge) => vec![edge],
            Self::Vertex(v) => vec![std::slice::from_ref(v)],
            Self::Faces(faces) => faces
                .iter()
                .filter(|&&f| (f as usize) < garment.mesh.face_count())
                .map(|&f| garment.mesh.face(f as usize))
                .collect(),
        }
    }
}

/// Where on the garment the spots of the failing frames lie.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Region {
    /// Groups holding them, in the order of the frames.
    pub groups: Vec<String>,
    /// The vertices of those in no group, ascending.
    pub vertices: Vec<u32>,
    /// The rest position of the first of `vertices`.
    pub rest: Option<[f64; 3]>,
}

/// One kind of failure over the run.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// What failed.
    pub kind: Kind,
    /// The failing frames, ascending.
    pub frames: Vec<u32>,
    /// The frame with the worst value.
    pub worst_frame: u32,
    /// The worst value: strain, deepest penetration (m), or crossing face pairs.
    pub worst: f64,
    /// The worst frame's spot, and where the failing frames' lie; `None` when the worst
    /// frame has no spot.
    pub place: Option<(Spot, Region)>,
}

/// Judges every frame of `stats` against the scene's `strain_limit` (0: not judged) and
/// `tailor check`'s test; `garment` names the places, `surface` (the garment's written
/// surface) maps the test's findings back to it.
pub fn assess(
    stats: &[FrameStats],
    strain_limit: f64,
    garment: &ObjDocument,
    surface: &Surface,
) -> Vec<Failure> {
    let mut failures = Vec::new();
    if strain_limit > 0.0 {
        let threshold = strain_limit + STRAIN_TOLERANCE;
        let kind = Kind::Strain {
            limit: strain_limit,
        };
        failures.extend(judge(kind, stats, garment, |s| {
            (s.max_strain > threshold).then_some((s.max_strain, Some(Spot::Edge(s.strained_edge))))
        }));
    }
    failures.extend(judge(Kind::Penetration, stats, garment, |s| {
        let found = &s.findings;
        let spot = found.deepest_vertex.and_then(|v| surface.control_vertex(v));
        (found.penetrating_vertices > 0).then_some((found.max_penetration, spot.map(Spot::Vertex)))
    }));
    failures.extend(judge(Kind::SelfIntersection, stats, garment, |s| {
        let found = &s.findings;
        let spot = found.crossing_faces.and_then(|[a, b]| {
            Some(Spot::Faces([
                surface.control_face(a)?,
                surface.control_face(b)?,
            ]))
        });
        let pairs = found.self_intersecting_pairs;
        (pairs > 0).then_some((pairs as f64, spot))
    }));
    failures
}

/// The failure of `kind` over `stats`, if any frame fails: `value` is the frame's figure and
/// spot when it fails.
fn judge(
    kind: Kind,
    stats: &[FrameStats],
    garment: &ObjDocument,
    value: impl Fn(&FrameStats) -> Option<(f64, Option<Spot>)>,
) -> Option<Failure> {
    let failing: Vec<(u32, f64, Option<Spot>)> = stats
        .iter()
        .filter_map(|s| value(s).map(|(v, spot)| (s.frame, v, spot)))
        .collect();
    let &(worst_frame, worst, spot) = failing
        .iter()
        .reduce(|a, b| if b.1 > a.1 { b } else { a })?;
    let spots = failing.iter().filter_map(|&(_, _, spot)| spot);
    Some(Failure {
        kind,
        frames: failing.iter().map(|&(frame, _, _)| frame).collect(),
        worst_frame,
        worst,
        place: spot.map(|spot| (spot, region(garment, spots))),
    })
}

/// Where `spots` lie on the garment.
fn region(garment: &ObjDocument, spots: impl Iterator<Item = Spot>) -> Region {
    let mut found = Region::default();
    for spot in spots {
        for part in spot.parts(garment) {
            match group_of(garment, part) {
                Some(name) if !found.groups.iter().any(|g| g == name) => {
                    found.groups.push(name.to_owned());
                }
                Some(_) => {}
                None => found.vertices.extend(part),
            }
        }
    }
    found.vertices.sort_unstable();
    found.vertices.dedup();
    found.rest = found
        .vertices
        .first()
        .map(|&v| garment.mesh.positions()[v as usize].coords.into());
    found
}

/// The smallest group of the garment with a face holding all of `vertices`, if any.
fn group_of<'a>(garment: &'a ObjDocument, vertices: &[u32]) -> Option<&'a str> {
    garment
        .groups
        .iter()
        .filter(|g| {
            g.faces.iter().any(|&f| {
                let face = garment.mesh.face(f as usize);
                vertices.iter().all(|v| face.contains(v))
            })
        })
        .min_by_key(|g| g.faces.len())
        .map(|g| g.name.as_str())
}

/// Ascending frame numbers as ranges: `[12, 13, 14, 33]` is "12-14, 33".
fn ranges(frames: &[u32]) -> String {
    let mut runs: Vec<(u32, u32)> = Vec::new();
    for &f in frames {
        match runs.last_mut() {
            Some((_, end)) if end.checked_add(1) == Some(f) => *end = f,
            _ => runs.push((f, f)),
        }
    }
    let text: Vec<String> = runs
        .into_iter()
        .map(|(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect();
    text.join(", ")
}

/// The warning, one line.
impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let frames = ranges(&self.frames);
        let at = self.worst_frame;
        match self.kind {
            Kind::Strain { limit } => write!(
                f,
                "strain more than {:.0} percentage point past the {:.1}% strain limit in frames \
                 {frames} (worst {:.1}% at frame {at}",
                STRAIN_TOLERANCE * 100.0,
                limit * 100.0,
                self.worst * 100.0
            )?,
            Kind::Penetration => write!(
                f,
                "cloth inside the body or within its thickness in frames {frames} (deepest {} \
                 at frame {at}",
                crate::check::depth(self.worst)
            )?,
            Kind::SelfIntersection => write!(
                f,
                "the cloth intersects itself in frames {frames} (most: {} face pairs at frame \
                 {at}",
                self.worst
            )?,
        }
        let Some((spot, region)) = &self.place else {
            return write!(f, ")");
        };
        match spot {
            Spot::Edge([a, b]) => write!(f, ", edge {a}-{b})")?,
            Spot::Vertex(v) => write!(f, ", vertex {v})")?,
            Spot::Faces([a, b]) if a == b => write!(f, ", face {a})")?,
            Spot::Faces([a, b]) => write!(f, ", faces {a} and {b})")?,
        }
        let names: Vec<String> = region.groups.iter().map(|g| format!("{g:?}")).collect();
        match names.len() {
            0 => {}
            1 => write!(f, " in group {}", names[0])?,
            _ => write!(f, " in groups {}", names.join(", "))?,
        }
        if let (Some(&first), Some([x, y, z])) = (region.vertices.first(), region.rest) {
            let shown: Vec<String> = region
                .vertices
                .iter()
                .take(VERTICES_SHOWN)
                .map(u32::to_string)
                .collect();
            let more = region.vertices.len().saturating_sub(VERTICES_SHOWN);
            write!(
                f,
                "{} at {} {}{} (in no group; vertex {first} rests at ({x:.3}, {y:.3}, {z:.3}))",
                if names.is_empty() { "" } else { " and" },
                if region.vertices.len() == 1 {
                    "vertex"
                } else {
                    "vertices"
                },
                shown.join(", "),
                if more > 0 {
                    format!(" and {more} more")
                } else {
                    String::new()
                }
            )?;
        }
        Ok(())
    }
}

/// `summary.json`'s `failures`: an object with a key per kind that failed (`strain`,
/// `penetration`, `self_intersection`), empty for a clean run. Each names its worst frame's
/// spot (`worst_edge`, `worst_vertex` or `worst_faces`, control mesh indices) and the
/// failing frames' `groups` and `ungrouped_vertices`.
pub fn json(failures: &[Failure]) -> Value {
    let mut all = Map::new();
    for failure in failures {
        let mut entry = json!({
            "frames": failure.frames,
            "frame_ranges": ranges(&failure.frames),
            "worst": failure.worst,
            "worst_frame": failure.worst_frame,
        });
        if let Kind::Strain { limit } = failure.kind {
            entry["strain_limit"] = json!(limit);
            entry["threshold"] = json!(limit + STRAIN_TOLERANCE);
        }
        if let Some((spot, region)) = &failure.place {
            match spot {
                Spot::Edge(edge) => entry["worst_edge"] = json!(edge),
                Spot::Vertex(v) => entry["worst_vertex"] = json!(v),
                Spot::Faces(faces) => entry["worst_faces"] = json!(faces),
            }
            entry["groups"] = json!(region.groups);
            entry["ungrouped_vertices"] = json!(region.vertices);
        }
        all.insert(failure.kind.key().into(), entry);
    }
    Value::Object(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::Findings;

    fn row(frame: u32, max_strain: f64, strained_edge: [u32; 2]) -> FrameStats {
        FrameStats {
            frame,
            max_strain,
            strained_edge,
            ..FrameStats::default()
        }
    }

    /// Two quads side by side: face 0 (vertices 1, 2, 5, 4) in no group, face 1 (vertices
    /// 0, 1, 4, 3) in group "panel"; and its surface at level 1, whose faces 0-3 lie in face
    /// 0 and 4-7 in face 1, and whose vertices 0-5 follow their own vertex, 6 (face 0's face
    /// point) vertex 1 and 7 (face 1's) vertex 0.
    fn strip() -> (ObjDocument, Surface) {
        let garment = tailor_subdiv::obj::parse(
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n\
             f 2 3 6 5\ng panel\nf 1 2 5 4\n",
            "strip.obj",
        )
        .unwrap();
        let surface = Surface::new(&garment.mesh, 1, false).unwrap();
        (garment, surface)
    }

    fn found(deepest: Option<(u32, f64)>, crossing: Option<[u32; 2]>) -> Findings {
        Findings {
            penetrating_vertices: usize::from(deepest.is_some()),
            max_penetration: deepest.map_or(0.0, |d| d.1),
            deepest_vertex: deepest.map(|d| d.0),
            self_intersecting_pairs: usize::from(crossing.is_some()),
            crossing_faces: crossing,
        }
    }

    fn warns(failure: &Failure, parts: &[&str]) {
        let warning = failure.to_string();
        for part in parts {
            assert!(warning.contains(part), "{part:?} not in {warning:?}");
        }
    }

    #[test]
    fn failures_name_frames_values_and_places() {
        let (garment, surface) = strip();
        let mut stats = vec![
            row(0, 0.0, [0, 1]),
            row(1, 0.5, [0, 3]),
            row(2, 0.109, [1, 4]),
            row(3, 0.3, [2, 5]),
            row(4, 0.111, [1, 4]),
        ];
        stats[2].findings = found(Some((2, 0.01)), Some([0, 3]));
        stats[4].findings = found(Some((7, 0.02)), None);
        stats[3].findings = found(None, Some([1, 5]));
        stats[3].findings.self_intersecting_pairs = 2;
        let failures = assess(&stats, 0.1, &garment, &surface);
        assert_eq!(failures.len(), 3, "{failures:?}");
        let strain = &failures[0];
        assert_eq!(strain.frames, [1, 3, 4]);
        assert_eq!((strain.worst_frame, strain.worst), (1, 0.5));
        let (spot, region) = strain.place.as_ref().unwrap();
        assert_eq!(*spot, Spot::Edge([0, 3]));
        assert_eq!(region.groups, ["panel"]);
        assert_eq!(region.vertices, [2, 5]);
        warns(
            strain,
            &[
                "frames 1, 3-4",
                "worst 50.0% at frame 1, edge 0-3",
                "in group \"panel\" and at vertices 2, 5",
                "vertex 2 rests at (2.000, 0.000, 0.000)",
            ],
        );
        // Refined vertex 7 follows vertex 0 (in "panel"), refined vertex 2 vertex 2 (in no
        // group).
        let penetration = &failures[1];
        assert_eq!(penetration.kind, Kind::Penetration);
        assert_eq!(penetration.frames, [2, 4]);
        let (spot, region) = penetration.place.as_ref().unwrap();
        assert_eq!(*spot, Spot::Vertex(0));
        assert_eq!(
            (region.groups.as_slice(), region.vertices.as_slice()),
            (&["panel".to_owned()][..], &[2][..])
        );
        warns(
            penetration,
            &[
                "deepest 20.00 mm at frame 4, vertex 0) in group \"panel\" and at vertex 2 (",
                "vertex 2 rests at (2.000, 0.000, 0.000)",
            ],
        );
        // Refined faces 1 and 5 lie in faces 0 and 1, refined faces 0 and 3 both in face 0;
        // the worst frame (3, two pairs) names its pair.
        let crossing = &failures[2];
        assert_eq!(crossing.kind, Kind::SelfIntersection);
        assert_eq!(crossing.frames, [2, 3]);
        let (spot, region) = crossing.place.as_ref().unwrap();
        assert_eq!(*spot, Spot::Faces([0, 1]));
        assert_eq!(region.groups, ["panel"]);
        assert_eq!(region.vertices, [1, 2, 4, 5]);
        warns(
            crossing,
            &["at frame 3, faces 0 and 1) in group \"panel\" and at vertices 1, 2, 4, 5 ("],
        );
        stats[3].findings.self_intersecting_pairs = 1;
        let first = assess(&stats, 0.1, &garment, &surface);
        assert_eq!(first[2].place.as_ref().unwrap().0, Spot::Faces([0, 0]));
        warns(
            &first[2],
            &["at frame 2, face 0) in group \"panel\" and at vertices 1, 2, 4, 5 ("],
        );

        let summary = json(&failures);
        assert_eq!(summary["strain"]["frame_ranges"], "1, 3-4");
        assert_eq!(summary["strain"]["worst_edge"], json!([0, 3]));
        assert_eq!(summary["penetration"]["worst"], 0.02);
        assert_eq!(summary["penetration"]["worst_vertex"], 0);
        assert_eq!(summary["penetration"]["groups"], json!(["panel"]));
        assert_eq!(summary["penetration"]["ungrouped_vertices"], json!([2]));
        assert_eq!(summary["self_intersection"]["worst_faces"], json!([0, 1]));
        // Limiting off: strain is not judged.
        assert_eq!(assess(&stats, 0.0, &garment, &surface).len(), 2);
        assert_eq!(json(&[]), json!({}));
    }

    #[test]
    fn frames_read_as_compact_ranges() {
        assert_eq!(ranges(&[]), "");
        assert_eq!(ranges(&[7]), "7");
        assert_eq!(ranges(&[12, 13, 14, 15, 16, 17, 18, 19, 33]), "12-19, 33");
        assert_eq!(ranges(&[0, 2, 3, 5]), "0, 2-3, 5");
    }
}
