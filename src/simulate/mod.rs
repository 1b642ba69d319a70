//! `tailor simulate SCENE.toml`: run one shot.
//!
//! The scene is read and validated whole first ([`crate::scene`]); nothing is written before
//! it passes. Then, built once: the garment's mass-spring [`Model`] and [`Simulator`]
//! (substeps of 1 / (fps · substeps) seconds: time is in seconds, never frames), the stencils
//! of its output surface, the body's stencils and collision hierarchy, and the attachment
//! [`Bindings`](attach::Bindings) made on the body's first frame; the refined body is the
//! simulator's obstacle. Per frame: the body's refined surface at the frame's end, attachment
//! targets and the obstacle moving on the straight line between the two poses, the implicit
//! steps (with the scene's thickness, friction and self-collision), then `cloth_control_####.obj`, `cloth_####.obj` and the
//! refined `body_####.obj`, each written atomically, the figures of `tailor check`'s test
//! ([`crate::check::inspect`]) and a checkpoint ([`crate::checkpoint`]). Frame 0 is the rest
//! pose. A step that fails (a non-finite value, a solve that does not converge after the
//! simulator's retries) or stretches an edge past [`MAX_STRAIN`] stops the run with an error
//! naming the frame; the frame is not written, so nothing non-finite reaches the disk.
//!
//! A run that ends is judged ([`quality`]): frames whose strain passed the scene's limit, or
//! where `tailor check`'s test found something, are warned about on standard error and listed
//! in `summary.json`. With `--strict` (or `[scene] strict = true`) they make the exit status 3,
//! after every frame, the checkpoint and the summary are written, so a pipeline can stop on a
//! bad shot and still look at it.
//!
//! Before the first frame, a run removes the temporaries that killed runs left in the output
//! directory and, unless it resumes, the files of an earlier run there: its own files' only
//! ([`outputs`]). Ctrl-C stops the run after the frame being
//! written, with its checkpoint, exit status 130 ([`crate::interrupt`]). A resumed run first
//! checks that the frames its checkpoint counts are there with the lengths they were written
//! with ([`outputs::check_written`]): files are not forced to disk ([`crate::output`]).
//!
//! Work runs on a rayon pool of `--threads` threads; every parallel loop in the crates reduces
//! in a fixed order, so the bytes written do not depend on the count. With two threads or more,
//! checking, writing and checkpointing a frame ([`Output`]) run on one more thread while the
//! next frame simulates: they took a third of the 64² drape's run, on a core the simulation's
//! serial passes leave idle much of the time. A failure on either side stops the run after
//! the frames simulated before it are written, so a checkpoint is never ahead of its files.

mod attach;
mod outputs;
mod quality;
mod summary;
mod surface;

use std::fs;
use std::io::{IsTerminal, Write};
use std::num::NonZeroUsize;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use tailor_cloth::{ContactState, Model, Motion, Settings, Simulator, State};
use tailor_collide::same_bits;
use tailor_subdiv::Point;
use tailor_subdiv::obj::Frames;

use crate::check::Clearances;
use crate::checkpoint::{self, Checkpoint, FrameStats};
use crate::interrupt;
use crate::output::{self, write_atomically};
use crate::scene::{self, Scene};
use attach::Bindings;
use outputs::Sequence;
use surface::Surface;

/// Strain (|l/L − 1| of an edge) past which a run counts as diverged: an edge ten times
/// its rest length is an explosion, not cloth.
pub const MAX_STRAIN: f64 = 10.0;

