//! Scene files: the TOML a technical director writes for one shot, and its validation.
//!
//! A scene names the garment (a Catmull-Clark control mesh with groups), its fabric, which
//! vertices are pinned or attached to the body, the body (an OBJ sequence, `body_####.obj`, or
//! one static OBJ), what to write, and whether a frame failing its quality fails the run. `assets/scenes/cape.toml` is the annotated example; every
//! key and its default is documented on the structs below. Paths are relative to the scene
//! file. Unknown keys are errors (a misspelt `thicknes` must not silently fall back to the
//! default).
//!
//! [`load`] reads and checks everything before anything is simulated or written: the garment
//! and every body frame the run needs are read (so a missing file, a NaN coordinate or a body
//! frame whose topology differs from the first is found up front), groups and vertex indices
//! in `pins`, `attach` and `stiffen` are resolved, and every number is range-checked. Each error
//! names the scene file and the key, or the mesh file and its line.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use nalgebra::Vector3;
use serde::Deserialize;
use tailor_cloth::{Integrator, Material, Stiffness};
use tailor_subdiv::obj::{self, ObjDocument, Precision};
use tailor_subdiv::{Mesh, Point};

use crate::sequence::Pattern;

/// The file as written: sections of optional keys.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    scene: SceneSection,
    cloth: ClothSection,
    body: Option<BodySection>,
    #[serde(default)]
    output: OutputSection,
}

/// `[scene]`: time, and how strict the run is.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields, default)]
struct SceneSection {
    /// Frames per second of the body animation and of the output.
    fps: f64,
    /// Frames simulated after the rest frame 0.
    frames: u32,
    /// Implicit steps per frame (the substep is 1 / (fps · substeps) seconds).
    substeps: u32,
    /// The implicit integrator.
    integrator: IntegratorName,
    /// m/s².
    gravity: [f64; 3],
    /// Exit with status 3 when a frame fails its quality, as `--strict` does.
    strict: bool,
}

impl Default for SceneSection {
    fn default() -> Self {
        Self {
            fps: 24.0,
            frames: 60,
            substeps: 5,
            integrator: IntegratorName::Bdf2,
            gravity: [0.0, -9.81, 0.0],
            strict: false,
        }
    }
}

/// Most frames a second: above it a frame is shorter than any motion a body file carries
/// (and `fps = 1e308` made the substep zero).
const MAX_FPS: f64 = 10_000.0;

/// The last frame a run may simulate: 11.5 hours at 24 fps, and far from `u32`'s end.
const MAX_FRAMES: u32 = 1_000_000;

/// Most substeps a frame: a thousand at 24 fps is a substep of 42 µs, past anything the
/// solver's accuracy can use (and 4294967295 ran for ever).
const MAX_SUBSTEPS: u32 = 1000;

/// Largest gravity component, m/s²: a thousand g.
const MAX_GRAVITY: f64 = 9_810.0;

/// `[scene] integrator`: the names of [`Integrator`]'s choices.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum IntegratorName {
    Bdf2,
    BackwardEuler,
}

/// `[cloth]`: the garment, its fabric and its constraints.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct ClothSection {
    mesh: PathBuf,
    #[serde(default = "default_material")]
    material: String,
    density: Option<f64>,
    stretch: Option<f64>,
    compression: Option<f64>,
    shear: Option<f64>,
    bend: Option<f64>,
    damping: Option<f64>,
    drag: Option<f64>,
    #[serde(default = "default_thickness")]
    thickness: f64,
    #[serde(default = "default_friction")]
    friction: f64,
    #[serde(default = "default_strain_limit")]
    strain_limit: f64,
    #[serde(default = "default_true")]
    self_collision: bool,
    #[serde(default)]
    pins: Vec<Selector>,
    #[serde(default)]
    attach: Vec<Selector>,
    #[serde(default)]
    stiffen: BTreeMap<String, Stiffen>,
}

fn default_material() -> String {
    "cotton".into()
}

fn default_thickness() -> f64 {
    0.005
}

fn default_friction() -> f64 {
    0.3
}

fn default_strain_limit() -> f64 {
    0.1
}

fn default_true() -> bool {
    true
}

/// One entry of `pins` or `attach`: a group of the garment (the vertices of its faces) or a
/// 0-based vertex index.
#[derive(Deserialize, Debug)]
#[serde(untagged)]
enum Selector {
    Group(String),
    Vertex(i64),
}

