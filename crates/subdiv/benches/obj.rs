//! OBJ writing and reading on the 100k-quad benchmark grid refined to level 2 (1.6 M faces,
//! 1.6 M vertices): [`obj::write`] into memory at single and full precision, and [`obj::parse`]
//! of each text; and the number formatting under the writer, one million coordinates through
//! ryu (what the writer uses) against Rust's `{}`. Throughput is in lines (or numbers) per
//! second. The whole `tailor subdivide` process against OpenSubdiv is timed by
//! `compare-osd`'s `whole`.
//!
//! `cargo bench -p tailor-subdiv --bench obj` (set `RAYON_NUM_THREADS=1` for one thread).

use std::io::Write;

use common::grid;
use divan::counter::ItemsCount;
use divan::{Bencher, black_box};
use tailor_subdiv::obj::{self, Precision};
use tailor_subdiv::{Mesh, subdivide};

mod common;

fn main() {
    divan::main();
}

/// The grid of 316² quads refined to level 2.
fn refined() -> Mesh {
    subdivide(&grid(316), 2, false).0
}

/// Vertex and face lines of `mesh`.
fn lines(mesh: &Mesh) -> ItemsCount {
    ItemsCount::new(mesh.vertex_count() + mesh.face_count())
}

fn text(mesh: &Mesh, precision: Precision) -> Vec<u8> {
    let mut out = Vec::new();
    obj::write(mesh, None, precision, &mut out).expect("in memory");
    out
}

#[divan::bench(args = [Precision::Single, Precision::Full], sample_count = 5)]
fn write(bencher: Bencher, precision: Precision) {
    let mesh = refined();
    bencher
        .counter(lines(&mesh))
        .bench(|| black_box(text(&mesh, precision)));
}

#[divan::bench(args = [Precision::Single, Precision::Full], sample_count = 5)]
fn parse(bencher: Bencher, precision: Precision) {
    let mesh = refined();
    let text = String::from_utf8(text(&mesh, precision)).expect("ASCII");
    bencher
        .counter(lines(&mesh))
        .bench(|| black_box(obj::parse(&text, "bench").expect("valid")));
}

/// A million coordinates of the refined grid, as written.
fn coordinates() -> Vec<f64> {
    let mesh = refined();
    let points = mesh.positions().iter().take(333_334);
    points
        .flat_map(|p| [p.x, p.y, p.z])
        .take(1_000_000)
        .collect()
}

#[divan::bench(args = ["ryu f32", "fmt f32", "ryu f64", "fmt f64"], sample_count = 5)]
fn format_numbers(bencher: Bencher, how: &str) {
    let xs = coordinates();
    let mut out = Vec::with_capacity(20 * xs.len());
    bencher.counter(ItemsCount::new(xs.len())).bench_local(|| {
        out.clear();
        let mut buffer = ryu::Buffer::new();
        for &x in &xs {
            match how {
                "ryu f32" => out.extend_from_slice(buffer.format(x as f32).as_bytes()),
                "fmt f32" => write!(out, "{}", x as f32).expect("in memory"),
                "ryu f64" => out.extend_from_slice(buffer.format(x).as_bytes()),
                _ => write!(out, "{x}").expect("in memory"),
            }
            out.push(b' ');
        }
        black_box(out.len())
    });
}
