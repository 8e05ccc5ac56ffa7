//! `.clod` bytes in memory aligned to 64 bytes, ready for `Hierarchy::from_bytes`, and for
//! large files, in huge pages where the system grants them.
//!
//! The format starts every section on a multiple of 64 bytes, so in memory aligned like this
//! no 32-byte record (the bounds a refinement pass reads for every active node, the split
//! records) straddles two cache lines; in a buffer aligned only to 8 or 16 bytes half of them
//! do, and each of those costs refinement a second cache line.
//!
//! A buffer of [`HUGE_PAGES_FROM`] bytes or more starts on a 2 MiB boundary, and on Linux it
//! asks for transparent huge pages (`madvise(MADV_HUGEPAGE)`) before its pages are first
//! touched; [`CameraPool`](crate::CameraPool) does the same for many cameras' states.
//! Refinement reads the hierarchy at addresses spread over the whole file (thousands of 4 KiB
//! pages for a terrain) and several cameras read it in different places, so with 4 KiB pages
//! those reads also miss the TLB; a huge page covers what hundreds of small ones would. Where
//! the system refuses (huge pages `never`, another OS), the memory is ordinary pages, and
//! memory the allocator hands out again after the process touched it keeps the pages it
//! already has, so how much of a buffer huge pages back varies from run to run
//! ([`AlignedBytes::huge_page_bytes`] says; the CLI demo's report prints it).

use std::path::Path;

use caveclod_core::{FormatError, Hierarchy};

use crate::error::LoadError;

/// The size of a huge page on x86-64 and AArch64 Linux.
const HUGE_PAGE: usize = 2 << 20;

/// Buffers this large start on a huge-page boundary and ask for huge pages (smaller ones
/// would waste most of a huge page).
pub const HUGE_PAGES_FROM: usize = 2 * HUGE_PAGE;

/// Owned bytes in cache-line-aligned memory (a file to load, or a buffer to serialise into).
#[derive(Default)]
pub struct AlignedBytes {
    /// The allocation; the bytes are `buf[start..start + len]`.
    buf: Vec<u8>,
    start: usize,
    len: usize,
}

impl std::fmt::Debug for AlignedBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "AlignedBytes({} bytes)", self.len)
    }
}

impl Clone for AlignedBytes {
    fn clone(&self) -> Self {
        Self::from_slice(self.bytes())
    }
}

impl PartialEq for AlignedBytes {
    fn eq(&self, other: &Self) -> bool {
        self.bytes() == other.bytes()
    }
}

impl Eq for AlignedBytes {}

impl AlignedBytes {
    /// `len` zero bytes.
    pub fn zeroed(len: usize) -> Self {
        if len < HUGE_PAGES_FROM {
            // Zeroed by the allocator in one step.
            let buf = vec![0u8; len + 64];
            let start = (64 - buf.as_ptr().addr() % 64) % 64;
            return Self { buf, start, len };
        }
        // Zeroed by the allocator: a large allocation is usually fresh pages of its own
        // mapping, which the system zeroes when each is first touched (see the module docs
        // for when it is not), so a large buffer costs its time as it is used (a page pool's
        // slots as pages arrive), not all at once here. Advised before the first touch.
        let mut buf = vec![0u8; len + HUGE_PAGE];
        // From the address itself: `align_offset` may answer "cannot" (`usize::MAX`) by its
        // contract; the reserve holds any offset below the alignment.
        let start = (HUGE_PAGE - buf.as_ptr().addr() % HUGE_PAGE) % HUGE_PAGE;
        advise_huge_pages(&mut buf, start, len);
        Self { buf, start, len }
    }

    /// A copy of `bytes`.
    pub fn from_slice(bytes: &[u8]) -> Self {
        let mut out = Self::zeroed(bytes.len());
        out.copy_from_slice(bytes);
        out
    }

    /// The file at `path`, read into aligned memory.
    pub fn read(path: &Path) -> Result<Self, LoadError> {
        let bytes = std::fs::read(path).map_err(|e| LoadError::io(path, e))?;
        Ok(Self::from_slice(&bytes))
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.buf[self.start..self.start + self.len]
    }