/// One entry of `stiffen`: a factor for all three energies, or one per energy.
#[derive(Deserialize, Debug)]
#[serde(untagged)]
enum Stiffen {
    All(f64),
    Each(StiffenEach),
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct StiffenEach {
    stretch: Option<f64>,
    shear: Option<f64>,
    bend: Option<f64>,
}

/// `[body]`: the animated character.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct BodySection {
    mesh: PathBuf,
    #[serde(default = "default_first_frame")]
    first_frame: u32,
    #[serde(default = "default_body_level")]
    subdivision_level: u32,
}

fn default_first_frame() -> u32 {
    1
}

fn default_body_level() -> u32 {
    2
}

/// `[output]`: what to write where.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields, default)]
struct OutputSection {
    dir: PathBuf,
    subdivision_level: u32,
    control_mesh: bool,
    limit_normals: bool,
    body: bool,
    precision: PrecisionName,
}

impl Default for OutputSection {
    fn default() -> Self {
        Self {
            dir: "out".into(),
            subdivision_level: 2,
            control_mesh: true,
            limit_normals: false,
            body: true,
            precision: PrecisionName::Single,
        }
    }
}

/// `[output] precision`: the names of [`Precision`]'s choices.
#[derive(Deserialize, Debug, Clone, Copy)]
#[serde(rename_all = "kebab-case")]
enum PrecisionName {
    Single,
    Full,
}

/// Deepest subdivision level accepted for output or body (each level multiplies faces by 4).
const MAX_LEVEL: u32 = 4;

/// A validated scene, paths resolved, meshes read.
#[derive(Debug)]
pub struct Scene {
    /// The scene file.
    pub path: PathBuf,
    /// Frames per second.
    pub fps: f64,
    /// Frames simulated after the rest frame (the last frame number).
    pub frames: u32,
    /// Implicit steps per frame.
    pub substeps: u32,
    /// The implicit integrator.
    pub integrator: Integrator,
    /// m/s².
    pub gravity: Vector3<f64>,
    /// Whether a frame failing its quality (strain, penetration, self-intersection) makes
    /// the run exit with status 3 once everything is written.
    pub strict: bool,
    /// The garment.
    pub cloth: Cloth,
    /// The body, if any.
    pub body: Option<Body>,
    /// What to write.
    pub output: Output,
    /// What determines the simulation, key by key, stored in checkpoints so a resume cannot
    /// continue a different shot.
    pub fingerprint: Fingerprint,
}

/// The scene keys a resumed run may change.
const IGNORED_ON_RESUME: [&str; 2] = ["[scene] frames", "[scene] strict"];

/// What determines a shot, key by key: a hash of each scene key's value, of the garment file
/// and of the body's first frame. `[scene] frames` is left out, so that a resumed run may
/// extend a shot (frames are simulated one after another, and frame 40 of a 60-frame run is
/// frame 40 of a 40-frame one), and so is `[scene] strict`, which only decides the exit
/// status. A key given with its default value counts as changed from the key left out, which
/// errs on the side of refusing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Fingerprint(pub Vec<(String, u64)>);

impl Fingerprint {
    /// The entries of the scene `table` (its text parsed), then `files` (name and bytes).
    fn new(table: &toml::Table, files: &[(&str, &[u8])]) -> Self {
        let mut entries = Vec::new();
        for (section, value) in table {
            let keys: Vec<(String, &toml::Value)> = match value.as_table() {
                Some(keys) => keys
                    .iter()
                    .map(|(key, value)| (format!("[{section}] {key}"), value))
                    .collect(),
                None => vec![(section.clone(), value)],
            };
            for (name, value) in keys {
                if !IGNORED_ON_RESUME.contains(&name.as_str()) {
                    entries.push((name, Fnv::hash(value.to_string().as_bytes())));
                }
            }
        }
        for (name, bytes) in files {
            entries.push(((*name).to_owned(), Fnv::hash(bytes)));
        }
        entries.sort();
        Self(entries)
    }

    /// The first entry, by name, that `self` and `other` do not share with the same hash.
    #[must_use]
    pub fn first_difference<'a>(&'a self, other: &'a Self) -> Option<&'a str> {
        let hash = |of: &Self, name: &str| of.0.iter().find(|(n, _)| n == name).map(|e| e.1);
        self.0
            .iter()
            .chain(&other.0)
            .map(|(name, _)| name.as_str())
            .filter(|name| hash(self, name) != hash(other, name))
            .min()
    }
}

