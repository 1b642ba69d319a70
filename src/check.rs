//! `tailor check`: quality control of a finished simulation. Per frame, the cloth vertices
//! inside the body or closer to it than the thickness, the deepest of them, and the cloth's
//! self-intersecting face pairs; a summary on standard output and optionally a JSON report,
//! written atomically like every file the tool writes, so a failed write leaves the earlier
//! report whole.
//! Counts say how bad a frame is, not where to look, so each frame also names its deepest
//! vertex and its first crossing face pair (in ascending order, so the same mesh always names
//! the same pair): here by the vertex's position and the faces' order in the file; `tailor
//! simulate` maps them back to the garment it simulated.
//!
//! A file is judged at the positions a renderer holds: one whose every coordinate is the
//! shortest text of an `f32` (as `tailor simulate` writes at its default precision) is read
//! as an `f32` reader reads it, each coordinate its nearest `f32`
//! (`tailor_subdiv::obj::Precision::of_text`); the run's own check judges those same values,
//! so the two agree to the bit. A file with more digits is read in `f64`.
//!
//! Inside/outside uses the body's pseudo-normals (`tailor_collide::Hierarchy::signed_distances`)
//! and needs a closed body; an open body is checked by distance only. Hierarchies are built for
//! the first frame and refit for every later frame of the same topology, and a frame measures
//! again only the vertices that may have come within the thickness since the frame before
//! ([`Clearances`]).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use nalgebra::Point3;
use serde_json::json;
use tailor_collide::{DistanceBounds, Hierarchy};
use tailor_subdiv::obj::Precision;

use crate::output;
use crate::polymesh_obj::{self, PolyMesh};
use crate::sequence::Pattern;

/// Arguments of `tailor check`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "A file whose every coordinate is the shortest text of a single-precision \
float (as `tailor simulate` writes by default) is judged as a renderer reads it, each \
coordinate that float; a file with more digits is read in double precision. \
Exit status: 0 when nothing is found, 1 when any vertex penetrates or any \
faces intersect, 2 when the input cannot be checked (unreadable file, non-finite coordinate, \
missing frame) or the summary or report cannot be written. When standard output is closed \
early (`| head`), the check stops quietly with exit status 0."
)]
pub struct Args {
    /// Cloth OBJ, or a frame sequence pattern such as `out/cloth_####.obj` (each run of `#` is
    /// the zero-padded frame number; every frame present is checked, and a frame missing
    /// between the first and the last is an error).
    pub cloth: PathBuf,
    /// Body OBJ, or a body sequence pattern such as `body_####.obj` matched frame by frame.
    /// A closed body (every edge shared by two faces, faces counter-clockwise seen from
    /// outside) has an inside: cloth vertices inside it, or closer than the thickness, count as
    /// penetrating. An open body has no inside: only vertices closer than the thickness count,
    /// so with thickness 0 nothing does, and a warning says so.
    #[arg(long, value_name = "BODY")]
    pub against: Option<PathBuf>,
    /// Minimum clearance between cloth and body, in metres; penetration is measured as how far
    /// a vertex would have to move out to reach it.
    #[arg(long, default_value_t = 0.0, value_name = "T")]
    pub thickness: f64,
    /// Also write the report as JSON: `{"frames": [{"frame", "penetrating_vertices",
    /// "max_penetration", "deepest_point", "self_intersecting_pairs", "crossing_faces"}],
    /// "total": {…}}` (the deepest vertex's position, and the first crossing pair as 0-based
    /// faces in the file's order, when found).
    #[arg(long, value_name = "REPORT.json")]
    pub json: Option<PathBuf>,
    /// Print a line for every frame of a sequence, not only for the frames with findings.
    #[arg(long, short)]
    pub verbose: bool,
}

/// What one frame has wrong.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Findings {
    /// Cloth vertices inside the body or closer to it than the thickness.
    pub penetrating_vertices: usize,
    /// How far the deepest of them would have to move out to reach the thickness, m.
    pub max_penetration: f64,
    /// The deepest of them (the lowest index of equals), a 0-based cloth vertex.
    pub deepest_vertex: Option<u32>,
    /// Face pairs of the cloth that share no vertex and cross.
    pub self_intersecting_pairs: usize,
    /// The first of them in ascending order, 0-based cloth faces, the lower first.
    pub crossing_faces: Option<[u32; 2]>,
}

