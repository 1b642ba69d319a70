//! The shots shipped in `assets/scenes/` are clean: `tailor demo` (the cape over the whole
//! 120-frame walk) and the skirt scene, run end to end by the built binary, then every frame
//! checked by `tailor check` against the body the cloth collided with, at the scene's
//! thickness: no cloth vertex of the written (subdivided) surface inside the body or closer
//! than the thickness, no self-intersecting face pairs, and no edge strained past 10%.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("shipped_shots_{name}"));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

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
    assert!(report.contains("121 frame(s) checked"), "{report}");
    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(dir.join(out).join("summary.json")).unwrap()).unwrap();
    let strain = summary["total"]["max_strain"].as_f64().unwrap();
    assert!(strain <= 0.1 + 1e-9, "worst strain {strain}");
}

#[test]
fn every_frame_of_the_demo_passes_check() {
    let dir = scratch("demo");
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
    let dir = scratch("skirt");
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
}