/// The garment and its fabric.
#[derive(Debug)]
pub struct Cloth {
    /// The control mesh file.
    pub path: PathBuf,
    /// The control mesh and its groups.
    pub doc: ObjDocument,
    /// The fabric: the preset with the scene's overrides.
    pub material: Material,
    /// Clearance kept from the body and between layers, m.
    pub thickness: f64,
    /// Coulomb friction coefficient against the body.
    pub friction: f64,
    /// Largest stretch or squash of an edge, a fraction of its rest length (0: no limit).
    pub strain_limit: f64,
    /// Whether the cloth collides with itself.
    pub self_collision: bool,
    /// Vertices fixed at their rest positions, ascending, without repeats.
    pub pins: Vec<u32>,
    /// Vertices bound to the body, ascending, without repeats.
    pub attach: Vec<u32>,
    /// Per-vertex stiffness multipliers (`stiffen`), indexed by [`Stiffness`].
    pub multipliers: [(Stiffness, Vec<f64>); 3],
}

/// The animated body: its rest control mesh and the control points of every frame needed.
#[derive(Debug)]
pub struct Body {
    /// The first frame's control mesh (topology, tags, options).
    pub rest: Mesh,
    /// Control points of simulation frames 0, 1, …; one entry for a static body.
    pub frames: Vec<Vec<Point>>,
    /// Catmull-Clark level the body is refined to for attachment and collision.
    pub level: u32,
}

impl Body {
    /// The control points at simulation frame `frame` (a static body has one pose).
    #[must_use]
    pub fn control(&self, frame: u32) -> &[Point] {
        let last = self.frames.len() - 1;
        &self.frames[(frame as usize).min(last)]
    }
}

/// What to write.
#[derive(Debug)]
pub struct Output {
    /// Output directory.
    pub dir: PathBuf,
    /// Catmull-Clark level of `cloth_####.obj`.
    pub level: u32,
    /// Whether to write `cloth_control_####.obj`.
    pub control_mesh: bool,
    /// Whether `cloth_####.obj` carries limit normals.
    pub limit_normals: bool,
    /// Whether to write the refined body `body_####.obj` beside the cloth.
    pub body: bool,
    /// Digits of the coordinates written: the shortest text of each as an `f32`, or as the
    /// `f64` itself. Only the files change: the simulation, the checkpoint and the figures of
    /// `tailor check`'s test keep every bit of the `f64`s.
    pub precision: Precision,
}

/// Reads and validates the scene at `path`, with the body frames of simulation frames
/// `0..=last_frame` (the scene's `frames` when `None`).
///
/// # Errors
/// Any problem with the scene or the files it names, with the file and the key or line.
pub fn load(path: &Path, last_frame: Option<u32>) -> Result<Scene> {
    let name = path.display().to_string();
    let text = fs::read_to_string(path).with_context(|| format!("reading {name}"))?;
    let file: SceneFile = toml::from_str(&text).map_err(|e| anyhow!("{name}: {e}"))?;
    let base = path.parent().unwrap_or(Path::new(""));
    let at = |key: &str| format!("{name}: {key}");
    let scene = &file.scene;
    positive(scene.fps, &at("[scene] fps"))?;
    if scene.fps > MAX_FPS {
        bail!(
            "{}: {} is above {MAX_FPS} frames a second",
            at("[scene] fps"),
            scene.fps
        );
    }
    let last = last_frame.unwrap_or(scene.frames);
    if last > MAX_FRAMES {
        let asked = match last_frame {
            Some(_) => "--frames".to_owned(),
            None => at("[scene] frames"),
        };
        bail!("{asked}: frame {last} is past {MAX_FRAMES}, the most a run simulates");
    }
    if !(1..=MAX_SUBSTEPS).contains(&scene.substeps) {
        bail!(
            "{}: {} is not between 1 and {MAX_SUBSTEPS}",
            at("[scene] substeps"),
            scene.substeps
        );
    }
    if !scene
        .gravity
        .iter()
        .all(|g| g.is_finite() && g.abs() <= MAX_GRAVITY)
    {
        bail!(
            "{}: each component must be finite and at most {MAX_GRAVITY} m/s² in size",
            at("[scene] gravity")
        );
    }
    let cloth = cloth(&file.cloth, base, &at)?;
    let body = file
        .body
        .as_ref()
        .map(|b| body(b, base, last, &at))
        .transpose()?;
    if body.is_none() && !cloth.attach.is_empty() {
        bail!(
            "{}: names vertices to attach, but the scene has no [body]",
            at("[cloth] attach")
        );
    }
    let out = &file.output;
    for (key, level) in [
        ("[output] subdivision_level", out.subdivision_level),
        (
            "[body] subdivision_level",
            body.as_ref().map_or(0, |b| b.level),
        ),
    ] {
        if level > MAX_LEVEL {
            bail!("{}: {level} is deeper than {MAX_LEVEL}", at(key));
        }
    }
    let table: toml::Table = text.parse().map_err(|e| anyhow!("{name}: {e}"))?;
    let garment = fs::read(&cloth.path).with_context(|| at("[cloth] mesh"))?;
    let mut files = vec![("[cloth] mesh (the file)", garment.as_slice())];
    let first_body: Vec<u8> = body
        .iter()
        .flat_map(|b| &b.frames[0])
        .flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes()))
        .collect();
    if body.is_some() {
        files.push(("[body] mesh (the first frame)", first_body.as_slice()));
    }
    Ok(Scene {
        path: path.to_path_buf(),
        fps: scene.fps,
        frames: scene.frames,
        substeps: scene.substeps,
        integrator: match scene.integrator {
            IntegratorName::Bdf2 => Integrator::Bdf2,
            IntegratorName::BackwardEuler => Integrator::BackwardEuler,
        },
        gravity: Vector3::from(scene.gravity),
        strict: scene.strict,
        cloth,
        body,
        output: Output {
            dir: base.join(&out.dir),
            level: out.subdivision_level,
            control_mesh: out.control_mesh,
            limit_normals: out.limit_normals,
            body: out.body,
            precision: match out.precision {
                PrecisionName::Single => Precision::Single,
                PrecisionName::Full => Precision::Full,
            },
        },
        fingerprint: Fingerprint::new(&table, &files),
    })
}

