//! The shots shipped in `assets/scenes/` are clean: `tailor demo` (the cape over the whole
//! 120-frame walk) and the skirt scene, run end to end by the built binary, then every frame
//! checked by `tailor check` against the body the cloth collided with, at the scene's
//! thickness: no cloth vertex of the written (subdivided) surface inside the body or closer
//! than the thickness, no self-intersecting face pairs, and no edge strained past 10%.
//!
//! Both shipped scenes, killed (SIGKILL) at several frames and resumed each time with
//! `--resume`, write the same bytes as an uninterrupted run: every OBJ, and `summary.json` but
//! for its timings.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use common::scratch;

mod common;

fn tailor(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.code().is_some(),
        "tailor {args:?} was killed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `tailor check` over the frames in `out` and asserts it exits 0 (clean); checks the
/// worst strain in `summary.json`.
fn assert_clean(dir: &Path, out: &str) {
    let cloth = format!("{out}/cloth_####.obj");
    let body = format!("{out}/body_####.obj");
    let check = tailor(
        dir,
        &["check", &cloth, "--against", &body, "--thickness", "0.005"],
    );
    let report = String::from_utf8_lossy(&check.stdout);
    assert_eq!(check.status.code(), Some(0), "{report}");
    // A clean sequence prints its summary alone, no line per frame.
    assert_eq!(
        report,
        "121 frames checked, all clean: 0 penetrating vertices (deepest 0.00 mm), 0 \
         self-intersecting face pairs\n"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(dir.join(out).join("summary.json")).unwrap()).unwrap();
    let strain = summary["total"]["max_strain"].as_f64().unwrap();
    assert!(strain <= 0.1 + 1e-9, "worst strain {strain}");
}

#[test]
fn every_frame_of_the_demo_passes_check() {
    let dir = scratch("shipped_shots_demo");
    let run = tailor(&dir, &["demo", "--quiet"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(dir.join("tailor-out/preview.png").exists());
    assert_clean(&dir, "tailor-out");
}

#[test]
fn every_frame_of_the_skirt_passes_check() {
    let dir = scratch("shipped_shots_skirt");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/skirt.toml");
    let run = tailor(
        &dir,
        &[
            "simulate",
            scene.to_str().unwrap(),
            "--out",
            "skirt",
            "--quiet",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_clean(&dir, "skirt");
    resume_after_kills(&dir, scene.to_str().unwrap(), "skirt", &[1, 12, 47, 90]);
}

#[test]
fn the_cape_killed_at_several_frames_resumes_to_the_same_bytes() {
    let dir = scratch("shipped_shots_cape");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cape.toml");
    let scene = scene.to_str().unwrap();
    let run = tailor(&dir, &["simulate", scene, "--out", "cape", "--quiet"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    resume_after_kills(&dir, scene, "cape", &[1, 24, 41]);
}

/// Runs `scene` into `{whole}_killed` in `dir`, killing the run (SIGKILL) once each frame of
/// `kills` is on disk and resuming it, then to its end; asserts that it wrote what the
/// uninterrupted run wrote into `whole`.
fn resume_after_kills(dir: &Path, scene: &str, whole: &str, kills: &[u32]) {
    let out = format!("{whole}_killed");
    for (k, frame) in kills.iter().enumerate() {
        let mut args = vec!["simulate", scene, "--out", &out, "--quiet"];
        if k > 0 {
            args.push("--resume");
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_tailor"))
            .current_dir(dir)
            .args(&args)
            .spawn()
            .unwrap();
        let written = dir.join(&out).join(format!("cloth_{frame:04}.obj"));
        let started = Instant::now();
        while !written.exists() {
            assert!(
                started.elapsed().as_secs() < 600,
                "frame {frame} never appeared"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
        child.kill().unwrap();
        child.wait().unwrap();
        assert!(
            !dir.join(&out).join("summary.json").exists(),
            "the run finished before it could be killed after frame {frame}"
        );
    }
    let run = tailor(
        dir,
        &["simulate", scene, "--out", &out, "--quiet", "--resume"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (a, b) = (outputs(&dir.join(whole)), outputs(&dir.join(&out)));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(
            bytes == &b[name],
            "{name} differs after kills at frames {kills:?}"
        );
    }
}

/// The files a run writes into `dir` by name: the bytes of every OBJ, and `summary.json`
/// without its timings.
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".obj") {
            files.insert(name, fs::read(&path).unwrap());
        } else if name == "summary.json" {
            let mut summary: serde_json::Value =
                serde_json::from_slice(&fs::read(&path).unwrap()).unwrap();
            strip_timings(&mut summary);
            files.insert(name, summary.to_string().into_bytes());
        }
    }
    files
}

/// Removes every key naming a time (`ms`, `ms_per_frame`...) from `value`, at any depth.
fn strip_timings(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(map) => {
            map.retain(|key, _| !key.split('_').any(|word| word == "ms"));
            map.values_mut().for_each(strip_timings);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(strip_timings),
        _ => {}
    }
}
