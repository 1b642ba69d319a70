//! Compressed sparse row (CSR) tables, and the one way they are built.
//!
//! Row `i` of a table is `items[offsets[i]..offsets[i + 1]]`: the layout of every relation of
//! a [`Level`](crate::topology::Level) (face → vertices, vertex → faces, …), of a stencil's
//! rows, and of the workspace's other flat tables (edges at a vertex, a sparse matrix's
//! pattern, the members of an aggregate).
//!
//! - Rows whose lengths are known: the offsets are the running totals of the lengths after a
//!   leading zero ([`offsets_from_counts`]).
//! - Items that arrive in any order, each naming its row: a counting sort ([`Csr::group_by`],
//!   [`group_into`]; Knuth, *The Art of Computer Programming* vol. 3, §5.2, "distribution
//!   counting"). One pass counts the items of each row, the running totals place the rows, a
//!   second pass writes each item at its row's cursor. It is stable: a row lists its items in
//!   the order they came. So a vertex's faces come in face order (the order OpenSubdiv's `Vtr`
//!   first builds, before orienting them), and pairs already sorted by row come out as they
//!   were, in O(n) rather than a sort's O(n log n).

use rayon::prelude::*;

use crate::mesh::to_u32;

/// A compressed sparse row table: row `i` is `items[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Csr {
    /// Row starts; one more than the number of rows.
    pub offsets: Vec<u32>,
    /// All rows' items, row after row.
    pub items: Vec<u32>,
}

impl Csr {
    /// Row `i`.
    #[must_use]
    #[inline]
    pub fn row(&self, i: usize) -> &[u32] {
        &self.items[self.range(i)]
    }

    /// The item range of row `i`.
    #[must_use]
    #[inline]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// Number of rows.
    #[must_use]
    #[inline]
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// A table with the given row lengths, items zeroed.
    pub(crate) fn with_counts(counts: impl IntoIterator<Item = u32>) -> Self {
        let offsets = offsets_from_counts(counts);
        Self {
            items: vec![0; *offsets.last().expect("offsets start at 0") as usize],
            offsets,
        }
    }

    /// The table of `rows` rows listing each `(row, item)` pair's item in its row, in the
    /// order of `pairs` (a stable counting sort, see the module docs); `pairs` is run twice.
    ///
    /// # Panics
    /// If a pair's row is `rows` or more.
    #[must_use]
    pub fn group_by<I>(rows: usize, pairs: I) -> Self
    where
        I: IntoIterator<Item = (u32, u32)>,
        I::IntoIter: Clone,
    {
        let mut table = Self::default();
        group_into(rows, pairs, &mut table.offsets, &mut table.items);
        table
    }
}

/// CSR offsets of rows of the given lengths: `[0, c₀, c₀ + c₁, …]`.
#[must_use]
pub fn offsets_from_counts(counts: impl IntoIterator<Item = u32>) -> Vec<u32> {
    let counts = counts.into_iter();
    let mut offsets = Vec::with_capacity(counts.size_hint().0 + 1);
    offsets.push(0);
    offsets.extend(counts);
    running_totals(&mut offsets);
    offsets
}

/// [`offsets_from_counts`] of `rows` rows whose lengths `length(row)` gives, computed in
/// parallel.
pub(crate) fn offsets_from_lengths(
    rows: usize,
    length: impl Fn(usize) -> usize + Sync,
) -> Vec<u32> {
    let mut offsets: Vec<u32> = (0..=rows)
        .into_par_iter()
        .map(|r| if r == 0 { 0 } else { to_u32(length(r - 1)) })
        .collect();
    running_totals(&mut offsets);
    offsets
}

/// [`Csr::group_by`] for items of any type, into `offsets` and `items` (their storage is
/// reused): `offsets` gets `rows + 1` row starts, `items` the items of each row in the order
/// of `pairs`, which is run twice.
///
/// # Panics
/// If a pair's row is `rows` or more.
pub fn group_into<T, I>(rows: usize, pairs: I, offsets: &mut Vec<u32>, items: &mut Vec<T>)
where
    T: Copy + Default,
    I: IntoIterator<Item = (u32, T)>,
    I::IntoIter: Clone,
{
    let pairs = pairs.into_iter();
    // Row r's count goes two places on, so that after the running totals `offsets[r + 1]` is
    // where row r starts: placing advances it to where row r + 1 starts, which leaves the
    // first `rows + 1` entries the table's offsets without a second array of cursors.
    offsets.clear();
    offsets.resize(rows + 2, 0);
    for (row, _) in pairs.clone() {
        offsets[row as usize + 2] += 1;
    }
    running_totals(offsets);
    items.clear();
    items.resize(offsets[rows + 1] as usize, T::default());
    for (row, item) in pairs {
        let cursor = &mut offsets[row as usize + 1];
        items[*cursor as usize] = item;
        *cursor += 1;
    }
    offsets.truncate(rows + 1);
}

/// Turns row lengths after a leading zero into CSR offsets, in place.
pub(crate) fn running_totals(offsets: &mut [u32]) {
    for i in 1..offsets.len() {
        offsets[i] += offsets[i - 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_are_running_totals() {
        assert_eq!(offsets_from_counts([3, 0, 2]), [0, 3, 3, 5]);
        assert_eq!(offsets_from_counts([]), [0]);
        let t = Csr::with_counts([2, 1]);
        assert_eq!((t.rows(), t.items.len(), t.range(1)), (2, 3, 2..3));
    }

    #[test]
    fn grouping_is_stable_and_keeps_empty_rows() {
        // Items 10..15 in rows 2, 0, 2, 0, 3: row 1 is empty, rows keep the items' order.
        let t = Csr::group_by(4, [(2, 10), (0, 11), (2, 12), (0, 13), (3, 14)]);
        assert_eq!(t.offsets, [0, 2, 2, 4, 5]);
        assert_eq!(t.items, [11, 13, 10, 12, 14]);
        assert_eq!(t.row(1), [] as [u32; 0]);
        assert_eq!(Csr::group_by(2, []), Csr::with_counts([0, 0]));
    }

    #[test]
    fn grouping_sorted_pairs_keeps_them_and_reuses_storage() {
        let pairs = [(0, 5), (0, 7), (1, 2), (3, 9)];
        let t = Csr::group_by(4, pairs);
        assert_eq!(t.items, pairs.map(|(_, item)| item));
        assert_eq!(t.offsets, [0, 2, 3, 3, 4]);
        // Fewer rows and items into the same vectors, with values of another type.
        let (mut offsets, mut items) = (t.offsets, vec![(0u32, 0u16); 9]);
        group_into(1, [(0, (1, 2))], &mut offsets, &mut items);
        assert_eq!((offsets, items), (vec![0, 1], vec![(1, 2)]));
    }

    #[test]
    #[should_panic(expected = "index out of bounds")]
    fn a_row_past_the_table_panics() {
        let _ = Csr::group_by(2, [(2, 0)]);
    }
}
