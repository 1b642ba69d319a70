//! The surface `tailor simulate` writes never passes through itself nor comes within the
//! thickness of the body, on every frame, at every subdivision level a scene may write.
//!
//! The shot is the sphere drape: a 2 m square sheet of n × n vertices falls 0.5 m onto a
//! sphere of radius 0.5 m (48 segments, 24 rings), cotton, 5 mm thick, friction 0.3,
//! self-collision on, 24 fps. The oracle is the per-frame check of the run itself
//! (`summary.json`: the test of `tailor check`, exact triangle–triangle crossings of faces that
//! share no vertex, and the distance of every written vertex to the body); a crossing the
//! check finds on the control mesh is not enough, it is the written `cloth_####.obj` that is
//! judged. Without the refined surface's own self-collision pass the 32² drape at 2 substeps
//! wrote crossing face pairs on frames 18–24 at level 1 and 19 onwards at level 2, with a clean
//! control mesh. Level 0 writes the control mesh, and that pass runs on it too: without it the
//! 64² drape at 5 substeps wrote 473 crossing pairs on 43 frames, the lift having moved control
//! points after the garment's own self tests.
//!
//! The suite runs the 32² drape at level 2 through its folding; the heavier drapes (64² and
//! 128², 2 and 5 substeps, levels 0–3) are `#[ignore]`d, and CI runs them in release.

use std::fs;
use std::path::Path;

use tailor_cloth::shapes;
use tailor_subdiv::Point;
use tailor_subdiv::obj::{self, Precision};

use common::{scratch, tailor};

mod common;

/// Runs the `n`² drape for `frames` frames at `substeps` a frame, writing level `level`, in a
/// fresh directory `name`, and returns its `summary.json`.
fn drape(name: &str, n: u32, substeps: u32, level: u32, frames: u32) -> serde_json::Value {
    let dir = scratch(name);
    let write = |file: &str, mesh: &tailor_subdiv::Mesh| {
        let mut text = Vec::new();
        obj::write(mesh, None, Precision::Full, &mut text).unwrap();
        fs::write(dir.join(file), text).unwrap();
    };
    write("sheet.obj", &shapes::centred_sheet(n, 2.0));
    write(
        "sphere.obj",
        &shapes::sphere(Point::new(0.0, -1.0, 0.0), 0.5, 24, 48),
    );
    let scene = format!(
        "[scene]\nfps = 24\nframes = {frames}\nsubsteps = {substeps}\n\n\
         [cloth]\nmesh = \"sheet.obj\"\nmaterial = \"cotton\"\nthickness = 0.005\n\
         friction = 0.3\nself_collision = true\n\n\
         [body]\nmesh = \"sphere.obj\"\nsubdivision_level = 0\n\n\
         [output]\ndir = \"out\"\nsubdivision_level = {level}\n"
    );
    let path = dir.join("drape.toml");
    fs::write(&path, scene).unwrap();
    let out = tailor(&["simulate", path.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    summary(&dir.join("out"))
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_slice(&fs::read(out.join("summary.json")).unwrap()).unwrap()
}

/// Asserts that the drape wrote every frame clean and kept its strain within the run's own
/// quality threshold.
fn assert_clean(n: u32, substeps: u32, level: u32, frames: u32) {
    let name = format!("written_surface_{n}_{substeps}_{level}");
    let summary = drape(&name, n, substeps, level, frames);
    let total = &summary["total"];
    assert_eq!(total["frames_simulated"], frames, "{summary}");
    assert_eq!(
        total["self_intersecting_pairs"], 0,
        "the {n}² drape at {substeps} substeps crosses itself at level {level}: {}",
        summary["failures"]
    );
    assert_eq!(
        total["penetrating_vertices"], 0,
        "the {n}² drape at {substeps} substeps comes within the thickness of the body at \
         level {level}: {}",
        summary["failures"]
    );
    // Strain is judged as the run judges it: no frame ends more than a percentage point past
    // the 10% limit. The collision passes after the limiter leave landing frames up to a few
    // tenths of a point past it (10.2% on the 64² drape's frame 11 at two substeps, with or
    // without the refined surface's pass).
    assert_eq!(summary["failures"], serde_json::json!({}), "{summary}");
}

#[test]
fn the_32_drape_writes_a_clean_level_2_surface() {
    assert_clean(32, 2, 2, 26);
}

#[test]
#[ignore = "minutes in a debug build; CI runs it in release"]
fn the_32_drape_writes_a_clean_surface_at_every_level() {
    for substeps in [2, 5] {
        for level in 0..=3 {
            assert_clean(32, substeps, level, 60);
        }
    }
}

#[test]
#[ignore = "minutes in a debug build; CI runs it in release"]
fn the_64_drape_writes_a_clean_surface() {
    for substeps in [2, 5] {
        for level in 0..=2 {
            assert_clean(64, substeps, level, 60);
        }
    }
    assert_clean(64, 2, 3, 60);
}

#[test]
#[ignore = "minutes in a debug build; CI runs it in release"]
fn the_128_drape_writes_a_clean_surface() {
    assert_clean(128, 2, 1, 60);
}
