//! Whether a shot met its quality. A run that stretches the cloth past its strain limit, or
//! leaves it in the body or through itself, still writes every frame; without a judgement at
//! the end it would finish exactly like a good one, and a pipeline would publish it. So the
//! figures already kept for every frame ([`FrameStats`]) are judged, and each kind of failure
//! is reported once, with its frames as compact ranges ("12-19, 33"), its worst value and,
//! for strain, where on the garment it happened:
//!
//! - strain: the frame ends with an edge more than [`STRAIN_TOLERANCE`] past the scene's
//!   `strain_limit`. Not judged when the limit is 0 (limiting off: any strain is allowed).
//!   The place is the garment group holding each failing frame's worst edge (the smallest
//!   such group, the most specific name), or, for edges in no group, their vertices.
//! - penetration and self-intersection: `tailor check`'s test, run on every frame's written
//!   surface, finds anything at all.
//!
//! The caller prints [`Failure`]s as warnings, puts [`json`] in `summary.json`, and decides
//! the exit status (`--strict`).

use std::fmt;

use serde_json::{Map, Value, json};
use tailor_subdiv::obj::ObjDocument;

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

/// Where on the garment the worst edges of the failing frames lie.
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
    /// Strain only: the worst frame's worst edge, and where the failing frames' lie.
    pub place: Option<([u32; 2], Region)>,
}

/// Judges every frame of `stats` against the scene's `strain_limit` (0: not judged) and
/// `tailor check`'s test; `garment` names the places.
pub fn assess(stats: &[FrameStats], strain_limit: f64, garment: &ObjDocument) -> Vec<Failure> {
    let threshold = strain_limit + STRAIN_TOLERANCE;
    let strained = |s: &FrameStats| (s.max_strain > threshold).then_some(s.max_strain);
    let mut failures = Vec::new();
    if strain_limit > 0.0
        && let Some(mut failure) = judge(
            Kind::Strain {
                limit: strain_limit,
            },
            stats,
            strained,
        )
    {
        let rows = stats.iter().filter(|s| strained(s).is_some());
        let worst = rows.clone().find(|s| s.frame == failure.worst_frame);
        let edge = worst.map_or([0, 0], |s| s.strained_edge);
        failure.place = Some((edge, region(garment, rows.map(|s| s.strained_edge))));
        failures.push(failure);
    }
    failures.extend(judge(Kind::Penetration, stats, |s| {
        (s.findings.penetrating_vertices > 0).then_some(s.findings.max_penetration)
    }));
    failures.extend(judge(Kind::SelfIntersection, stats, |s| {
        let pairs = s.findings.self_intersecting_pairs;
        (pairs > 0).then_some(pairs as f64)
    }));
    failures
}

/// The failure of `kind` over `stats`, if any frame fails: `value` is the frame's figure
/// when it fails.
fn judge(
    kind: Kind,
    stats: &[FrameStats],
    value: impl Fn(&FrameStats) -> Option<f64>,
) -> Option<Failure> {
    let failing: Vec<(u32, f64)> = stats
        .iter()
        .filter_map(|s| value(s).map(|v| (s.frame, v)))
        .collect();
    let &(worst_frame, worst) = failing
        .iter()
        .reduce(|a, b| if b.1 > a.1 { b } else { a })?;
    Some(Failure {
        kind,
        frames: failing.iter().map(|&(frame, _)| frame).collect(),
        worst_frame,
        worst,
        place: None,
    })
}

/// Where `edges` lie on the garment.
fn region(garment: &ObjDocument, edges: impl Iterator<Item = [u32; 2]>) -> Region {
    let mut found = Region::default();
    for edge in edges {
        match group_of(garment, edge) {
            Some(name) if !found.groups.iter().any(|g| g == name) => {
                found.groups.push(name.to_owned());
            }
            Some(_) => {}
            None => found.vertices.extend(edge),
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

/// The smallest group of the garment with a face holding both ends of `edge`, if any.
fn group_of(garment: &ObjDocument, [a, b]: [u32; 2]) -> Option<&str> {
    garment
        .groups
        .iter()
        .filter(|g| {
            g.faces.iter().any(|&f| {
                let face = garment.mesh.face(f as usize);
                face.contains(&a) && face.contains(&b)
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
                "cloth inside the body or within its thickness in frames {frames} (deepest \
                 {:.4} m at frame {at}",
                self.worst
            )?,
            Kind::SelfIntersection => write!(
                f,
                "the cloth intersects itself in frames {frames} (most: {} face pairs at frame \
                 {at}",
                self.worst
            )?,
        }
        let Some(([a, b], region)) = &self.place else {
            return write!(f, ")");
        };
        write!(f, ", edge {a}-{b})")?;
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
                "{} at vertices {}{} (in no group; vertex {first} rests at ({x:.3}, {y:.3}, {z:.3}))",
                if names.is_empty() { "" } else { " and" },
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
/// `penetration`, `self_intersection`), empty for a clean run.
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
        if let Some((edge, region)) = &failure.place {
            entry["worst_edge"] = json!(edge);
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

    #[test]
    fn failures_name_frames_values_and_places() {
        // Two quads side by side: the left one in group "panel", the right one in none.
        let garment = tailor_subdiv::obj::parse(
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n\
             f 2 3 6 5\ng panel\nf 1 2 5 4\n",
            "strip.obj",
        )
        .unwrap();
        let mut stats = vec![
            row(0, 0.0, [0, 1]),
            row(1, 0.5, [0, 3]),
            row(2, 0.109, [1, 4]),
            row(3, 0.3, [2, 5]),
            row(4, 0.111, [1, 4]),
        ];
        stats[2].findings = Findings {
            penetrating_vertices: 2,
            max_penetration: 0.01,
            self_intersecting_pairs: 0,
            ..Findings::default()
        };
        let failures = assess(&stats, 0.1, &garment);
        assert_eq!(failures.len(), 2, "{failures:?}");
        let strain = &failures[0];
        assert_eq!(strain.frames, [1, 3, 4]);
        assert_eq!((strain.worst_frame, strain.worst), (1, 0.5));
        let (edge, region) = strain.place.as_ref().unwrap();
        assert_eq!(*edge, [0, 3]);
        assert_eq!(region.groups, ["panel"]);
        assert_eq!(region.vertices, [2, 5]);
        let warning = strain.to_string();
        for part in [
            "frames 1, 3-4",
            "worst 50.0% at frame 1, edge 0-3",
            "in group \"panel\" and at vertices 2, 5",
            "vertex 2 rests at (2.000, 0.000, 0.000)",
        ] {
            assert!(warning.contains(part), "{part:?} not in {warning:?}");
        }
        assert_eq!(failures[1].kind, Kind::Penetration);
        assert_eq!(failures[1].frames, [2]);
        let summary = json(&failures);
        assert_eq!(summary["strain"]["frame_ranges"], "1, 3-4");
        assert_eq!(summary["penetration"]["worst"], 0.01);
        // Limiting off: strain is not judged.
        assert_eq!(assess(&stats, 0.0, &garment).len(), 1);
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