/// Arguments of `tailor simulate`.
#[derive(clap::Args, Debug, Clone)]
#[command(
    after_help = "Writes per frame cloth_control_####.obj (the simulated control mesh, \
with UVs and groups), cloth_####.obj (its Catmull-Clark surface) and body_####.obj (the refined \
body), frame 0 being the rest pose; then summary.json. A checkpoint (tailor_checkpoint.bin) is \
written after every frame for --resume, which refuses a frame before it whose file is missing \
or not the length written. A frame fails its quality when an edge ends it more \
than 1 percentage point past the scene's strain_limit (a 10% limit fails above 11%; not judged \
when the limit is 0) or tailor check's test finds a penetration or a self-intersection; each \
failure is warned about on standard error (frames, worst value, where on the garment) and listed \
under \"failures\" in summary.json. Exit status: 0 done (warnings or not), 1 bad scene or a \
diverging simulation, 2 bad arguments, 3 with --strict or [scene] strict = true when a frame \
failed its quality (everything is written first), 130 stopped by Ctrl-C after a frame and its \
checkpoint (--resume continues; a second Ctrl-C stops at once). Temporaries of these files \
that a killed run left (.cloth_0020.obj.tmp-PID) are removed at the start of a run, and so are \
these files of an earlier run unless resuming."
)]
pub struct Args {
    /// Scene file (TOML; see assets/scenes/cape.toml).
    pub scene: PathBuf,
    /// Output directory, instead of the scene's `[output] dir`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Frames to write, both ends included: `A..B`, `A..` or `..B` (default: 0 to the
    /// scene's `frames`). Frames before A are simulated but not written.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// Worker threads of the simulation (default: one per core); with two or more, one more
    /// thread checks and writes each frame while the next simulates. The output is the same
    /// for any count.
    #[arg(long, value_name = "N")]
    pub threads: Option<NonZeroUsize>,
    /// Continue from the checkpoint in the output directory (from the start if there is
    /// none), with the same bytes as an uninterrupted run. The scene may have more `frames`
    /// (to extend a finished shot); any other change is refused, naming the key.
    #[arg(long)]
    pub resume: bool,
    /// No progress bar or notes on standard error (quality warnings are still printed).
    #[arg(short, long)]
    pub quiet: bool,
    /// Exit with status 3 when a frame fails its quality, once everything is written (as the
    /// scene's `[scene] strict = true`).
    #[arg(long)]
    pub strict: bool,
    /// Stop after writing this frame and its checkpoint, as if interrupted (for tests).
    #[arg(long, hide = true, value_name = "FRAME")]
    pub stop_after: Option<u32>,
}

/// An inclusive range of frame numbers; either end may be left open.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame written (0 when open).
    pub start: Option<u32>,
    /// Last frame simulated and written (the scene's `frames` when open).
    pub end: Option<u32>,
}

impl FromStr for FrameRange {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let Some((a, b)) = s.split_once("..") else {
            return Err(format!("{s:?} is not a range such as 10..20, 10.. or ..20"));
        };
        let end = |x: &str| -> Result<Option<u32>, String> {
            let x = x.trim();
            if x.is_empty() {
                Ok(None)
            } else {
                x.parse()
                    .map(Some)
                    .map_err(|_| format!("{x:?} is not a frame number"))
            }
        };
        let range = Self {
            start: end(a)?,
            end: end(b.strip_prefix('=').unwrap_or(b))?,
        };
        if let (Some(a), Some(b)) = (range.start, range.end)
            && a > b
        {
            return Err(format!("the range {s} is empty"));
        }
        Ok(range)
    }
}

/// Runs `tailor simulate`: exit 0, 3 when strict and a frame failed its quality, 130 when
/// stopped by Ctrl-C.
///
/// # Errors
/// A bad scene, an unwritable output, or a diverging simulation.
pub fn run(args: &Args) -> Result<ExitCode> {
    let outcome = run_in_pool(args)?;
    Ok(if outcome.interrupted {
        ExitCode::from(interrupt::STATUS)
    } else if outcome.rejected {
        ExitCode::from(3)
    } else {
        ExitCode::SUCCESS
    })
}

/// How a run that did not fail ended.
pub struct Outcome {
    /// The output directory.
    pub dir: PathBuf,
    /// A frame failed its quality and the run is strict.
    pub rejected: bool,
    /// Ctrl-C stopped the run after a frame and its checkpoint.
    pub interrupted: bool,
}

/// Simulates the scene on a pool of `args.threads` threads.
///
/// # Errors
/// As [`run`].
pub fn run_in_pool(args: &Args) -> Result<Outcome> {
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.threads {
        pool = pool.num_threads(n.get());
    }
    let pool = pool.build().context("starting worker threads")?;
    pool.install(|| simulate(args))
}

