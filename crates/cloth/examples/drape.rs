//! The sphere drape, frame by frame: a 2 m square sheet of n² vertices falling 0.5 m
//! onto a sphere of radius 0.5 m, 60 frames at 24 fps (the default substeps, or `--substeps`
//! a frame). Prints per frame the time, the solver's work (Newton and CG iterations), the
//! contacts, the fail-safe's impacts and the worst edge strain, then the totals: the figures
//! behind the `step` benchmark, and a digest of the final positions' bits (FNV-1a), so a
//! change meant to keep the numbers (a faster product, another thread count) can show that it
//! kept them to the last bit.
//!
//! `cargo run --release -p tailor-cloth --example drape -- [N] [--self] [--frames F] [--substeps S]
//! [--backward-euler]` (the library's default integrator, BDF2, unless `--backward-euler`)

use std::time::Instant;

use tailor_cloth::shapes::{centred_sheet, sphere};
use tailor_cloth::{Integrator, Material, Model, Settings, Simulator, State};
use tailor_subdiv::Point;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut n = 64;
    let mut frames = 60;
    let mut self_collision = false;
    let mut substeps: Option<u32> = None;
    let mut integrator = Settings::default().integrator;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--self" => self_collision = true,
            "--backward-euler" => integrator = Integrator::BackwardEuler,
            "--frames" => frames = args.next().ok_or("--frames needs a count")?.parse()?,
            "--substeps" => {
                substeps = Some(args.next().ok_or("--substeps needs a count")?.parse()?);
            }
            size => n = size.parse()?,
        }
    }
    let garment = centred_sheet(n, 2.0);
    let model = Model::new(&garment, &Material::COTTON)?;
    let defaults = Settings::default();
    let settings = Settings {
        self_collision,
        integrator,
        max_substep: substeps.map_or(defaults.max_substep, |s| 1.0 / (24.0 * f64::from(s))),
        ..defaults
    };
    let mut sim = Simulator::new(model, settings)?;
    let ball = sphere(Point::new(0.0, -1.0, 0.0), 0.5, 24, 48);
    sim.set_obstacle(ball.positions(), ball.face_offsets(), ball.face_vertices())?;
    let mut state = State::at_rest(sim.model());
    println!("frame      ms  newton      cg  contacts  impacts  strain");
    let (mut total_ms, mut worst_strain, mut total_cg) = (0.0, 0.0f64, 0u64);
    for frame in 1..=frames {
        let start = Instant::now();
        let report = sim.step(&mut state, 1.0 / 24.0)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        total_ms += ms;
        worst_strain = worst_strain.max(report.max_strain);
        total_cg += u64::from(report.cg_iterations);
        println!(
            "{frame:5} {ms:7.1} {:7} {:7} {:9} {:8} {:6.1}%",
            report.newton_iterations,
            report.cg_iterations,
            report.contacts,
            report.impacts,
            100.0 * report.max_strain
        );
    }
    println!(
        "{n}² self-collision {}: {:.1} ms/frame, {:.1} CG iterations/frame, worst strain {:.1}%",
        if self_collision { "on" } else { "off" },
        total_ms / f64::from(frames),
        total_cg as f64 / f64::from(frames),
        100.0 * worst_strain
    );
    let digest = state
        .positions
        .iter()
        .flat_map(|p| p.coords.iter())
        .flat_map(|c| c.to_bits().to_le_bytes())
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, byte| {
            (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3)
        });
    println!("final positions digest {digest:016x}");
    Ok(())
}
