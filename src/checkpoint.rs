//! Checkpoints: everything `tailor simulate --resume` needs to continue a run exactly.
//!
//! After every frame the simulator's whole state at the frame boundary is written atomically
//! to `tailor_checkpoint.bin` in the output directory: positions, velocities and the time
//! (the `f64` the solver accumulates, so later substeps land on the same instants), the
//! positions and velocities one substep back with that substep's length (BDF2 steps from
//! two states: [`tailor_cloth::State::previous`]), what friction carries into the next step
//! for each vertex's body contact ([`tailor_cloth::ContactState`]: lifted off, sticking, and
//! the contact's normal force), the frame number, and the per-frame figures of the summary so
//! far.
//!
//! That is all the state, because everything else a step reads is a function of the scene
//! or is rebuilt within the step: attachment targets and the body's motion are recomputed
//! from the body frames at every frame; the conjugate-gradient solve of each substep starts
//! from the substep's own velocities; the multigrid's aggregates are read off the matrix of
//! the rest shape when the simulator is made; contact sets, impact zones and the strain
//! limiter's order are made afresh in each substep; the collision hierarchies are built from
//! the rest shapes and refit from positions. So a resumed run computes the same bits as an
//! uninterrupted one (`tests/shipped_shots.rs` kills the shipped scenes at several frames and
//! compares every file).
//!
//! The format is little-endian binary, every `f64` stored as its exact bits:
//!
//! ```text
//! "TAILORCK"  u32 version
//! u32 keys  keys × (u32 length, UTF-8 name, u64 hash)        the scene's fingerprint
//! u32 frame  f64 time  u32 vertices
//! vertices × (3 f64 position)  vertices × (3 f64 velocity)
//! vertices × (u8 lifted)  vertices × (u8 stuck)  vertices × (f64 normal force)
//! u8 previous (0 or 1), if 1: f64 step  vertices × (3 f64 position)  vertices × (3 f64 velocity)
//! u32 rows  rows × (u32 frame, f64 ms, f64 strain, 2 u32 strained edge, u32 substeps, u32 cg,
//!                   3 u64 written, u64 penetrating, f64 deepest, u8 has deepest vertex,
//!                   [u32 deepest vertex], u64 self-intersecting pairs, u8 has crossing faces,
//!                   [2 u32 crossing faces])
//! ```
//!
//! The bracketed fields are there only when the flag before them is 1. The deepest vertex
//! and the crossing faces are on the refined surface, as `tailor check`'s test finds them;
//! the quality warnings map them to the garment at the end of the run, resumed or not.
//!
//! The fingerprint ([`crate::scene::Fingerprint`]) refuses a checkpoint of another scene,
//! garment or body, naming the first key that changed; `[scene] frames` may change, so a
//! finished shot can be extended.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use tailor_cloth::Vec3;
use tailor_cloth::{ContactState, Previous, State};
use tailor_subdiv::Point;

use crate::check::Findings;
use crate::output::{remove_spare, write_exchanging};
use crate::scene::Fingerprint;

const MAGIC: &[u8; 8] = b"TAILORCK";
const VERSION: u32 = 7;

/// The checkpoint's file name.
pub const FILE: &str = "tailor_checkpoint.bin";

/// The checkpoint file in an output directory.
#[must_use]
pub fn path(dir: &Path) -> PathBuf {
    dir.join(FILE)
}

/// The figures of one simulated frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Frame number.
    pub frame: u32,
    /// Wall time of the frame's simulation steps, ms.
    pub ms: f64,
    /// Largest |l/L − 1| over the control mesh's edges at the end of the frame.
    pub max_strain: f64,
    /// The control vertices of the edge with that strain, to say where a limit was passed.
    pub strained_edge: [u32; 2],
    /// Substeps taken, counting halved retries.
    pub substeps: u32,
    /// Conjugate-gradient iterations.
    pub cg_iterations: u32,
    /// The length in bytes of each of the frame's files as written: the control mesh, the
    /// surface, the body; 0 for one not written (a sequence the scene turns off, a frame
    /// before the first asked for, a device written in place).
    pub written: [u64; 3],
    /// What `tailor check` finds in the frame's output.
    pub findings: Findings,
}