/// The findings of one frame: `cloth` and `body` refit at the frame's positions,
/// `cloth_positions` the cloth's vertices; `last` holds what the
/// frame before measured of the body's clearance and takes this frame's.
///
/// # Errors
/// When a cloth position is not finite.
pub fn inspect(
    cloth: &Hierarchy,
    cloth_positions: &[Point3<f64>],
    body: Option<&Hierarchy>,
    thickness: f64,
    last: &mut Clearances,
) -> Result<Findings> {
    let crossing = cloth.self_intersections();
    let mut found = Findings {
        self_intersecting_pairs: crossing.len(),
        crossing_faces: crossing.first().copied(),
        ..Findings::default()
    };
    if let Some(body) = body {
        let clearance = last.measure(body, cloth_positions, thickness)?;
        for (v, &gap) in clearance.iter().enumerate() {
            if gap < thickness {
                found.penetrating_vertices += 1;
                let depth = thickness - gap;
                if found.deepest_vertex.is_none() || depth > found.max_penetration {
                    found.max_penetration = depth;
                    found.deepest_vertex = Some(u32::try_from(v)?);
                }
            }
        }
    }
    Ok(found)
}

impl Findings {
    /// The counts as a JSON object.
    pub fn json(&self) -> serde_json::Value {
        json!({
            "penetrating_vertices": self.penetrating_vertices,
            "max_penetration": self.max_penetration,
            "self_intersecting_pairs": self.self_intersecting_pairs,
        })
    }

    /// Nothing penetrates and nothing crosses.
    pub fn is_clean(&self) -> bool {
        self.penetrating_vertices == 0 && self.self_intersecting_pairs == 0
    }
}

/// The mesh of OBJ file `path` as a renderer holds it (when every coordinate is the shortest
/// text of an `f32`, each rounded to that `f32`; see the module docs), and its positions as
/// the text writes them, for naming a vertex by where it is in the file.
fn read_as_rendered(path: &Path) -> Result<(PolyMesh, Vec<Point3<f64>>)> {
    let mut mesh = polymesh_obj::read(path)?;
    let written = mesh.positions.clone();
    let coordinates = written.iter().flat_map(|p| p.coords.iter().copied());
    let precision = Precision::of_text(coordinates);
    for p in &mut mesh.positions {
        p.coords.apply(|x| *x = precision.round(*x));
    }
    Ok((mesh, written))
}

/// Runs `tailor check`: exit 0 clean, 1 found, 2 cannot check.
///
/// # Errors
/// Only standard output closed by its reader ([`output::stdout_closed`]); other problems,
/// with the input or with writing the summary or the report, are printed and give exit
/// status 2, since 1 means the cloth was found wanting.
pub fn run(args: &Args) -> Result<ExitCode> {
    match check(args) {
        Ok(true) => Ok(ExitCode::SUCCESS),
        Ok(false) => Ok(ExitCode::from(1)),
        Err(err) if output::stdout_closed(&err) => Err(err),
        Err(err) => {
            output::print_error(&err);
            Ok(ExitCode::from(2))
        }
    }
}

