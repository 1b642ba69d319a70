//! End-to-end tests of `tailor preview`: a directory of frames gives a contact sheet with one
//! tile per chosen frame, showing the cloth in colour and the body in grey when there are body
//! files; the same input gives the same bytes; a missing directory exits 2 and a directory
//! without frames (or a missing frame) exits 1 with a clear message and writes nothing.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

use common::scratch;

mod common;

/// Runs `tailor preview ARGS`.
fn tailor(args: &[&str]) -> Output {
    common::tailor(&[&["preview"], args].concat())
}

fn asset(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(path)
}

/// A simulation output directory from the committed assets: the cape control mesh as the cloth
/// of frames 0, 10 and 20, with the mannequin's frames as bodies when `bodies` is set.
fn output_dir(name: &str, bodies: bool) -> PathBuf {
    let dir = scratch(name);
    for frame in ["0000", "0010", "0020"] {
        fs::copy(
            asset("garments/cape.obj"),
            dir.join(format!("cloth_{frame}.obj")),
        )
        .unwrap();
        if bodies {
            let body = asset(&format!("mannequin/body_{frame}.obj"));
            fs::copy(body, dir.join(format!("body_{frame}.obj"))).unwrap();
        }
    }
    dir
}

fn run_ok(args: &[&str]) -> String {
    let out = tailor(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    stderr
}

fn run_fails(args: &[&str], code: i32, message: &str) {
    let out = tailor(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "{stderr}");
    assert!(stderr.contains(message), "{stderr:?} lacks {message:?}");
}

/// The 8-bit RGB pixels of a PNG file, row-major.
struct Sheet {
    width: u32,
    height: u32,
    bytes: Vec<u8>,
}

impl Sheet {
    fn dimensions(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn get_pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 3 * (y * self.width + x) as usize;
        [self.bytes[i], self.bytes[i + 1], self.bytes[i + 2]]
    }
}

fn read_png(path: &Path) -> Sheet {
    let file = std::io::BufReader::new(fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut bytes).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    bytes.truncate(info.buffer_size());
    Sheet {
        width: info.width,
        height: info.height,
        bytes,
    }
}

/// Counts the pixels of the `i`-th 64 × 80 tile (4-pixel gaps) that are red (the cloth's
/// outside) and grey (the body: equal channels, darker than the backdrop).
fn tile_colours(sheet: &Sheet, columns: u32, i: u32) -> (usize, usize) {
    let (x0, y0) = (4 + (i % columns) * 68, 4 + (i / columns) * 84);
    let (mut red, mut grey) = (0, 0);
    for y in y0..y0 + 80 {
        for x in x0..x0 + 64 {
            let [r, g, b] = sheet.get_pixel(x, y);
            if r > g.saturating_add(50) && r > b.saturating_add(50) {
                red += 1;
            } else if r == g && g == b && r < 220 {
                grey += 1;
            }
        }
    }
    (red, grey)
}

#[test]
fn draws_cloth_and_body_in_every_tile() {
    let dir = output_dir("bodies", true);
    let png = dir.join("sheet.png");
    let stderr = run_ok(&[
        dir.to_str().unwrap(),
        "--size",
        "64x80",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(stderr.contains("3 frame(s) (cloth and body)"), "{stderr}");
    let sheet = read_png(&png);
    // Three tiles about square: two columns, two rows.
    assert_eq!(sheet.dimensions(), (2 * 68 + 4, 2 * 84 + 4));
    for i in 0..3 {
        let (red, grey) = tile_colours(&sheet, 2, i);
        assert!(red > 150 && grey > 150, "tile {i}: {red} red, {grey} grey");
    }
}

#[test]
fn without_body_files_draws_the_cloth_alone() {
    let dir = output_dir("cloth_only", false);
    let png = dir.join("sheet.png");
    let args = [
        dir.to_str().unwrap(),
        "--size",
        "64x80",
        "--frames",
        "0-20x20",
        "-o",
    ];
    let stderr = run_ok(&[&args[..], &[png.to_str().unwrap()]].concat());
    assert!(stderr.contains("2 frame(s) (cloth only"), "{stderr}");
    let sheet = read_png(&png);
    assert_eq!(sheet.dimensions(), (2 * 68 + 4, 84 + 4));
    let (red, grey) = tile_colours(&sheet, 2, 1);
    assert!(red > 300 && grey == 0, "{red} red, {grey} grey");
}

/// The same input gives the same PNG and GIF bytes, whatever the shading, and a body given with
/// `--body` is drawn.
#[test]
fn same_bytes_twice() {
    let dir = output_dir("twice", false);
    let body = asset("mannequin/body_####.obj");
    for shading in ["flat", "phong"] {
        let mut outputs = Vec::new();
        for run in 0..2 {
            let png = dir.join(format!("{shading}{run}.png"));
            let gif = dir.join(format!("{shading}{run}.gif"));
            run_ok(&[
                dir.to_str().unwrap(),
                "--size",
                "48x48",
                "--shading",
                shading,
                "--body",
                body.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
                "--gif",
                gif.to_str().unwrap(),
            ]);
            outputs.push((fs::read(&png).unwrap(), fs::read(&gif).unwrap()));
        }
        assert!(outputs[0] == outputs[1], "{shading}: bytes differ");
        assert!(outputs[0].1.starts_with(b"GIF89a"));
    }
}

#[test]
fn a_missing_directory_is_a_usage_error() {
    let dir = scratch("preview_cli_missing");
    let png = dir.join("p.png");
    let missing = dir.join("no-such-dir");
    run_fails(
        &[missing.to_str().unwrap(), "-o", png.to_str().unwrap()],
        2,
        "no-such-dir: no such directory",
    );
    run_fails(&[dir.to_str().unwrap(), "--size", "9x9"], 2, "WIDTHxHEIGHT");
    run_fails(
        &[dir.to_str().unwrap(), "--frames", "5-3"],
        2,
        "runs backwards",
    );
    assert!(!png.exists());
}

#[test]
fn no_frames_or_a_missing_frame_is_an_error_and_writes_nothing() {
    let empty = scratch("preview_cli_empty");
    let png = empty.join("p.png");
    run_fails(
        &[empty.to_str().unwrap(), "-o", png.to_str().unwrap()],
        1,
        "has no cloth_####.obj files",
    );
    let dir = output_dir("missing_frame", true);
    let args = [
        dir.to_str().unwrap(),
        "--frames",
        "0,15",
        "-o",
        png.to_str().unwrap(),
    ];
    run_fails(&args, 1, "no frame 15 in");
    fs::remove_file(dir.join("body_0010.obj")).unwrap();
    let args = [dir.to_str().unwrap(), "-o", png.to_str().unwrap()];
    run_fails(&args, 1, "body_0010.obj is missing");
    assert_eq!(
        fs::read_dir(&empty).unwrap().count(),
        0,
        "something was written"
    );
}
