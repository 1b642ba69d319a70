//! End-to-end tests of `tailor check`: a clean cloth exits 0, a penetrating or self-intersecting
//! one exits 1 with hand-counted findings in the JSON report (and where: the deepest vertex's
//! position, the first crossing face pair), and input that cannot be checked exits 2 with a
//! message naming the file. The report replaces an earlier one whole, never rewriting it in
//! place.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

use common::scratch;

mod common;

/// Runs `tailor check ARGS`.
fn tailor(args: &[&str]) -> Output {
    common::tailor(&[&["check"], args].concat())
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path
}

/// The unit cube `[0, 1]³`, six outward quads.
const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n\
f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

/// A 2 × 2 sheet of quads at height `z` over the grid `xs × ys`.
fn sheet(xs: [f64; 3], ys: [f64; 3], z: f64) -> String {
    let mut text = String::new();
    for y in ys {
        for x in xs {
            text += &format!("v {x} {y} {z}\n");
        }
    }
    for j in 0..2 {
        for i in 0..2 {
            let v = j * 3 + i + 1;
            text += &format!("f {} {} {} {}\n", v, v + 1, v + 4, v + 3);
        }
    }
    text
}

/// Above the cube: clean.
fn clean_sheet() -> String {
    sheet([0.0, 0.5, 1.0], [0.0, 0.5, 1.0], 1.5)
}

/// At height 0.9 over x ∈ {0.2, 0.6, 1.4}, y ∈ {0.3, 0.5, 1.7}: the four vertices with x < 1
/// and y < 1 are inside the cube, each 0.1 below its top face, nearer than any side; of equals
/// the first read, (0.2, 0.3, 0.9), is the deepest.
fn sunk_sheet() -> String {
    sheet([0.2, 0.6, 1.4], [0.3, 0.5, 1.7], 0.9)
}

/// Two quads crossing through each other, sharing no vertex: one self-intersecting pair.
const CROSSED: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
v 0.5 0.2 -0.5\nv 0.5 0.8 -0.5\nv 0.5 0.8 0.5\nv 0.5 0.2 0.5\nf 1 2 3 4\nf 5 6 7 8\n";

/// Runs `tailor check ARGS --json DIR/report.json`, asserts the exit code and returns the
/// report.
fn report(dir: &Path, args: &[&Path], options: &[&str], code: i32) -> serde_json::Value {
    let json = dir.join("report.json");
    let mut all: Vec<&str> = args.iter().map(|p| p.to_str().unwrap()).collect();
    all.extend(options);
    all.extend(["--json", json.to_str().unwrap()]);
    let out = tailor(&all);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&fs::read_to_string(json).unwrap()).unwrap()
}

#[test]
fn clean_cloth_exits_0() {
    let dir = scratch("check_cli_clean");
    let cloth = write(&dir, "cloth.obj", &clean_sheet());
    let body = write(&dir, "body.obj", CUBE);
    let r = report(&dir, &[&cloth, Path::new("--against"), &body], &[], 0);
    assert_eq!(r["total"]["penetrating_vertices"], 0);
    assert_eq!(r["total"]["self_intersecting_pairs"], 0);
    assert_eq!(r["frames"].as_array().unwrap().len(), 1);
    assert!(r["frames"][0].get("deepest_point").is_none());
    assert!(r["frames"][0].get("crossing_faces").is_none());
}