/// Checks every frame, prints the summary, writes the report; `true` when clean.
fn check(args: &Args) -> Result<bool> {
    if !(args.thickness >= 0.0 && args.thickness.is_finite()) {
        bail!(
            "--thickness must be a finite number >= 0, not {}",
            args.thickness
        );
    }
    let frames = frames(args)?;
    let mut cloth = Reuse::default();
    let mut body = Reuse::default();
    let mut warned_open = false;
    let mut clearances = Clearances::default();
    let mut rows = Vec::with_capacity(frames.len());
    let mut total = Findings::default();
    for (frame, cloth_path, body_path) in &frames {
        let (cloth_mesh, written) = read_as_rendered(cloth_path)?;
        let cloth_h = cloth.hierarchy(&cloth_mesh, cloth_path)?;
        let body_h = match body_path {
            Some(body_path) => {
                let (body_mesh, _) = read_as_rendered(body_path)?;
                let body_h = body.hierarchy(&body_mesh, body_path)?;
                if !body_h.is_closed() && !warned_open {
                    eprintln!(
                        "warning: {} is not closed, so it has no inside; only cloth vertices \
                         closer than the thickness ({}) are counted",
                        body_path.display(),
                        args.thickness
                    );
                    warned_open = true;
                }
                Some(body_h)
            }
            None => None,
        };
        let found = inspect(
            cloth_h,
            &cloth_mesh.positions,
            body_h,
            args.thickness,
            &mut clearances,
        )
        .with_context(|| format!("checking {}", cloth_path.display()))?;
        let deepest = found
            .deepest_vertex
            .and_then(|v| written.get(v as usize))
            .map(|p| [p.x, p.y, p.z]);
        total.penetrating_vertices += found.penetrating_vertices;
        total.max_penetration = total.max_penetration.max(found.max_penetration);
        total.self_intersecting_pairs += found.self_intersecting_pairs;
        if frames.len() > 1 && (args.verbose || !found.is_clean()) {
            let what = format!("frame {frame}");
            output::print(&(line(&what, &found, deepest, body_h.is_some()) + "\n"))?;
        }
        rows.push((*frame, found, deepest));
    }
    // The total of one frame is that frame, places included; over several frames the places
    // are on each frame's line.
    let (total, deepest) = match rows.as_slice() {
        [(_, only, deepest)] => (*only, *deepest),
        _ => (total, None),
    };
    let what = match (
        frames.len(),
        rows.iter().filter(|r| !r.1.is_clean()).count(),
    ) {
        (1, _) => "1 frame checked".to_owned(),
        (n, 0) => format!("{n} frames checked, all clean"),
        (n, found) => format!("{n} frames checked, {found} with findings"),
    };
    let against = args.against.is_some();
    output::print(&(line(&what, &total, deepest, against) + "\n"))?;
    if let Some(path) = &args.json {
        let report = json!({
            "frames": rows.iter().map(|(frame, f, deepest)| {
                let mut row = f.json();
                row["frame"] = json!(frame);
                if let Some(point) = deepest {
                    row["deepest_point"] = json!(point);
                }
                if let Some(pair) = f.crossing_faces {
                    row["crossing_faces"] = json!(pair);
                }
                row
            }).collect::<Vec<_>>(),
            "total": total.json(),
        });
        let text = serde_json::to_string_pretty(&report)? + "\n";
        output::write_atomically(path, |w| w.write_all(text.as_bytes()))?;
    }
    Ok(total.is_clean())
}

/// The frames to check: `(frame, cloth file, body file)`; a single file is frame 0.
fn frames(args: &Args) -> Result<Vec<(u32, PathBuf, Option<PathBuf>)>> {
    let body_pattern = args.against.as_deref().and_then(Pattern::parse);
    let body_for = |frame: u32| match (&body_pattern, &args.against) {
        (Some(pattern), _) => Some(pattern.path(frame)),
        (None, body) => body.clone(),
    };
    let Some(pattern) = Pattern::parse(&args.cloth) else {
        return Ok(vec![(0, args.cloth.clone(), body_for(0))]);
    };
    let numbers = pattern.frames()?;
    if numbers.is_empty() {
        bail!("no file matches {}", args.cloth.display());
    }
    if let Some(pair) = numbers.windows(2).find(|pair| pair[1] != pair[0] + 1) {
        bail!(
            "{} is missing from the sequence {} (frames {} to {} are there)",
            pattern.path(pair[0] + 1).display(),
            args.cloth.display(),
            numbers[0],
            numbers[numbers.len() - 1]
        );
    }
    Ok(numbers
        .into_iter()
        .map(|n| (n, pattern.path(n), body_for(n)))
        .collect())
}