fn simulate(args: &Args) -> Result<Outcome> {
    let range = args.frames.unwrap_or_default();
    let scene = scene::load(&args.scene, range.end)?;
    let first = range.start.unwrap_or(0);
    let last = range.end.unwrap_or(scene.frames);
    let dir = args.out.clone().unwrap_or_else(|| scene.output.dir.clone());
    let out = &scene.output;
    // The written cloth surface (and the control mesh as written beside it), the simulator
    // and the refined body do not need each other to be made: they are made at once.
    let ((cloth, control), (simulator, body)) = rayon::join(
        || {
            rayon::join(
                || Surface::new(&scene.cloth.doc.mesh, out.level, out.limit_normals),
                || {
                    (out.control_mesh && out.level > 0)
                        .then(|| Surface::new(&scene.cloth.doc.mesh, 0, false))
                        .transpose()
                },
            )
        },
        || {
            rayon::join(
                || Shot::simulator(&scene),
                || {
                    let body = scene.body.as_ref();
                    body.map(|b| Surface::new(&b.rest, b.level, false))
                        .transpose()
                },
            )
        },
    );
    let (cloth, control_surface, simulator, body) = (cloth?, control?, simulator?, body?);
    let mut shot = Shot::new(&scene, simulator, &cloth, body.clone())?;
    let vertex_count = scene.cloth.doc.mesh.vertex_count();
    let resumed = if args.resume {
        checkpoint::load(&dir, &scene.fingerprint, vertex_count)?
    } else {
        None
    };
    if args.resume && resumed.is_none() && !args.quiet {
        eprintln!(
            "note: no checkpoint in {}; starting from frame 0",
            dir.display()
        );
    }
    let (mut state, stats, next) = match resumed {
        Some(c) => {
            outputs::check_written(&dir, &c.stats)?;
            shot.simulator.restore_contact_state(&c.contacts)?;
            (c.state, c.stats, c.frame + 1)
        }
        None => (State::at_rest(shot.simulator.model()), Vec::new(), 0),
    };
    if next > last + 1 {
        bail!(
            "the checkpoint in {} is at frame {}, past the last frame asked ({last}); \
             raise [scene] frames or run without --resume",
            dir.display(),
            next - 1
        );
    }
    fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let stale = outputs::remove_temporaries(&dir)?;
    if stale > 0 && !args.quiet {
        eprintln!(
            "note: removed {stale} temporary file(s) left in {} by an interrupted run",
            dir.display()
        );
    }
    interrupt::watch()?;
    if next > 0 {
        shot.pose_body(next - 1);
    }
    let progress = progress_bar(
        u64::from(last.saturating_sub(next) + 1),
        args.quiet || next > last,
    );
    let mut output = Output::new(&scene, &dir, first, stats, cloth, control_surface, body);
    // A run from frame 0 writes every file afresh: the output removes an earlier run's before
    // its first frame, beside the simulation (see `Output::earlier`).
    output.earlier = (next == 0).then_some(Earlier { quiet: args.quiet });
    let mut simulate = |deliver: &mut dyn FnMut(Simulated) -> bool| {
        run_frames(&mut shot, &mut state, next..=last, args, &progress, deliver)
    };
    // Checking and writing a frame overlap the simulation of the next on a thread of their
    // own, when the pool has threads to spare for it, at the lowest priority (see
    // `yield_to_the_simulation`).
    let (simulated, output) = if rayon::current_num_threads() > 1 {
        std::thread::scope(|scope| {
            let (frames, received) = mpsc::sync_channel::<Simulated>(1);
            let writer = scope.spawn(move || {
                output_pool()?.install(|| {
                    for done in received {
                        output.frame(done)?;
                    }
                    Ok(output)
                })
            });
            let simulated = simulate(&mut |done| frames.send(done).is_ok());
            drop(frames);
            let output = writer
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (simulated, output)
        })
    } else {
        let mut failed = None;
        let simulated =
            simulate(&mut |done| output.frame(done).map_err(|err| failed = Some(err)).is_ok());
        (simulated, failed.map_or(Ok(output), Err))
    };
    // The frames simulated are written (and checkpointed) before any error is told; the
    // checkpoint's spare goes either way.
    let released = checkpoint::release(&dir);
    let output = output?;
    released?;
    if let Some(frame) = simulated? {
        progress.abandon();
        let interrupted = interrupt::requested();
        if interrupted {
            eprintln!("interrupted after frame {frame} and its checkpoint; --resume continues");
        } else if !args.quiet {
            eprintln!("stopped after frame {frame}, as asked");
        }
        return Ok(Outcome {
            dir,
            rejected: false,
            interrupted,
        });
    }
    let stats = output.stats;
    progress.finish_and_clear();
    let failures = quality::assess(
        &stats,
        scene.cloth.strain_limit,
        &scene.cloth.doc,
        &output.cloth,
    );
    let summary = summary::report(&scene.path, &dir, scene.cloth.thickness, &stats, &failures)?;
    for failure in &failures {
        eprintln!("warning: {failure}");
    }
    let rejected = !failures.is_empty() && (args.strict || scene.strict);
    if rejected {
        eprintln!(
            "the shot failed its quality and is strict ({}): exit status 3",
            if args.strict {
                "--strict"
            } else {
                "[scene] strict = true"
            }
        );
    }
    // Last, so that a reader of standard output going away early loses nothing else; and a
    // reader gone away does not change the exit status a strict run owes.
    let printed = output::print(&format!(
        "{summary}frames {first} to {last}: {}\n",
        dir.join("cloth_####.obj").display()
    ));
    match printed {
        Err(err) if !output::stdout_closed(&err) => return Err(err),
        _ => {}
    }
    Ok(Outcome {
        dir,
        rejected,
        interrupted: false,
    })
}