#[test]
fn penetrating_cloth_exits_1_with_counts() {
    let dir = scratch("check_cli_penetrating");
    let cloth = write(&dir, "cloth.obj", &sunk_sheet());
    let body = write(&dir, "body.obj", CUBE);
    let args: [&Path; 3] = [&cloth, Path::new("--against"), &body];
    let r = report(&dir, &args, &["--thickness", "0"], 1);
    assert_eq!(r["total"]["penetrating_vertices"], 4);
    // The file's short decimals are f32 text, read as a renderer holds them: 0.9 and the
    // cube's 1 are 0.1 apart to an f32 step.
    assert!((r["total"]["max_penetration"].as_f64().unwrap() - 0.1).abs() < 1e-7);
    assert_eq!(r["frames"][0]["penetrating_vertices"], 4);
    assert_eq!(
        r["frames"][0]["deepest_point"],
        serde_json::json!([0.2, 0.3, 0.9])
    );
    // A clearance of 0.05 adds to the depth but catches no outside vertex (the nearest is
    // 0.4 away).
    let r = report(&dir, &args, &["--thickness", "0.05"], 1);
    assert_eq!(r["total"]["penetrating_vertices"], 4);
    assert!((r["total"]["max_penetration"].as_f64().unwrap() - 0.15).abs() < 1e-7);
    let out = tailor(&[cloth.to_str().unwrap(), "--against", body.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("4 penetrating vertices (deepest 100.00 mm at (0.200, 0.300, 0.900))"),
        "{stdout}"
    );
}

/// A file written as `f32` text is judged as a renderer reads it, each coordinate its nearest
/// `f32`; one written with more digits in `f64`. Over the top of a box at z = 0, at thickness
/// 0.005, a vertex written as 0.005 holds 0.004999999888241291 in an `f32`, a tenth of a
/// nanometre inside; one written as 0.0050000001 is read as that `f64`, outside.
#[test]
fn a_file_of_f32_text_is_judged_as_f32() {
    let dir = scratch("check_cli_f32_text");
    let below = CUBE.replace(" 0\n", " -1\n").replace(" 1\n", " 0\n");
    let body = write(&dir, "body.obj", &below);
    for (height, penetrating) in [("0.005", 1), ("0.0050000001", 0)] {
        // A triangle with one vertex over the top at `height`, the others far above.
        let cloth = write(
            &dir,
            "cloth.obj",
            &format!("v 0.5 0.5 {height}\nv 0.6 0.5 1\nv 0.5 0.6 1\nf 1 2 3\n"),
        );
        let code = if penetrating > 0 { 1 } else { 0 };
        let args: [&Path; 3] = [&cloth, Path::new("--against"), &body];
        let r = report(&dir, &args, &["--thickness", "0.005"], code);
        assert_eq!(
            r["total"]["penetrating_vertices"], penetrating,
            "{height}: {r}"
        );
        if penetrating > 0 {
            // The deepest vertex is named as the file writes it.
            assert_eq!(
                r["frames"][0]["deepest_point"],
                serde_json::json!([0.5, 0.5, 0.005])
            );
        }
    }
}

#[test]
fn self_intersecting_cloth_exits_1() {
    let dir = scratch("check_cli_crossed");
    let cloth = write(&dir, "cloth.obj", CROSSED);
    let r = report(&dir, &[&cloth], &[], 1);
    assert_eq!(r["total"]["self_intersecting_pairs"], 1);
    assert_eq!(r["total"]["penetrating_vertices"], 0);
    assert_eq!(r["frames"][0]["crossing_faces"], serde_json::json!([0, 1]));
    let out = tailor(&[cloth.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Without a body nothing is said to penetrate: the line says it was not checked.
    assert_eq!(
        stdout,
        "1 frame checked: 1 self-intersecting face pairs (first: faces 0 and 1); no body given \
         (--against), penetration not checked\n"
    );
}

#[test]
fn sequences_are_checked_frame_by_frame() {
    let dir = scratch("check_cli_sequence");
    write(&dir, "cloth_0001.obj", &clean_sheet());
    write(&dir, "cloth_0002.obj", &sunk_sheet());
    write(&dir, "cloth_0003.obj", &clean_sheet());
    for frame in 1..=3 {
        write(&dir, &format!("body_{frame:04}.obj"), CUBE);
    }
    let cloth = dir.join("cloth_####.obj");
    let body = dir.join("body_####.obj");
    let r = report(&dir, &[&cloth, Path::new("--against"), &body], &[], 1);
    let frames = r["frames"].as_array().unwrap();
    let column =
        |key: &str| -> Vec<u64> { frames.iter().map(|f| f[key].as_u64().unwrap()).collect() };
    assert_eq!(column("frame"), vec![1, 2, 3]);
    assert_eq!(column("penetrating_vertices"), vec![0, 4, 0]);
    assert_eq!(r["total"]["penetrating_vertices"], 4);

    // Standard output names the frames with findings and the summary; --verbose every frame.
    let lines = |extra: &[&str]| -> Vec<String> {
        let mut args = vec![cloth.to_str().unwrap(), "--against", body.to_str().unwrap()];
        args.extend_from_slice(extra);
        let out = tailor(&args);
        assert_eq!(out.status.code(), Some(1));
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        stdout.lines().map(str::to_owned).collect()
    };
    let quiet = lines(&[]);
    assert_eq!(quiet.len(), 2, "{quiet:?}");
    assert!(quiet[0].starts_with("frame 2: 4 penetrating vertices (deepest 100.00 mm"));
    assert!(quiet[1].starts_with("3 frames checked, 1 with findings: 4 penetrating vertices"));
    let verbose = lines(&["--verbose"]);
    assert_eq!(verbose.len(), 4, "{verbose:?}");
    assert!(verbose[0].starts_with("frame 1: 0 penetrating vertices (deepest 0.00 mm)"));

    // A missing body frame cannot be checked.
    fs::remove_file(dir.join("body_0003.obj")).unwrap();
    let out = tailor(&[cloth.to_str().unwrap(), "--against", body.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("body_0003.obj"));

    // Nor can a sequence with a frame missing in the middle.
    write(&dir, "body_0003.obj", CUBE);
    fs::remove_file(dir.join("cloth_0002.obj")).unwrap();
    let out = tailor(&[cloth.to_str().unwrap(), "--against", body.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cloth_0002.obj is missing"), "{err}");
}

#[test]
fn open_body_is_checked_by_distance_with_a_warning() {
    let dir = scratch("check_cli_open");
    let cloth = write(&dir, "cloth.obj", &sunk_sheet());
    // Only the cube's top face: the sheet lies 0.1 below it.
    let body = write(
        &dir,
        "lid.obj",
        "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\n",
    );
    let out = tailor(&[cloth.to_str().unwrap(), "--against", body.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not closed"));
    let out = tailor(&[
        cloth.to_str().unwrap(),
        "--against",
        body.to_str().unwrap(),
        "--thickness",
        "0.2",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("4 penetrating vertices"));
}

#[test]
fn unreadable_input_exits_2_naming_the_file() {
    let dir = scratch("check_cli_unreadable");
    let missing = dir.join("nowhere.obj");
    let out = tailor(&[missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nowhere.obj"));

    let nan = write(&dir, "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n");
    let out = tailor(&[nan.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("nan.obj:3: "), "{err}");
    // The reader every command shares: a face of two corners and a forward reference are
    // errors naming their lines, not clean cloth.
    for (name, text, line) in [
        ("two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", 5),
        ("ahead.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3),
    ] {
        let bad = write(&dir, name, text);
        let out = tailor(&[bad.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(&format!("{name}:{line}: ")), "{err}");
    }

    let cloth = write(&dir, "cloth.obj", &clean_sheet());
    let out = tailor(&[cloth.to_str().unwrap(), "--against", nan.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nan.obj"));

    let out = tailor(&[cloth.to_str().unwrap(), "--thickness", "-1"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn the_report_replaces_the_earlier_one_whole() {
    // A second name for the earlier report sees whether it was rewritten in place (where a
    // failed write would leave it cut short) or replaced by a new file.
    let dir = scratch("check_cli_replace");
    let cloth = write(&dir, "cloth.obj", &clean_sheet());
    let earlier = write(&dir, "report.json", "{\"earlier\": true}\n");
    fs::hard_link(&earlier, dir.join("kept.json")).unwrap();
    let r = report(&dir, &[&cloth], &[], 0);
    assert_eq!(r["total"]["penetrating_vertices"], 0);
    assert_eq!(
        fs::read_to_string(dir.join("kept.json")).unwrap(),
        "{\"earlier\": true}\n"
    );
}
