//! [`Refreshed`] keeps a stencil table's output for control points that move a few at a time:
//! after any sequence of moves (none, one point, a few, a third of them, all, one back to where
//! it was) its points are, bit for bit, the table applied to the control points, whichever
//! rows it computed again.

use common::grid_at;
use tailor_subdiv::{Point, Refiner, Refreshed};

mod common;

#[test]
fn refreshed_points_are_the_whole_tables_bits_after_any_moves() {
    let n = 12;
    let mesh = grid_at(n, |i, j| {
        Point::new(i as f64, j as f64, ((i * 3 + j * 5) % 7) as f64 * 0.1)
    });
    let table = Refiner::new(&mesh, 2).stencils();
    let mut control = mesh.positions().to_vec();
    let mut saved = control[n + 2];
    let count = control.len();
    let mut refreshed = Refreshed::new(&table);
    let mut whole = vec![Point::origin(); table.len()];
    let moves: [Vec<usize>; 9] = [
        vec![],
        vec![],
        vec![5],
        vec![0, 1, 2, 40, count - 1],
        (0..count).step_by(3).collect(),
        vec![],
        (0..count).collect(),
        vec![n + 2],
        vec![],
    ];
    for (step, moved) in moves.iter().enumerate() {
        if step == 7 {
            saved = control[n + 2];
        }
        for &j in moved {
            control[j].y += 1e-3 * (step + j) as f64;
        }
        if step == 8 {
            // Back to where it was before the last move.
            control[n + 2] = saved;
        }
        let points = refreshed.update(&table, &control).to_vec();
        table.apply(&control, &mut whole);
        let bits = |p: &[Point]| -> Vec<[u64; 3]> {
            p.iter()
                .map(|q| [q.x.to_bits(), q.y.to_bits(), q.z.to_bits()])
                .collect()
        };
        assert_eq!(bits(&points), bits(&whole), "step {step}");
        assert_eq!(refreshed.points(), &whole[..], "step {step}");
    }
}
