//! Uniform cubic B-spline subdivision in one variable, the rule Catmull-Clark reduces to on a
//! regular grid.
//!
//! Away from extraordinary vertices and sharp features, Catmull-Clark refinement is the
//! tensor product of the cubic B-spline curve rules (Catmull & Clark 1978; Stam 1998, §2):
//! an edge point is `(a + b) / 2`, a vertex point `(a + 6b + c) / 8`. Over one span, the
//! level-`N` points are therefore fixed combinations of the span's four control points, which is
//! what OpenSubdiv's regular patches (`Far::PatchTable`, `PatchDescriptor::REGULAR`) exploit for
//! limit evaluation and what [`crate::evaluator`] exploits for refinement.

/// The weights, over the four control points at parameters −1, 0, 1 and 2, of the level-`levels`
/// refined points at parameters `i / 2^levels`, `i = 0..=2^levels`: the span `[0, 1]` with its
/// ends.
///
/// Every weight is a dyadic rational with a denominator of at most `8^levels`, so the table is
/// exact in `f64` for any level a mesh can be refined to.
#[must_use]
pub fn span_weights(levels: usize) -> Vec<[f64; 4]> {
    // Points over parameters -1 - .. 2, as weights of the control points; each step keeps the
    // points whose rule has both neighbours, so the kept range shrinks towards [0, 1] by half
    // a spacing on each side per level.
    let mut points: Vec<[f64; 4]> = (0..4)
        .map(|i| {
            let mut w = [0.0; 4];
            w[i] = 1.0;
            w
        })
        .collect();
    for _ in 0..levels {
        let mut next = Vec::with_capacity(2 * points.len() - 1);
        for i in 0..points.len() - 1 {
            if i > 0 {
                next.push(combine(
                    &[points[i - 1], points[i], points[i + 1]],
                    &[0.125, 0.75, 0.125],
                ));
            }
            next.push(combine(&[points[i], points[i + 1]], &[0.5, 0.5]));
        }
        points = next;
    }
    // `points` now spans [-2^-levels, 1 + 2^-levels]: drop the outer two.
    points[1..points.len() - 1].to_vec()
}

fn combine(points: &[[f64; 4]], weights: &[f64]) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (p, &w) in points.iter().zip(weights) {
        for (o, &x) in out.iter_mut().zip(p) {
            *o += w * x;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_zero_is_the_span_ends() {
        assert_eq!(
            span_weights(0),
            vec![[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
        );
    }

    #[test]
    fn level_one_is_vertex_edge_vertex() {
        assert_eq!(
            span_weights(1),
            vec![
                [0.125, 0.75, 0.125, 0.0],
                [0.0, 0.5, 0.5, 0.0],
                [0.0, 0.125, 0.75, 0.125]
            ]
        );
    }

    #[test]
    fn level_two_by_hand() {
        // 1/4 is the edge point of 0 and 1/2: ((1, 6, 1, 0) / 8 + (0, 4, 4, 0) / 8) / 2.
        let w = span_weights(2);
        assert_eq!(w.len(), 5);
        assert_eq!(w[1], [1.0 / 16.0, 10.0 / 16.0, 5.0 / 16.0, 0.0]);
        assert_eq!(w[2], [1.0 / 64.0, 31.0 / 64.0, 31.0 / 64.0, 1.0 / 64.0]);
    }

    #[test]
    fn weights_form_a_partition_of_unity_and_reproduce_lines() {
        for levels in 0..6 {
            let w = span_weights(levels);
            assert_eq!(w.len(), (1 << levels) + 1);
            for (i, row) in w.iter().enumerate() {
                assert_eq!(row.iter().sum::<f64>(), 1.0);
                // B-splines reproduce linear functions: control values -1, 0, 1, 2.
                let t: f64 = row
                    .iter()
                    .zip([-1.0, 0.0, 1.0, 2.0])
                    .map(|(a, b)| a * b)
                    .sum();
                assert_eq!(t, i as f64 / f64::from(1 << levels));
            }
        }
    }
}