/// The body's clearance of the cloth's vertices at the last frame measured, so that the next
/// frame measures again only the vertices that may have come within the thickness
/// ([`DistanceBounds`]: a signed distance changes by at most how far its point moved plus how
/// far the body's vertices moved). The findings come from the vertices within the thickness
/// alone, which are all measured, so they are those of measuring every vertex; in the 64²
/// drape most of the written surface hangs clear of the sphere, and measuring it all took an
/// eighth of the run.
#[derive(Default)]
pub struct Clearances {
    /// Each cloth vertex's signed distance from a closed body, or a lower bound of it past the
    /// thickness.
    bounds: DistanceBounds,
    /// Each cloth vertex's distance from an open body within the thickness, else infinity.
    gap: Vec<f64>,
    todo: Vec<u32>,
    queries: Vec<Point3<f64>>,
    /// Each cloth vertex's closest body face when last measured, where its next walk starts
    /// (the stale vertices are scattered over the cloth, so the one before in the list is
    /// seldom near).
    faces: Vec<Option<u32>>,
    seeds: Vec<Option<u32>>,
}

impl Clearances {
    /// The clearance of each of `cloth` from `body`: the signed distance of a closed body,
    /// exact within the thickness; for an open body, the distance when within the thickness,
    /// else infinity.
    fn measure(
        &mut self,
        body: &Hierarchy,
        cloth: &[Point3<f64>],
        thickness: f64,
    ) -> Result<&[f64]> {
        if !body.is_closed() {
            let closest = body.closest_points(cloth, thickness)?;
            self.gap.clear();
            self.gap.extend(
                closest
                    .iter()
                    .map(|c| c.map_or(f64::INFINITY, |c| c.distance)),
            );
            self.bounds.forget();
            return Ok(&self.gap);
        }
        self.bounds.stale(body, cloth, thickness, &mut self.todo);
        // A vertex farther than the thickness from the body's box is that far outside the
        // body: the box is its bound, and only the rest are measured.
        let bounds = &mut self.bounds;
        self.todo.retain(|&i| {
            let outside = body.box_distance(&cloth[i as usize]);
            let far = outside > thickness;
            if far {
                bounds.set(i, outside);
            }
            !far
        });
        self.queries.clear();
        self.queries
            .extend(self.todo.iter().map(|&i| cloth[i as usize]));
        if self.faces.len() != cloth.len() {
            self.faces = vec![None; cloth.len()];
        }
        self.seeds.clear();
        // Any face is a sound seed; one past a body of fewer faces (a sequence whose body
        // changed) is dropped.
        let faces = body.face_count();
        self.seeds.extend(
            self.todo
                .iter()
                .map(|&i| self.faces[i as usize].filter(|&f| (f as usize) < faces)),
        );
        let measured = body.signed_distances_seeded(&self.queries, &self.seeds)?;
        for (&i, (d, face)) in self.todo.iter().zip(measured) {
            self.bounds.set(i, d);
            self.faces[i as usize] = face;
        }
        Ok(self.bounds.bounds())
    }
}

/// A summary line; a frame's names where its deepest vertex is and its first crossing pair.
/// Depths are in millimetres; without a body (`against` false) the line says penetration was
/// not checked rather than counting none.
fn line(what: &str, f: &Findings, deepest: Option<[f64; 3]>, against: bool) -> String {
    let first = f.crossing_faces.map_or(String::new(), |[a, b]| {
        format!(" (first: faces {a} and {b})")
    });
    let crossings = format!(
        "{} self-intersecting face pairs{first}",
        f.self_intersecting_pairs
    );
    if !against {
        return format!("{what}: {crossings}; no body given (--against), penetration not checked");
    }
    let at = deepest.map_or(String::new(), |[x, y, z]| {
        format!(" at ({x:.3}, {y:.3}, {z:.3})")
    });
    format!(
        "{what}: {} penetrating vertices (deepest {}{at}), {crossings}",
        f.penetrating_vertices,
        depth(f.max_penetration)
    )
}

/// A penetration depth `m` (metres) for people: in millimetres to two decimals, or in
/// micrometres to three where that would read 0.00 mm (rounding to `f32` leaves points
/// nanometres inside the thickness, and "0.00 mm" for a failing frame says nothing).
#[must_use]
pub fn depth(m: f64) -> String {
    if m == 0.0 || m.abs() >= 5e-6 {
        format!("{:.2} mm", m * 1e3)
    } else {
        format!("{:.3} µm", m * 1e6)
    }
}

