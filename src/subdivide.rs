//! `tailor subdivide`: refine an OBJ control mesh the way OpenSubdiv does.
//!
//! Options come from the file's OpenSubdiv tags (`t interpolateboundary`, `t creasemethod`, ...)
//! and the flags override them. The refined mesh keeps OpenSubdiv's vertex and face order, its
//! UVs, and `t crease`/`t corner` lines for the sharpness left after refinement; hole faces are
//! not written.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use tailor_subdiv::obj::{self, Precision};
use tailor_subdiv::{
    BoundaryInterpolation, CreaseMethod, FVarLinear, Mesh, MeshError, TriangleRule, Validation,
};

use crate::output;

/// Arguments of `tailor subdivide`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Control mesh (OBJ with optional OpenSubdiv `t` tags); `-` reads standard input.
    pub input: PathBuf,
    /// Refinement level (each level splits every face into quads, four per quad).
    #[arg(short, long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=8))]
    pub level: u32,
    /// Output OBJ; `-` or absent writes standard output.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Move every vertex to its limit position.
    #[arg(long)]
    pub limit: bool,
    /// Write limit normals (`vn`).
    #[arg(long)]
    pub normals: bool,
    /// Boundary interpolation: none, edge-only, edge-and-corner.
    #[arg(long, value_parser = parse::<BoundaryInterpolation>)]
    pub boundary: Option<BoundaryInterpolation>,
    /// Semi-sharp crease decay: uniform, chaikin.
    #[arg(long, value_parser = parse::<CreaseMethod>)]
    pub crease_method: Option<CreaseMethod>,
    /// Edge rule next to triangles: catmark, smooth.
    #[arg(long, value_parser = parse::<TriangleRule>)]
    pub triangle_rule: Option<TriangleRule>,
    /// Face-varying (UV) interpolation: none, corners-only, corners-plus1, corners-plus2,
    /// boundaries, all.
    #[arg(long, value_parser = parse::<FVarLinear>)]
    pub fvar_linear: Option<FVarLinear>,
    /// The faces are clockwise (left-handed): reverse them on reading.
    #[arg(long)]
    pub left_handed: bool,
    /// Digits of the coordinates written: single (the shortest text that reads back as the
    /// same f32, as renderers keep them) or full (the same f64).
    #[arg(long, default_value_t = Precision::Single, value_parser = parse::<Precision>)]
    pub precision: Precision,
}

fn parse<T: FromStr<Err = tailor_subdiv::options::UnknownOption>>(s: &str) -> Result<T, String> {
    s.parse()
        .map_err(|e: tailor_subdiv::options::UnknownOption| e.to_string())
}

/// Faces beyond which a refinement is refused rather than exhausting memory.
const MAX_FACES: usize = 200_000_000;

/// Peak memory of `tailor subdivide` per face written, bytes: the refinement's tables, the
/// mesh and the formatted text (the cape, with its UVs, at levels 4, 5 and 6 peaks at 620,
/// 580 and 516 bytes a face written, resident), rounded up.
const BYTES_PER_FACE: u64 = 640;

/// The same with `--limit` or `--normals`, which add the limit stencils and positions (the
/// cape at level 6 with both peaks at 1056 bytes a face).
const BYTES_PER_FACE_LIMIT: u64 = 1100;

/// The memory this process may still take, bytes, when the system says: the least of the
/// memory available (`/proc/meminfo`), what is left under the cgroup's limit
/// (`/sys/fs/cgroup/memory.max`) and the address-space limit (`ulimit -v`,
/// `/proc/self/limits`). `None` where none of them can be read.
fn available_memory() -> Option<u64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let number = |text: &str| text.trim().parse::<u64>().ok();
    let meminfo = read("/proc/meminfo").and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
        Some(number(line.split_whitespace().nth(1)?)? * 1024)
    });
    let cgroup = read("/sys/fs/cgroup/memory.max")
        .and_then(|max| number(&max))
        .map(|max| {
            let used = read("/sys/fs/cgroup/memory.current").and_then(|c| number(&c));
            max.saturating_sub(used.unwrap_or(0))
        });
    let address_space = read("/proc/self/limits").and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("Max address space"))?;
        number(line.split_whitespace().nth(3)?)
    });
    [meminfo, cgroup, address_space].into_iter().flatten().min()
}

