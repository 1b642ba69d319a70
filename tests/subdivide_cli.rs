//! `tailor subdivide` end to end: golden files for real shapes, standard input and output, and
//! bad input that must fail with a message naming file and line and leave no output behind.
//!
//! Golden files live in `tests/golden/`; regenerate them only on purpose, with
//! `TAILOR_BLESS=1 cargo test --test subdivide_cli`, and say why in the commit.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn tailor(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run tailor");
    if let Some(text) = stdin {
        child
            .stdin
            .take()
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
    }
    drop(child.stdin.take());
    child.wait_with_output().unwrap()
}

fn shape(name: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    root.join("crates/subdiv/tests/data/opensubdiv/shapes")
        .join(name)
        .display()
        .to_string()
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("subdivide_cli");
    fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn golden(name: &str, produced: &[u8]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(name);
    if std::env::var_os("TAILOR_BLESS").is_some() {
        fs::write(&path, produced).unwrap();
    }
    let expected =
        fs::read(&path).unwrap_or_else(|_| panic!("missing golden file {}", path.display()));
    assert!(
        expected == produced,
        "{name} differs from its golden file (TAILOR_BLESS=1 regenerates)"
    );
}

#[test]
fn creased_cube_level_two_matches_golden() {
    let out = scratch("cube_creases1_l2.obj");
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_cube_creases1.obj"),
            "-l",
            "2",
            "-o",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = String::from_utf8_lossy(&o.stderr);
    assert!(
        summary.contains("6 faces -> 96 faces (level 2)"),
        "{summary}"
    );
    golden("cube_creases1_l2.obj", &fs::read(out).unwrap());
}

#[test]
fn limit_surface_with_normals_matches_golden() {
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_edgecorner.obj"),
            "-l",
            "1",
            "--limit",
            "--normals",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    golden("edgecorner_l1_limit.obj", &o.stdout);
}

#[test]
fn flags_override_tags_and_stdin_works() {
    let text = fs::read_to_string(shape("catmark_edgecorner.obj")).unwrap();
    let tagged = tailor(&["subdivide", "-", "-l", "1"], Some(&text));
    let overridden = tailor(
        &["subdivide", "-", "-l", "1", "--boundary", "edge-only"],
        Some(&text),
    );
    assert!(tagged.status.success() && overridden.status.success());
    assert_ne!(
        tagged.stdout, overridden.stdout,
        "--boundary must change the edge-and-corner shape"
    );
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_edgecorner.obj"),
            "-l",
            "1",
            "--boundary",
            "edge-only",
        ],
        None,
    );
    assert_eq!(o.stdout, overridden.stdout);
}

#[test]
fn bad_input_names_file_and_line_and_writes_nothing() {
    let out = scratch("never.obj");
    let _ = fs::remove_file(&out);
    let o = tailor(
        &["subdivide", "-", "-l", "1", "-o", out.to_str().unwrap()],
        Some("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("<stdin>:4"), "{err}");
    assert!(!out.exists());
    let o = tailor(&["subdivide", "missing.obj"], None);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.obj"));
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_cube.obj"),
            "--crease-method",
            "sharp",
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(2), "usage errors exit 2");
}

#[test]
fn failed_run_keeps_the_previous_output() {
    let out = scratch("kept.obj");
    fs::write(&out, "previous").unwrap();
    let o = tailor(
        &["subdivide", "-", "-o", out.to_str().unwrap()],
        Some("v 0 0 nan\nf 1 1 1\n"),
    );
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(fs::read_to_string(&out).unwrap(), "previous");
}

#[test]
fn a_refinement_larger_than_memory_is_refused_before_it_starts() {
    // Under a 1 GB address-space limit (`ulimit -v`), level 7 of the cape (7.9 M faces, about
    // 5 GB) is refused with what it needs; level 3 goes through. Without the estimate the
    // refinement aborted on a failed allocation.
    let dir = scratch("memory");
    fs::create_dir_all(&dir).unwrap();
    let cape = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/garments/cape.obj");
    let limited = |level: &str| {
        let out = dir.join(format!("cape_{level}.obj"));
        Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v 1000000 && exec \"$0\" subdivide \"$1\" -l {level} -o \"$2\""
            ))
            .arg(env!("CARGO_BIN_EXE_tailor"))
            .arg(&cape)
            .arg(&out)
            .output()
            .unwrap()
    };
    let refused = limited("7");
    let error = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{error}");
    assert!(
        error.contains("makes 7864320 faces and needs about 5.0 GB")
            && error.contains("GB is available"),
        "{error}"
    );
    assert!(!dir.join("cape_7.obj").exists());
    let small = limited("3");
    assert!(
        small.status.success(),
        "{}",
        String::from_utf8_lossy(&small.stderr)
    );
}
