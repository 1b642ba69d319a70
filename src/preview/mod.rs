//! `tailor preview`: a contact sheet (PNG) and optionally an animated GIF of chosen frames of a
//! simulation, drawn by a small software rasterizer, because people look at cloth, they do not
//! read vertex lists.
//!
//! The pipeline, one file per step: [`camera`] frames every vertex of every chosen frame once,
//! so the picture does not jump between frames; [`shade`] computes normals and lights a point;
//! [`raster`] fills triangles with edge functions and a z-buffer; [`render`] draws the cloth
//! and the body of each frame into its own tile; [`sheet`] labels the tiles with the
//! [`font`] and lays them out in a [`picture`] (PNG through the `png` crate); [`gif`] animates
//! them; [`frames`] finds and reads the files.
//!
//! **For the simulate command**: call [`render_sheet`] (or [`render::render_frames`] for the
//! tiles, e.g. for [`gif::encode`]) with in-memory meshes and write the image with
//! [`write_png`]. For `tailor preview DIR` to show a body, write the body surface the cloth
//! collided with (the refined body, not its control mesh) as `body_####.obj` beside each
//! `cloth_####.obj`, with the same frame numbers; otherwise `--body` names it.

pub mod camera;
pub mod font;
pub mod frames;
pub mod gif;
pub mod picture;
pub mod raster;
pub mod render;
pub mod shade;
pub mod sheet;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;
use std::time::Instant;

use anyhow::Result;
use nalgebra::Point3;

use crate::output::write_atomically;
use crate::polymesh_obj::PolyMesh;
use frames::FrameList;
use picture::Picture;

/// A polygon mesh borrowed for drawing: positions and CSR faces, the layout of [`PolyMesh`]
/// and `tailor_subdiv::Mesh`. Faces are counter-clockwise seen from outside.
#[derive(Clone, Copy, Debug)]
pub struct MeshView<'a> {
    /// Vertex positions.
    pub positions: &'a [Point3<f64>],
    /// Face `f` uses `face_vertices[face_offsets[f]..face_offsets[f + 1]]`.
    pub face_offsets: &'a [u32],
    /// Vertex indices of all faces, one after another; each must index `positions`.
    pub face_vertices: &'a [u32],
}

impl<'a> From<&'a PolyMesh> for MeshView<'a> {
    fn from(mesh: &'a PolyMesh) -> Self {
        Self {
            positions: &mesh.positions,
            face_offsets: &mesh.face_offsets,
            face_vertices: &mesh.face_vertices,
        }
    }
}

/// What one tile of the sheet shows.
#[derive(Clone, Copy, Debug)]
pub struct FrameMeshes<'a> {
    /// The frame number written on the tile.
    pub frame: u32,
    /// The cloth surface (subdivided), drawn in colour, both sides lit.
    pub cloth: MeshView<'a>,
    /// The body, drawn in grey, when there is one.
    pub body: Option<MeshView<'a>>,
}

/// How surfaces are shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Shading {
    /// One normal per polygon: facets show, as in the mesh.
    Flat,
    /// Vertex normals interpolated per pixel: smooth.
    Phong,
}

/// How the pictures are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Width of one frame's picture, in pixels.
    pub width: u32,
    /// Height of one frame's picture, in pixels.
    pub height: u32,
    /// Flat or Phong shading.
    pub shading: Shading,
    /// Viewing direction about +Y, in degrees: 0 from the front (+Z), 90 from +X, 180 from
    /// behind.
    pub azimuth: f64,
    /// Viewing direction above the horizon, in degrees, strictly between −90 and 90.
    pub elevation: f64,
}

impl Default for Options {
    /// 320 × 400 tiles, Phong shading, seen from behind and to the mannequin's left (a cape
    /// hangs at the back), slightly from above.
    fn default() -> Self {
        Self {
            width: 320,
            height: 400,
            shading: Shading::Phong,
            azimuth: 150.0,
            elevation: 15.0,
        }
    }
}

/// Renders `frames` as a contact sheet: one tile per frame, in order, from one fixed camera.
///
/// # Panics
/// When `frames` is empty or a face indexes past its mesh's positions.
#[must_use]
pub fn render_sheet(frames: &[FrameMeshes], options: &Options) -> Picture {
    sheet::compose(&render::render_frames(frames, options))
}

/// Writes `image` as a PNG file, atomically.
///
/// # Errors
/// When the file cannot be written.
pub fn write_png(path: &Path, picture: &Picture) -> Result<()> {
    write_atomically(path, |out| picture.write_png(out))?;
    Ok(())
}

