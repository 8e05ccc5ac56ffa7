//! One array of fixed-size records in an unlinked temporary file: appended through a
//! buffer, read back by positioned reads of a range or of a sorted set of ids (near ids
//! read together, one read per run).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::marker::PhantomData;
use std::ops::Range;
use std::os::unix::fs::FileExt;

use bytemuck::Pod;

/// Size of a writer's buffer.
const BUFFER: usize = 1 << 20;

/// Bytes of records between two wanted ids below which one read takes both (and the records
/// between): a positioned read costs a system call, reading a few pages more costs less.
const GAP_BYTES: usize = 16 << 10;

/// Most bytes one read of [`Column::gather`] takes: sparse ids over a long range (the few
/// triangles left alive across a whole late level) are read a bounded run at a time.
const RUN_BYTES: usize = 1 << 20;

/// Records appended to an unlinked temporary file.
pub(crate) struct ColumnWriter<T> {
    out: BufWriter<File>,
    len: usize,
    record: PhantomData<T>,
}

impl<T: Pod> ColumnWriter<T> {
    /// An empty column in a new unlinked temporary file ([`tempfile::tempfile`]: the
    /// system's temporary directory), gone when dropped.
    pub(crate) fn new() -> std::io::Result<Self> {
        Ok(Self {
            out: BufWriter::with_capacity(BUFFER, tempfile::tempfile()?),
            len: 0,
            record: PhantomData,
        })
    }

    /// Appends `records`.
    pub(crate) fn push(&mut self, records: &[T]) -> std::io::Result<()> {
        self.len += records.len();
        self.out.write_all(bytemuck::cast_slice(records))
    }

    /// Appends one record.
    pub(crate) fn push_one(&mut self, record: T) -> std::io::Result<()> {
        self.push(std::slice::from_ref(&record))
    }

    /// The column, its buffer flushed.
    pub(crate) fn finish(self) -> std::io::Result<Column<T>> {
        let file = self.out.into_inner().map_err(|e| e.into_error())?;
        Ok(Column {
            file,
            len: self.len,
            record: PhantomData,
        })
    }
}

/// Records in an unlinked temporary file, read by positioned reads.
pub(crate) struct Column<T> {
    file: File,
    len: usize,
    record: PhantomData<T>,
}

impl<T> std::fmt::Debug for Column<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Column").field("len", &self.len).finish()
    }
}

impl<T: Pod> Column<T> {
    /// Records.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Records `range`.
    pub(crate) fn read(&self, range: Range<usize>) -> std::io::Result<Vec<T>> {
        let mut out = vec![T::zeroed(); range.len()];
        self.read_into(range.start, &mut out)?;
        Ok(out)
    }

    /// Records `start..start + out.len()` into `out`.
    pub(crate) fn read_into(&self, start: usize, out: &mut [T]) -> std::io::Result<()> {
        if start + out.len() > self.len {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "a read past the end of a welded store's column",
            ));
        }
        let size = std::mem::size_of::<T>();
        self.file
            .read_exact_at(bytemuck::cast_slice_mut(out), (start * size) as u64)
    }

    /// The records of `ids` (ascending, each once), in that order: the ids split into runs
    /// whose gaps are under [`GAP_BYTES`] and whose length is under [`RUN_BYTES`], one read
    /// a run.
    pub(crate) fn gather(&self, ids: &[u32]) -> std::io::Result<Vec<T>> {
        debug_assert!(ids.windows(2).all(|w| w[0] < w[1]));
        let size = std::mem::size_of::<T>().max(1);
        let (gap, longest) = ((GAP_BYTES / size).max(1), (RUN_BYTES / size).max(1));
        let mut out = Vec::with_capacity(ids.len());
        let mut run = Vec::new();
        let mut i = 0;
        while i < ids.len() {
            let first = ids[i] as usize;
            let mut j = i + 1;
            while j < ids.len()
                && (ids[j] - ids[j - 1]) as usize <= gap
                && ids[j] as usize - first < longest
            {
                j += 1;
            }
            let last = ids[j - 1] as usize;
            run.resize(last + 1 - first, T::zeroed());
            self.read_into(first, &mut run)?;
            out.extend(ids[i..j].iter().map(|&x| run[x as usize - first]));
            i = j;
        }
        Ok(out)
    }

    /// Calls `f` with the records in order, `chunk` at a time, each with the index of its
    /// first record.
    pub(crate) fn for_each_chunk<E: From<std::io::Error>>(
        &self,
        chunk: usize,
        mut f: impl FnMut(usize, &[T]) -> Result<(), E>,
    ) -> Result<(), E> {
        let mut buffer = Vec::new();
        let mut start = 0;
        while start < self.len {
            let n = chunk.max(1).min(self.len - start);
            buffer.resize(n, T::zeroed());
            self.read_into(start, &mut buffer)?;
            f(start, &buffer)?;
            start += n;
        }
        Ok(())
    }

    /// Every record, in memory.
    pub(crate) fn read_all(&self) -> std::io::Result<Vec<T>> {
        self.read(0..self.len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_reads_back_ranges_and_gathered_ids() {
        let mut w = ColumnWriter::<u32>::new().unwrap();
        let values: Vec<u32> = (0..100_000).map(|i| i * 7 + 1).collect();
        w.push(&values[..50_000]).unwrap();
        for &v in &values[50_000..] {
            w.push_one(v).unwrap();
        }
        let c = w.finish().unwrap();
        assert_eq!(c.len(), values.len());
        assert_eq!(c.read(10..20).unwrap(), values[10..20]);
        let ids = [0u32, 1, 5, 4000, 4001, 60_000, 99_999];
        let got = c.gather(&ids).unwrap();
        assert_eq!(got, ids.map(|i| values[i as usize]));
        assert!(c.read(99_990..100_001).is_err());
        let mut seen = Vec::new();
        c.for_each_chunk::<std::io::Error>(3000, |start, chunk| {
            assert_eq!(start, seen.len());
            seen.extend_from_slice(chunk);
            Ok(())
        })
        .unwrap();
        assert_eq!(seen, values);
        assert_eq!(c.read_all().unwrap(), values);
    }
}
