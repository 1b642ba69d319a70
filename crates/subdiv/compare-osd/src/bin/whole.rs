//! `whole TAILOR [RUNS] [-- TAILOR_ARGS...]`: `tailor subdivide` against OpenSubdiv 3.7
//! (`osd_subdivide`, built beside this program) as whole processes, reading, refinement and
//! writing together, on a cube-sphere of 99,846 quads refined to level 2 (1,597,536 faces).
//!
//! The input is made once (full-precision coordinates, `obj::write` at
//! [`Precision::Full`]) in the system's temporary directory. Each run starts tailor, then
//! OpenSubdiv, one after the other, so a load on the machine falls on both alike; the medians
//! of the runs (5 by default) and their ratio, OpenSubdiv's ÷ tailor's (above 1: tailor is
//! faster), are printed with the output sizes. The outputs' vertices are compared as a check
//! that both did the same work (tailor keeps OpenSubdiv's vertex order). Arguments after `--`
//! go to `tailor subdivide` (`-- --precision full`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use tailor_subdiv::obj::{self, Precision};
use tailor_subdiv::{Mesh, Point};

/// Quads along each edge of the cube: 6 · 129² = 99,846 quads.
const SIDE: u32 = 129;

/// Refinement level.
const LEVEL: &str = "2";

/// A cube of `n` × `n` quads a side, its vertices pushed out onto the unit sphere; faces
/// counter-clockwise seen from outside.
fn cube_sphere(n: u32) -> Mesh {
    let mut index = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |lattice: [u32; 3]| -> u32 {
        *index.entry(lattice).or_insert_with(|| {
            let p = lattice.map(|c| 2.0 * f64::from(c) / f64::from(n) - 1.0);
            positions.push(Point::from(unit(p)));
            u32::try_from(positions.len() - 1).expect("fits")
        })
    };
    let mut faces = Vec::new();
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for outward in [false, true] {
            for j in 0..n {
                for i in 0..n {
                    let at = |i: u32, j: u32| {
                        let mut l = [0; 3];
                        l[axis] = if outward { n } else { 0 };
                        (l[b], l[c]) = (i, j);
                        l
                    };
                    let mut quad =
                        [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)].map(&mut vertex);
                    if !outward {
                        quad.reverse();
                    }
                    faces.push(quad);
                }
            }
        }
    }
    Mesh::from_polygons(positions, &faces).expect("a closed manifold")
}

/// `p` scaled to unit length.
fn unit(p: [f64; 3]) -> [f64; 3] {
    let length = p.iter().map(|c| c * c).sum::<f64>().sqrt();
    p.map(|c| c / length)
}

/// Wall time of running `program` with `args` to the end, seconds.
fn time(program: &Path, args: &[&str]) -> f64 {
    let start = Instant::now();
    let out = Command::new(program)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running {}: {e}", program.display()));
    let seconds = start.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "{} failed: {}",
        program.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    seconds
}

fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        (xs[n / 2 - 1] + xs[n / 2]) / 2.0
    }
}

/// The `v` lines of an OBJ file as numbers.
fn vertices(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).expect("readable output");
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .flat_map(|l| l.split(' ').map(|w| w.parse::<f64>().expect("number")))
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (ours, extra) = match args.iter().position(|a| a == "--") {
        Some(k) => (&args[..k], &args[k + 1..]),
        None => (&args[..], &[][..]),
    };
    let (tailor, runs) = match ours {
        [tailor] => (PathBuf::from(tailor), 5),
        [tailor, runs] => (
            PathBuf::from(tailor),
            runs.parse().expect("RUNS is a number"),
        ),
        _ => {
            eprintln!("usage: whole TAILOR [RUNS] [-- TAILOR_ARGS...]");
            std::process::exit(2);
        }
    };
    let osd = std::env::current_exe()
        .expect("own path")
        .with_file_name("osd_subdivide");
    let dir = std::env::temp_dir().join("tailor-whole");
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let input = dir.join("cube_sphere_100k.obj");
    let mut text = Vec::new();
    obj::write(&cube_sphere(SIDE), None, Precision::Full, &mut text).expect("in memory");
    std::fs::write(&input, &text).expect("input written");
    let (ours_out, osd_out) = (dir.join("tailor.obj"), dir.join("osd.obj"));
    let path = |p: &Path| p.to_str().expect("UTF-8 path").to_owned();
    let (input, ours_out_s, osd_out_s) = (path(&input), path(&ours_out), path(&osd_out));
    let mut tailor_args = vec!["subdivide", &input, "-l", LEVEL, "-o", &ours_out_s];
    tailor_args.extend(extra.iter().map(String::as_str));

    let (mut t, mut o) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        t.push(time(&tailor, &tailor_args));
        o.push(time(&osd, &[&input, LEVEL, &osd_out_s]));
    }

    let (a, b) = (vertices(&ours_out), vertices(&osd_out));
    assert_eq!(a.len(), b.len(), "refined vertex counts");
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-5, "refined points differ by {diff}");
    let size = |p: &Path| std::fs::metadata(p).map_or(0.0, |m| m.len() as f64 / 1e6);
    let list = |xs: &[f64]| {
        xs.iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!(
        "cube-sphere {} quads -> level {LEVEL}, {runs} alternated runs, `tailor subdivide {}`",
        6 * SIDE * SIDE,
        tailor_args[1..].join(" ")
    );
    println!("tailor      s: {}", list(&t));
    println!("OpenSubdiv  s: {}", list(&o));
    let (mt, mo) = (median(t), median(o));
    println!(
        "medians: tailor {mt:.3} s ({:.0} MB), OpenSubdiv {mo:.3} s ({:.0} MB); \
         OpenSubdiv / tailor {:.2}; vertices agree within {diff:.1e}",
        size(&ours_out),
        size(&osd_out),
        mo / mt
    );
}