/// A frame the simulation finished, for the output: its figures so far, the state and what
/// friction carries after it, and where the body is.
struct Simulated {
    row: FrameStats,
    state: State,
    contacts: ContactState,
    /// The refined body at the frame.
    body: Option<Vec<Point>>,
}

/// Simulates `frames`, handing each to `deliver` (which says whether the output still takes
/// frames). Returns the frame after which an interrupt or `--stop-after` stopped the run, or
/// `None` when every frame was simulated or the output stopped taking them.
fn run_frames(
    shot: &mut Shot,
    state: &mut State,
    frames: RangeInclusive<u32>,
    args: &Args,
    progress: &ProgressBar,
    deliver: &mut dyn FnMut(Simulated) -> bool,
) -> Result<Option<u32>> {
    for frame in frames {
        let start = Instant::now();
        let mut row = FrameStats {
            frame,
            ..FrameStats::default()
        };
        if frame > 0 {
            shot.step(state, frame, &mut row).with_context(|| {
                format!("simulating frame {frame} of {}", shot.scene.path.display())
            })?;
        }
        row.ms = start.elapsed().as_secs_f64() * 1e3;
        shot.measure(state, &mut row)?;
        let done = Simulated {
            row,
            state: state.clone(),
            contacts: shot.simulator.contact_state().clone(),
            body: shot.body.as_ref().map(|track| track.posed.clone()),
        };
        if !deliver(done) {
            return Ok(None);
        }
        progress.set_message(format!(
            "{:.0} ms/frame",
            start.elapsed().as_secs_f64() * 1e3
        ));
        progress.inc(1);
        if interrupt::requested() || args.stop_after == Some(frame) {
            return Ok(Some(frame));
        }
    }
    Ok(None)
}