/// A run's state at the end of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// The scene's fingerprint.
    pub fingerprint: Fingerprint,
    /// The last frame completed.
    pub frame: u32,
    /// Positions, velocities and time after it.
    pub state: State,
    /// What the simulator's friction carries after it.
    pub contacts: ContactState,
    /// Figures of every frame so far.
    pub stats: Vec<FrameStats>,
}

/// Writes `checkpoint` atomically into `dir`, over the one before the last
/// ([`write_exchanging`]); [`release`] removes that spare when the run is done.
///
/// # Errors
/// Any I/O error, naming the file.
pub fn save(dir: &Path, checkpoint: &Checkpoint) -> Result<()> {
    write_exchanging(&path(dir), |w| encode(checkpoint, w))?;
    Ok(())
}

/// Removes the spare [`save`] keeps in `dir` between checkpoints.
///
/// # Errors
/// When it exists and cannot be removed, naming it.
pub fn release(dir: &Path) -> Result<()> {
    remove_spare(&path(dir))
}

fn encode(c: &Checkpoint, w: &mut impl Write) -> io::Result<()> {
    let count = |n: usize| u32::try_from(n).map_err(io::Error::other);
    w.write_all(MAGIC)?;
    w.write_all(&VERSION.to_le_bytes())?;
    w.write_all(&count(c.fingerprint.0.len())?.to_le_bytes())?;
    for (name, hash) in &c.fingerprint.0 {
        w.write_all(&count(name.len())?.to_le_bytes())?;
        w.write_all(name.as_bytes())?;
        w.write_all(&hash.to_le_bytes())?;
    }
    w.write_all(&c.frame.to_le_bytes())?;
    w.write_all(&c.state.time.to_le_bytes())?;
    w.write_all(&count(c.state.positions.len())?.to_le_bytes())?;
    let write_motion = |w: &mut dyn Write, positions: &[Point], velocities: &[Vec3]| {
        let coords = positions.iter().flat_map(|p| p.coords.iter());
        for x in coords.chain(velocities.iter().flat_map(|v| v.iter())) {
            w.write_all(&x.to_le_bytes())?;
        }
        io::Result::Ok(())
    };
    write_motion(w, &c.state.positions, &c.state.velocities)?;
    for flags in [&c.contacts.lifted, &c.contacts.stuck] {
        let flags: Vec<u8> = flags.iter().map(|&b| u8::from(b)).collect();
        w.write_all(&flags)?;
    }
    for force in &c.contacts.normal_force {
        w.write_all(&force.to_le_bytes())?;
    }
    match &c.state.previous {
        None => w.write_all(&[0])?,
        Some(p) => {
            w.write_all(&[1])?;
            w.write_all(&p.step.to_le_bytes())?;
            write_motion(w, &p.positions, &p.velocities)?;
        }
    }
    w.write_all(&count(c.stats.len())?.to_le_bytes())?;
    for s in &c.stats {
        let f = &s.findings;
        w.write_all(&s.frame.to_le_bytes())?;
        w.write_all(&s.ms.to_le_bytes())?;
        w.write_all(&s.max_strain.to_le_bytes())?;
        for v in s.strained_edge {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&s.substeps.to_le_bytes())?;
        w.write_all(&s.cg_iterations.to_le_bytes())?;
        for length in s.written {
            w.write_all(&length.to_le_bytes())?;
        }
        w.write_all(&(f.penetrating_vertices as u64).to_le_bytes())?;
        w.write_all(&f.max_penetration.to_le_bytes())?;
        write_optional(w, f.deepest_vertex.as_ref().map(std::slice::from_ref))?;
        w.write_all(&(f.self_intersecting_pairs as u64).to_le_bytes())?;
        write_optional(w, f.crossing_faces.as_ref().map(|pair| pair.as_slice()))?;
    }
    Ok(())
}

