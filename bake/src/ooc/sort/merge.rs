//! The merges of the sorted runs: of their keys into one sorted key file, counting the
//! occupied octree cells on the way ([`merge_keys`]), and of their records from any position
//! of the sorted order ([`SortedSoup::merge_from`]).

use std::cmp::Reverse;
use std::collections::binary_heap::{BinaryHeap, PeekMut};
use std::fs::File;
use std::io::{self, Write};
use std::os::unix::fs::FileExt;
use std::path::PathBuf;

use bytemuck::Pod;

use super::{Run, SortedSoup};
use crate::base::temp::TempSpace;
use crate::ooc::error::OocError;
use crate::ooc::soup::{SoupTriangle, KEY_LEVELS, RECORD_BYTES};

/// Counts the depths at which `key` starts a new cell after `prev`.
fn count_new_cells(occupied: &mut [u64; KEY_LEVELS as usize + 1], prev: Option<u64>, key: u64) {
    let first = match prev {
        None => 0,
        Some(p) if p == key => return,
        Some(p) => {
            let bit = 63 - (p ^ key).leading_zeros(); // highest differing bit
            (KEY_LEVELS - bit / 3) as usize
        }
    };
    for o in &mut occupied[first..] {
        *o += 1;
    }
}

/// A run's records (or keys) from a position on, read in blocks.
struct Cursor<T: Pod> {
    file: File,
    /// Next record of the file to read into the block.
    next: u64,
    /// One past the last record to read.
    end: u64,
    block: Vec<T>,
    at: usize,
    len: usize,
}

impl<T: Pod> Cursor<T> {
    /// Records `start..end` of `file`, read `block` at a time.
    fn new(file: File, start: u64, end: u64, block: usize) -> io::Result<Self> {
        let block = (block as u64).min(end.saturating_sub(start)).max(1) as usize;
        let mut c = Self {
            file,
            next: start,
            end,
            block: vec![T::zeroed(); block],
            at: 0,
            len: 0,
        };
        c.refill()?;
        Ok(c)
    }

    fn refill(&mut self) -> io::Result<()> {
        let n = (self.end.saturating_sub(self.next)).min(self.block.len() as u64) as usize;
        let size = std::mem::size_of::<T>() as u64;
        self.file.read_exact_at(
            bytemuck::cast_slice_mut(&mut self.block[..n]),
            self.next * size,
        )?;
        self.next += n as u64;
        self.at = 0;
        self.len = n;
        Ok(())
    }

    fn head(&self) -> Option<&T> {
        (self.at < self.len).then(|| &self.block[self.at])
    }

    fn advance(&mut self) -> io::Result<()> {
        self.at += 1;
        if self.at == self.len {
            self.refill()?;
        }
        Ok(())
    }
}

/// A k-way merge of sorted cursors, by key then by cursor.
struct Merge<T: Pod> {
    cursors: Vec<Cursor<T>>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
    key: fn(&T) -> u64,
}

impl<T: Pod> Merge<T> {
    fn new(cursors: Vec<Cursor<T>>, key: fn(&T) -> u64) -> Self {
        let heap = cursors
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.head().map(|t| Reverse((key(t), i as u32))))
            .collect();
        Self { cursors, heap, key }
    }

    /// Calls `f` on the next `n` items in order. The leading run gives everything it has
    /// before the next best head in one go, without touching the heap: inputs read in a
    /// spatially coherent order (scans, terrains, exported models) make long stretches.
    fn take(&mut self, n: u64, mut f: impl FnMut(&T)) -> io::Result<()> {
        let mut left = n;
        while left > 0 {
            // The next best head: the smaller child of the heap's root.
            let bound = match self.heap.as_slice() {
                [_, b] => Some(b.0),
                [_, b, c, ..] => Some(b.0.min(c.0)),
                _ => None,
            };
            let Some(mut top) = self.heap.peek_mut() else {
                return Err(io::Error::other("the sorted runs end early"));
            };
            let i = top.0 .1;
            let c = &mut self.cursors[i as usize];
            loop {
                f(&c.block[c.at]);
                left -= 1;
                c.advance()?;
                let Some(t) = c.head() else {
                    PeekMut::pop(top);
                    break;
                };
                let k = (self.key)(t);
                if left == 0 || bound.is_some_and(|b| (k, i) > b) {
                    // Sifts down when `top` drops.
                    top.0 = (k, i);
                    break;
                }
            }
        }
        Ok(())
    }
}

/// Records merged from the sorted runs, from some position of the sorted order on
/// ([`SortedSoup::merge_from`]).
pub struct SoupMerge(Merge<SoupTriangle>);

