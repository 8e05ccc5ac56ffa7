//! External merge sort of the soup by spatial key, in memory-bounded chunks, merged on demand.
//!
//! [`RunBuilder`] receives the soup from a reader: it fills a chunk, and when the chunk is full
//! a writer thread sorts it by key and writes it as a sorted run, while the reader fills a
//! second chunk: reading and sorting overlap on two cores. The two chunks together take the
//! memory share the builder is given. A builder of keys alone (`RunBuilder::<u64>`, what
//! [`super::simplify`] uses: its second pass reads the faces again) sorts the keys in place
//! and writes only them, 8 bytes a triangle. A builder of records
//! (`RunBuilder::<SoupTriangle>`) sorts `(key, index)` pairs and gathers once, so the
//! 96-byte records move once, and writes each run twice: its records, and its keys alone.
//!
//! The runs are never merged into one sorted file of records. [`RunBuilder::finish`] merges
//! only the keys into one sorted key file, counting on the way the distinct octree cells the
//! triangles' centroids fall in at every depth ([`SortedSoup::occupied`]): the number of
//! clusters (and so of output triangles) a clustering level will give, known before
//! clustering. The octree is built over that key file. Records, where the runs have them, are
//! merged as they are consumed: [`SortedSoup::merge_from`] starts a k-way merge of the runs at
//! any position of the sorted order (found by binary searches on the runs' keys), so a
//! consumer can take any range of the octree's leaves straight from the merge without a
//! sorted file of records.
//!
//! The sorted order is by key, then by run, then by position in the run: the same wherever a
//! merge starts. The merges take a run's items in stretches, up to the next best run's head,
//! touching the heap once per stretch: runs of an input read in a spatially coherent order
//! interleave little.
//!
//! The builder and its runs are in `runs`, the runs' radix sort in `radix`, the merges of
//! keys and of records in `merge`.

mod merge;
mod radix;
mod runs;

use std::path::PathBuf;

use bytemuck::Pod;

use super::soup::{Cube, SoupTriangle, KEY_LEVELS};

pub use merge::SoupMerge;
pub use runs::RunBuilder;

/// What a sort chunk holds per triangle: its whole record ([`SoupTriangle`]) or its key alone
/// (`u64`, for a pass that needs only the order and the occupied cells).
pub trait RunItem: Pod + Default + Send + Sync {
    /// Whether runs of this item have records besides their keys.
    const RECORDS: bool;
    /// The item of a triangle.
    fn of(t: &SoupTriangle) -> Self;
    /// Its spatial key.
    fn key(&self) -> u64;
}

impl RunItem for SoupTriangle {
    const RECORDS: bool = true;
    fn of(t: &SoupTriangle) -> Self {
        *t
    }
    fn key(&self) -> u64 {
        self.key
    }
}

impl RunItem for u64 {
    const RECORDS: bool = false;
    fn of(t: &SoupTriangle) -> Self {
        t.key
    }
    fn key(&self) -> u64 {
        *self
    }
}

/// One sorted run on disk.
#[derive(Clone, Debug)]
pub struct Run {
    /// Its records, sorted by key (`None` for a run of keys alone).
    pub records: Option<PathBuf>,
    /// Its keys alone, in the same order.
    pub keys: PathBuf,
    /// Triangles in it.
    pub count: u64,
}

/// The sorted soup on disk: sorted runs and the merged keys.
pub struct SortedSoup {
    /// The runs, in the order they were written.
    pub runs: Vec<Run>,
    /// Every key in sorted order (`u64` each): the octree's storage.
    pub keys: PathBuf,
    /// Triangles in all.
    pub triangles: u64,
    /// Bounding cube of the keys.
    pub cube: Cube,
    /// Distinct key prefixes (occupied octree cells) at depths `0..=KEY_LEVELS`.
    pub occupied: [u64; KEY_LEVELS as usize + 1],
}

#[cfg(test)]
mod tests;
