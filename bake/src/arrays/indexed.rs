//! Making an array record by record on all cores.

use rayon::prelude::*;

/// `record(0..n)` in order, made on all cores: each record depends on its index alone, so
/// the array is the same whatever the threads.
pub(crate) fn collect_indexed<T: Send>(
    n: usize,
    record: impl Fn(usize) -> T + Sync + Send,
) -> Vec<T> {
    (0..n).into_par_iter().map(record).collect()
}