/// A progress bar on standard error with frame, ms/frame and ETA; hidden when standard error
/// is not a terminal or when asked.
fn progress_bar(frames: u64, hidden: bool) -> ProgressBar {
    let target = if hidden || !std::io::stderr().is_terminal() {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(frames), target);
    bar.set_style(
        ProgressStyle::with_template("[{bar:30}] frame {pos}/{len} · {msg} · ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.enable_steady_tick(Duration::from_millis(500));
    bar
}

/// The animated body as the simulation sees it: its refined surface (built at rest, for the
/// refinement and the attachments' bindings) and where that surface is at the last frame
/// stepped to. The output checks against its own copy, refit at the frame it writes.
struct BodyTrack {
    surface: Surface,
    bindings: Bindings,
    posed: Vec<Point>,
}

/// The context of an error in making the simulator of `scene`'s garment.
fn building_cloth(scene: &Scene) -> String {
    format!("building the cloth model of {}", scene.cloth.path.display())
}

/// Everything built once for a shot.
struct Shot<'a> {
    scene: &'a Scene,
    simulator: Simulator,
    body: Option<BodyTrack>,
    /// Seconds per frame.
    dt: f64,
}

impl<'a> Shot<'a> {
    /// The simulator of `scene`'s garment, its pins set, without its collision surface or
    /// the body.
    fn simulator(scene: &Scene) -> Result<Simulator> {
        let c = &scene.cloth;
        let in_cloth = || building_cloth(scene);
        let mut model = Model::new(&c.doc.mesh, &c.material).with_context(in_cloth)?;
        for (which, values) in &c.multipliers {
            model
                .set_multipliers(*which, values)
                .with_context(in_cloth)?;
        }
        let settings = Settings {
            max_substep: 1.0 / (scene.fps * f64::from(scene.substeps)),
            integrator: scene.integrator,
            gravity: scene.gravity,
            thickness: c.thickness,
            friction: c.friction,
            strain_limit: c.strain_limit,
            self_collision: c.self_collision,
            ..Settings::default()
        };
        let mut simulator = Simulator::new(model, settings).with_context(in_cloth)?;
        simulator
            .pin(&c.pins, Motion::Fixed)
            .with_context(in_cloth)?;
        Ok(simulator)
    }

    /// The shot of `scene` from its `simulator` (see [`Self::simulator`]), whose garment
    /// writes `cloth`, against the refined `body` of the scene's.
    fn new(
        scene: &'a Scene,
        mut simulator: Simulator,
        cloth: &Surface,
        body: Option<Surface>,
    ) -> Result<Self> {
        let c = &scene.cloth;
        // The written faces at every level, the control mesh's own at level 0: the lift moves
        // control points after the garment's self tests, and only the written surface's
        // self tests, alternating with the lift, keep what is written clear.
        simulator
            .set_collision_surface(cloth.stencils().clone(), Some(cloth.hierarchy()))
            .with_context(|| building_cloth(scene))?;
        let body = match body {
            Some(surface) => {
                let bindings = Bindings::new(
                    surface.hierarchy(),
                    surface.mesh().positions(),
                    c.doc.mesh.positions(),
                    &c.attach,
                )?;
                let rest = surface.mesh();
                simulator
                    .set_obstacle(rest.positions(), rest.face_offsets(), rest.face_vertices())
                    .context("making the refined body the obstacle")?;
                let posed = rest.positions().to_vec();
                Some(BodyTrack {
                    surface,
                    bindings,
                    posed,
                })
            }
            None => None,
        };
        Ok(Self {
            scene,
            simulator,
            body,
            dt: 1.0 / scene.fps,
        })
    }

    /// Puts the body at simulation frame `frame` (when resuming).
    fn pose_body(&mut self, frame: u32) {
        if let (Some(track), Some(body)) = (&mut self.body, &self.scene.body) {
            track.posed = track.surface.refine(body.control(frame));
        }
    }

    /// Steps from the end of frame `frame − 1` to the end of `frame`.
    fn step(&mut self, state: &mut State, frame: u32, row: &mut FrameStats) -> Result<()> {
        if let (Some(track), Some(body)) = (&mut self.body, &self.scene.body) {
            let end = track.surface.refine(body.control(frame));
            let start = &track.posed;
            let targets = track.bindings.targets(start, &end, self.dt);
            self.simulator
                .set_attachment_targets(state.time, &targets)?;
            let t0 = state.time;
            self.simulator
                .set_obstacle_motion(t0, start, t0 + self.dt, &end)?;
            track.posed = end;
        }
        let report = self.simulator.step(state, self.dt)?;
        row.substeps = report.substeps;
        row.cg_iterations = report.cg_iterations;
        Ok(())
    }

    /// The frame's worst edge; an error when the simulation diverged.
    fn measure(&self, state: &State, row: &mut FrameStats) -> Result<()> {
        let worst = self.simulator.model().worst_edge(&state.positions);
        (row.strained_edge, row.max_strain) = worst.unwrap_or_default();
        if row.max_strain.is_nan() || row.max_strain > MAX_STRAIN {
            bail!(
                "frame {}: the simulation diverged (an edge stretched to {:.0}% strain); \
                 try more substeps or a stiffer material",
                row.frame,
                row.max_strain * 100.0
            );
        }
        Ok(())
    }
}

/// The output thread: a pool of one thread of its own (so it never waits on the simulation's
/// pool), at the lowest priority (see [`yield_to_the_simulation`]).
fn output_pool() -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .start_handler(|_| yield_to_the_simulation())
        .build()
        .context("starting the output thread")
}