/// Reads a control mesh from a file, or standard input for `-`.
pub fn read_mesh(path: &Path) -> Result<obj::ObjDocument> {
    let (text, source) = if path.as_os_str() == "-" {
        let mut text = String::new();
        std::io::stdin()
            .read_to_string(&mut text)
            .context("reading standard input")?;
        (text, "<stdin>".to_owned())
    } else {
        let source = path.display().to_string();
        match std::fs::read(path) {
            Ok(bytes) => (String::from_utf8_lossy(&bytes).into_owned(), source),
            Err(error) => {
                return Err(obj::ObjError::Io {
                    file: source,
                    error,
                }
                .into());
            }
        }
    };
    match obj::parse(&text, &source) {
        Err(
            first @ obj::ObjError::At {
                problem: obj::Problem::Mesh(MeshError::RepeatedVertex { .. }),
                ..
            },
        ) => {
            // OpenSubdiv reads a face that repeats a vertex: its repeated corners make a
            // degenerate edge, non-manifold and so infinitely sharp (four of its regression
            // shapes have such faces). So does the tool, saying where the first one is.
            let validation = Validation {
                allow_degenerate_faces: true,
            };
            let doc = obj::parse_with(&text, &source, validation)?;
            let degenerate = (0..doc.mesh.face_count())
                .filter(|&f| {
                    let face = doc.mesh.face(f);
                    face.iter().enumerate().any(|(i, v)| face[..i].contains(v))
                })
                .count();
            eprintln!(
                "warning: {first}: read as OpenSubdiv reads it, the repeated corners making a \
                 degenerate, infinitely sharp edge ({degenerate} such face(s) in all)"
            );
            Ok(doc)
        }
        read => Ok(read?),
    }
}

/// Runs the command.
///
/// # Errors
/// Unreadable or invalid input, an output that cannot be written, a refinement too large.
pub fn run(args: &Args) -> Result<ExitCode> {
    let start = Instant::now();
    let mut mesh = read_mesh(&args.input)?.mesh;
    if args.left_handed {
        mesh = mesh.with_reversed_faces();
    }
    apply_overrides(&mut mesh, args);
    let level = args.level as usize;
    let faces_out = refined_face_count(&mesh, level);
    if faces_out > MAX_FACES {
        bail!(
            "level {level} would make {faces_out} faces from {}; the limit is {MAX_FACES}",
            args.input.display()
        );
    }
    let per_face = if args.limit || args.normals {
        BYTES_PER_FACE_LIMIT
    } else {
        BYTES_PER_FACE
    };
    let needed = faces_out as u64 * per_face;
    if let Some(available) = available_memory()
        && needed > available
    {
        let gb = |bytes: u64| bytes as f64 / 1e9;
        bail!(
            "level {level} of {} makes {faces_out} faces and needs about {:.1} GB of memory; \
             {:.1} GB is available",
            args.input.display(),
            gb(needed),
            gb(available)
        );
    }
    let (mut refined, limit) = tailor_subdiv::subdivide(&mesh, level, args.limit || args.normals);
    let normals = match limit {
        Some(limit) => {
            if args.limit {
                refined.set_positions(&limit.positions)?;
                if let Some(uvs) = limit.uvs {
                    refined = refined.with_uvs(uvs)?;
                }
            }
            args.normals.then_some(limit.normals)
        }
        None => None,
    };
    let out = args.output.clone().unwrap_or_else(|| PathBuf::from("-"));
    output::write_to(&out, |w| {
        obj::write(&refined, normals.as_deref(), args.precision, &mut { w })
    })?;
    let written = refined.face_count() - refined.holes().len();
    eprintln!(
        "{}: {} faces -> {} faces (level {level}) in {:.1} ms",
        args.input.display(),
        mesh.face_count(),
        written,
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(ExitCode::SUCCESS)
}

fn apply_overrides(mesh: &mut Mesh, args: &Args) {
    let o = &mut mesh.options;
    o.boundary = args.boundary.unwrap_or(o.boundary);
    o.crease_method = args.crease_method.unwrap_or(o.crease_method);
    o.triangle_rule = args.triangle_rule.unwrap_or(o.triangle_rule);
    o.fvar_linear = args.fvar_linear.unwrap_or(o.fvar_linear);
}

/// Faces after `level` refinements: an n-gon makes n quads, each quad four per level after.
fn refined_face_count(mesh: &Mesh, level: usize) -> usize {
    if level == 0 {
        return mesh.face_count();
    }
    mesh.face_vertices()
        .len()
        .saturating_mul(4usize.saturating_pow(level as u32 - 1))
}