/// A flag, then `values` when there are some.
fn write_optional(w: &mut impl Write, values: Option<&[u32]>) -> io::Result<()> {
    w.write_all(&[u8::from(values.is_some())])?;
    for v in values.unwrap_or_default() {
        w.write_all(&v.to_le_bytes())?;
    }
    Ok(())
}

/// Reads the checkpoint in `dir`, if there is one, checking it belongs to the scene with
/// `fingerprint` and a garment of `vertices` vertices.
///
/// # Errors
/// An unreadable, truncated or foreign checkpoint, naming the file (and for a foreign one
/// the first scene key that differs).
pub fn load(dir: &Path, fingerprint: &Fingerprint, vertices: usize) -> Result<Option<Checkpoint>> {
    let file = path(dir);
    let bytes = match fs::read(&file) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", file.display())),
    };
    let c = decode(&bytes).with_context(|| format!("reading {}", file.display()))?;
    if let Some(key) = c.fingerprint.first_difference(fingerprint) {
        bail!(
            "{} was written for another shot ({key} differs); only [scene] frames and \
             strict may change between a run and its resumption; run without --resume to \
             start over",
            file.display()
        );
    }
    if c.state.positions.len() != vertices {
        bail!(
            "{} holds {} vertices, the garment has {vertices}",
            file.display(),
            c.state.positions.len()
        );
    }
    Ok(Some(c))
}

/// A cursor over the checkpoint's bytes.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N]> {
        let Some((head, rest)) = self.0.split_first_chunk::<N>() else {
            bail!("the file is truncated");
        };
        self.0 = rest;
        Ok(*head)
    }

    fn u32(&mut self) -> Result<u32> {
        self.take().map(u32::from_le_bytes)
    }

    fn u64(&mut self) -> Result<u64> {
        self.take().map(u64::from_le_bytes)
    }

    fn f64(&mut self) -> Result<f64> {
        self.take().map(f64::from_le_bytes)
    }

    fn vec3(&mut self) -> Result<Vec3> {
        Ok(Vec3::new(self.f64()?, self.f64()?, self.f64()?))
    }

    /// `n` positions, then `n` velocities.
    fn motion(&mut self, n: usize) -> Result<(Vec<Point>, Vec<Vec3>)> {
        let positions = (0..n)
            .map(|_| self.vec3().map(Point::from))
            .collect::<Result<_>>()?;
        let velocities = (0..n).map(|_| self.vec3()).collect::<Result<_>>()?;
        Ok((positions, velocities))
    }

    fn count(&mut self) -> Result<usize> {
        Ok(usize::try_from(self.u64()?)?)
    }

    fn flag(&mut self) -> Result<bool> {
        match self.take::<1>()? {
            [0] => Ok(false),
            [1] => Ok(true),
            [x] => bail!("bad flag {x}"),
        }
    }

    /// A flag, then `N` values when it is set (as [`write_optional`] writes them).
    fn optional<const N: usize>(&mut self) -> Result<Option<[u32; N]>> {
        if !self.flag()? {
            return Ok(None);
        }
        let mut values = [0; N];
        for v in &mut values {
            *v = self.u32()?;
        }
        Ok(Some(values))
    }
}