/// Gives the calling thread (the output thread) the lowest scheduling priority, nice 19.
///
/// The simulation keeps every core busy only part of the time: between its parallel passes it
/// runs serial ones (strain limiting, the impulse rounds) on one thread and the other cores
/// wait. At the default priority the output thread shares the cores with the simulation's
/// workers when they are all busy and delays them; at nice 19 a worker the simulation wakes
/// takes the core back sooner, and the whole process of the 64² drape at one substep on two
/// cores took 8% less wall time (`docs/BENCHMARKS.md`), the same bytes written. It still
/// costs: a thread running beside the simulation delays its fork-joins at any priority, so
/// the output's CPU time is worth cutting too. The output thread cannot fall behind by more
/// than a frame: the simulation waits for it then (the frames go through a channel of one),
/// and the output thread, then the only one of the process with work, runs at full speed.
/// Where the system shares the cores fairly between processes or their control groups first
/// (Linux's autogroups, one per `setsid`, the cgroups of systemd and of farm schedulers), the
/// priority counts only against the threads of the process's own group, and jobs elsewhere
/// on a shared machine cannot starve it. A busy job started from the same shell is in that
/// group: the output thread then runs only while the simulation waits for it, and the
/// process gets about one core's worth, as on one thread (`docs/BENCHMARKS.md`).
///
/// Linux keeps a nice value per thread (`setpriority` on the thread's id); elsewhere the value
/// is the process's, and this does nothing. A failure leaves the default priority, which is
/// only slower, so it is not reported.
fn yield_to_the_simulation() {
    #[cfg(target_os = "linux")]
    {
        let lowest = 19;
        let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), lowest);
    }
}

/// What is checked and written of each frame, with the figures of every frame so far.
struct Output<'a> {
    scene: &'a Scene,
    dir: &'a Path,
    /// The first frame written.
    first: u32,
    /// The text of the garment's control mesh, with its groups, but its positions.
    control: Frames,
    /// The control mesh as written, rounded apart where it would cross
    /// ([`Surface::round_crossings_apart`]), when it is written beside a refined surface; at
    /// level 0 the written surface is the control mesh.
    control_surface: Option<Surface>,
    cloth: Surface,
    /// The text of the written cloth surface but its positions and normals.
    cloth_text: Frames,
    /// The refined body, set at each frame's pose (from the simulation) for the check.
    body: Option<Surface>,
    /// The text of the written body but its positions.
    body_text: Option<Frames>,
    /// The refined body's positions at the last frame, and the bytes of its file once written
    /// there: a body that holds still is neither rounded and refit again nor formatted again.
    body_still: Option<(Vec<Point>, Option<Vec<u8>>)>,
    /// The check's clearances of the frame before.
    clearances: Clearances,
    stats: Vec<FrameStats>,
    /// Whether an earlier run's files are still to be removed from `dir`, which the first
    /// frame does before writing anything ([`outputs::remove_earlier`]): on the output's
    /// thread, beside the simulation (`docs/DESIGN.md`).
    earlier: Option<Earlier>,
}

/// An earlier run's files to remove before the first frame, and whether to say so.
struct Earlier {
    quiet: bool,
}

impl<'a> Output<'a> {
    /// The output of `scene` into `dir` from frame `first` on, after the figures `stats` of
    /// the frames before it, writing `cloth` (and `control_surface`, the control mesh as
    /// written beside a refined surface) with the refined `body`.
    fn new(
        scene: &'a Scene,
        dir: &'a Path,
        first: u32,
        stats: Vec<FrameStats>,
        cloth: Surface,
        control_surface: Option<Surface>,
        body: Option<Surface>,
    ) -> Self {
        let precision = scene.output.precision;
        let doc = &scene.cloth.doc;
        Self {
            scene,
            dir,
            first,
            control: Frames::new(&doc.mesh, &doc.groups, false, precision),
            control_surface,
            cloth_text: cloth.frames(precision),
            cloth,
            body_text: body.as_ref().map(|b| b.frames(precision)),
            body,
            body_still: None,
            clearances: Clearances::default(),
            stats,
            earlier: None,
        }
    }