/// A hierarchy kept across frames while the topology stays the same.
#[derive(Default)]
struct Reuse {
    built: Option<(Vec<u32>, Vec<u32>, Hierarchy)>,
}

impl Reuse {
    /// The hierarchy of `mesh`: refit when the faces match the previous frame, else rebuilt.
    fn hierarchy(&mut self, mesh: &PolyMesh, path: &Path) -> Result<&Hierarchy> {
        let context = || format!("checking {}", path.display());
        let built = match self.built.take() {
            Some((offsets, vertices, mut h))
                if offsets == mesh.face_offsets
                    && vertices == mesh.face_vertices
                    && h.vertex_count() == mesh.positions.len() =>
            {
                h.refit(&mesh.positions, 0.0).with_context(context)?;
                (offsets, vertices, h)
            }
            _ => {
                let h = Hierarchy::build(&mesh.positions, &mesh.face_offsets, &mesh.face_vertices)
                    .with_context(context)?;
                (mesh.face_offsets.clone(), mesh.face_vertices.clone(), h)
            }
        };
        Ok(&self.built.insert(built).2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tailor_cloth::shapes::{centred_sheet, sphere};

    #[test]
    fn depths_read_in_millimetres_or_below_them_in_micrometres() {
        assert_eq!(depth(0.0), "0.00 mm");
        assert_eq!(depth(0.1), "100.00 mm");
        assert_eq!(depth(2.5e-5), "0.03 mm");
        // A point rounded nanometres inside the thickness: not "0.00 mm".
        assert_eq!(depth(2.4e-8), "0.024 µm");
        assert_eq!(depth(4.9e-6), "4.900 µm");
    }

    /// A sheet sinks through a ball that moves sideways, over frames whose steps shrink and
    /// grow: the clearances measured again only where a point may have come within the
    /// thickness, and bounded by the ball's box where it is farther from that, count the same
    /// penetrations, as deep and at the same vertex, as the exact signed distances of every
    /// point, and are lower bounds of them.
    #[test]
    fn clearances_measured_again_where_needed_find_what_measuring_all_finds() {
        let thickness = 0.01;
        let ball = sphere(Point3::origin(), 0.5, 12, 24);
        let sheet = centred_sheet(24, 2.0);
        let faces = (ball.face_offsets(), ball.face_vertices());
        let mut h = Hierarchy::build(ball.positions(), faces.0, faces.1).unwrap();
        let mut last = Clearances::default();
        let mut penetrating = 0;
        let mut skipped = 0;
        for frame in 0..40 {
            let t = f64::from(frame);
            let shift = nalgebra::Vector3::new(0.01 * t, 0.0, 0.002 * t * t % 0.05);
            let body: Vec<Point3<f64>> = ball.positions().iter().map(|p| p + shift).collect();
            h.refit(&body, 0.0).unwrap();
            let depth = 0.6 - 0.03 * t + 0.01 * (0.7 * t).sin();
            let cloth: Vec<Point3<f64>> = sheet
                .positions()
                .iter()
                .map(|p| Point3::new(p.x, depth - 0.2 * (p.x * p.x + p.z * p.z), p.z))
                .collect();
            let remembered = last.measure(&h, &cloth, thickness).unwrap().to_vec();
            // Skipped by the bounds kept from frame to frame, not by the box alone.
            let near_box = cloth
                .iter()
                .filter(|p| h.box_distance(p) <= thickness)
                .count();
            skipped += u32::from(last.todo.len() < near_box);
            let fresh = h.signed_distances(&cloth).unwrap();
            for (i, (r, f)) in remembered.iter().zip(&fresh).enumerate() {
                assert!(
                    (*r < thickness) == (*f < thickness) && (*f >= thickness || r == f),
                    "frame {frame}, vertex {i}: {r} against {f}"
                );
                assert!(*r <= *f + 1e-12, "frame {frame}, vertex {i}: {r} > {f}");
            }
            penetrating += fresh.iter().filter(|&&d| d < thickness).count();
        }
        assert!(
            penetrating > 1000,
            "the sheet must sink into the ball: {penetrating}"
        );
        assert!(
            skipped > 20,
            "most frames must skip some vertices: {skipped}"
        );
    }
}
