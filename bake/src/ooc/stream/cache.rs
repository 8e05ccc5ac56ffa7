//! The vertex look-up: a direct-mapped cache of blocks of fixed-size records, read from a
//! file of them or decoded from the input where its vertices have a fixed stride.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;

use bytemuck::Pod;

/// Records per block of a [`BlockCache`].
const BLOCK_LEN: u64 = 1024;

/// Where a [`BlockCache`]'s records come from.
pub trait RecordSource<T> {
    /// Records `first..first + dst.len()` into `dst`.
    fn read(&mut self, first: u64, dst: &mut [T]) -> io::Result<()>;
}

/// A file of the records' bytes.
impl<T: Pod> RecordSource<T> for File {
    fn read(&mut self, first: u64, dst: &mut [T]) -> io::Result<()> {
        let size = std::mem::size_of::<T>() as u64;
        self.read_exact_at(bytemuck::cast_slice_mut(dst), first * size)
    }
}

/// A direct-mapped cache of fixed-size records: blocks of `BLOCK_LEN` records in a
/// power-of-two number of slots (so a look-up is shifts and masks, no division).
pub struct BlockCache<T: Pod, S: RecordSource<T> = File> {
    source: S,
    count: u64,
    mask: u64,
    tags: Vec<u64>,
    data: Vec<T>,
}

impl<T: Pod, S: RecordSource<T>> BlockCache<T, S> {
    /// A cache of at most about `bytes` (at least two blocks) over `count` records of
    /// `source`.
    pub fn new(source: S, count: u64, bytes: usize) -> Self {
        let size = std::mem::size_of::<T>().max(1);
        let fit = (bytes / (size * BLOCK_LEN as usize)).max(2);
        let blocks = count.div_ceil(BLOCK_LEN).max(1) as usize;
        // The largest power of two that fits the budget, no larger than needed.
        let slots =
            (1usize << (usize::BITS - 1 - fit.leading_zeros())).min(blocks.next_power_of_two());
        Self {
            source,
            count,
            mask: slots as u64 - 1,
            tags: vec![u64::MAX; slots],
            data: vec![T::zeroed(); slots * BLOCK_LEN as usize],
        }
    }

    /// The source, to change how it reads; [`BlockCache::clear`] then drops what it read
    /// before.
    pub fn source_mut(&mut self) -> &mut S {
        &mut self.source
    }

    /// Forgets every cached block.
    pub fn clear(&mut self) {
        self.tags.fill(u64::MAX);
    }

    /// Record `i` (below the count).
    #[inline]
    pub fn get(&mut self, i: u64) -> io::Result<T> {
        self.get_ref(i).copied()
    }

    /// Record `i` (below the count), by reference: a record copied straight to where it goes
    /// is not moved through a `Result` on the stack.
    #[inline]
    pub fn get_ref(&mut self, i: u64) -> io::Result<&T> {
        let block = i / BLOCK_LEN;
        let slot = (block & self.mask) as usize;
        let bl = BLOCK_LEN as usize;
        if self.tags[slot] != block {
            self.load(block, slot)?;
        }
        Ok(&self.data[slot * bl + (i % BLOCK_LEN) as usize])
    }

    #[cold]
    fn load(&mut self, block: u64, slot: usize) -> io::Result<()> {
        let bl = BLOCK_LEN as usize;
        let start = block * BLOCK_LEN;
        let n = (self.count - start).min(BLOCK_LEN) as usize;
        let dst = &mut self.data[slot * bl..slot * bl + n];
        self.source.read(start, dst)?;
        self.tags[slot] = block;
        Ok(())
    }
}

// ---------------------------------------------------------------- PLY
