//! Records appended to an unlinked temporary file and read back in order, a chunk at a time:
//! what the join keeps per triangle and per vertex until the groups are known.

use std::fs::File;
use std::io::{self, BufWriter, Read, Seek, SeekFrom, Write};
use std::marker::PhantomData;

use bytemuck::Pod;

/// Records a read-back hands over at a time.
const CHUNK: usize = 1 << 16;

/// A spool of fixed-size records.
pub(super) struct Spool<T> {
    out: BufWriter<File>,
    len: usize,
    record: PhantomData<T>,
}

impl<T: Pod> Spool<T> {
    /// An empty spool in a new unlinked temporary file (the system's temporary directory).
    pub(super) fn new() -> io::Result<Self> {
        Ok(Self {
            out: BufWriter::with_capacity(1 << 20, tempfile::tempfile()?),
            len: 0,
            record: PhantomData,
        })
    }

    pub(super) fn push(&mut self, record: T) -> io::Result<()> {
        self.len += 1;
        self.out.write_all(bytemuck::bytes_of(&record))
    }

    /// Records so far.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Hands every record, in order, to `f` a chunk at a time.
    pub(super) fn for_each_chunk(
        &mut self,
        mut f: impl FnMut(&[T]) -> io::Result<()>,
    ) -> io::Result<()> {
        self.out.flush()?;
        let file = self.out.get_mut();
        file.seek(SeekFrom::Start(0))?;
        // On the heap: a chunk is too large for the stack.
        let mut buf: Vec<T> = Vec::new();
        buf.resize(CHUNK, T::zeroed());
        let mut left = self.len;
        while left > 0 {
            let n = left.min(CHUNK);
            file.read_exact(bytemuck::cast_slice_mut(&mut buf[..n]))?;
            f(&buf[..n])?;
            left -= n;
        }
        file.seek(SeekFrom::End(0))?;
        Ok(())
    }
}
