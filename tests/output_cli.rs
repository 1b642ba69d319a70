//! Where the tool's output goes, end to end.
//!
//! - Standard output closed early by its reader (`| head -1`) stops every command that
//!   prints quietly, with exit status 0: no panic, nothing on standard error. Standard output
//!   that cannot be written (`> /dev/full`) is an error naming it.

use std::fs::{self, File};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("output_cli_{name}"));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A cube's control mesh.
fn cube() -> String {
    root()
        .join("crates/subdiv/tests/data/opensubdiv/shapes/catmark_cube.obj")
        .display()
        .to_string()
}

/// Every command that prints to standard output, with arguments that make it print; `dir`
/// takes what they write to files.
fn printing_commands(dir: &Path) -> Vec<Vec<String>> {
    let cape = root().join("assets/garments/cape.obj");
    let scene = root().join("assets/scenes/cape.toml");
    let out = dir.join("shot");
    [
        vec!["info", &cube()],
        vec!["check", cape.to_str().unwrap()],
        vec!["subdivide", &cube(), "-l", "5"],
        vec![
            "simulate",
            scene.to_str().unwrap(),
            "--frames",
            "..1",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
    ]
    .into_iter()
    .map(|args| args.into_iter().map(String::from).collect())
    .collect()
}

/// Runs tailor with `args`, standard output a pipe whose reader takes `lines` lines then
/// closes it.
fn with_reader_gone(args: &[String], lines: usize) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut reader = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..lines {
        reader.read_line(&mut String::new()).unwrap();
    }
    drop(reader);
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_pipe_stops_quietly() {
    let dir = scratch("pipe");
    for args in printing_commands(&dir) {
        // Closed before anything is printed, and after the first line of a long output.
        for lines in [0, 1] {
            let o = with_reader_gone(&args, lines);
            assert_eq!(
                o.status.code(),
                Some(0),
                "{args:?} after {lines} line(s): {}",
                String::from_utf8_lossy(&o.stderr)
            );
            assert!(
                o.stderr.is_empty(),
                "{args:?} after {lines} line(s) printed {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
}

#[test]
fn a_full_standard_output_is_an_error_naming_it() {
    let dir = scratch("full");
    for args in printing_commands(&dir) {
        let o = Command::new(env!("CARGO_BIN_EXE_tailor"))
            .args(&args)
            .stdout(File::options().write(true).open("/dev/full").unwrap())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        // `check` keeps 1 for cloth found wanting: it cannot check, 2.
        let code = if args[0] == "check" { 2 } else { 1 };
        assert_eq!(o.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(
            stderr.contains("error: writing standard output"),
            "{args:?}: {stderr}"
        );
    }
}