/// Largest tile side accepted by `--size` (it is rendered at twice that).
const MAX_SIDE: u32 = 2048;

/// A tile size `WxH`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    width: u32,
    height: u32,
}

impl FromStr for Size {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let parsed = text
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)));
        match parsed {
            Some((width, height))
                if (16..=MAX_SIDE).contains(&width) && (16..=MAX_SIDE).contains(&height) =>
            {
                Ok(Self { width, height })
            }
            _ => Err(format!(
                "{text:?} is not WIDTHxHEIGHT with each side from 16 to {MAX_SIDE} pixels"
            )),
        }
    }
}

/// Arguments of `tailor preview`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "DIR holds cloth_####.obj (the subdivided cloth of each frame) and, when the \
run had a body, body_####.obj with the same frame numbers. Exit status: 0 when the pictures are \
written, 1 when DIR has no frames or a file cannot be read or written, 2 for a usage error (no \
such directory, a bad option)."
)]
pub struct Args {
    /// Simulation output directory.
    pub dir: PathBuf,
    /// Frames to show: `0,30,60`, `0-120` or `0-120x10` (every 10th), or a mix. By default all
    /// frames when there are at most 12, else 12 evenly spaced from the first to the last.
    #[arg(long, value_name = "LIST")]
    pub frames: Option<FrameList>,
    /// The contact sheet (PNG).
    #[arg(short, long, value_name = "PNG", default_value = "preview.png")]
    pub output: PathBuf,
    /// Also write the chosen frames as an animated GIF.
    #[arg(long, value_name = "GIF")]
    pub gif: Option<PathBuf>,
    /// Frames per second of the GIF.
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..=100))]
    pub fps: u32,
    /// Flat (facets) or Phong (smooth) shading.
    #[arg(long, value_enum, default_value_t = Shading::Phong)]
    pub shading: Shading,
    /// Size of one frame's picture, in pixels.
    #[arg(long, value_name = "WxH", default_value = "320x400")]
    pub size: Size,
    /// Body OBJ, or a body sequence pattern such as `scene/body_####.obj`, when DIR has no
    /// body files (or to use another body).
    #[arg(long, value_name = "BODY")]
    pub body: Option<PathBuf>,
    /// View direction about the vertical, in degrees: 0 from the front (+Z), 90 from +X, 180
    /// from behind.
    #[arg(long, default_value_t = 150.0, allow_negative_numbers = true)]
    pub azimuth: f64,
    /// View direction above the horizon, in degrees (−89 to 89).
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
    pub elevation: f64,
}

/// Runs `tailor preview`: exit 0 when written, 1 on a runtime error, 2 on a usage error.
///
/// # Errors
/// When no frames are found or a file cannot be read or written.
pub fn run(args: &Args) -> Result<ExitCode> {
    let usage = if !args.dir.is_dir() {
        Some(format!("{}: no such directory", args.dir.display()))
    } else if !(-89.0..=89.0).contains(&args.elevation) || !args.azimuth.is_finite() {
        Some("--elevation must be from -89 to 89 and --azimuth finite".to_owned())
    } else {
        None
    };
    if let Some(message) = usage {
        eprintln!("error: {message}");
        return Ok(ExitCode::from(2));
    }
    let start = Instant::now();
    let available = frames::available(&args.dir)?;
    let chosen = frames::choose(&args.dir, &available, args.frames.as_ref())?;
    let loaded = frames::load(&args.dir, &chosen, args.body.as_deref())?;
    let meshes: Vec<FrameMeshes> = loaded
        .iter()
        .map(|l| FrameMeshes {
            frame: l.frame,
            cloth: (&l.cloth).into(),
            body: l.body.as_ref().map(Into::into),
        })
        .collect();
    let options = Options {
        width: args.size.width,
        height: args.size.height,
        shading: args.shading,
        azimuth: args.azimuth,
        elevation: args.elevation,
    };
    let sheet = render_sheet(&meshes, &options);
    write_png(&args.output, &sheet)?;
    if let Some(path) = &args.gif {
        let tiles = render::render_frames(&meshes, &options);
        write_atomically(path, |out| gif::encode(out, &tiles, args.fps))?;
    }
    let bodies = if meshes.iter().any(|m| m.body.is_some()) {
        "cloth and body"
    } else {
        "cloth only, no body files"
    };
    eprintln!(
        "{}: {} frame(s) ({bodies}), {}x{} in {:.1} s",
        args.output.display(),
        meshes.len(),
        sheet.width(),
        sheet.height(),
        start.elapsed().as_secs_f64()
    );
    Ok(ExitCode::SUCCESS)
}
