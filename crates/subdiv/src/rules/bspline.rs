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
    let levels = u32::try_from(levels).expect("a sensible level");
    (0..=1i64 << levels).map(|i| point(levels, i)).collect()
}

/// [`span_weights`] as an array, at compile time, for kernels specialised on the number of
/// points `S = 2^levels + 1`.
///
/// # Panics
/// At compile time, if `S − 1` is not a power of two.
#[must_use]
pub const fn span_table<const S: usize>() -> [[f64; 4]; S] {
    assert!(S >= 2 && (S - 1).is_power_of_two(), "S = 2^levels + 1");
    let levels = (S - 1).trailing_zeros();
    let mut table = [[0.0; 4]; S];
    let mut i = 0;
    while i < S {
        table[i] = point(levels, i as i64);
        i += 1;
    }
    table
}

/// The weights of level-`levels` point `i` (at parameter `i / 2^levels`, `−1 ≤ i ≤ 2^levels + 1`):
/// at level 0 a control point; above, a vertex point `(a + 6b + c) / 8` (even `i`) or an edge
/// point `(a + b) / 2` (odd `i`) of the level below. Those need the level below's points
/// `⌊i/2⌋ − 1 ..= ⌊i/2⌋ + 1`, which stay in its range.
const fn point(levels: u32, i: i64) -> [f64; 4] {
    if levels == 0 {
        let mut w = [0.0; 4];
        w[(i + 1) as usize] = 1.0;
        return w;
    }
    let h = i.div_euclid(2);
    let (rule, first): (&[f64], i64) = if i.rem_euclid(2) == 0 {
        (&[0.125, 0.75, 0.125], h - 1)
    } else {
        (&[0.5, 0.5], h)
    };
    let mut out = [0.0; 4];
    let mut r = 0;
    while r < rule.len() {
        let w = point(levels - 1, first + r as i64);
        let mut k = 0;
        while k < 4 {
            out[k] += rule[r] * w[k];
            k += 1;
        }
        r += 1;
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
    fn compile_time_table_is_the_same_rule() {
        let by_hand = [
            [10.0, 44.0, 10.0, 0.0].map(|w| w / 64.0),
            [1.0, 10.0, 5.0, 0.0].map(|w| w / 16.0),
            [1.0, 31.0, 31.0, 1.0].map(|w| w / 64.0),
            [0.0, 5.0, 10.0, 1.0].map(|w| w / 16.0),
            [0.0, 10.0, 44.0, 10.0].map(|w| w / 64.0),
        ];
        assert_eq!(span_table::<5>(), by_hand);
        assert_eq!(span_table::<3>().to_vec(), span_weights(1));
        assert_eq!(span_table::<9>().to_vec(), span_weights(3));
        assert_eq!(span_table::<17>().to_vec(), span_weights(4));
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