    /// Checks a simulated frame, writes its files and then its checkpoint; the first frame of
    /// a run from frame 0 removes an earlier run's files before.
    fn frame(&mut self, done: Simulated) -> Result<()> {
        let Simulated {
            mut row,
            state,
            contacts,
            body,
        } = done;
        let frame = row.frame;
        if let Some(Earlier { quiet }) = self.earlier.take() {
            let removed = outputs::remove_earlier(self.dir)?;
            if removed > 0 && !quiet {
                eprintln!(
                    "note: removed {removed} file(s) of an earlier run from {}",
                    self.dir.display()
                );
            }
        }
        let precision = self.scene.output.precision;
        self.cloth
            .set(self.cloth.refine(&state.positions), precision)?;
        if let (Some(surface), Some(posed)) = (&mut self.body, body) {
            let still = self.body_still.as_ref().is_some_and(|(at, _)| {
                at.len() == posed.len() && at.iter().zip(&posed).all(|(p, q)| same_bits(p, q))
            });
            if !still {
                surface.set(posed.clone(), precision)?;
                self.body_still = Some((posed, None));
            }
        }
        let inspect = |output: &mut Self| {
            crate::check::inspect(
                output.cloth.hierarchy(),
                output.cloth.mesh().positions(),
                output.body.as_ref().map(Surface::hierarchy),
                output.scene.cloth.thickness,
                &mut output.clearances,
            )
            .with_context(|| format!("checking frame {frame}"))
        };
        row.findings = inspect(self)?;
        if row.findings.self_intersecting_pairs > 0 {
            let exact = self.cloth.refine(&state.positions);
            self.cloth.round_crossings_apart(&exact, precision)?;
            row.findings = inspect(self)?;
        }
        if frame >= self.first {
            row.written = self.write(frame, &state)?;
        }
        self.stats.push(row);
        checkpoint::save(
            self.dir,
            &Checkpoint {
                fingerprint: self.scene.fingerprint.clone(),
                frame,
                state,
                contacts,
                stats: self.stats.clone(),
            },
        )
    }

    /// Writes frame `frame`'s files into `dir`; returns their lengths as the checkpoint
    /// records them ([`FrameStats::written`]).
    fn write(&mut self, frame: u32, state: &State) -> Result<[u64; 3]> {
        let name = |sequence| outputs::frame_file(self.dir, sequence, frame);
        let out = &self.scene.output;
        let mut written = [0; 3];
        if out.control_mesh {
            if let Some(control) = &mut self.control_surface {
                control.set(state.positions.clone(), out.precision)?;
                control.round_crossings_apart(&state.positions, out.precision)?;
            }
            let surface = self.control_surface.as_ref().unwrap_or(&self.cloth);
            written[Sequence::Control as usize] =
                write_atomically(&name(Sequence::Control), |w| {
                    self.control.write(surface.mesh().positions(), None, w)
                })?;
        }
        written[Sequence::Surface as usize] =
            self.cloth
                .write(&name(Sequence::Surface), &state.positions, &self.cloth_text)?;
        if out.body
            && let (Some(surface), Some(text), Some(body)) =
                (&self.body, &self.body_text, &self.scene.body)
        {
            let kept = self.body_still.as_mut().and_then(|(_, bytes)| bytes.take());
            let bytes = match kept {
                Some(bytes) => bytes,
                None => surface.text(body.control(frame), text)?,
            };
            written[Sequence::Body as usize] =
                write_atomically(&name(Sequence::Body), |w| w.write_all(&bytes))?;
            if let Some((_, kept)) = &mut self.body_still {
                *kept = Some(bytes);
            }
        }
        Ok(written)
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use rustix::process::getpriority_process;
    use rustix::thread::gettid;

    /// The output pool's thread runs at nice 19 and the thread that made the pool keeps its
    /// priority (Linux keeps one per thread).
    #[test]
    fn only_the_output_thread_yields() {
        let own = || getpriority_process(Some(gettid())).expect("the thread's priority");
        let before = own();
        let pool = super::output_pool().expect("the output thread");
        let lowered = pool.install(own);
        assert_eq!(lowered, 19);
        assert_eq!(own(), before);
    }
}