impl SoupMerge {
    /// Calls `f` on the next `n` triangles in sorted order.
    pub fn take(&mut self, n: u64, f: &mut dyn FnMut(&SoupTriangle)) -> Result<(), OocError> {
        self.0
            .take(n, f)
            .map_err(|e| OocError::temp("reading a sorted run", e))
    }
}

impl SortedSoup {
    /// A merge of the runs' records starting at position `first` of the sorted order, using
    /// about `buffer_bytes` of read buffers.
    pub fn merge_from(&self, first: u64, buffer_bytes: usize) -> Result<SoupMerge, OocError> {
        let rerr = |e| OocError::temp("reading a sorted run", e);
        let open = |p: &PathBuf| File::open(p).map_err(rerr);
        let mut starts = vec![0u64; self.runs.len()];
        if first >= self.triangles {
            for (s, r) in starts.iter_mut().zip(&self.runs) {
                *s = r.count;
            }
        } else if first > 0 {
            // Before `first`: every key below its key, then the equal keys run by run.
            let key = read_key(&open(&self.keys)?, first).map_err(rerr)?;
            let mut need = first;
            let mut equal = Vec::with_capacity(self.runs.len());
            for (s, r) in starts.iter_mut().zip(&self.runs) {
                let f = open(&r.keys)?;
                let lo = lower_bound(&f, r.count, |k| k < key).map_err(rerr)?;
                let hi = lower_bound(&f, r.count, |k| k <= key).map_err(rerr)?;
                *s = lo;
                equal.push(hi - lo);
                need = need.checked_sub(lo).ok_or_else(disagree)?;
            }
            for (s, e) in starts.iter_mut().zip(equal) {
                let t = need.min(e);
                *s += t;
                need -= t;
            }
            if need > 0 {
                return Err(disagree());
            }
        }
        let block = (buffer_bytes / self.runs.len().max(1) / RECORD_BYTES).clamp(16, 1 << 15);
        let cursors = self
            .runs
            .iter()
            .zip(starts)
            .map(|(r, s)| {
                let records = r.records.as_ref().ok_or_else(|| {
                    OocError::temp(
                        "reading a sorted run",
                        io::Error::other("the runs were sorted without their records"),
                    )
                })?;
                Cursor::new(open(records)?, s, r.count, block).map_err(rerr)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(SoupMerge(Merge::new(cursors, |t: &SoupTriangle| t.key)))
    }
}

fn disagree() -> OocError {
    OocError::temp(
        "reading the sorted runs",
        io::Error::other("the runs disagree with the merged keys"),
    )
}

/// Key `i` of a key file.
fn read_key(f: &File, i: u64) -> io::Result<u64> {
    let mut b = [0u8; 8];
    f.read_exact_at(&mut b, i * 8)?;
    Ok(u64::from_le_bytes(b))
}

/// The first index of a sorted key file of `count` keys whose key fails `before`.
fn lower_bound(f: &File, count: u64, before: impl Fn(u64) -> bool) -> io::Result<u64> {
    let (mut a, mut b) = (0, count);
    while a < b {
        let mid = a + (b - a) / 2;
        if before(read_key(f, mid)?) {
            a = mid + 1;
        } else {
            b = mid;
        }
    }
    Ok(a)
}

/// Merges the runs' keys into one sorted key file, counting occupied cells; returns the file,
/// the number of keys and the counts.
pub(super) fn merge_keys(
    temp: &TempSpace,
    runs: &[Run],
    merge_bytes: usize,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<(PathBuf, u64, [u64; KEY_LEVELS as usize + 1]), OocError> {
    let total: u64 = runs.iter().map(|r| r.count).sum();
    let rerr = |e| OocError::temp("reading a sorted run", e);
    let werr = |e| OocError::temp("writing the sorted keys", e);
    let block = (merge_bytes / runs.len().max(1) / 8).clamp(512, 1 << 19);
    let cursors = runs
        .iter()
        .map(|r| {
            let f = File::open(&r.keys).map_err(rerr)?;
            Cursor::new(f, 0, r.count, block).map_err(rerr)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut merge = Merge::new(cursors, |k: &u64| *k);
    let mut w = temp.create("sorted-keys", 1 << 20).map_err(werr)?;
    let mut occupied = [0u64; KEY_LEVELS as usize + 1];
    let mut prev = None;
    let mut out: Vec<u64> = Vec::with_capacity(1 << 16);
    let mut done = 0;
    while done < total {
        let n = (total - done).min(1 << 16);
        out.clear();
        merge
            .take(n, |&k| {
                count_new_cells(&mut occupied, prev, k);
                prev = Some(k);
                out.push(k);
            })
            .map_err(rerr)?;
        w.write_all(bytemuck::cast_slice(&out)).map_err(werr)?;
        done += n;
        progress(done, total);
    }
    let path = w.finish().map_err(werr)?;
    Ok((path, total, occupied))
}
