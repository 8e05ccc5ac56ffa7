//! The reader's buffers: a bounded set, handed out to reads and taken back through a free
//! list when the caller drops a [`PageBuffer`].

use std::sync::{Arc, Mutex, PoisonError};

use crate::aligned::AlignedBytes;

/// Buffers not in use, shared with every [`PageBuffer`] so that dropping one (on any thread,
/// even after the reader is gone) returns its memory.
pub(super) type FreeList = Arc<Mutex<Vec<AlignedBytes>>>;

/// The reader's buffers: those free, and how many exist.
#[derive(Debug)]
pub(super) struct BufferPool {
    free: FreeList,
    /// Buffers made so far; never more than `max`.
    allocated: usize,
    max: usize,
    /// Each buffer's size.
    size: usize,
}

impl BufferPool {
    /// Room for `max` buffers of `size` bytes, none made yet.
    pub(super) fn new(max: usize, size: usize) -> Self {
        Self {
            free: Arc::new(Mutex::new(Vec::with_capacity(max))),
            allocated: 0,
            max,
            size,
        }
    }

    /// A free buffer, or a new one while fewer than `max` exist; `None` when every buffer is
    /// in a read or held by the caller.
    pub(super) fn take(&mut self) -> Option<AlignedBytes> {
        if let Some(b) = lock(&self.free).pop() {
            return Some(b);
        }
        if self.allocated == self.max {
            return None;
        }
        self.allocated += 1;
        Some(AlignedBytes::zeroed(self.size))
    }

    /// A buffer back to the free list (a failed read's).
    pub(super) fn give_back(&self, b: AlignedBytes) {
        lock(&self.free).push(b);
    }

    /// `b`'s first `len` bytes as a buffer for the caller, returned here when dropped.
    pub(super) fn wrap(&self, b: AlignedBytes, len: usize) -> PageBuffer {
        PageBuffer {
            bytes: Some(b),
            len,
            free: Arc::clone(&self.free),
        }
    }

    /// Buffers made so far.
    pub(super) fn allocated(&self) -> usize {
        self.allocated
    }
}

/// The free list, whole even if a thread panicked holding it (a push or pop leaves it valid).
fn lock(free: &FreeList) -> std::sync::MutexGuard<'_, Vec<AlignedBytes>> {
    free.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The bytes of a finished read, 64-byte aligned. Dropping it returns the memory to the
/// reader for the next read, so a caller that copies the bytes out (or parses them) and drops
/// the buffer keeps the reader from allocating; one that holds buffers holds back reads
/// ([`SubmitError::NoBuffer`](super::SubmitError::NoBuffer)).
pub struct PageBuffer {
    /// Always `Some` until dropped.
    bytes: Option<AlignedBytes>,
    len: usize,
    free: FreeList,
}

impl PageBuffer {
    /// The bytes read.
    pub fn bytes(&self) -> &[u8] {
        match &self.bytes {
            Some(b) => &b[..self.len],
            None => &[],
        }
    }

    /// Returns the memory to the reader now (the same as dropping the buffer).
    pub fn recycle(self) {
        drop(self);
    }
}

impl Drop for PageBuffer {
    fn drop(&mut self) {
        if let Some(b) = self.bytes.take() {
            lock(&self.free).push(b);
        }
    }
}

impl std::ops::Deref for PageBuffer {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        self.bytes()
    }
}

impl AsRef<[u8]> for PageBuffer {
    fn as_ref(&self) -> &[u8] {
        self.bytes()
    }
}

impl std::fmt::Debug for PageBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "PageBuffer({} bytes)", self.len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_most_max_buffers_exist_and_dropped_ones_come_back() {
        let mut pool = BufferPool::new(2, 100);
        let a = pool.take().unwrap();
        let b = pool.take().unwrap();
        assert!(pool.take().is_none());
        let page = pool.wrap(a, 10);
        assert_eq!(page.len(), 10);
        assert_eq!(page.as_ptr() as usize % 64, 0);
        drop(page);
        pool.give_back(b);
        assert!(pool.take().is_some());
        assert!(pool.take().is_some());
        assert!(pool.take().is_none());
        assert_eq!(pool.allocated(), 2);
    }
}
