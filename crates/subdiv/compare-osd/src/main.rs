//! tailor-subdiv and OpenSubdiv 3.7 (the C++ library, through the `opensubdiv-petite` crate)
//! side by side, in one process, on the benchmark grids of 10k and 100k quads refined to level 2.
//!
//! For each library it times topology refinement (ours on one and two threads, OpenSubdiv on one;
//! with the minimal last level that evaluation needs, [`Refiner::for_evaluation`] against
//! OpenSubdiv's default, and with the full last level), position interpolation level by level,
//! stencil table construction and stencil application, each as the best of several runs, and
//! prints the ratios (OpenSubdiv time / our time: above 1 means we are faster). Peak memory is measured in a
//! fresh child process per operation, as the growth of the peak resident set (`VmHWM`) over the
//! mesh alone, so it counts C++ and Rust allocations alike.
//!
//! OpenSubdiv runs in single precision here (the wrapper's primvars and stencil weights are
//! `f32`); ours in double. Both use OpenSubdiv's default vertex order, so the refined points are
//! compared once as a check that both did the same work.
//!
//! `cargo run --release` in this folder (see README.md).

use std::hint::black_box;
use std::process::Command;
use std::time::{Duration, Instant};

use opensubdiv_petite::far::{
    self, PrimvarRefiner, StencilTable as OsdStencils, StencilTableOptions,
    TopologyRefiner as OsdRefiner,
};
use tailor_subdiv::{Mesh, Point, Refiner};

#[path = "../../benches/common/mod.rs"]
mod common;
mod osd;

/// Refinement level of every case.
const LEVEL: usize = 2;

/// OpenSubdiv's input: face sizes and corners as `u32`, positions as `f32`.
struct OsdMesh {
    sizes: Vec<u32>,
    corners: Vec<u32>,
    vertices: usize,
    positions: Vec<f32>,
}

impl OsdMesh {
    fn new(mesh: &Mesh) -> Self {
        Self {
            sizes: mesh
                .face_offsets()
                .windows(2)
                .map(|w| w[1] - w[0])
                .collect(),
            corners: mesh.face_vertices().to_vec(),
            vertices: mesh.vertex_count(),
            positions: mesh
                .positions()
                .iter()
                .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
                .collect(),
        }
    }

    /// Topology refined uniformly to [`LEVEL`] with our options (edge-only boundaries).
    fn refine(&self, full_topology_in_last_level: bool) -> OsdRefiner {
        osd::refine(
            self.vertices,
            &self.sizes,
            &self.corners,
            LEVEL,
            full_topology_in_last_level,
        )
    }

    /// Positions of the last level, level by level (`Far::PrimvarRefiner::Interpolate`).
    fn interpolate(&self, refiner: &OsdRefiner) -> Vec<f32> {
        let primvars = PrimvarRefiner::new(refiner).expect("primvar refiner");
        let mut current = self.positions.clone();
        for level in 1..=LEVEL {
            current = primvars
                .interpolate(level, 3, &current)
                .expect("level exists");
        }
        current
    }

    /// Stencils of the last level only, intermediate levels factorized away.
    fn stencils(refiner: &OsdRefiner) -> OsdStencils {
        let options = StencilTableOptions {
            interpolation_mode: far::stencil_table::InterpolationMode::Vertex,
            generate_intermediate_levels: false,
            factorize_intermediate_levels: true,
            max_level: LEVEL,
            ..StencilTableOptions::default()
        };
        OsdStencils::new(refiner, options).expect("OpenSubdiv stencils")
    }
}

/// Best wall time of `runs` calls.
fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            black_box(f());
            start.elapsed()
        })
        .min()
        .expect("at least one run")
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn ms(d: Duration) -> String {
    format!("{:.2}", d.as_secs_f64() * 1e3)
}

/// One table row: ours on 1 and 2 threads, OpenSubdiv on 1, and the ratios.
fn row(what: &str, ours: [Duration; 2], osd: Duration) {
    let ratio = |d: Duration| osd.as_secs_f64() / d.as_secs_f64();
    println!(
        "| {what} | {} | {} | {} | {:.2} | {:.2} |",
        ms(ours[0]),
        ms(ours[1]),
        ms(osd),
        ratio(ours[0]),
        ratio(ours[1])
    );
}

/// The operations whose peak memory a child process measures.
const PEAKS: [&str; 8] = [
    "ours-topology",
    "osd-topology",
    "ours-topology-full",
    "osd-topology-full",
    "ours-topology+positions",
    "osd-topology+positions",
    "ours-stencils",
    "osd-stencils",
];

/// Runs `what` once on the grid of side `side` and returns the growth of the peak resident set,
/// in bytes (child-process mode).
fn peak_of(what: &str, side: usize) -> usize {
    let mesh = common::grid(side);
    let osd = OsdMesh::new(&mesh);
    let before = high_water_mark();
    match what {
        "ours-topology" => drop(black_box(Refiner::for_evaluation(&mesh, LEVEL))),
        "ours-topology-full" => drop(black_box(Refiner::new(&mesh, LEVEL))),
        "ours-topology+positions" => {
            let refiner = Refiner::for_evaluation(&mesh, LEVEL);
            drop(black_box(refiner.refine(mesh.positions())));
        }
        "ours-stencils" => drop(black_box(Refiner::for_evaluation(&mesh, LEVEL).stencils())),
        "osd-topology" => drop(black_box(osd.refine(false))),
        "osd-topology-full" => drop(black_box(osd.refine(true))),
        "osd-topology+positions" => drop(black_box(osd.interpolate(&osd.refine(false)))),
        "osd-stencils" => drop(black_box(OsdMesh::stencils(&osd.refine(false)))),
        _ => panic!("unknown operation {what}"),
    }
    high_water_mark() - before
}

