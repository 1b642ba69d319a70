//! The Cusick drape test (BS 5058, ISO 9073-9): a disc of fabric laid flat on a closed
//! cylindrical pedestal drapes round it under gravity. The standard's geometry: a 30 cm disc
//! on an 18 cm pedestal, here an O-grid of quads with hems of 4·40 edges of 5.9 mm, thickness
//! 2 mm, friction 0.3, at 24 fps. Prints, for every simulated second, the median and the
//! largest vertex speed over the second's last frame (displacement over the frame's length, so
//! position corrections count as motion) and the drape coefficient
//! ([`tailor_cloth::shapes::drape_coefficient`]); a drape at rest has every vertex still and a
//! coefficient that does not depend on the substep.
//!
//! `cargo run --release -p tailor-cloth --example cusick -- [MATERIAL] [SUBSTEPS] [SECONDS]
//! [self on|off] [strain on|off] [--scale S] [--n N]`
//!
//! MATERIAL is cotton, silk, denim or leather (default cotton), SUBSTEPS a frame (5), SECONDS
//! simulated (15), self-collision and strain limiting on by default; `--scale` shrinks the
//! fabric and the pedestal together (0.5: a 15 cm disc on a 9 cm pedestal), `--n` sets the
//! core's cells per side (40; the hem has 4n edges, the rings about n/π).

use tailor_cloth::shapes::{cylinder, disc, drape_coefficient};
use tailor_cloth::{Material, Model, Settings, Simulator, State};
use tailor_subdiv::Point;

const FPS: f64 = 24.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut positional = Vec::new();
    let (mut scale, mut n) = (1.0, 40u32);
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--scale" => scale = args.next().ok_or("--scale needs a factor")?.parse()?,
            "--n" => n = args.next().ok_or("--n needs a count")?.parse()?,
            _ => positional.push(arg),
        }
    }
    let arg = |k: usize, default: &str| positional.get(k).map_or(default.to_owned(), Clone::clone);
    let material = match arg(0, "cotton").as_str() {
        "cotton" => Material::COTTON,
        "silk" => Material::SILK,
        "denim" => Material::DENIM,
        "leather" => Material::LEATHER,
        other => return Err(format!("unknown material {other}").into()),
    };
    let substeps: u32 = arg(1, "5").parse()?;
    let seconds: u32 = arg(2, "15").parse()?;
    let on = |k: usize| arg(k, "on") == "on";
    let (radius, pedestal) = (0.15 * scale, 0.09 * scale);
    let thickness = 0.002;
    let rings = (f64::from(n) / std::f64::consts::PI).ceil() as u32;
    let mut fabric = disc(radius, n, rings);
    let lifted: Vec<Point> = fabric
        .positions()
        .iter()
        .map(|p| p + tailor_cloth::Vec3::y() * thickness)
        .collect();
    fabric.set_positions(&lifted)?;
    let model = Model::new(&fabric, &material)?;
    let settings = Settings {
        max_substep: 1.0 / (FPS * f64::from(substeps)),
        thickness,
        friction: 0.3,
        self_collision: on(3),
        strain_limit: if on(4) {
            Settings::default().strain_limit
        } else {
            0.0
        },
        ..Settings::default()
    };
    let mut sim = Simulator::new(model, settings)?;
    let stand = cylinder(
        Point::new(0.0, -1.5 * radius, 0.0),
        pedestal,
        1.5 * radius,
        64,
    );
    sim.set_obstacle(
        stand.positions(),
        stand.face_offsets(),
        stand.face_vertices(),
    )?;
    let mut state = State::at_rest(sim.model());
    println!(
        "{} vertices, hem edges {:.1} mm, {substeps} substeps a frame",
        fabric.vertex_count(),
        1e3 * std::f64::consts::TAU * radius / f64::from(4 * n)
    );
    println!("second  median mm/s  max mm/s  drape coefficient  contacts");
    let mut last = state.positions.clone();
    for second in 1..=seconds {
        let mut contacts = 0;
        for _ in 0..FPS as u32 {
            last.clone_from(&state.positions);
            contacts = sim.step(&mut state, 1.0 / FPS)?.contacts;
        }
        let mut speeds: Vec<f64> = state
            .positions
            .iter()
            .zip(&last)
            .map(|(p, q)| 1e3 * (p - q).norm() * FPS)
            .collect();
        speeds.sort_by(f64::total_cmp);
        println!(
            "{second:6} {:12.2} {:9.2} {:18.3} {:9}",
            speeds[speeds.len() / 2],
            speeds[speeds.len() - 1],
            drape_coefficient(&fabric, &state.positions, pedestal),
            contacts
        );
    }
    Ok(())
}