/// Checks that `value` is finite and > 0.
fn positive(value: f64, place: &str) -> Result<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        bail!("{place} = {value}: must be a finite number > 0")
    }
}

fn cloth(c: &ClothSection, base: &Path, at: &dyn Fn(&str) -> String) -> Result<Cloth> {
    let path = base.join(&c.mesh);
    let doc = obj::read(&path).with_context(|| at("[cloth] mesh"))?;
    let preset = match c.material.to_ascii_lowercase().as_str() {
        "cotton" => Material::COTTON,
        "silk" => Material::SILK,
        "denim" => Material::DENIM,
        "leather" => Material::LEATHER,
        other => bail!(
            "{}: unknown material {other:?} (presets: cotton, silk, denim, leather)",
            at("[cloth] material")
        ),
    };
    let pick = |given: Option<f64>, preset: f64| given.unwrap_or(preset);
    let material = Material {
        density: pick(c.density, preset.density),
        stretch: pick(c.stretch, preset.stretch),
        compression: pick(c.compression, preset.compression),
        shear: pick(c.shear, preset.shear),
        bend: pick(c.bend, preset.bend),
        damping: pick(c.damping, preset.damping),
        drag: pick(c.drag, preset.drag),
    };
    if let Err(err) = material.validate() {
        let key = match err {
            tailor_cloth::ClothError::BadMaterial { name, .. } => name,
            _ => "material",
        };
        bail!("{}: {err}", at(&format!("[cloth] {key}")));
    }
    positive(c.thickness, &at("[cloth] thickness"))?;
    if !(c.friction >= 0.0 && c.friction.is_finite()) {
        bail!(
            "{} = {}: must be a finite number >= 0",
            at("[cloth] friction"),
            c.friction
        );
    }
    if !(0.0..1.0).contains(&c.strain_limit) {
        bail!(
            "{} = {}: must be at least 0 (no limit) and below 1",
            at("[cloth] strain_limit"),
            c.strain_limit
        );
    }
    let groups = Groups::new(&doc, &path);
    let pins = groups.select(&c.pins, &at("[cloth] pins"))?;
    let attach = groups.select(&c.attach, &at("[cloth] attach"))?;
    let n = doc.mesh.vertex_count();
    let mut multipliers = [
        (Stiffness::Stretch, vec![1.0; n]),
        (Stiffness::Shear, vec![1.0; n]),
        (Stiffness::Bend, vec![1.0; n]),
    ];
    for (group, factor) in &c.stiffen {
        let place = at(&format!("[cloth] stiffen.{group}"));
        let vertices = groups.vertices(group).with_context(|| place.clone())?;
        let factors = match factor {
            Stiffen::All(f) => [Some(*f); 3],
            Stiffen::Each(e) => [e.stretch, e.shear, e.bend],
        };
        for ((_, m), f) in multipliers.iter_mut().zip(factors) {
            let Some(f) = f else { continue };
            if !(f >= 0.0 && f.is_finite()) {
                bail!("{place} = {f}: must be a finite number >= 0");
            }
            for &v in &vertices {
                m[v as usize] *= f;
            }
        }
    }
    Ok(Cloth {
        path,
        doc,
        material,
        thickness: c.thickness,
        friction: c.friction,
        strain_limit: c.strain_limit,
        self_collision: c.self_collision,
        pins,
        attach,
        multipliers,
    })
}