fn decode(bytes: &[u8]) -> Result<Checkpoint> {
    let mut r = Reader(bytes);
    if &r.take::<8>()? != MAGIC {
        bail!("not a tailor checkpoint");
    }
    let version = r.u32()?;
    if version != VERSION {
        bail!("checkpoint version {version}; this tailor reads version {VERSION}");
    }
    let keys = r.u32()?;
    let fingerprint = Fingerprint(
        (0..keys)
            .map(|_| {
                let length = r.u32()? as usize;
                let Some((name, rest)) = r.0.split_at_checked(length) else {
                    bail!("the file is truncated");
                };
                r.0 = rest;
                let name = String::from_utf8(name.to_vec())?;
                Ok((name, r.u64()?))
            })
            .collect::<Result<_>>()?,
    );
    let frame = r.u32()?;
    let time = r.f64()?;
    let n = r.u32()? as usize;
    let (positions, velocities) = r.motion(n)?;
    let mut flags = || (0..n).map(|_| r.flag()).collect::<Result<Vec<_>>>();
    let (lifted, stuck) = (flags()?, flags()?);
    let normal_force = (0..n).map(|_| r.f64()).collect::<Result<_>>()?;
    let contacts = ContactState {
        lifted,
        stuck,
        normal_force,
    };
    let previous = if r.flag()? {
        let step = r.f64()?;
        let (positions, velocities) = r.motion(n)?;
        Some(Previous {
            positions,
            velocities,
            step,
        })
    } else {
        None
    };
    let rows = r.u32()?;
    let stats = (0..rows)
        .map(|_| {
            Ok(FrameStats {
                frame: r.u32()?,
                ms: r.f64()?,
                max_strain: r.f64()?,
                strained_edge: [r.u32()?, r.u32()?],
                substeps: r.u32()?,
                cg_iterations: r.u32()?,
                written: [r.u64()?, r.u64()?, r.u64()?],
                findings: Findings {
                    penetrating_vertices: r.count()?,
                    max_penetration: r.f64()?,
                    deepest_vertex: r.optional()?.map(|[v]| v),
                    self_intersecting_pairs: r.count()?,
                    crossing_faces: r.optional()?,
                },
            })
        })
        .collect::<Result<_>>()?;
    if !r.0.is_empty() {
        bail!("{} unexpected bytes at the end", r.0.len());
    }
    Ok(Checkpoint {
        fingerprint,
        frame,
        state: State {
            positions,
            velocities,
            time,
            previous,
        },
        contacts,
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_exact_bits_and_rejects_damage() {
        let c = Checkpoint {
            fingerprint: Fingerprint(vec![
                ("[cloth] friction".to_owned(), 0x1234_5678_9abc_def0),
                ("[scene] fps".to_owned(), 7),
            ]),
            frame: 7,
            state: State {
                positions: vec![Point::new(0.1, -2.5e-300, 1.0 / 3.0); 2],
                velocities: vec![Vec3::new(f64::MIN_POSITIVE, -0.0, 7.0); 2],
                time: 7.0 / 24.0,
                previous: Some(Previous {
                    positions: vec![Point::new(-0.0, 1e-310, 2.0); 2],
                    velocities: vec![Vec3::new(3.0, f64::MAX, -1.5); 2],
                    step: 1.0 / 120.0,
                }),
            },
            contacts: ContactState {
                lifted: vec![true, false],
                stuck: vec![false, true],
                normal_force: vec![0.0, 2.5e-4],
            },
            stats: vec![
                FrameStats {
                    frame: 6,
                    ms: 11.0,
                    ..FrameStats::default()
                },
                FrameStats {
                    frame: 7,
                    ms: 12.5,
                    max_strain: 0.03,
                    strained_edge: [4, 1],
                    substeps: 5,
                    cg_iterations: 40,
                    written: [0, u64::MAX, 1_234_567],
                    findings: Findings {
                        penetrating_vertices: 3,
                        max_penetration: 0.001,
                        deepest_vertex: Some(u32::MAX),
                        self_intersecting_pairs: 1,
                        crossing_faces: Some([9, 0x0102_0304]),
                    },
                },
            ],
        };
        let mut bytes = Vec::new();
        encode(&c, &mut bytes).unwrap();
        let back = decode(&bytes).unwrap();
        assert_eq!(back, c);
        assert!(back.state.velocities[0].y.is_sign_negative());
        assert!(decode(&bytes[..bytes.len() - 1]).is_err());
        // The last byte before the last row's crossing faces is their flag.
        let flag = bytes.len() - 9;
        assert_eq!(bytes[flag], 1);
        bytes[flag] = 2;
        let error = decode(&bytes).unwrap_err().to_string();
        assert!(error.contains("bad flag 2"), "{error}");
        bytes[flag] = 0;
        assert!(
            decode(&bytes).is_err(),
            "8 bytes too many without the faces"
        );
        bytes[0] = b'X';
        assert!(decode(&bytes).is_err());
    }
}