/// `VmHWM` of this process, in bytes.
fn high_water_mark() -> usize {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<usize>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// Peak memory of `what` measured in a fresh child process, in MB.
fn peak_mb(what: &str, side: usize) -> Option<f64> {
    let exe = std::env::current_exe().ok()?;
    let out = Command::new(exe)
        .args(["--peak", what, &side.to_string()])
        .output()
        .ok()?;
    let bytes: f64 = String::from_utf8_lossy(&out.stdout).trim().parse().ok()?;
    Some(bytes / 1e6)
}

fn compare(side: usize) {
    let mesh = common::grid(side);
    let osd = OsdMesh::new(&mesh);
    let runs = if side > 200 { 7 } else { 21 };
    let pools = [pool(1), pool(2)];
    let ours = |f: &(dyn Fn() + Sync)| pools.each_ref().map(|p| best(runs, || p.install(f)));

    let topology = ours(&|| drop(black_box(Refiner::for_evaluation(&mesh, LEVEL))));
    let osd_topology = best(runs, || osd.refine(false));
    let topology_full = ours(&|| drop(black_box(Refiner::new(&mesh, LEVEL))));
    let osd_topology_full = best(runs, || osd.refine(true));

    let refiner = Refiner::for_evaluation(&mesh, LEVEL);
    let osd_refiner = osd.refine(false);
    let positions = ours(&|| drop(black_box(refiner.refine(mesh.positions()))));
    let osd_positions = best(runs, || osd.interpolate(&osd_refiner));
    let everything = ours(&|| {
        let refiner = Refiner::for_evaluation(&mesh, LEVEL);
        drop(black_box(refiner.refine(mesh.positions())));
    });
    let osd_everything = best(runs, || osd.interpolate(&osd.refine(false)));

    let stencil_build = ours(&|| drop(black_box(refiner.stencils())));
    let osd_stencil_build = best(runs, || OsdMesh::stencils(&osd_refiner));
    let stencils = refiner.stencils();
    let osd_stencils = OsdMesh::stencils(&osd_refiner);
    // The wrapper applies OpenSubdiv's stencils to one float per point, so xyz is three passes
    // over separate coordinate arrays; ours applies to whole points (and to one f64 per point).
    let coordinate =
        |k: usize| -> Vec<f32> { osd.positions.iter().skip(k).step_by(3).copied().collect() };
    let osd_xyz = [coordinate(0), coordinate(1), coordinate(2)];
    let scalars: Vec<f64> = mesh.positions().iter().map(|p| p.x).collect();
    let mut out = vec![Point::origin(); stencils.len()];
    let mut out_scalar = vec![0.0; stencils.len()];
    let apply = pools.each_ref().map(|p| {
        best(runs * 3, || {
            p.install(|| stencils.apply(black_box(mesh.positions()), &mut out));
        })
    });
    let osd_apply = best(runs * 3, || {
        osd_xyz
            .each_ref()
            .map(|c| osd_stencils.update_values(black_box(c), None, None))
    });
    let apply_scalar = pools.each_ref().map(|p| {
        best(runs * 3, || {
            p.install(|| stencils.apply(black_box(&scalars), &mut out_scalar));
        })
    });
    let osd_apply_scalar = best(runs * 3, || {
        osd_stencils.update_values(black_box(&osd_xyz[0]), None, None)
    });

    // Same work: the same refined points, to single precision.
    let ours_points = refiner.refine(mesh.positions());
    let theirs = osd.interpolate(&osd_refiner);
    assert_eq!(ours_points.len() * 3, theirs.len(), "refined vertex counts");
    let max_diff = ours_points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .zip(&theirs)
        .map(|(a, &b)| (a - f64::from(b)).abs())
        .fold(0.0, f64::max);
    assert!(max_diff < 1e-5, "refined points differ by {max_diff}");

    let faces = side * side;
    println!(
        "\n### {faces} quads -> level {LEVEL} ({} faces, {} vertices; points agree within {max_diff:.1e})\n",
        faces * 4usize.pow(LEVEL as u32),
        ours_points.len()
    );
    println!(
        "| ms (best of {runs}) | ours 1 thread | ours 2 threads | OpenSubdiv 1 thread | OSD/ours 1T | OSD/ours 2T |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    row("topology (minimal last level)", topology, osd_topology);
    row(
        "topology (full last level)",
        topology_full,
        osd_topology_full,
    );
    row("positions, level by level", positions, osd_positions);
    row("topology + positions", everything, osd_everything);
    row("stencil table build", stencil_build, osd_stencil_build);
    row("stencil application, xyz", apply, osd_apply);
    row(
        "stencil application, 1 value",
        apply_scalar,
        osd_apply_scalar,
    );

    let peaks: Vec<String> = PEAKS
        .iter()
        .map(|what| {
            peak_mb(what, side).map_or_else(|| format!("{what}: ?"), |mb| format!("{what} {mb:.0}"))
        })
        .collect();
    println!("\npeak memory over the mesh, MB: {}", peaks.join(", "));
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let [flag, what, side] = args.as_slice()
        && flag == "--peak"
    {
        let side = side.parse().expect("grid side");
        println!("{}", peak_of(what, side));
        return;
    }
    println!("tailor-subdiv vs OpenSubdiv 3.7 (opensubdiv-petite, f32), uniform level {LEVEL}");
    for side in [100, 316] {
        compare(side);
    }
}
