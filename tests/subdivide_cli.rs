//! `tailor subdivide` end to end: golden files for real shapes, standard input and output, and
//! bad input that must fail with a message naming file and line and leave no output behind.
//! The golden files are written with `--precision full`; the default output is checked against
//! them number by number (each the shortest text of the same value rounded to `f32`), and the
//! bytes against a run on one thread.
//!
//! Golden files live in `tests/golden/`; regenerate them only on purpose, with
//! `TAILOR_BLESS=1 cargo test --test subdivide_cli`, and say why in the commit.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::shape;

mod common;

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
            "--precision",
            "full",
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
            "--precision",
            "full",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    golden("edgecorner_l1_limit.obj", &o.stdout);
}

/// Asserts that `single` is `full` with every number the shortest text of its value rounded
/// to `f32`: the same lines and words, numbers reading back as the same `f32` in at most 9
/// significant digits; integers (indices) and tag lines unchanged.
fn is_single_of_full(single: &str, full: &str) {
    let (a, b): (Vec<_>, Vec<_>) = (single.lines().collect(), full.lines().collect());
    assert_eq!(a.len(), b.len());
    for (s, f) in a.iter().zip(&b) {
        if f.starts_with("t ") || f.starts_with("f ") {
            assert_eq!(s, f);
            continue;
        }
        let (ws, wf): (Vec<_>, Vec<_>) = (s.split(' ').collect(), f.split(' ').collect());
        assert_eq!(ws.len(), wf.len(), "{s} against {f}");
        assert_eq!(ws[0], wf[0]);
        for (x, y) in ws[1..].iter().zip(&wf[1..]) {
            let rounded = y.parse::<f64>().unwrap() as f32;
            assert_eq!(
                x.parse::<f32>().unwrap().to_bits(),
                rounded.to_bits(),
                "{x} for {y}"
            );
            let mantissa = x.split('e').next().unwrap_or_default();
            let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
            assert!(
                digits.trim_start_matches('0').len() <= 9,
                "{x}: more significant digits than an f32 needs"
            );
            assert!(x.len() <= y.len(), "{x} longer than {y}");
        }
    }
}

#[test]
fn default_precision_rounds_the_golden_numbers_to_f32() {
    let single = tailor(
        &["subdivide", &shape("catmark_cube_creases1.obj"), "-l", "2"],
        None,
    );
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let full = fs::read_to_string(golden.join("cube_creases1_l2.obj")).unwrap();
    is_single_of_full(&String::from_utf8(single.stdout).unwrap(), &full);
    let args = ["subdivide", &shape("catmark_edgecorner.obj"), "-l", "1"];
    let single = tailor(&[&args[..], &["--limit", "--normals"]].concat(), None);
    let full = fs::read_to_string(golden.join("edgecorner_l1_limit.obj")).unwrap();
    is_single_of_full(&String::from_utf8(single.stdout).unwrap(), &full);
}

/// `tailor subdivide` with `RAYON_NUM_THREADS` set to `threads`, writing `out`.
fn subdivide_on(threads: &str, input: &str, level: &str, out: &Path, extra: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(["subdivide", input, "-l", level, "-o", out.to_str().unwrap()])
        .args(extra)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Reading and writing go in parallel chunks (of 256 KiB of input, of 16k lines of output):
/// inputs and outputs of several chunks give the same bytes on one thread and on three, and
/// the mesh the library refines, in its order.
#[test]
fn the_bytes_do_not_depend_on_the_thread_count() {
    let dir = scratch("threads");
    fs::create_dir_all(&dir).unwrap();
    // Level 5 of the creased cube: 6144 faces, 6146 vertices, as input of several chunks.
    let input = dir.join("cube_l5.obj");
    subdivide_on(
        "1",
        &shape("catmark_cube_creases1.obj"),
        "5",
        &input,
        &["--precision", "full"],
    );
    assert!(fs::metadata(&input).unwrap().len() > 2 << 18);
    let control = tailor_subdiv::obj::read(&input).unwrap().mesh;
    let (refined, _) = tailor_subdiv::subdivide(&control, 2, false);
    let input = input.to_str().unwrap();
    for extra in [&[][..], &["--precision", "full", "--normals"]] {
        // Level 2 of that: 98,304 faces, six chunks of faces.
        let (one, three) = (dir.join("one.obj"), dir.join("three.obj"));
        subdivide_on("1", input, "2", &one, extra);
        subdivide_on("3", input, "2", &three, extra);
        let (a, b) = (fs::read(&one).unwrap(), fs::read(&three).unwrap());
        assert!(a.len() > 3_000_000);
        assert!(
            a == b,
            "{extra:?}: one thread and three wrote different bytes"
        );
        let back = tailor_subdiv::obj::parse(&String::from_utf8(a).unwrap(), "one").unwrap();
        assert_eq!(back.mesh.face_vertices(), refined.face_vertices());
        let rounded = |m: &tailor_subdiv::Mesh| -> Vec<u32> {
            let p = m.positions().iter();
            p.flat_map(|p| p.iter().map(|&c| (c as f32).to_bits()))
                .collect()
        };
        assert!(
            rounded(&back.mesh) == rounded(&refined),
            "{extra:?}: positions out of order"
        );
    }
}

/// `--precision full` writes every coordinate so that it reads back as the same `f64`: the
/// output read back is the mesh the library refines, bit for bit.
#[test]
fn full_precision_reads_back_as_the_refined_mesh() {
    let path = shape("catmark_cube_creases1.obj");
    let mesh = tailor_subdiv::obj::read(Path::new(&path)).unwrap().mesh;
    let (refined, limit) = tailor_subdiv::subdivide(&mesh, 3, true);
    let limit = limit.unwrap();
    for (extra, positions) in [
        (&[][..], refined.positions().to_vec()),
        (&["--limit"][..], limit.positions.clone()),
    ] {
        let o = tailor(
            &[
                &["subdivide", &path, "-l", "3", "--precision", "full"],
                extra,
            ]
            .concat(),
            None,
        );
        let back = tailor_subdiv::obj::parse(&String::from_utf8(o.stdout).unwrap(), "out").unwrap();
        let bits = |p: &[tailor_subdiv::Point]| -> Vec<u64> {
            p.iter()
                .flat_map(|p| p.iter().map(|c| c.to_bits()))
                .collect()
        };
        assert_eq!(bits(back.mesh.positions()), bits(&positions), "{extra:?}");
        assert_eq!(back.mesh.creases(), refined.creases());
    }
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
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_cube.obj"),
            "--precision",
            "double",
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(2), "usage errors exit 2");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("unknown precision 'double' (expected one of: single full)"),
        "{err}"
    );
}

