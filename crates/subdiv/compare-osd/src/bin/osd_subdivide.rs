//! `osd_subdivide IN.obj LEVEL OUT.obj`: OpenSubdiv 3.7's uniform refinement as a whole process,
//! the baseline `whole` times `tailor subdivide` against.
//!
//! Plain OBJ in and out, as a program built on OpenSubdiv would do it: `v` and `f` lines read
//! one after another into `f32` positions and face tables (other statements skipped), topology
//! refined with edge-only boundaries (tailor's default) and the minimal last level,
//! positions interpolated level by level (`Far::PrimvarRefiner::Interpolate`), then `v` lines
//! with Rust's `{}` of `f32` (the shortest text that reads back as the same `f32`) and `f`
//! lines through a `BufWriter`. One thread, as OpenSubdiv's `Far` refines.

use std::fs::File;
use std::io::{BufWriter, Write};

use opensubdiv_petite::far::PrimvarRefiner;

#[path = "../osd.rs"]
mod osd;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, level, output] = args.as_slice() else {
        eprintln!("usage: osd_subdivide IN.obj LEVEL OUT.obj");
        std::process::exit(2);
    };
    let level: usize = level.parse().expect("LEVEL is a number");
    let text = std::fs::read_to_string(input).expect("readable input");

    let (mut positions, mut sizes, mut corners) = (Vec::<f32>::new(), Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => positions.extend(words.take(3).map(|w| w.parse::<f32>().expect("number"))),
            Some("f") => {
                let before = corners.len();
                corners.extend(words.map(|w| {
                    let index = w.split('/').next().unwrap_or(w);
                    index.parse::<u32>().expect("positive index") - 1
                }));
                sizes.push((corners.len() - before) as u32);
            }
            _ => {}
        }
    }

    let refiner = osd::refine(positions.len() / 3, &sizes, &corners, level, false);
    let primvars = PrimvarRefiner::new(&refiner).expect("primvar refiner");
    for l in 1..=level {
        positions = primvars
            .interpolate(l, 3, &positions)
            .expect("level exists");
    }

    let mut out = BufWriter::new(File::create(output).expect("writable output"));
    for p in positions.chunks_exact(3) {
        writeln!(out, "v {} {} {}", p[0], p[1], p[2]).expect("write");
    }
    let last = refiner.level(level).expect("last level");
    for face in last.face_vertices_iter() {
        out.write_all(b"f").expect("write");
        for &v in face {
            write!(out, " {}", u32::from(v) + 1).expect("write");
        }
        out.write_all(b"\n").expect("write");
    }
    out.flush().expect("write");
}
