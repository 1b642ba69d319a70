//! What the command-line tests share: a fresh directory, a run of the tool, the repository's
//! files.

#![allow(dead_code)] // Each test file uses what it needs.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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
