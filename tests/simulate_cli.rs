//! `tailor simulate` end to end on a small generated shot: a 5 × 5-quad sheet attached by one
//! row to the top of a cube, draping over its edge, 10 frames.
//!
//! - The output at `[output] precision = "full"` reproduces the committed golden files
//!   (`tests/golden/simulate/`) within a tolerance; regenerate them only on purpose, with
//!   `TAILOR_BLESS=1 cargo test --test simulate_cli`, and say why in the commit. The default
//!   output has every number of the full one rounded to `f32`, and the same summary.
//! - The bytes do not depend on the thread count.
//! - A run stopped after a frame, killed midway, or interrupted by Ctrl-C (exit 130, no
//!   temporary left) and resumed writes the same bytes as one uninterrupted run; a run removes
//!   the temporaries of its own files that a killed run left, and nothing else; a finished shot resumed with more `frames` equals the longer shot;
//!   a resume with any other change to the shot is refused, naming the key, and so is one
//!   whose frames before the checkpoint lost or changed their files.
//! - Each bad input is refused before anything is written, with a message naming the file and
//!   the key or line, and leaves an earlier run's output untouched.
//! - A shot whose cloth is torn past its strain limit says so (a warning naming the frames and
//!   the group, `failures` in `summary.json`) and, with `--strict` or `[scene] strict = true`,
//!   exits 3 once every file is written; a clean shot warns of nothing and passes `--strict`.
//! - A shot whose cloth lies in the body and through itself says where on the garment (the
//!   group of the control vertex or faces the refined surface's findings map to), in the
//!   warning and in `summary.json`, resumed or not.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::scratch;

mod common;

/// Runs `tailor simulate ARGS`.
fn tailor(args: &[&str]) -> Output {
    common::tailor(&[&["simulate"], args].concat())
}

/// A closed unit cube `[0, 1]³`, faces counter-clockwise seen from outside, moved by `dx`.
fn cube(dx: f64) -> String {
    let mut text = String::new();
    for (x, y, z) in [
        (0, 0, 0),
        (1, 0, 0),
        (0, 1, 0),
        (1, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (0, 1, 1),
        (1, 1, 1),
    ] {
        text += &format!("v {} {y} {z}\n", f64::from(x) + dx);
    }
    text + "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n"
}

/// A 5 × 5-quad sheet in the plane y = 1.1 (over the cube), from z = 0.3 to 1.3, so that
/// it sticks out over the cube's front edge and drapes over it, with UVs and the groups `sheet`
/// (every face) and `top` (the row at the back, attached to the cube's top).
fn sheet() -> String {
    let n = 5;
    let mut text = String::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
            text += &format!("v {} 1.1 {}\n", 0.1 + 0.8 * u, 0.3 + v);
        }
    }
    for j in 0..=n {
        for i in 0..=n {
            text += &format!("vt {} {}\n", f64::from(i) / 5.0, f64::from(j) / 5.0);
        }
    }
    for j in 0..n {
        text += if j == 0 { "g sheet top\n" } else { "g sheet\n" };
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
            text += &format!("f {a}/{a} {b}/{b} {c}/{c} {d}/{d}\n");
        }
    }
    text
}

const SCENE: &str = r#"[scene]
fps = 24
frames = 10
substeps = 4

[cloth]
mesh = "sheet.obj"
material = "cotton"
density = 0.2
thickness = 0.01
pins = []
attach = ["top"]
stiffen = { top = 2.0 }

[body]
mesh = "cube.obj"
subdivision_level = 1

[output]
dir = "out"
subdivision_level = 1
"#;

/// Text replacements `(from, to)` applied to the scene.
type Edit<'a> = &'a [(&'a str, &'a str)];

/// Writes the shot's files into `dir`, the scene with `edit` applied (`(from, to)` text
/// replacements); returns the scene's path.
fn shot(dir: &Path, edit: Edit) -> PathBuf {
    fs::write(dir.join("sheet.obj"), sheet()).unwrap();
    fs::write(dir.join("cube.obj"), cube(0.0)).unwrap();
    let mut scene = SCENE.to_owned();
    for (from, to) in edit {
        assert!(scene.contains(from), "{from:?} not in the scene");
        scene = scene.replace(from, to);
    }
    let path = dir.join("scene.toml");
    fs::write(&path, scene).unwrap();
    path
}

/// The files in `dir` whose names pass `keep`, by name.
fn files(dir: &Path, keep: fn(&str) -> bool) -> BTreeMap<String, Vec<u8>> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), p))
        .filter(|(name, _)| keep(name))
        .map(|(name, p)| (name, fs::read(&p).unwrap()))
        .collect()
}

/// Every OBJ in `dir`, by name.
fn objs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    files(dir, |name| name.ends_with(".obj"))
}

/// Every file in `dir`, by name.
fn everything(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    files(dir, |_| true)
}

