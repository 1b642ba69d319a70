//! Writes the sphere drape (see `drape.rs`) into a directory as `sheet.obj`, `sphere.obj` and
//! `drape.toml`, 60 frames writing subdivision level 1 into `out` beside them: the scene the
//! README's comparison with Blender runs.
//!
//!     cargo run --release --example drape_scene -- N SUBSTEPS DIR [NUDGE]
//!     target/release/tailor simulate DIR/drape.toml
//!
//! NUDGE moves the sphere that many metres along x (0 by default). The drape is chaotic
//! where it folds: a nanometre gives another trajectory of the same shot, so a change that
//! alters the trajectory (a response or solver setting) is judged over a few nudged variants
//! rather than on one run (`docs/BENCHMARKS.md`).

mod drape;

use std::fs;
use std::path::PathBuf;
use std::process::ExitCode;

use drape::Drape;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (n, substeps, dir, nudge) = match args.as_slice() {
        [n, substeps, dir] => (n, substeps, dir, "0"),
        [n, substeps, dir, nudge] => (n, substeps, dir, nudge.as_str()),
        _ => {
            eprintln!(
                "usage: drape_scene N SUBSTEPS DIR [NUDGE] (the sheet's vertices a side, 2 to \
                 1024; the sphere moved NUDGE metres along x)"
            );
            return ExitCode::from(2);
        }
    };
    let (Ok(n), Ok(substeps)) = (n.parse::<u32>(), substeps.parse::<u32>()) else {
        eprintln!("drape_scene: N and SUBSTEPS must be whole numbers, got {n} and {substeps}");
        return ExitCode::from(2);
    };
    let Some(nudge) = nudge.parse::<f64>().ok().filter(|x| x.abs() <= 1.0) else {
        eprintln!("drape_scene: NUDGE must be a distance in metres, at most 1, got {nudge}");
        return ExitCode::from(2);
    };
    if !(2..=1024).contains(&n) || !(1..=1000).contains(&substeps) {
        eprintln!("drape_scene: N must be 2 to 1024 and SUBSTEPS 1 to 1000");
        return ExitCode::from(2);
    }
    let drape = Drape {
        n,
        substeps,
        level: 1,
        frames: 60,
        nudge,
    };
    let dir = PathBuf::from(dir);
    let written = fs::create_dir_all(&dir)
        .and_then(|()| drape.write_meshes(&dir))
        .and_then(|()| fs::write(dir.join("drape.toml"), drape.scene()));
    match written {
        Ok(()) => {
            println!("wrote {}", dir.join("drape.toml").display());
            ExitCode::SUCCESS
        }
        Err(err) => {
            eprintln!("drape_scene: {}: {err}", dir.display());
            ExitCode::FAILURE
        }
    }
}