#[test]
fn faces_that_repeat_a_vertex_are_read_as_opensubdiv_reads_them_with_a_warning() {
    // catmark_nonman_quadpole8: face 1, `f 4 3 5 5` on line 19, and seven more like it.
    let out = scratch("quadpole8.obj");
    let o = tailor(
        &[
            "subdivide",
            &shape("catmark_nonman_quadpole8.obj"),
            "-l",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("catmark_nonman_quadpole8.obj:19: face 1 uses vertex 4 more than once")
            && err.contains("(8 such face(s) in all)"),
        "{err}"
    );
    // What OpenSubdiv makes of it is `tests/opensubdiv_cli.rs`'s; here, a mesh was written.
    assert!(fs::read_to_string(&out).unwrap().contains("\nf "));
    let o = tailor(&["info", &shape("catmark_nonman_quadpole8.obj")], None);
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn errors_quote_a_few_dozen_characters_of_a_huge_bad_input() {
    // A 100,000-digit token in an OBJ, then in a scene file: the message names the place and
    // quotes the start, not all of it.
    let token = "9".repeat(100_000);
    let o = tailor(
        &["subdivide", "-", "-l", "1"],
        Some(&format!("v 0 0 0\nv 1 0 0\nv 0 1 {token}x\nf 1 2 3\n")),
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("<stdin>:3: malformed number '9999") && err.contains("… (100001 bytes)'"),
        "{err}"
    );
    assert!(err.len() < 200, "{} bytes of error", err.len());
    let scene = scratch("huge_token.toml");
    fs::write(&scene, format!("[scene]\nfps = {token}x\n")).unwrap();
    let o = tailor(&["simulate", scene.to_str().unwrap()], None);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("huge_token.toml") && err.contains("line 2"),
        "{err}"
    );
    assert!(err.len() < 2000, "{} bytes of error", err.len());
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
    let limited_to = |kilobytes: u32, level: &str, extra: &str| {
        let out = dir.join(format!("cape_{level}.obj"));
        Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v {kilobytes} && exec \"$0\" subdivide \"$1\" -l {level} {extra} -o \"$2\""
            ))
            .arg(env!("CARGO_BIN_EXE_tailor"))
            .arg(&cape)
            .arg(&out)
            .output()
            .unwrap()
    };
    let limited = |level: &str| limited_to(1_000_000, level, "");
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
    // Limit positions and normals take about twice the memory: level 6 with both (2.0 GB
    // resident) is refused under 2 GB, where the plain estimate (1.3 GB) let it start.
    let refused = limited_to(2_000_000, "6", "--limit --normals");
    let error = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{error}");
    assert!(
        error.contains("makes 1966080 faces and needs about 2.2 GB"),
        "{error}"
    );
}

/// What `tailor subdivide` writes by default is read by `tailor info`, `tailor check` and
/// `tailor subdivide` itself.
#[test]
fn the_default_output_is_read_by_info_check_and_subdivide() {
    let out = scratch("read_back.obj");
    let written = tailor(
        &[
            "subdivide",
            &shape("catmark_cube_creases1.obj"),
            "-l",
            "3",
            "-o",
            out.to_str().unwrap(),
        ],
        None,
    );
    assert!(written.status.success());
    let out = out.to_str().unwrap();
    let info = tailor(&["info", out], None);
    let report = String::from_utf8_lossy(&info.stdout);
    assert!(report.contains("faces            384"), "{report}");
    let check = tailor(&["check", out], None);
    assert_eq!(
        check.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
    let again = tailor(&["subdivide", out, "-l", "1"], None);
    assert!(again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("384 faces -> 1536 faces"));
}