fn run_ok(args: &[&str]) -> Output {
    let out = tailor(args);
    assert!(
        out.status.success(),
        "tailor simulate {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Compares an OBJ with its golden file: the same tokens, numbers within 1e-9 relative.
fn golden(name: &str, produced: &[u8]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden/simulate")
        .join(name);
    if std::env::var_os("TAILOR_BLESS").is_some() {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(&path, produced).unwrap();
        return;
    }
    let expected = fs::read_to_string(&path)
        .unwrap_or_else(|_| panic!("missing golden file {}", path.display()));
    let produced = String::from_utf8(produced.to_vec()).unwrap();
    let (a, b): (Vec<_>, Vec<_>) = (expected.lines().collect(), produced.lines().collect());
    assert_eq!(a.len(), b.len(), "{name}: line count differs from golden");
    for (line, (a, b)) in a.iter().zip(&b).enumerate() {
        let (ta, tb): (Vec<_>, Vec<_>) = (a.split(' ').collect(), b.split(' ').collect());
        let same = ta.len() == tb.len()
            && ta.iter().zip(&tb).all(|(x, y)| {
                x == y
                    || match (x.parse::<f64>(), y.parse::<f64>()) {
                        (Ok(x), Ok(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
                        _ => false,
                    }
            });
        assert!(
            same,
            "{name}:{}: {b:?} differs from golden {a:?} (TAILOR_BLESS=1 regenerates)",
            line + 1
        );
    }
}

#[test]
fn short_shot_matches_golden_with_one_and_two_threads() {
    let dir = scratch("simulate_cli_golden");
    let scene = shot(&dir, &[(FULL.0, FULL.1)]);
    let scene = scene.to_str().unwrap();
    let one = dir.join("one");
    let two = dir.join("two");
    let out = run_ok(&[scene, "--out", one.to_str().unwrap(), "--threads", "1"]);
    run_ok(&[
        scene,
        "--out",
        two.to_str().unwrap(),
        "--threads",
        "2",
        "--quiet",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("10 frames simulated"), "{stdout}");
    assert!(
        out.stderr.is_empty(),
        "no progress bar off a terminal: {:?}",
        out.stderr
    );

    let files = objs(&one);
    assert_eq!(
        files.len(),
        3 * 11,
        "cloth, control and body for frames 0..=10"
    );
    assert!(
        files == objs(&two),
        "--threads 1 and 2 wrote different bytes"
    );
    for name in [
        "cloth_control_0005.obj",
        "cloth_control_0010.obj",
        "cloth_0010.obj",
    ] {
        golden(name, &files[name]);
    }
    let control = String::from_utf8_lossy(&files["cloth_control_0000.obj"]).into_owned();
    assert!(control.contains("g sheet top\n") && control.contains("vt "));
    assert_eq!(control.lines().filter(|l| l.starts_with("v ")).count(), 36);

    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(one.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["frames"].as_array().unwrap().len(), 11);
    assert_eq!(summary["total"]["frames_simulated"], 10);
    // The invariants the golden frames must satisfy, whatever their digits: strain within the
    // default 10% limit, and on every written frame no point within the thickness of the body
    // and no crossing faces (the per-frame check of the written surface).
    let total = &summary["total"];
    assert!(
        total["max_strain"].as_f64().unwrap() <= 0.1 + 1e-9,
        "{total}"
    );
    assert_eq!(total["penetrating_vertices"], 0, "{total}");
    assert_eq!(total["self_intersecting_pairs"], 0, "{total}");
    assert_eq!(total["frames_not_clean"], 0, "{total}");
}

/// The scene edit that writes full precision.
const FULL: (&str, &str) = ("dir = \"out\"", "dir = \"out\"\nprecision = \"full\"");

/// Every number of `single` reads back as the `f32` nearest the same number of `full`, in at
/// most 9 significant digits; everything else is the same.
fn rounds_to_f32(name: &str, single: &[u8], full: &[u8]) {
    let (single, full) = (
        String::from_utf8_lossy(single),
        String::from_utf8_lossy(full),
    );
    let (a, b): (Vec<_>, Vec<_>) = (
        single.split_whitespace().collect(),
        full.split_whitespace().collect(),
    );
    assert_eq!(a.len(), b.len(), "{name}");
    for (x, y) in a.iter().zip(&b) {
        match (x.parse::<f32>(), y.parse::<f64>()) {
            (Ok(x32), Ok(y64)) if x != y => {
                assert_eq!(x32.to_bits(), (y64 as f32).to_bits(), "{name}: {x} for {y}");
                let digits: String = x.chars().filter(char::is_ascii_digit).collect();
                assert!(digits.trim_start_matches('0').len() <= 9, "{name}: {x}");
            }
            _ => assert_eq!(x, y, "{name}"),
        }
    }
}

#[test]
fn default_precision_writes_each_number_as_its_f32() {
    let dir = scratch("simulate_cli_precision");
    let full = dir.join("full");
    // The body a little off the grid of binary fractions, so that its refined points take
    // more digits in full than in single precision, as the cloth's do.
    let off_grid = |dir: &Path| fs::write(dir.join("cube.obj"), cube(0.1)).unwrap();
    let scene = shot(&dir, &[(FULL.0, FULL.1)]);
    off_grid(&dir);
    run_ok(&[
        scene.to_str().unwrap(),
        "--out",
        full.to_str().unwrap(),
        "--quiet",
    ]);
    let scene = shot(&dir, &[]);
    off_grid(&dir);
    let (one, two) = (dir.join("one"), dir.join("two"));
    let scene = scene.to_str().unwrap();
    run_ok(&[scene, "--out", one.to_str().unwrap(), "--threads", "1"]);
    run_ok(&[scene, "--out", two.to_str().unwrap(), "--threads", "2"]);
    let (single, full_files) = (objs(&one), objs(&full));
    assert!(
        single == objs(&two),
        "--threads 1 and 2 wrote different bytes"
    );
    assert_eq!(single.len(), full_files.len());
    for (name, bytes) in &single {
        rounds_to_f32(name, bytes, &full_files[name]);
    }
    // Each of the three sequences is written at the precision asked.
    for prefix in ["cloth_0", "cloth_control_", "body_"] {
        let size = |files: &BTreeMap<String, Vec<u8>>| -> usize {
            let of_kind = files.iter().filter(|(name, _)| name.starts_with(prefix));
            of_kind.map(|(_, bytes)| bytes.len()).sum()
        };
        assert!(size(&single) < size(&full_files), "{prefix}");
    }
    // The simulation is the f64s' at either precision, and its judgement (of the positions
    // as written) finds the same: the same summary, times aside.
    let figures = |dir: &Path| {
        let mut s = summary(dir);
        for frame in s["frames"].as_array_mut().unwrap() {
            frame.as_object_mut().unwrap().remove("ms");
        }
        s["total"]
            .as_object_mut()
            .unwrap()
            .retain(|k, _| !k.contains("ms"));
        s
    };
    assert_eq!(figures(&one), figures(&full));
}

#[test]
fn stopped_and_resumed_run_writes_the_same_bytes() {
    let dir = scratch("simulate_cli_resume");
    let scene = shot(&dir, &[]);
    let scene = scene.to_str().unwrap();
    let whole = dir.join("whole");
    let parts = dir.join("parts");
    let (whole_s, parts_s) = (whole.to_str().unwrap(), parts.to_str().unwrap());
    run_ok(&[scene, "--out", whole_s]);
    run_ok(&[scene, "--out", parts_s, "--stop-after", "7", "--quiet"]);
    assert!(parts.join("cloth_0007.obj").exists());
    assert!(!parts.join("cloth_0008.obj").exists());
    run_ok(&[scene, "--out", parts_s, "--resume", "--quiet"]);
    let (a, b) = (objs(&whole), objs(&parts));
    assert_eq!(a.len(), b.len());
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs after resuming");
    }
    // A checkpoint of another shot is refused, naming the key that changed.
    for (from, to, key) in [
        ("density = 0.2", "density = 0.3", "[cloth] density"),
        ("substeps = 4", "substeps = 5", "[scene] substeps"),
        (
            "subdivision_level = 1\n\n[output]",
            "\n[output]",
            "[body] subdivision_level",
        ),
        (FULL.0, FULL.1, "[output] precision"),
    ] {
        shot(&dir, &[(from, to)]);
        let out = tailor(&[scene, "--out", parts_s, "--resume"]);
        assert_eq!(out.status.code(), Some(1));
        let error = String::from_utf8_lossy(&out.stderr);
        assert!(
            error.contains(&format!("another shot ({key} differs)")),
            "{error}"
        );
    }
    shot(&dir, &[]);
    fs::write(
        dir.join("sheet.obj"),
        sheet().replacen("v 0.1 1.1", "v 0.11 1.1", 1),
    )
    .unwrap();
    let out = tailor(&[scene, "--out", parts_s, "--resume"]);
    let error = String::from_utf8_lossy(&out.stderr);
    assert!(error.contains("[cloth] mesh (the file) differs"), "{error}");
}

/// Something done to a file.
type Damage = fn(&Path);

/// Files are not forced to disk, so a power cut can lose frames a checkpoint counts as
/// written: a resume refuses a frame file that is missing or of another length than the run
/// wrote, naming it, and changes nothing; with the file back it resumes.
#[test]
fn a_resume_refuses_frames_lost_since_the_checkpoint() {
    let dir = scratch("simulate_cli_lost_frames");
    let scene = shot(&dir, &[]);
    let scene = scene.to_str().unwrap();
    let parts = dir.join("parts");
    let parts_s = parts.to_str().unwrap();
    run_ok(&[scene, "--out", parts_s, "--stop-after", "5", "--quiet"]);
    let written = everything(&parts);
    let truncate: Damage = |path| fs::write(path, b"").unwrap();
    let remove: Damage = |path| fs::remove_file(path).unwrap();
    let lengthen: Damage = |path| {
        let mut bytes = fs::read(path).unwrap();
        bytes.push(b'\n');
        fs::write(path, bytes).unwrap();
    };
    let longer = format!("is {} bytes", written["cloth_control_0000.obj"].len() + 1);
    let damages = [
        ("cloth_0003.obj", truncate, "is 0 bytes"),
        ("body_0005.obj", remove, "is missing"),
        ("cloth_control_0000.obj", lengthen, &longer),
    ];
    for (name, damage, found) in damages {
        let path = parts.join(name);
        damage(&path);
        let damaged = everything(&parts);
        let out = tailor(&[scene, "--out", parts_s, "--resume", "--quiet"]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let error = String::from_utf8_lossy(&out.stderr);
        assert!(
            error.contains(&format!("{name} {found}")) && error.contains("run without --resume"),
            "{error}"
        );
        assert!(
            everything(&parts) == damaged,
            "a refused resume changed files"
        );
        fs::write(&path, &written[name]).unwrap();
    }
    run_ok(&[scene, "--out", parts_s, "--resume", "--quiet"]);
    assert!(parts.join("cloth_0010.obj").exists());
}

#[test]
fn a_finished_shot_extended_by_resuming_equals_the_longer_shot() {
    let dir = scratch("simulate_cli_extend");
    let long = shot(&dir, &[("frames = 10", "frames = 16")]);
    let whole = dir.join("whole");
    run_ok(&[
        long.to_str().unwrap(),
        "--out",
        whole.to_str().unwrap(),
        "--quiet",
    ]);
    let short = shot(&dir, &[]);
    let parts = dir.join("parts");
    let (short, parts_s) = (short.to_str().unwrap(), parts.to_str().unwrap());
    run_ok(&[short, "--out", parts_s, "--quiet"]);
    assert!(parts.join("summary.json").exists() && !parts.join("cloth_0011.obj").exists());
    // More frames, and strict (which decides only the exit status), may change.
    shot(&dir, &[("frames = 10", "frames = 16\nstrict = true")]);
    run_ok(&[short, "--out", parts_s, "--resume", "--quiet"]);
    let (a, b) = (objs(&whole), objs(&parts));
    assert_eq!(a.len(), 3 * 17);
    assert_eq!(a.len(), b.len());
    for (name, bytes) in &a {
        assert!(bytes == &b[name], "{name} differs in the extended shot");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&fs::read(parts.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["total"]["frames_simulated"], 16);
    // A shot cannot be shortened past its checkpoint.
    shot(&dir, &[("frames = 10", "frames = 12")]);
    let out = tailor(&[short, "--out", parts_s, "--resume"]);
    assert_eq!(out.status.code(), Some(1));
    let error = String::from_utf8_lossy(&out.stderr);
    assert!(
        error.contains("at frame 16, past the last frame asked (12)"),
        "{error}"
    );
}

/// Runs a 40-frame shot whole, and again stopped by `kill -SIGNAL` once frame 4 is on disk;
/// checks that no file under a final name is cut short, resumes the stopped run, and checks
/// that it wrote the same bytes as the whole one and left no temporary. Returns how the
/// stopped run ended and what it printed on standard error.
fn stopped_and_resumed(name: &str, signal: &str) -> (std::process::ExitStatus, String) {
    let dir = scratch(name);
    let scene = shot(&dir, &[("frames = 10", "frames = 40")]);
    let scene = scene.to_str().unwrap();
    let whole = dir.join("whole");
    let stopped = dir.join("stopped");
    let (whole_s, stopped_s) = (whole.to_str().unwrap(), stopped.to_str().unwrap());
    run_ok(&[scene, "--out", whole_s, "--quiet"]);
    let child = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args(["simulate", scene, "--out", stopped_s, "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while !stopped.join("cloth_0004.obj").exists() {
        assert!(started.elapsed().as_secs() < 300, "frame 4 never appeared");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let kill = Command::new("kill")
        .args(["-s", signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    assert!(
        !stopped.join("summary.json").exists(),
        "the run finished before it could be stopped"
    );
    // Whatever the signal interrupted, no half-written file is left under a final name.
    for (name, bytes) in objs(&stopped) {
        let text = String::from_utf8(bytes).unwrap();
        assert!(text.ends_with('\n'), "{name} is cut short");
    }
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let temporaries = |dir: &Path| files(dir, |name| name.contains(".tmp-"));
    let left = temporaries(&stopped);
    run_ok(&[scene, "--out", stopped_s, "--resume", "--quiet"]);
    assert!(
        temporaries(&stopped).is_empty(),
        "{left:?} were not removed"
    );
    let (a, b) = (objs(&whole), objs(&stopped));
    assert_eq!(a.len(), b.len());
    for (name, bytes) in &a {
        assert!(
            bytes == &b[name],
            "{name} differs after the {signal} and resume"
        );
    }
    if signal == "INT" {
        assert!(left.is_empty(), "Ctrl-C left {:?}", left.keys());
    }
    (out.status, stderr)
}

#[test]
fn killed_and_resumed_run_writes_the_same_bytes() {
    // SIGKILL: no chance to clean up.
    stopped_and_resumed("kill", "KILL");
}

#[test]
fn interrupted_run_stops_after_a_frame_and_resumes() {
    let (status, stderr) = stopped_and_resumed("interrupt", "INT");
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("--resume continues"), "{stderr}");
}

#[test]
fn stale_temporaries_of_its_own_files_are_removed() {
    let dir = scratch("simulate_cli_stale");
    let scene = shot(&dir, &[]);
    let scene = scene.to_str().unwrap();
    let out = dir.join("out");
    fs::create_dir_all(&out).unwrap();
    let own = [".cloth_0003.obj.tmp-99999", ".tailor_checkpoint.bin.tmp-7"];
    let others = [
        ".notes.tmp-1",
        ".cloth_0003.obj.tmp-x",
        "cloth_0003.obj.tmp-5",
    ];
    for name in own.iter().chain(&others) {
        fs::write(out.join(name), "stale").unwrap();
    }
    let o = run_ok(&[scene, "--out", out.to_str().unwrap(), "--frames", "..1"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("removed 2 temporary file(s)"), "{stderr}");
    for name in own {
        assert!(!out.join(name).exists(), "{name} is still there");
    }
    for name in others {
        assert!(out.join(name).exists(), "{name} was removed");
    }
    // Quietly with --quiet.
    fs::write(out.join(own[0]), "stale").unwrap();
    let o = run_ok(&[
        scene,
        "--out",
        out.to_str().unwrap(),
        "--frames",
        "..1",
        "--quiet",
    ]);
    assert!(!out.join(own[0]).exists());
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn a_fresh_run_removes_the_files_of_an_earlier_one() {
    let dir = scratch("simulate_cli_fresh");
    let scene = shot(&dir, &[]);
    let scene = scene.to_str().unwrap();
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    run_ok(&[scene, "--out", out_s, "--quiet"]);
    fs::write(out.join("notes.txt"), "mine").unwrap();
    let earlier = everything(&out).len() - 1;
    // A shorter shot into the same directory: frames 4 to 10 of the longer one must go.
    let o = run_ok(&[scene, "--out", out_s, "--frames", "..3"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(&format!("removed {earlier} file(s) of an earlier run")),
        "{stderr}"
    );
    let names: Vec<String> = everything(&out).into_keys().collect();
    let mut expected = vec!["notes.txt".to_owned(), "summary.json".to_owned()];
    for frame in 0..=3 {
        for prefix in ["body", "cloth", "cloth_control"] {
            expected.push(format!("{prefix}_{frame:04}.obj"));
        }
    }
    expected.push("tailor_checkpoint.bin".to_owned());
    expected.sort();
    assert_eq!(names, expected);
    // Resuming keeps them.
    let o = run_ok(&[scene, "--out", out_s, "--resume"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("earlier run"));
    assert!(out.join("cloth_0010.obj").exists());
}

#[test]
fn bad_input_is_refused_before_anything_is_written() {
    let dir = scratch("simulate_cli_bad");
    let scene = shot(&dir, &[]);
    let out_dir = dir.join("out");
    run_ok(&[scene.to_str().unwrap(), "--frames", "..2", "--quiet"]);
    let before = everything(&out_dir);
    assert!(before.contains_key("cloth_0002.obj"));

    let nan_sheet = sheet().replacen("v 0.1 1.1 0.3", "v 0.1 nan 0.3", 1);
    fs::write(dir.join("nan.obj"), nan_sheet).unwrap();
    let seq = dir.join("seq");
    fs::create_dir_all(&seq).unwrap();
    fs::write(seq.join("body_0000.obj"), cube(0.0)).unwrap();
    fs::write(seq.join("body_0001.obj"), cube(0.01)).unwrap();
    let changed = cube(0.02).replace("f 2 4 8 6\n", "f 2 4 8\nf 2 8 6\n");
    fs::write(seq.join("body_0002.obj"), changed).unwrap();

    let cases: &[(Edit, &[&str])] = &[
        (
            &[("sheet.obj", "missing.obj")],
            &["[cloth] mesh", "missing.obj"],
        ),
        (&[("sheet.obj", "nan.obj")], &["nan.obj:1:", "not finite"]),
        (
            &[
                ("frames = 10", "frames = 2"),
                (
                    "mesh = \"cube.obj\"",
                    "mesh = \"seq/body_####.obj\"\nfirst_frame = 0",
                ),
            ],
            &["[body] mesh", "body_0002.obj", "topology"],
        ),
        (
            &[(
                "mesh = \"cube.obj\"",
                "mesh = \"seq/body_####.obj\"\nfirst_frame = 1",
            )],
            &["[body] mesh", "body_0003.obj does not exist"],
        ),
        (
            &[("mesh = \"cube.obj\"", "mesh = \"nobody.obj\"")],
            &["[body] mesh", "nobody.obj"],
        ),
        (
            &[(FULL.0, "dir = \"out\"\nprecision = \"double\"")],
            &["scene.toml", "precision", "unknown variant `double`"],
        ),
        (
            &[("pins = []", "pins = [\"collar\"]")],
            &["[cloth] pins[0]", "group \"collar\"", "sheet, top"],
        ),
        (
            &[("attach = [\"top\"]", "attach = [\"top\", 36]")],
            &["[cloth] attach[1]", "vertex 36"],
        ),
        (
            &[("attach = [\"top\"]", "attach = [-1]")],
            &["[cloth] attach[0]", "vertex -1"],
        ),
        (
            &[("stiffen = { top = 2.0 }", "stiffen = { hem = 2.0 }")],
            &["stiffen.hem", "\"hem\""],
        ),
        (
            &[("density = 0.2", "density = -0.2")],
            &["[cloth] density", "-0.2"],
        ),
        (&[("density = 0.2", "density = 0.0")], &["[cloth] density"]),
        (
            &[("frames = 10", "frames = 4294967295")],
            &["[scene] frames", "past 1000000"],
        ),
        (
            &[
                ("frames = 10", "frames = 1000000"),
                (
                    "mesh = \"cube.obj\"",
                    "mesh = \"seq/body_####.obj\"\nfirst_frame = 0",
                ),
            ],
            &["[body] mesh", "body_0003.obj does not exist"],
        ),
        (
            &[("substeps = 4", "substeps = 4294967295")],
            &["[scene] substeps", "4294967295 is not between 1 and 1000"],
        ),
        (
            &[("fps = 24", "fps = 1e308")],
            &["[scene] fps", "above 10000"],
        ),
        (
            &[("fps = 24", "fps = 24\ngravity = [0, -1e300, 0]")],
            &["[scene] gravity", "at most 9810"],
        ),
        (
            &[("thickness = 0.01", "thickness = 0")],
            &["[cloth] thickness", "> 0"],
        ),
        (
            &[("thickness = 0.01", "thicknes = 0.01")],
            &["scene.toml", "unknown field `thicknes`"],
        ),
        (
            &[("material = \"cotton\"", "material = \"tweed\"")],
            &["[cloth] material", "tweed"],
        ),
        (&[("fps = 24", "fps = 0")], &["[scene] fps"]),
    ];
    for (edit, expected) in cases {
        let scene = shot(&dir, edit);
        let out = tailor(&[scene.to_str().unwrap(), "--quiet"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{edit:?}: {stderr}");
        assert!(
            stderr.contains("scene.toml") || stderr.contains(".obj"),
            "{stderr}"
        );
        for e in *expected {
            assert!(stderr.contains(e), "{edit:?}: {e:?} not in {stderr:?}");
        }
        assert!(
            everything(&out_dir) == before,
            "{edit:?} changed the earlier output"
        );
    }

    let scene = shot(&dir, &[]);
    let out = tailor(&[scene.to_str().unwrap(), "--frames", "5..2"]);
    assert_eq!(out.status.code(), Some(2), "a usage error");
    assert!(everything(&out_dir) == before);
}

/// The shot's cube sliding 0.3 m along x each frame (a body sequence) for `frames` frames,
/// the sheet's attached row riding on it while its far row (vertices 30-35) is pinned: by
/// frame 2 the rows are dragged 25% further apart than the sheet's length, which no strain
/// limiter can hold, so the edges between them (group `sheet`, not `top`) end frames past
/// the 10% limit. `edit` applies further replacements to the scene.
fn dragged(dir: &Path, frames: u32, edit: Edit) -> PathBuf {
    let seq = dir.join("seq");
    fs::create_dir_all(&seq).unwrap();
    for k in 0..=frames {
        let body = cube(0.3 * f64::from(k));
        fs::write(seq.join(format!("body_{k:04}.obj")), body).unwrap();
    }
    let count = format!("frames = {frames}");
    let mut all: Vec<(&str, &str)> = vec![
        ("frames = 10", count.as_str()),
        ("pins = []", "pins = [30, 31, 32, 33, 34, 35]"),
        (
            "mesh = \"cube.obj\"",
            "mesh = \"seq/body_####.obj\"\nfirst_frame = 0",
        ),
    ];
    all.extend_from_slice(edit);
    shot(dir, &all)
}

/// The vertex positions of an OBJ's text, read by the project's own reader.
fn vertices(text: &[u8]) -> Vec<[f64; 3]> {
    let text = String::from_utf8_lossy(text);
    let doc = tailor_subdiv::obj::parse(&text, "written").unwrap();
    doc.mesh
        .positions()
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect()
}

/// The written body is the frame's pose whether the body moves or holds still (a body that
/// holds still writes the bytes of the frame before again without formatting them): the
/// cube still for two frames, moved, still again, moved.
#[test]
fn written_body_follows_a_body_that_stops_and_starts() {
    let dir = scratch("simulate_cli_stop_start");
    let seq = dir.join("seq");
    fs::create_dir_all(&seq).unwrap();
    let offsets = [0.0, 0.0, 0.3, 0.3, 0.3, 0.5];
    for (k, dx) in offsets.iter().enumerate() {
        fs::write(seq.join(format!("body_{k:04}.obj")), cube(*dx)).unwrap();
    }
    let count = format!("frames = {}", offsets.len() - 1);
    let scene = shot(
        &dir,
        &[
            ("frames = 10", count.as_str()),
            (
                "mesh = \"cube.obj\"",
                "mesh = \"seq/body_####.obj\"\nfirst_frame = 0",
            ),
        ],
    );
    let out = dir.join("out");
    run_ok(&[
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let written = objs(&out);
    let first = vertices(&written["body_0000.obj"]);
    assert!(!first.is_empty());
    for (k, dx) in offsets.iter().enumerate() {
        let body = vertices(&written[&format!("body_{k:04}.obj")]);
        assert_eq!(body.len(), first.len(), "frame {k}");
        for (p, q) in body.iter().zip(&first) {
            // Refinement commutes with a translation; each number is written as an f32.
            let moved = [q[0] + dx, q[1], q[2]];
            for (a, b) in p.iter().zip(moved) {
                assert!(
                    (a - b).abs() < 1e-6,
                    "frame {k}: {p:?} is not {q:?} moved by {dx}"
                );
            }
        }
    }
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn strained_shot_warns_and_exits_3_only_when_strict() {
    let dir = scratch("simulate_cli_strained");
    let scene = dragged(&dir, 4, &[]);
    let scene = scene.to_str().unwrap();
    let lenient = dir.join("lenient");
    let out = run_ok(&[scene, "--out", lenient.to_str().unwrap(), "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report = summary(&lenient);
    let strain = &report["failures"]["strain"];
    // The failing frames are exactly those whose worst edge ends past 11%.
    let past: Vec<u64> = report["frames"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["max_strain"].as_f64().unwrap() > 0.11)
        .map(|f| f["frame"].as_u64().unwrap())
        .collect();
    assert!(!past.is_empty(), "the shot was not strained: {report}");
    let frames: Vec<u64> = strain["frames"]
        .as_array()
        .unwrap_or_else(|| panic!("no strain failure in {report}"))
        .iter()
        .map(|f| f.as_u64().unwrap())
        .collect();
    assert_eq!(frames, past);
    assert_eq!(strain["groups"], serde_json::json!(["sheet"]));
    assert_eq!(strain["worst"], report["total"]["max_strain"]);
    let ranges = strain["frame_ranges"].as_str().unwrap();
    for part in [
        "warning: strain".to_owned(),
        format!("in frames {ranges} ("),
        "in group \"sheet\"".to_owned(),
    ] {
        assert!(stderr.contains(&part), "{part:?} not in {stderr:?}");
    }

    // Strict by flag or by the scene: the same files, then exit 3.
    let strict = dir.join("strict");
    let out = tailor(&[scene, "--out", strict.to_str().unwrap(), "--strict"]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(objs(&strict).len(), 3 * 5, "every frame is written");
    assert!(objs(&strict) == objs(&lenient));
    assert_eq!(summary(&strict)["failures"], report["failures"]);
    assert!(strict.join("tailor_checkpoint.bin").exists());
    let keyed = dir.join("keyed");
    let scene = dragged(&dir, 4, &[("substeps = 4", "substeps = 4\nstrict = true")]);
    let scene = scene.to_str().unwrap();
    let out = tailor(&[scene, "--out", keyed.to_str().unwrap(), "--quiet"]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(objs(&keyed) == objs(&lenient));
    // A reader of standard output gone away does not change what a strict run owes.
    let piped = dir.join("piped");
    let child = Command::new(env!("CARGO_BIN_EXE_tailor"))
        .args([
            "simulate",
            scene,
            "--out",
            piped.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = child;
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    // Resumed, frames 2 and 3 are judged from the checkpoint and give the same failures.
    let parts = dir.join("parts");
    let parts_s = parts.to_str().unwrap();
    run_ok(&[scene, "--out", parts_s, "--stop-after", "3", "--quiet"]);
    let out = tailor(&[scene, "--out", parts_s, "--resume", "--quiet"]);
    assert_eq!(out.status.code(), Some(3));
    assert_eq!(summary(&parts)["failures"], report["failures"]);
}

#[test]
fn clean_shot_warns_of_nothing_and_passes_strict() {
    let dir = scratch("simulate_cli_clean");
    let scene = shot(&dir, &[]);
    let out = tailor(&[scene.to_str().unwrap(), "--strict"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    assert_eq!(summary(&dir.join("out"))["failures"], serde_json::json!({}));
}

/// The shot's sheet lowered into the cube (y = 0.9, its back rows 0.1 under the top) with a
/// quad `flap` standing through its overhang (x 0.3-0.7 at z = 1.2, y 0.7-1.1), every vertex
/// pinned so that no collision can move the cloth out: every frame penetrates and crosses
/// where the rest pose does.
fn pierced(dir: &Path, frames: u32) -> PathBuf {
    let count = format!("frames = {frames}");
    let scene = shot(
        dir,
        &[
            ("frames = 10", &count),
            ("pins = []", "pins = [\"sheet\", \"flap\"]"),
            ("attach = [\"top\"]", "attach = []"),
        ],
    );
    let flap = "v 0.3 0.7 1.2\nv 0.7 0.7 1.2\nv 0.7 1.1 1.2\nv 0.3 1.1 1.2\n\
                g flap\nf 37/1 38/2 39/8 40/7\n";
    let sheet = sheet().replace(" 1.1 ", " 0.9 ") + flap;
    fs::write(dir.join("sheet.obj"), sheet).unwrap();
    scene
}

#[test]
fn penetrating_and_crossing_shot_names_the_places() {
    let dir = scratch("simulate_cli_pierced");
    let scene = pierced(&dir, 2);
    let scene = scene.to_str().unwrap();
    let whole = dir.join("whole");
    let out = run_ok(&[scene, "--out", whole.to_str().unwrap(), "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let report = summary(&whole);
    let failures = &report["failures"];
    let penetration = &failures["penetration"];
    assert_eq!(
        penetration["frames"],
        serde_json::json!([0, 1, 2]),
        "{report}"
    );
    assert_eq!(
        penetration["groups"],
        serde_json::json!(["top"]),
        "{report}"
    );
    let vertex = penetration["worst_vertex"].as_u64().unwrap();
    assert!(vertex < 12, "vertex {vertex} is not in the rows of top");
    let crossing = &failures["self_intersection"];
    assert_eq!(crossing["frames"], serde_json::json!([0, 1, 2]), "{report}");
    assert_eq!(
        crossing["groups"],
        serde_json::json!(["sheet", "flap"]),
        "{report}"
    );
    let faces = crossing["worst_faces"].as_array().unwrap();
    assert!((20..25).contains(&faces[0].as_u64().unwrap()), "{report}");
    assert_eq!(faces[1], 25, "{report}");
    for part in [
        "warning: cloth inside the body or within its thickness in frames 0-2 (".to_owned(),
        format!(", vertex {vertex}) in group \"top\""),
        "warning: the cloth intersects itself in frames 0-2 (".to_owned(),
        format!(", faces {} and 25) in groups \"sheet\", \"flap\"", faces[0]),
    ] {
        assert!(stderr.contains(&part), "{part:?} not in {stderr:?}");
    }

    // Resumed, frames 0 and 1 are judged from the checkpoint and name the same places.
    let parts = dir.join("parts");
    let parts_s = parts.to_str().unwrap();
    run_ok(&[scene, "--out", parts_s, "--stop-after", "1", "--quiet"]);
    let out = run_ok(&[scene, "--out", parts_s, "--resume", "--quiet"]);
    assert_eq!(summary(&parts)["failures"], *failures);
    assert_eq!(String::from_utf8_lossy(&out.stderr), stderr);
}

#[test]
fn a_diverging_shot_stops_at_its_frame_with_the_frames_before_it_written() {
    // A hundred g on a sheet with almost no stiffness and no strain limit: an edge passes ten
    // times its rest length in frame 4. The run stops there naming the frame, frames 0–3 are
    // written with their checkpoint, frame 4 is not, whether the frames are written on the
    // simulating thread (one thread) or on one of their own (two).
    let dir = scratch("simulate_cli_diverging");
    let scene = shot(
        &dir,
        &[
            ("substeps = 4", "substeps = 4\ngravity = [0, -1000, 0]"),
            (
                "material = \"cotton\"\ndensity = 0.2",
                "material = \"silk\"\nstretch = 1.0\ncompression = 0.1\nshear = 1.0\n\
                 strain_limit = 0",
            ),
        ],
    );
    let scene = scene.to_str().unwrap();
    let mut written = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.join(format!("threads_{threads}"));
        let out = out.to_str().unwrap();
        for resume in [false, true] {
            let mut args = vec![scene, "--out", out, "--threads", threads, "--quiet"];
            if resume {
                args.push("--resume");
            }
            let run = tailor(&args);
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert_eq!(run.status.code(), Some(1), "{stderr}");
            assert!(
                stderr.contains("frame 4: the simulation diverged"),
                "{threads} thread(s), resumed {resume}: {stderr}"
            );
        }
        let files = objs(Path::new(out));
        let names: Vec<&str> = files.keys().map(String::as_str).collect();
        assert_eq!(
            names,
            [
                "body_0000.obj",
                "body_0001.obj",
                "body_0002.obj",
                "body_0003.obj",
                "cloth_0000.obj",
                "cloth_0001.obj",
                "cloth_0002.obj",
                "cloth_0003.obj",
                "cloth_control_0000.obj",
                "cloth_control_0001.obj",
                "cloth_control_0002.obj",
                "cloth_control_0003.obj",
            ],
            "{threads} thread(s)"
        );
        assert!(Path::new(out).join("tailor_checkpoint.bin").exists());
        written.push(files);
    }
    assert!(
        written[0] == written[1],
        "--threads 1 and 2 wrote different bytes"
    );
}
