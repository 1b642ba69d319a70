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
//! The control mesh the run writes beside it (`cloth_control_####.obj`) must not cross itself
//! either: the next substep's self tests start from it and cannot undo a crossing. The refined
//! surface's pass moves control points the control mesh's own tests have not seen, and the
//! strain limiting after the lift pulls layers too: without the control mesh's tests after
//! them, the 64² drape at 5 substeps wrote a crossed control mesh on 43 of 61 frames (its
//! written surface clean), and at 1 substep a frame the crossings grew into a tangle, 47%
//! strained, its written surface crossed on 47 frames.
//!
//! The suite runs the 32² drape at level 2 through its folding; the heavier drapes are
//! `#[ignore]`d, and CI runs them in release: 32² at 2 and 5 substeps, levels 0–3; 64² at 1
//! (levels 0–1), 2 and 5 (levels 0–2) substeps and at level 3; 128² at 1, 2 and 5 substeps
//! at level 1 and at 2 substeps at level 2. The 128² drape at level 3 (2 substeps) was
//! clean too, run by hand: 151 s and 7 GB of files, too much for CI; so were the 128² drape
//! at 5 substeps at level 2 (50 s) and at level 3 (163 s, 7 GB).

use std::path::PathBuf;

use common::{check_findings, check_written, scratch, simulate_scene};
use drape::Drape;

mod common;
#[path = "../examples/drape_scene/drape.rs"]
mod drape;

/// Runs the `n`² drape for `frames` frames at `substeps` a frame, writing level `level`, the
/// sphere moved by `nudge` metres along x, in a fresh directory `name`, and returns its output
/// directory and its `summary.json`.
fn drape(
    name: &str,
    n: u32,
    [substeps, level, frames]: [u32; 3],
    nudge: f64,
) -> (PathBuf, serde_json::Value) {
    let dir = scratch(name);
    let drape = Drape {
        n,
        substeps,
        level,
        frames,
        nudge,
    };
    drape.write_meshes(&dir).unwrap();
    let summary = simulate_scene(&dir, "drape.toml", &drape.scene());
    (dir.join("out"), summary)
}

/// Asserts that the drape wrote every frame clean and kept its strain within the run's own
/// quality threshold.
fn assert_clean(n: u32, substeps: u32, level: u32, frames: u32) {
    assert_clean_at(n, [substeps, level, frames], 0.0);
}

/// [`assert_clean`] with the sphere moved by `nudge` metres along x. Neither the written
/// surface nor the control mesh may cross itself, and no written point may come within the
/// thickness of the body, on any frame.
fn assert_clean_at(n: u32, [substeps, level, frames]: [u32; 3], nudge: f64) {
    let name = format!("written_surface_{n}_{substeps}_{level}_{nudge:e}");
    let (dir, summary) = drape(&name, n, [substeps, level, frames], nudge);
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
    // The files as a user checks them: read back from their text, against the body written
    // beside them. A point the run left exactly at the thickness, rounded to the text's
    // `f32`, lay nanometres inside it on 4 of the 64² drape's 61 frames at one substep.
    let findings = check_written(&dir, 0.005);
    assert!(
        findings.is_none(),
        "the {n}² drape at {substeps} substeps writes files that `tailor check` finds wanting \
         (level {level}): {findings:?}"
    );
    if dir.join("cloth_control_0000.obj").exists() {
        let findings = check_findings(&dir.join("cloth_control_####.obj"), &[]);
        assert!(
            findings.is_none(),
            "the {n}² drape at {substeps} substeps writes a control mesh that crosses itself \
             (level {level}): {findings:?}"
        );
    }
    // Strain is judged as the run judges it: no frame ends more than a percentage point past
    // the 10% limit.
    assert_eq!(summary["failures"], serde_json::json!({}), "{summary}");
    // A clean run's files go (the 128² drape at level 2 writes 1.8 GB); a failing one's stay
    // to be looked at.
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

/// Two layers 30 nm apart round to the same `f32` and would be written touching; their
/// corners are rounded apart instead, one `f32` step, and the written surface and control
/// mesh are clean as the run and `tailor check` read them. Frame 0, the rest pose, is written
/// before any step.
#[test]
fn layers_nearer_than_an_f32_step_are_written_apart() {
    let dir = scratch("written_surface_layers");
    let mut text = String::new();
    for y in ["1.00000003", "1"] {
        for k in 0..9 {
            let (x, z) = (0.3 + 0.1 * f64::from(k % 3), 0.3 + 0.1 * f64::from(k / 3));
            text += &format!("v {x} {y} {z}\n");
        }
    }
    for layer in 0..2 {
        for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let v = 9 * layer + 3 * j + i + 1;
            text += &format!("f {} {} {} {}\n", v, v + 3, v + 4, v + 1);
        }
    }
    std::fs::write(dir.join("layers.obj"), text).unwrap();
    let scene = "[scene]\nfps = 24\nframes = 1\nsubsteps = 1\n\n\
                 [cloth]\nmesh = \"layers.obj\"\nmaterial = \"cotton\"\nthickness = 0.005\n\
                 self_collision = true\n\n[output]\ndir = \"out\"\nsubdivision_level = 1\n";
    let summary = simulate_scene(&dir, "layers.toml", scene);
    assert_eq!(summary["total"]["self_intersecting_pairs"], 0, "{summary}");
    let out = dir.join("out");
    for files in ["cloth_####.obj", "cloth_control_####.obj"] {
        let findings = check_findings(&out.join(files), &[]);
        assert!(findings.is_none(), "{files}: {findings:?}");
    }
    // The upper layer went up a step (the f32 after 1), the lower stayed at 1.
    let written = std::fs::read_to_string(out.join("cloth_control_0000.obj")).unwrap();
    let heights: Vec<&str> = written
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| l.split(' ').nth(1).unwrap())
        .collect();
    assert_eq!(heights, [["1.0000001"; 9], ["1"; 9]].concat());
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
    // At one substep a frame the cloth falls 10 cm a step onto the sphere.
    for level in 0..=1 {
        assert_clean(64, 1, level, 60);
    }
    for substeps in [2, 5] {
        for level in 0..=2 {
            assert_clean(64, substeps, level, 60);
        }
    }
    assert_clean(64, 2, 3, 60);
    // The drape is chaotic: the sphere moved by a few nanometres folds the cloth another way.
    // Moved by 3 nm (3.0000000000000004e-9 m), the control mesh crossed itself on 3 frames
    // when the strain limiting after a lift was not followed by the control mesh's own self
    // tests.
    for k in 1..=3 {
        assert_clean_at(64, [5, 1, 60], f64::from(k) * 1e-9);
    }
}

#[test]
#[ignore = "minutes in a debug build; CI runs it in release"]
fn the_128_drape_writes_a_clean_surface() {
    // At one substep a frame a substep's settling takes up to fourteen rounds. With at most
    // eight, the sphere moved by 1 nm left the written surface crossed on 24 frames.
    for substeps in [1, 2, 5] {
        assert_clean(128, substeps, 1, 60);
    }
    assert_clean(128, 2, 2, 60);
    assert_clean_at(128, [1, 1, 60], 1e-9);
}
