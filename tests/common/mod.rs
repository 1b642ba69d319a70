//! What the command-line tests share: a fresh directory, a run of the tool, the repository's
//! files.

#![allow(dead_code)] // Each test file uses what it needs.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use tailor_subdiv::Mesh;
use tailor_subdiv::obj::{self, Precision};

/// A fresh, empty directory `name` under the build's temporary directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `tailor ARGS` and waits for it.
pub fn tailor(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(args)
        .output()
        .unwrap()
}

/// The repository's root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The path of OpenSubdiv regression shape `name` the tests carry.
pub fn shape(name: &str) -> String {
    root()
        .join("crates/subdiv/tests/data/opensubdiv/shapes")
        .join(name)
        .display()
        .to_string()
}

/// Writes `mesh` into `dir` as `file`, coordinates in full.
pub fn write_mesh(dir: &Path, file: &str, mesh: &Mesh) {
    let mut text = Vec::new();
    obj::write(mesh, None, Precision::Full, &mut text).unwrap();
    fs::write(dir.join(file), text).unwrap();
}

/// Writes `scene` into `dir` as `file`, runs `tailor simulate` on it and asserts it succeeded;
/// returns the run's `summary.json`. The scene writes into `dir/out`.
pub fn simulate_scene(dir: &Path, file: &str, scene: &str) -> serde_json::Value {
    let path = dir.join(file);
    fs::write(&path, scene).unwrap();
    let out = tailor(&["simulate", path.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&fs::read(dir.join("out/summary.json")).unwrap()).unwrap()
}

/// Runs `tailor check` on the frames `pattern` names, with its options `options`, and returns
/// its report when it finds anything (or fails), `None` when every frame is clean.
pub fn check_findings(pattern: &Path, options: &[&str]) -> Option<String> {
    let mut args = vec!["check", pattern.to_str().unwrap()];
    args.extend(options);
    let out = tailor(&args);
    (out.status.code() != Some(0)).then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// [`check_findings`] on the written surface `dir/cloth_####.obj` against the body written
/// beside it, `dir/body_####.obj`, within `thickness`: the files as a user checks them.
pub fn check_written(dir: &Path, thickness: f64) -> Option<String> {
    let body = dir.join("body_####.obj");
    let thickness = thickness.to_string();
    check_findings(
        &dir.join("cloth_####.obj"),
        &[
            "--against",
            body.to_str().unwrap(),
            "--thickness",
            &thickness,
        ],
    )
}
