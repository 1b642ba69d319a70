//! What the hierarchy and the topology hold in memory, for their `bytes` reports.

/// Heap bytes of a vector: its capacity times its element size.
pub(crate) fn heap<T>(v: &Vec<T>) -> usize {
    v.capacity() * size_of::<T>()
}