    /// The bytes, to write into (a file being serialised, a test's corruption).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.buf[self.start..self.start + self.len]
    }

    /// The hierarchy in the bytes (validated on each call).
    pub fn hierarchy(&self) -> Result<Hierarchy<'_>, FormatError> {
        Hierarchy::from_bytes(self.bytes())
    }

    /// How many bytes of the memory mapping that holds these bytes the kernel backs with
    /// huge pages (`AnonHugePages` in `/proc/self/smaps`); `None` where that cannot be read
    /// (another OS) or no mapping holds them. The mapping may be larger than the buffer.
    pub fn huge_page_bytes(&self) -> Option<u64> {
        let at = self.bytes().as_ptr() as u64;
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            let mut words = line.split_whitespace();
            let first = words.next().unwrap_or("");
            if let Some((lo, hi)) = first.split_once('-') {
                if let (Ok(lo), Ok(hi)) = (u64::from_str_radix(lo, 16), u64::from_str_radix(hi, 16))
                {
                    inside = lo <= at && at < hi;
                    continue;
                }
            }
            if inside && first == "AnonHugePages:" {
                return words.next()?.parse::<u64>().ok().map(|kb| kb * 1024);
            }
        }
        None
    }
}

impl std::ops::Deref for AlignedBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        self.bytes()
    }
}

impl std::ops::DerefMut for AlignedBytes {
    fn deref_mut(&mut self) -> &mut [u8] {
        self.bytes_mut()
    }
}

/// Asks the kernel for transparent huge pages over the whole huge pages inside
/// `buf`'s reserved bytes `start..start + len` (`start` on a huge-page boundary). Advice
/// only: a refusal leaves ordinary pages, so its result is not checked.
#[cfg(target_os = "linux")]
fn advise_huge_pages(buf: &mut Vec<u8>, start: usize, len: usize) {
    let whole = len / HUGE_PAGE * HUGE_PAGE;
    if whole == 0 || start + whole > buf.capacity() {
        return;
    }
    let at = buf.as_mut_ptr().wrapping_add(start);
    // SAFETY: `at..at + whole` lies inside `buf`'s allocation (checked against its capacity
    // above) and starts on a huge-page boundary, so on a page boundary, as `madvise`
    // requires. `MADV_HUGEPAGE` changes how the kernel backs those pages, not what they hold
    // or who may access them, so no Rust reference or value is affected.
    unsafe {
        libc::madvise(at.cast(), whole, libc::MADV_HUGEPAGE);
    }
}

/// Huge pages are asked for on Linux only; elsewhere the buffer is ordinary memory.
#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_buf: &mut Vec<u8>, _start: usize, _len: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_and_large_buffers_are_aligned_and_hold_their_bytes() {
        for len in [
            0,
            1,
            63,
            64,
            1000,
            HUGE_PAGES_FROM - 1,
            HUGE_PAGES_FROM + 12_345,
        ] {
            let src: Vec<u8> = (0..len).map(|i| (i * 7 + 3) as u8).collect();
            let a = AlignedBytes::from_slice(&src);
            assert_eq!(a.bytes(), &src[..]);
            assert_eq!(a.bytes().as_ptr() as usize % 64, 0, "len {len}");
            if len >= HUGE_PAGES_FROM {
                assert_eq!(a.bytes().as_ptr() as usize % HUGE_PAGE, 0, "len {len}");
            }
            let b = a.clone();
            assert_eq!(a, b);
            assert_eq!(b.bytes().as_ptr() as usize % 64, 0);
        }
        if cfg!(target_os = "linux") {
            // The mapping of a buffer is found, whether or not the kernel granted huge pages.
            assert!(AlignedBytes::zeroed(HUGE_PAGES_FROM)
                .huge_page_bytes()
                .is_some());
        }
        let mut z = AlignedBytes::zeroed(100);
        assert!(z.iter().all(|&b| b == 0));
        z[99] = 1;
        assert_eq!(z.bytes()[99], 1);
        assert_eq!(AlignedBytes::default().bytes(), &[] as &[u8]);
    }

    #[test]
    fn a_missing_file_names_itself() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing.clod");
        let e = AlignedBytes::read(&path).unwrap_err();
        assert_eq!(e.path(), path);
        assert!(e.to_string().contains("missing.clod"), "{e}");
    }
}