/// The garment's groups, for `pins`, `attach` and `stiffen`.
struct Groups<'a> {
    doc: &'a ObjDocument,
    file: &'a Path,
}

impl<'a> Groups<'a> {
    fn new(doc: &'a ObjDocument, file: &'a Path) -> Self {
        Self { doc, file }
    }

    /// The vertices of a group's faces, ascending.
    fn vertices(&self, name: &str) -> Result<Vec<u32>> {
        let Some(group) = self.doc.groups.iter().find(|g| g.name == name) else {
            let names: Vec<&str> = self.doc.groups.iter().map(|g| g.name.as_str()).collect();
            bail!(
                "group {name:?} is not in {} (its groups: {})",
                self.file.display(),
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            );
        };
        let mut vertices: Vec<u32> = group
            .faces
            .iter()
            .flat_map(|&f| self.doc.mesh.face(f as usize))
            .copied()
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        Ok(vertices)
    }

    /// The vertices a `pins` or `attach` list names, ascending, without repeats.
    fn select(&self, list: &[Selector], place: &str) -> Result<Vec<u32>> {
        let count = self.doc.mesh.vertex_count();
        let mut out = Vec::new();
        for (i, item) in list.iter().enumerate() {
            match item {
                Selector::Group(name) => out.extend(
                    self.vertices(name)
                        .with_context(|| format!("{place}[{i}]"))?,
                ),
                Selector::Vertex(v) => match u32::try_from(*v) {
                    Ok(v) if (v as usize) < count => out.push(v),
                    _ => bail!(
                        "{place}[{i}]: vertex {v} is out of range ({} has {count} vertices, \
                         numbered from 0)",
                        self.file.display()
                    ),
                },
            }
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

fn body(b: &BodySection, base: &Path, last: u32, at: &dyn Fn(&str) -> String) -> Result<Body> {
    let path = base.join(&b.mesh);
    let place = at("[body] mesh");
    // Paths are made one by one and checked as they come, so that a scene asking for more
    // frames than there are files stops at the first missing one, whatever it asks.
    let mut files: Vec<PathBuf> = Vec::new();
    match Pattern::parse(&path) {
        Some(pattern) => {
            for k in 0..=last {
                let Some(number) = b.first_frame.checked_add(k) else {
                    bail!(
                        "{place}: frame {} + {k} is past the last frame number",
                        b.first_frame
                    );
                };
                let file = pattern.path(number);
                if !file.is_file() {
                    bail!("{place}: {} does not exist", file.display());
                }
                files.push(file);
            }
        }
        None if path.is_file() => files.push(path.clone()),
        None => bail!("{place}: {} does not exist", path.display()),
    }
    let first = obj::read(&files[0]).with_context(|| place.clone())?;
    let rest = first.mesh;
    let mut frames = vec![rest.positions().to_vec()];
    for file in &files[1..] {
        let mesh = obj::read(file).with_context(|| place.clone())?.mesh;
        if mesh.face_offsets() != rest.face_offsets()
            || mesh.face_vertices() != rest.face_vertices()
            || mesh.vertex_count() != rest.vertex_count()
        {
            bail!(
                "{place}: {} ({} vertices, {} faces) does not have the topology of the first \
                 frame {} ({} vertices, {} faces); every frame must have the same vertices and faces",
                file.display(),
                mesh.vertex_count(),
                mesh.face_count(),
                files[0].display(),
                rest.vertex_count(),
                rest.face_count()
            );
        }
        frames.push(mesh.positions().to_vec());
    }
    Ok(Body {
        rest,
        frames,
        level: b.subdivision_level,
    })
}

/// 64-bit FNV-1a: a stable hash (unlike `std`'s, the same in every build) for fingerprints.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn hash(bytes: &[u8]) -> u64 {
        let mut hash = Self::new();
        hash.bytes(bytes);
        hash.0
    }
}
